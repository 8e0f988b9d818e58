// rostest of EventParticleFilter's localiser interface (event_particle_filter_localisation.test):
// initialpose (rviz's "2D Pose Estimate") re-seeds the filter within one event message, also
// given in another frame; bad initial poses are dropped with the node running on; the
// global_localization service spreads the particles (particlecloud) and the diagnostics report
// the search; odom -> base_link from tf moves the estimate (~use_odometry). The events are those
// a static upward-looking eDVS sees under test/data/ceiling_lines.yaml.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2/utils.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"

#include "rostest_util.h"

namespace {

// The scene of test/data/ceiling_lines.yaml, the default camera, mount_xyz = [0.1, 0, 0.3].
const std::vector<double> kLinesX{-2.3, -1.5, -0.85, -0.2, 0.55, 1.3, 2.1};
const std::vector<double> kLinesY{-2.6, -1.7, -0.9, -0.35, 0.4, 1.15, 1.9, 2.5};
constexpr double kMountX = 0.1;

// Pixels that see a line when base_link is at (x, y, theta), shuffled.
std::vector<std::pair<int, int>> edgePixels(double x, double y, double theta) {
  const double f = 2.59 / 0.03, w = 2.59 / f;
  const double c = std::cos(theta), s = std::sin(theta);
  const double sx = x + c * kMountX, sy = y + s * kMountX;
  std::vector<std::pair<int, int>> pixels;
  for (int v = 0; v < 128; ++v) {
    for (int u = 0; u < 128; ++u) {
      const double dx = (u - 63.5) * w, dy = (v - 63.5) * w;
      const double wx = sx + c * dx - s * dy, wy = sy + s * dx + c * dy;
      bool edge = false;
      for (double a : kLinesX) edge = edge || std::abs(wx - a) < 0.012;
      for (double b : kLinesY) edge = edge || std::abs(wy - b) < 0.012;
      if (edge) pixels.emplace_back(u, v);
    }
  }
  std::shuffle(pixels.begin(), pixels.end(), std::mt19937(1));
  return pixels;
}

std::int64_t g_t_us = 1700000000000000;  // event time, rising over all tests

class LocalisationTest : public ::testing::Test {
 public:
  void SetUp() override {
    events_pub_ = nh_.advertise<ebslam_msgs::EventArray>("events", 100);
    initial_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("initialpose", 10);
    pose_sub_ = nh_.subscribe("pose", 1000, &LocalisationTest::onPose, this);
    cloud_sub_ = nh_.subscribe("particlecloud", 100, &LocalisationTest::onCloud, this);
    diag_sub_ = nh_.subscribe("/diagnostics", 100, &LocalisationTest::onDiagnostics, this);
    ebslam_ros_test::spinUntil(
        [&] { return events_pub_.getNumSubscribers() > 0 && initial_pub_.getNumSubscribers() > 0; },
        10.0);
    ASSERT_GT(events_pub_.getNumSubscribers(), 0u);
    ASSERT_GT(initial_pub_.getNumSubscribers(), 0u) << "the filter does not subscribe initialpose";
    ros::WallDuration(0.3).sleep();
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poses_.push_back(*m); }
  void onCloud(const geometry_msgs::PoseArray::ConstPtr& m) { clouds_.push_back(*m); }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    for (const auto& status : m->status) {
      if (status.name.find("ebpf") == std::string::npos) continue;
      for (const auto& kv : status.values) diagnostics_[kv.key] = kv.value;
    }
  }

