// rostest of the ClosedLoopSimulator nodelet (closed_loop_simulator.test, a 2 m x 1.2 m box, the
// robot starting 0.85 m before the east wall's contact): stands at the map origin without
// commands, drives forward on cmd_vel with events in the driver's conventions until the front
// bumper reports the wall, stops when cmd_vel stops or turns non-finite, reverses on command.
// Stamps on the simulator's /clock. Waits are on simulated progress with long wall timeouts.
#include <ebslam_msgs/Bump.h>
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/Marker.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace {

class ClosedLoopSimulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cmd_pub_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 10);
    events_sub_ = nh_.subscribe<ebslam_msgs::EventArray>(
        "events", 1000,
        [this](const ebslam_msgs::EventArray::ConstPtr& m) { arrays_.push_back(*m); });
    bump_sub_ = nh_.subscribe<ebslam_msgs::Bump>(
        "bump", 1000, [this](const ebslam_msgs::Bump::ConstPtr& m) { bumps_.push_back(*m); });
    pose_sub_ = nh_.subscribe<geometry_msgs::PoseStamped>(
        "ground_truth/pose", 1000,
        [this](const geometry_msgs::PoseStamped::ConstPtr& m) { poses_.push_back(*m); });
    clock_sub_ = nh_.subscribe<rosgraph_msgs::Clock>(
        "/clock", 1000, [this](const rosgraph_msgs::Clock::ConstPtr& m) { clock_ = m->clock; });
    plan_sub_ = nh_.subscribe<visualization_msgs::Marker>(
        "floor_plan", 1, [this](const visualization_msgs::Marker::ConstPtr& m) { plan_ = *m; });
  }

  bool waitFor(const std::function<bool()>& done, double timeout_s = 60.0,
               const std::function<void()>& step = {}) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::WallTime::now() < end) {
      if (step) step();
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.02).sleep();
    }
    return false;
  }

  // Spins while the simulation advances by dt_s (by the ground truth's stamps).
  bool runFor(double dt_s, const std::function<void()>& step = {}) {
    if (poses_.empty()) return false;
    const ros::Time until = poses_.back().header.stamp + ros::Duration(dt_s);
    return waitFor([&] { return poses_.back().header.stamp >= until; }, 60.0 + 20.0 * dt_s, step);
  }

  void command(double v, double omega) {
    geometry_msgs::Twist t;
    t.linear.x = v;
    t.angular.z = omega;
    cmd_pub_.publish(t);
  }

  double x() const { return poses_.back().pose.position.x; }
  double y() const { return poses_.back().pose.position.y; }

  ros::NodeHandle nh_;
  ros::Publisher cmd_pub_;
  ros::Subscriber events_sub_, bump_sub_, pose_sub_, clock_sub_, plan_sub_;
  std::vector<ebslam_msgs::EventArray> arrays_;
  std::vector<ebslam_msgs::Bump> bumps_;
  std::vector<geometry_msgs::PoseStamped> poses_;
  ros::Time clock_;
  visualization_msgs::Marker plan_;
};

TEST_F(ClosedLoopSimulatorTest, DrivesBumpsStopsAndReverses) {
  ASSERT_TRUE(waitFor([&] { return poses_.size() > 10 && cmd_pub_.getNumSubscribers() > 0; }));
  // No command: the robot stands at the map frame's origin (its start pose).
  ASSERT_TRUE(runFor(0.5));
  EXPECT_NEAR(x(), 0.0, 1e-9);
  EXPECT_NEAR(y(), 0.0, 1e-9);
  EXPECT_EQ(poses_.back().header.frame_id, "map");
  EXPECT_GE(poses_.front().header.stamp, ros::Time(500.0));
  // The floor plan in the map frame: the box's corner (0, 0) lies at (-1, -0.6).
  ASSERT_TRUE(waitFor([&] { return !plan_.points.empty(); }));
  EXPECT_EQ(plan_.header.frame_id, "map");
  EXPECT_EQ(plan_.points.size(), 8u);  // 4 walls, 2 points each
  EXPECT_NEAR(plan_.points.front().x, -1.0, 1e-9);
  EXPECT_NEAR(plan_.points.front().y, -0.6, 1e-9);

  // Forward at 0.3 m/s until the front bumper touches the east wall (0.85 m ahead).
  arrays_.clear();
  bumps_.clear();
  ASSERT_TRUE(waitFor([&] { return !bumps_.empty() && bumps_.back().segments != 0u; }, 120.0,
                      [&] { command(0.3, 0.0); }));
  const ebslam_msgs::Bump contact = bumps_.back();
  EXPECT_EQ(contact.header.frame_id, "base_link");
  EXPECT_EQ(contact.segment_count, 8);
  EXPECT_TRUE(contact.segments & 1u) << contact.segments;  // the front segment
  EXPECT_NEAR(contact.direction, 0.0, 0.4);
  ros::spinOnce();
  EXPECT_NEAR(x(), 0.85, 0.02);
  EXPECT_NEAR(y(), 0.0, 0.01);
  // Events of the motion, in the driver's conventions, on the simulator's clock.
  std::size_t events = 0;
  ros::Time previous(0);
  for (const auto& a : arrays_) {
    EXPECT_EQ(a.header.frame_id, "edvs_optical_frame");
    EXPECT_EQ(a.width, 128u);
    EXPECT_EQ(a.height, 128u);
    if (!a.events.empty()) {
      EXPECT_EQ(a.header.stamp, a.events.back().ts);
    }
    for (const auto& e : a.events) {
      EXPECT_LT(e.x, 128);
      EXPECT_LT(e.y, 128);
      EXPECT_GE(e.ts, previous);
      previous = e.ts;
    }
    events += a.events.size();
  }
  EXPECT_GT(events, 1000u);
  EXPECT_LE(contact.header.stamp, clock_);
  for (std::size_t i = 1; i < bumps_.size(); ++i) {
    EXPECT_GT(bumps_[i].header.stamp, bumps_[i - 1].header.stamp);
  }

  // No more commands: after ~cmd_timeout the robot stands (pressing no longer: no contact).
  ASSERT_TRUE(runFor(1.5));
  const double stopped_x = x();
  ASSERT_TRUE(runFor(1.0));
  EXPECT_NEAR(x(), stopped_x, 1e-9);
  EXPECT_EQ(bumps_.back().segments, 0u);

  // A non-finite command brakes (the robot does not move).
  ASSERT_TRUE(runFor(1.0, [&] { command(std::numeric_limits<double>::quiet_NaN(), 0.0); }));
  EXPECT_NEAR(x(), stopped_x, 1e-9);

  // Reverse on command: the robot backs away from the wall.
  ASSERT_TRUE(runFor(1.0, [&] { command(-0.2, 0.0); }));
  EXPECT_LT(x(), stopped_x - 0.05);

  // Ground truth on tf.
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ASSERT_TRUE(waitFor([&] { return buffer.canTransform("map", "ground_truth", ros::Time(0)); }));
  const auto gt = buffer.lookupTransform("map", "ground_truth", ros::Time(0));
  EXPECT_LT(gt.transform.translation.x, stopped_x);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "closed_loop_simulator_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