  // odom -> base_link at event time t_us (the node looks it up at its batches' last event).
  void sendOdometry(std::int64_t t_us, double x, double y, double yaw) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = ebslam_msgs::toRosTime(t_us);
    t.header.frame_id = "odom";
    t.child_frame_id = "base_link";
    t.transform.translation.x = x;
    t.transform.translation.y = y;
    tf2::Quaternion q;
    q.setRPY(0, 0, yaw);
    t.transform.rotation.x = q.x();
    t.transform.rotation.y = q.y();
    t.transform.rotation.z = q.z();
    t.transform.rotation.w = q.w();
    tf_.sendTransform(t);
  }

  // One message of `count` events at the edge pixels of base_link pose (x, y, theta), 5 us apart;
  // returns its stamp once the pose with that stamp arrived (zero time if none came).
  ros::Time publishEvents(double x, double y, double theta, std::size_t count = 2000) {
    const std::vector<std::pair<int, int>> pixels = edgePixels(x, y, theta);
    ebslam_msgs::EventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = 128;
    msg.events.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      const auto& p = pixels[i % pixels.size()];
      msg.events[i].x = static_cast<std::uint16_t>(p.first);
      msg.events[i].y = static_cast<std::uint16_t>(p.second);
      msg.events[i].ts = ebslam_msgs::toRosTime(g_t_us + static_cast<std::int64_t>(i) * 5);
      msg.events[i].polarity = (i & 1u) != 0;
    }
    msg.header.stamp = msg.events.back().ts;
    g_t_us += 10000;
    events_pub_.publish(msg);
    const ros::Time stamp = msg.header.stamp;
    const bool arrived = ebslam_ros_test::spinUntil(
        [&] { return !poses_.empty() && poses_.back().header.stamp == stamp; }, 5.0);
    return arrived ? stamp : ros::Time();
  }

  void publishInitialPose(const std::string& frame, double x, double y, double yaw,
                          double sigma = 0.01) {
    geometry_msgs::PoseWithCovarianceStamped msg;
    msg.header.frame_id = frame;
    msg.header.stamp = ros::Time::now();
    msg.pose.pose.position.x = x;
    msg.pose.pose.position.y = y;
    tf2::Quaternion q;
    q.setRPY(0, 0, yaw);
    msg.pose.pose.orientation.x = q.x();
    msg.pose.pose.orientation.y = q.y();
    msg.pose.pose.orientation.z = q.z();
    msg.pose.pose.orientation.w = q.w();
    msg.pose.covariance[0] = msg.pose.covariance[7] = sigma * sigma;
    msg.pose.covariance[35] = 0.01 * 0.01;
    publishInitial(msg);
  }

  void publishInitial(const geometry_msgs::PoseWithCovarianceStamped& msg) {
    initial_pub_.publish(msg);
    ebslam_ros_test::spinUntil([] { return false; }, 0.3);  // delivered before the next events
  }

  static void expectPose(const geometry_msgs::PoseWithCovarianceStamped& p, double x, double y,
                         double yaw, double tolerance_m) {
    EXPECT_NEAR(p.pose.pose.position.x, x, tolerance_m);
    EXPECT_NEAR(p.pose.pose.position.y, y, tolerance_m);
    EXPECT_NEAR(std::remainder(tf2::getYaw(p.pose.pose.orientation) - yaw, 2 * M_PI), 0.0, 0.05);
  }

  bool awaitDiagnostic(const std::string& key, const std::string& value) {
    return ebslam_ros_test::spinUntil(
        [&] { return diagnostics_.count(key) > 0 && diagnostics_[key] == value; }, 5.0);
  }

  ros::NodeHandle nh_;
  ros::Publisher events_pub_, initial_pub_;
  ros::Subscriber pose_sub_, cloud_sub_, diag_sub_;
  tf2_ros::TransformBroadcaster tf_;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
  std::vector<geometry_msgs::PoseArray> clouds_;
  std::map<std::string, std::string> diagnostics_;
};

TEST_F(LocalisationTest, InitialPoseReseedsWithinOneMessage) {
  ASSERT_FALSE(publishEvents(0.1, -0.2, 0.3).isZero()) << "no pose at the start";
  expectPose(poses_.back(), 0.1, -0.2, 0.3, 0.03);
  publishInitialPose("map", 0.9, 0.6, -0.5);
  const ros::Time stamp = publishEvents(0.9, 0.6, -0.5);
  ASSERT_FALSE(stamp.isZero());
  // The first pose after the initial pose is already there, stamped with the events in map.
  EXPECT_EQ(poses_.back().header.stamp, stamp);
  EXPECT_EQ(poses_.back().header.frame_id, "map");
  expectPose(poses_.back(), 0.9, 0.6, -0.5, 0.03);
  EXPECT_TRUE(awaitDiagnostic("initial poses accepted", "1"));
}

// rviz sends its fixed frame: the pose is transformed into map (map -> rviz_fixed: +1 m in x).
TEST_F(LocalisationTest, InitialPoseInAnotherFrameIsTransformed) {
  publishInitialPose("rviz_fixed", -1.4, 0.3, 0.2);
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2).isZero());
  expectPose(poses_.back(), -0.4, 0.3, 0.2, 0.03);
}

TEST_F(LocalisationTest, BadInitialPosesAreDroppedAndTheNodeRunsOn) {
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2).isZero());
  publishInitialPose("nowhere", 1.0, 1.0, 0.0);  // no tf for the frame
  geometry_msgs::PoseWithCovarianceStamped bad;
  bad.header.frame_id = "map";
  bad.pose.pose.orientation.w = 1.0;
  bad.pose.pose.position.x = 1.0;
  bad.pose.covariance[0] = std::numeric_limits<double>::quiet_NaN();
  publishInitial(bad);
  bad.pose.covariance[0] = 0.0;
  bad.pose.pose.orientation.w = 0.0;  // not a rotation
  publishInitial(bad);
  bad.pose.pose.orientation.w = 1.0;
  bad.pose.covariance[0] = -1.0;  // not a covariance
  publishInitial(bad);
  // The filter keeps its pose and runs on.
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2).isZero());
  expectPose(poses_.back(), -0.4, 0.3, 0.2, 0.03);
  EXPECT_TRUE(awaitDiagnostic("initial poses rejected", "4"));
}

TEST_F(LocalisationTest, GlobalLocalizationSpreadsTheParticles) {
  ros::ServiceClient global = nh_.serviceClient<std_srvs::Empty>("global_localization");
  ASSERT_TRUE(global.waitForExistence(ros::Duration(5.0)));
  std_srvs::Empty call;
  ASSERT_TRUE(global.call(call));
  // particlecloud (AMCL's name) is published while subscribed.
  ebslam_ros_test::spinUntil([&] { return cloud_sub_.getNumPublishers() > 0; }, 5.0);
  const ros::Time stamp = publishEvents(-0.4, 0.3, 0.2, 300);
  ASSERT_FALSE(stamp.isZero());
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return !clouds_.empty() && clouds_.back().header.stamp == stamp; }, 5.0));
  const geometry_msgs::PoseArray& cloud = clouds_.back();
  EXPECT_EQ(cloud.header.frame_id, "map");
  ASSERT_GE(cloud.poses.size(), 500u);
  double mx = 0, my = 0, sx = 0, sy = 0;
  for (const auto& p : cloud.poses) mx += p.position.x, my += p.position.y;
  mx /= cloud.poses.size();
  my /= cloud.poses.size();
  for (const auto& p : cloud.poses) {
    sx += std::pow(p.position.x - mx, 2);
    sy += std::pow(p.position.y - my, 2);
  }
  // Over the 6 m x 6 m map: a uniform spread's standard deviation is about 1.7 m.
  EXPECT_GT(std::sqrt(sx / cloud.poses.size()), 1.0);
  EXPECT_GT(std::sqrt(sy / cloud.poses.size()), 1.0);
  // The published covariance says so (honest while searching): a standard deviation of metres
  // (0.2 x the hypotheses' variance of about 3 m^2 by default).
  EXPECT_GT(poses_.back().pose.covariance[0], 0.25);
  EXPECT_GT(poses_.back().pose.covariance[7], 0.25);
  EXPECT_TRUE(awaitDiagnostic("tracking state", "global_search"));
  // An initial pose ends the search.
  publishInitialPose("map", -0.4, 0.3, 0.2);
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2).isZero());
  expectPose(poses_.back(), -0.4, 0.3, 0.2, 0.03);
  EXPECT_TRUE(awaitDiagnostic("tracking state", "tracking"));
}

// ~use_odometry: base_link drives 0.3 m forward in odom between two event messages; the events
// of the second message are few (a featureless stretch), so the motion comes from odometry.
TEST_F(LocalisationTest, OdometryTfMovesTheEstimate) {
  publishInitialPose("map", -0.4, 0.3, 0.2);
  sendOdometry(g_t_us + 9995, 5.0, 2.0, 1.0);  // odom's own origin is anywhere
  ebslam_ros_test::spinUntil([] { return false; }, 0.3);
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2).isZero());
  expectPose(poses_.back(), -0.4, 0.3, 0.2, 0.03);
  // 0.3 m forward along base_link's x (odom yaw 1.0 rad).
  sendOdometry(g_t_us + 995, 5.0 + 0.3 * std::cos(1.0), 2.0 + 0.3 * std::sin(1.0), 1.0);
  ebslam_ros_test::spinUntil([] { return false; }, 0.3);
  ASSERT_FALSE(publishEvents(-0.4, 0.3, 0.2, 200).isZero());
  expectPose(poses_.back(), -0.4 + 0.3 * std::cos(0.2), 0.3 + 0.3 * std::sin(0.2), 0.2, 0.03);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_particle_filter_localisation_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
