// rostest of the EventSlam3d nodelet (event_slam3d.test). The test publishes the depth events of
// a sensor moving along a known path in the synthetic textured room of
// ebslam/simulation/synthetic_depth_events.h and asserts the outputs' content (pose against the
// path, map cloud on the room's edges), frames, stamps (the last event's time), the tf tree, the
// lazy topics, the services and the knobs, and that injected bad input is reported and handled with
// the node running on. Every wait is for a message, with generous wall-time limits.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_listener.h>
#include <unistd.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/simulation/synthetic_depth_events.h>
#include <ebslam/slam/ebslam3d.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "ebslam_msgs/event_conversions.h"

#include "rostest_util.h"

namespace {

constexpr std::int64_t kT0 = 1700000000000000;  // event time of the path's start [us]
constexpr double kDurationS = 3.0;              // the path [s]
constexpr std::size_t kEventsPerMessage = 400;
constexpr int kParticles = 100;  // ~num_particles in the .test file

// ~initial_pose and ~mount_xyz of the .test file; ~mount_rpy is the default (optical frame
// looking along base_link's x).
Eigen::Isometry3d initialBase() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(0.5, -0.2, 0.1);
  return t;
}
Eigen::Isometry3d mount() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(0.1, 0.0, 0.3);
  return t;
}

Eigen::Isometry3d toIsometry(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = q.normalized().toRotationMatrix();
  t.translation() = p;
  return t;
}

Eigen::Isometry3d fromMsg(const geometry_msgs::Pose& p) {
  return toIsometry(
      Eigen::Vector3d(p.position.x, p.position.y, p.position.z),
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z));
}

// The core test's path (ebslam3d_test.cpp): starts and ends at rest; 0.3 m sideways, 0.1 m up and
// back, a turn of 0.3 rad about y and a nod of 0.15 rad (sensor frame, from the start pose).
ebslam::Trajectory testPath() {
  ebslam::Trajectory path;
  for (int k = 0; k <= 400; ++k) {
    const double t = kDurationS * k / 400.0;
    const double u = 0.5 * (1.0 - std::cos(M_PI * t / kDurationS));
    ebslam::StampedPose p;
    p.t_s = t;
    p.position = Eigen::Vector3d(0.3 * u, 0.1 * std::sin(M_PI * u), 0.05 * u);
    p.orientation = Eigen::AngleAxisd(0.3 * u, Eigen::Vector3d::UnitY()) *
                    Eigen::AngleAxisd(0.15 * std::sin(M_PI * u), Eigen::Vector3d::UnitX());
    path.push_back(p);
  }
  return path;
}

struct Scene {
  ebslam::Trajectory path = testPath();
  std::vector<Eigen::Vector3f> room;
  ebslam::PointEventVector events;  // t_us from 0 at the path's start
  Scene() {
    ebslam::SyntheticRoomConfig config;
    config.margin_m = 1.0;
    config.edges_per_square_m = 8;
    room = ebslam::makeSyntheticRoom(path, config);
    events =
        ebslam::simulateDepthEvents(room, ebslam::SyntheticDepthSensor{}, path, 0.0, kDurationS);
  }
  // True base_link in map at path time t_s: initial * mount * S(t) * mount^-1.
  Eigen::Isometry3d truth(double t_s) const {
    const ebslam::StampedPose s = ebslam::interpolatePose(path, t_s);
    return initialBase() * mount() * toIsometry(s.position, s.orientation) * mount().inverse();
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

ebslam_msgs::DepthEvent toMsg(const ebslam::PointEvent& e, std::int64_t t0_us) {
  ebslam_msgs::DepthEvent m;
  const Eigen::Vector3f& p = e.point;
  // Pixel of the point on the synthetic 128 x 128 sensor (f = 160 px, centre 64 px).
  m.x = static_cast<std::uint16_t>(std::clamp(160.0 * p.x() / p.z() + 64.0, 0.0, 127.0));
  m.y = static_cast<std::uint16_t>(std::clamp(160.0 * p.y() / p.z() + 64.0, 0.0, 127.0));
  m.ts = ebslam_msgs::toRosTime(t0_us + e.t_us);
  m.polarity = (e.t_us & 1) != 0;
  m.depth = p.z();
  m.point.x = p.x();
  m.point.y = p.y();
  m.point.z = p.z();
  return m;
}

// Index of the scene's first event at or after path time t_s (the end for t_s past the path).
std::size_t indexOf(double t_s) {
  const auto& events = scene().events;
  const auto t_us = static_cast<std::int64_t>(std::llround(t_s * 1e6));
  return static_cast<std::size_t>(
      std::lower_bound(events.begin(), events.end(), t_us,
                       [](const ebslam::PointEvent& e, std::int64_t t) { return e.t_us < t; }) -
      events.begin());
}

// Event time of the next message, shared by all tests of a run so that a test never sends the
// node back in time unless it means to.
std::int64_t g_next_t = kT0;

class EventSlam3dTest : public ::testing::Test {
 public:
  void SetUp() override {
    events_pub_ = nh_.advertise<ebslam_msgs::DepthEventArray>("depth_events", 100);
    pose_sub_ = nh_.subscribe("pose", 1000, &EventSlam3dTest::onPose, this);
    ebslam_ros_test::spinUntil([&] { return events_pub_.getNumSubscribers() > 0; }, 20.0);
    ASSERT_GT(events_pub_.getNumSubscribers(), 0u) << "the nodelet did not subscribe";
    ebslam_ros_test::spinUntil([&] { return pose_sub_.getNumPublishers() > 0; }, 20.0);
    ros::WallDuration(0.3).sleep();
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    poses_.push_back(*msg);
  }

  // Events [begin, end) of the scene as one message, path time 0 at t0_us.
  static ebslam_msgs::DepthEventArray message(std::size_t begin, std::size_t end,
                                              std::int64_t t0_us) {
    ebslam_msgs::DepthEventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = 128;
    for (std::size_t i = begin; i < end; ++i) {
      msg.events.push_back(toMsg(scene().events[i], t0_us));
    }
    if (!msg.events.empty()) msg.header.stamp = msg.events.back().ts;
    return msg;
  }

  // Publishes and waits for the pose stamped `stamp` (default: the last event's time).
  bool publishAndAwait(const ebslam_msgs::DepthEventArray& msg, ros::Time stamp = ros::Time()) {
    if (stamp.isZero()) stamp = msg.events.back().ts;
    events_pub_.publish(msg);
    return ebslam_ros_test::spinUntil(
        [&] { return !poses_.empty() && poses_.back().header.stamp == stamp; }, 60.0);
  }

  // Feeds the scene's events of path time [t0_s, t1_s) with path time 0 at t0_us; returns the
  // path time of the last event sent [s].
  double feed(double t0_s, double t1_s, std::int64_t t0_us) {
    const auto& events = scene().events;
    const std::size_t begin = indexOf(t0_s), end = indexOf(t1_s);
    for (std::size_t i = begin; i < end; i += kEventsPerMessage) {
      const ebslam_msgs::DepthEventArray msg =
          message(i, std::min(end, i + kEventsPerMessage), t0_us);
      EXPECT_TRUE(publishAndAwait(msg)) << "no pose stamped with the last event, event " << i;
      g_next_t = std::max(g_next_t, ebslam_msgs::toMicroseconds(msg.header.stamp) + 1);
    }
    return end > begin ? 1e-6 * static_cast<double>(events[end - 1].t_us) : t0_s;
  }

  // The last pose against the path at the pose's time (path time 0 at t0_us).
  void expectNearTruth(std::int64_t t0_us, double tolerance_m, double tolerance_rad) {
    ASSERT_FALSE(poses_.empty());
    const auto& last = poses_.back();
    const double t_s =
        1e-6 * static_cast<double>(ebslam_msgs::toMicroseconds(last.header.stamp) - t0_us);
    const Eigen::Isometry3d truth = scene().truth(t_s);
    const Eigen::Isometry3d estimate = fromMsg(last.pose.pose);
    EXPECT_LT((estimate.translation() - truth.translation()).norm(), tolerance_m)
        << "at path time " << t_s << " s: estimate " << estimate.translation().transpose()
        << ", truth " << truth.translation().transpose();
    EXPECT_LT(Eigen::AngleAxisd(estimate.rotation() * truth.rotation().transpose()).angle(),
              tolerance_rad)
        << "at path time " << t_s << " s";
  }

  std::map<std::string, std::string> diagnostics() {
    std::map<std::string, std::string> values;
    diagnostic_msgs::DiagnosticArray latest;
    auto sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10,
        [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) { latest = *m; });
    // The second update after now holds every message processed before now.
    for (int k = 0; k < 2; ++k) {
      latest.status.clear();
      EXPECT_TRUE(ebslam_ros_test::spinUntil([&] { return !latest.status.empty(); }, 20.0));
    }
    if (!latest.status.empty()) {
      for (const auto& kv : latest.status[0].values) values[kv.key] = kv.value;
    }
    return values;
  }

  ros::NodeHandle nh_;
  ros::Publisher events_pub_;
  ros::Subscriber pose_sub_;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
};

TEST_F(EventSlam3dTest, TracksThePathWithEventStampsFramesAndLazyOutputs) {
  ASSERT_GT(scene().events.size(), 5000u);
  std::vector<geometry_msgs::PoseArray> particles;
  std::vector<nav_msgs::Path> paths;
  std::vector<sensor_msgs::PointCloud2> clouds;
  auto particles_sub = nh_.subscribe<geometry_msgs::PoseArray>(
      "particles", 10,
      [&](const geometry_msgs::PoseArray::ConstPtr& m) { particles.push_back(*m); });
  auto path_sub = nh_.subscribe<nav_msgs::Path>(
      "path", 10, [&](const nav_msgs::Path::ConstPtr& m) { paths.push_back(*m); });
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return particles_sub.getNumPublishers() > 0 && path_sub.getNumPublishers() > 0; },
      20.0));
  ros::WallDuration(0.3).sleep();

  const std::int64_t t0 = g_next_t;
  std::set<std::int64_t> stamps;  // of every message sent [us]
  feed(0.0, kDurationS, t0);
  for (const auto& p : poses_) stamps.insert(ebslam_msgs::toMicroseconds(p.header.stamp));
  const auto& last = poses_.back();
  EXPECT_EQ(last.header.frame_id, "map");
  EXPECT_EQ(ebslam_msgs::toMicroseconds(last.header.stamp), t0 + scene().events.back().t_us);
  expectNearTruth(t0, 0.05, 3.0 * M_PI / 180.0);
  // Every pose of the run near the path (not just the last).
  double worst = 0.0, sum_sq = 0.0;
  for (const auto& p : poses_) {
    const double t_s = 1e-6 * static_cast<double>(ebslam_msgs::toMicroseconds(p.header.stamp) - t0);
    const double error =
        (fromMsg(p.pose.pose).translation() - scene().truth(t_s).translation()).norm();
    worst = std::max(worst, error);
    sum_sq += error * error;
  }
  const double rmse = std::sqrt(sum_sq / static_cast<double>(poses_.size()));
  std::cout << poses_.size() << " poses, position RMSE " << rmse << " m, worst " << worst << " m\n";
  // The same trajectory as the offline core on the same messages: the core with the node's
  // parameters (the workspace yaml on top of the default preset) fed message by message.
  {
    ros::NodeHandle slam_nh("/slam");
    ebslam::Ebslam3dConfig c = ebslam::Ebslam3dConfig::defaults();
    c.num_particles = slam_nh.param("num_particles", c.num_particles);
    c.batch_size = slam_nh.param("batch_size", c.batch_size);
    c.resample_every = slam_nh.param("resample_every", c.resample_every);
    c.event_share = slam_nh.param("event_share", c.event_share);
    c.sigma_position_m = slam_nh.param("sigma_position", c.sigma_position_m);
    c.sigma_rotation_rad = slam_nh.param("sigma_rotation", c.sigma_rotation_rad);
    c.sigma_position_per_sqrt_s = slam_nh.param("sigma_position_time", c.sigma_position_per_sqrt_s);
    c.sigma_rotation_per_sqrt_s = slam_nh.param("sigma_rotation_time", c.sigma_rotation_per_sqrt_s);
    c.diffusion_min_scale = slam_nh.param("diffusion_min_scale", c.diffusion_min_scale);
    c.diffusion_max_scale = slam_nh.param("diffusion_max_scale", c.diffusion_max_scale);
    c.reference_angular_speed = slam_nh.param("reference_angular_speed", c.reference_angular_speed);
    c.reference_linear_speed = slam_nh.param("reference_linear_speed", c.reference_linear_speed);
    c.max_event_rate = slam_nh.param("max_event_rate", c.max_event_rate);
    c.score_alpha = slam_nh.param("score_alpha", c.score_alpha);
    c.voxel_size_m = slam_nh.param("voxel_size", c.voxel_size_m);
    c.focal_px = slam_nh.param("focal_px", c.focal_px);
    const Eigen::Isometry3d start = initialBase() * mount();
    ebslam::Pose3 start_pose;
    start_pose.position = start.translation();
    start_pose.orientation = Eigen::Quaterniond(start.rotation());
    ebslam::EventSlam3d offline(c, start_pose);
    const std::size_t begin = indexOf(0.0), end = indexOf(kDurationS);
    std::size_t k = 0;
    double worst_difference = 0.0;
    for (std::size_t i = begin; i < end; i += kEventsPerMessage, ++k) {
      const ebslam_msgs::DepthEventArray msg = message(i, std::min(end, i + kEventsPerMessage), t0);
      ebslam::PointEventVector events;
      for (const auto& e : msg.events) {
        events.push_back(
            {ebslam_msgs::toMicroseconds(e.ts), Eigen::Vector3f(e.point.x, e.point.y, e.point.z)});
      }
      offline.process(events);
      ASSERT_LT(k, poses_.size());
      Eigen::Isometry3d core = Eigen::Isometry3d::Identity();
      core.linear() = offline.estimate().orientation.normalized().toRotationMatrix();
      core.translation() = offline.estimate().position;
      const Eigen::Isometry3d base = core * mount().inverse();
      const Eigen::Isometry3d node = fromMsg(poses_[k].pose.pose);
      worst_difference =
          std::max(worst_difference, (base.translation() - node.translation()).norm());
    }
    EXPECT_EQ(k, poses_.size());
    EXPECT_LT(worst_difference, 1e-6) << "node and offline core differ";
  }
  EXPECT_LT(rmse, 0.04);
  EXPECT_LT(worst, 0.08);
  // Covariance: symmetric, positive on the diagonal, small (particles within centimetres).
  const auto& c = last.pose.covariance;
  for (int i = 0; i < 6; ++i) {
    EXPECT_GT(c[7 * i], 0.0) << i;
    EXPECT_LT(c[7 * i], 1e-3) << i;
    for (int j = 0; j < 6; ++j) EXPECT_DOUBLE_EQ(c[6 * i + j], c[6 * j + i]);
  }

  ASSERT_TRUE(
      ebslam_ros_test::spinUntil([&] { return !particles.empty() && !paths.empty(); }, 10.0));
  EXPECT_EQ(particles.back().header.frame_id, "map");
  EXPECT_EQ(static_cast<int>(particles.back().poses.size()), kParticles);
  EXPECT_EQ(stamps.count(ebslam_msgs::toMicroseconds(particles.back().header.stamp)), 1u);
  EXPECT_EQ(paths.back().header.frame_id, "map");
  EXPECT_LE(paths.back().poses.size(), 50u);  // ~path_length in the .test file
  EXPECT_GT(paths.back().poses.size(), 1u);

  // The map cloud, while subscribed: voxel centres on the room's edges (map frame = the room's
  // frame moved to the sensor's start pose).
  auto map_sub = nh_.subscribe<sensor_msgs::PointCloud2>(
      "map", 2, [&](const sensor_msgs::PointCloud2::ConstPtr& m) { clouds.push_back(*m); });
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !clouds.empty(); }, 20.0)) << "no map cloud";
  const sensor_msgs::PointCloud2& cloud = clouds.back();
  EXPECT_EQ(cloud.header.frame_id, "map");
  EXPECT_EQ(ebslam_msgs::toMicroseconds(cloud.header.stamp), t0 + scene().events.back().t_us);
  ASSERT_GT(cloud.width * cloud.height, 200u);
  const Eigen::Isometry3d room_to_map = initialBase() * mount();
  std::set<std::tuple<int, int, int>> edge_cells;  // 2 cm cells holding a room point
  const auto cell = [](const Eigen::Vector3d& p) {
    return std::make_tuple(static_cast<int>(std::floor(p.x() / 0.02)),
                           static_cast<int>(std::floor(p.y() / 0.02)),
                           static_cast<int>(std::floor(p.z() / 0.02)));
  };
  for (const Eigen::Vector3f& p : scene().room) {
    const Eigen::Vector3d m = room_to_map * p.cast<double>();
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz)
          edge_cells.insert(cell(m + 0.02 * Eigen::Vector3d(dx, dy, dz)));
      }
    }
  }
  std::size_t on_edges = 0, total = 0;
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z"),
      value(cloud, "intensity");
  for (; x != x.end(); ++x, ++y, ++z, ++value) {
    ++total;
    EXPECT_GT(*value, 1.0f);  // ~map_threshold
    on_edges += edge_cells.count(cell(Eigen::Vector3d(*x, *y, *z)));
  }
  EXPECT_GT(static_cast<double>(on_edges), 0.9 * static_cast<double>(total))
      << on_edges << " of " << total << " voxels near the room's edges";
}

TEST_F(EventSlam3dTest, TfTreeRunsMapOdomBaseLinkSensor) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ros::WallDuration(1.0).sleep();  // the listener connects to the node's tf publishers
  // Back to the path's start (the sensor is at its end): reset, then the path from its start.
  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("reset", reset));
  feed(0.0, 0.4, g_next_t);
  ASSERT_FALSE(poses_.empty());
  const ros::Time stamp = poses_.back().header.stamp;
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return buffer.canTransform("map", "edvs_optical_frame", stamp); }, 20.0));
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkRep105Chain(buffer, "edvs_optical_frame", stamp));
  const auto base = buffer.lookupTransform("map", "base_link", stamp);
  EXPECT_NEAR(base.transform.translation.x, poses_.back().pose.pose.position.x, 1e-9);
  EXPECT_NEAR(base.transform.translation.z, poses_.back().pose.pose.position.z, 1e-9);
  const auto sensor = buffer.lookupTransform("base_link", "edvs_optical_frame", stamp);
  EXPECT_NEAR(sensor.transform.translation.x, 0.1, 1e-9);
  EXPECT_NEAR(sensor.transform.translation.z, 0.3, 1e-9);
  // Optical z (forward) along base_link's x.
  const Eigen::Quaterniond q(sensor.transform.rotation.w, sensor.transform.rotation.x,
                             sensor.transform.rotation.y, sensor.transform.rotation.z);
  EXPECT_NEAR((q * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-6);
}

// Bad input: each case has its reason, the node keeps publishing correct poses.
TEST_F(EventSlam3dTest, BadInputIsReportedAndHandled) {
  const auto before = diagnostics();
  const auto count = [](const std::map<std::string, std::string>& v, const std::string& key) {
    const auto it = v.find(key);
    EXPECT_NE(it, v.end()) << "no diagnostics value '" << key << "'";
    return it == v.end() ? 0ll : std::stoll(it->second);
  };

  // The stream restarts from the path's start 20 s back in time (a looping bag): the filter
  // restarts at ~initial_pose with an empty map, the poses follow the new stamps.
  const std::int64_t back = g_next_t - 20000000;
  feed(0.0, 1.0, back);
  EXPECT_EQ(ebslam_msgs::toMicroseconds(poses_.back().header.stamp),
            back + scene().events[indexOf(1.0) - 1].t_us);
  expectNearTruth(back, 0.05, 3.0 * M_PI / 180.0);
  const std::size_t poses_before = poses_.size();
  const long long messages_before = count(diagnostics(), "messages");

  // Empty message and a message in another frame: no pose.
  ebslam_msgs::DepthEventArray empty;
  empty.header.frame_id = "edvs_optical_frame";
  empty.header.stamp = ebslam_msgs::toRosTime(back + 1000000);
  events_pub_.publish(empty);
  ebslam_msgs::DepthEventArray other = message(0, 50, back + 1000000);
  other.header.frame_id = "camera_depth_optical_frame";
  events_pub_.publish(other);
  // Only events without depth (NaN): no pose.
  ebslam_msgs::DepthEventArray nans = message(0, 50, back + 1000000);
  for (auto& e : nans.events) {
    e.depth = std::numeric_limits<float>::quiet_NaN();
    e.point.x = e.point.y = e.point.z = std::numeric_limits<float>::quiet_NaN();
  }
  events_pub_.publish(nans);
  // Positive signal: the node's message counter includes the three (it counts a message and
  // publishes its poses under one lock, before the diagnostics that show the count).
  EXPECT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return count(diagnostics(), "messages") >= messages_before + 3; }, 60.0));
  ros::spinOnce();
  EXPECT_EQ(poses_.size(), poses_before);

  // The next second of the path with, every 5th event, a bad one mixed in (NaN depth, NaN point
  // with a depth, 1e6 m, 1e30 m, 1 cm away) and one event 0.5 ms early (jitter): the bad ones are
  // skipped, the pose follows the path, stamped with the last event.
  const auto& events = scene().events;
  const std::size_t begin = indexOf(1.0), end = indexOf(2.0);
  std::size_t no_depth = 0, out_of_range = 0;
  for (std::size_t i = begin; i < end; i += kEventsPerMessage) {
    ebslam_msgs::DepthEventArray msg = message(i, std::min(end, i + kEventsPerMessage), back);
    std::vector<ebslam_msgs::DepthEvent> mixed;
    for (std::size_t k = 0; k < msg.events.size(); ++k) {
      mixed.push_back(msg.events[k]);
      if (k % 5 != 2 || k + 1 == msg.events.size()) continue;
      ebslam_msgs::DepthEvent bad = msg.events[k];
      switch ((k / 5) % 5) {
        case 0:
          bad.depth = std::numeric_limits<float>::quiet_NaN();
          bad.point.x = bad.point.y = bad.point.z = std::numeric_limits<float>::quiet_NaN();
          ++no_depth;
          break;
        case 1:
          bad.point.y = std::numeric_limits<float>::quiet_NaN();
          ++no_depth;
          break;
        case 2:
          bad.depth = bad.point.z = 1e6f;
          ++out_of_range;
          break;
        case 3:
          bad.depth = bad.point.z = bad.point.x = 1e30f;
          ++out_of_range;
          break;
        default:
          bad.depth = bad.point.z = 0.01f;
          bad.point.x = bad.point.y = 0.0f;
          ++out_of_range;
          break;
      }
      mixed.push_back(bad);
    }
    msg.events = mixed;
    if (i == begin) msg.events[20].ts = msg.events[19].ts - ros::Duration(0.0005);
    ASSERT_TRUE(publishAndAwait(msg)) << "no pose for the message at event " << i;
  }
  expectNearTruth(back, 0.05, 3.0 * M_PI / 180.0);

  // A 10 s pause: a reason, and the filter continues where it was.
  const std::int64_t later = back + 10000000;
  feed(2.0, kDurationS, later);
  expectNearTruth(later, 0.05, 3.0 * M_PI / 180.0);
  g_next_t = std::max(g_next_t, later + events.back().t_us + 1);

  const auto after = diagnostics();
  EXPECT_EQ(count(after, "restarts after time jumps") - count(before, "restarts after time jumps"),
            1);
  EXPECT_EQ(count(after, "empty messages") - count(before, "empty messages"), 1);
  EXPECT_EQ(count(after, "messages in a wrong frame") - count(before, "messages in a wrong frame"),
            1);
  EXPECT_EQ(count(after, "events without depth") - count(before, "events without depth"),
            static_cast<long long>(no_depth + 50));
  EXPECT_EQ(count(after, "events out of range") - count(before, "events out of range"),
            static_cast<long long>(out_of_range));
  EXPECT_EQ(count(after, "events clamped in time") - count(before, "events clamped in time"), 1);
  EXPECT_EQ(count(after, "pauses longer than gap_warning") -
                count(before, "pauses longer than gap_warning"),
            1);
}

TEST_F(EventSlam3dTest, ResetSaveMapAndKnobs) {
  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("reset", reset));  // back to the path's start
  std::int64_t t0 = g_next_t;
  feed(0.0, 1.0, t0);
  expectNearTruth(t0, 0.05, 3.0 * M_PI / 180.0);
  // save_map writes the voxels as PLY or PCD to ~map_file.
  std_srvs::Trigger save;
  const std::string base = ::testing::TempDir() + "ebslam3d_map_" + std::to_string(::getpid());
  for (const std::string extension : {".ply", ".pcd"}) {
    ros::param::set("/slam/map_file", base + extension);
    ASSERT_TRUE(ros::service::call("save_map", save));
    EXPECT_TRUE(save.response.success) << save.response.message;
    std::ifstream in(base + extension);
    ASSERT_TRUE(in.good());
    std::string line;
    long long declared = -1, lines = 0;
    bool in_data = false;
    while (std::getline(in, line)) {
      if (in_data) {
        ++lines;
        float x = 0, y = 0, z = 0, v = 0;
        EXPECT_EQ(std::sscanf(line.c_str(), "%f %f %f %f", &x, &y, &z, &v), 4) << line;
        EXPECT_GT(v, 1.0f);
      } else if (line.rfind("element vertex ", 0) == 0 || line.rfind("POINTS ", 0) == 0) {
        declared = std::stoll(line.substr(line.rfind(' ') + 1));
      } else if (line == "end_header" || line == "DATA ascii") {
        in_data = true;
      }
    }
    EXPECT_GT(declared, 100);
    EXPECT_EQ(lines, declared);
    std::remove((base + extension).c_str());
  }
  ros::param::set("/slam/map_file", base + ".txt");
  ASSERT_TRUE(ros::service::call("save_map", save));
  EXPECT_FALSE(save.response.success);
  ros::param::set("/slam/map_file", "/nonexistent_dir/map.ply");
  ASSERT_TRUE(ros::service::call("save_map", save));
  EXPECT_FALSE(save.response.success);

  // More particles at runtime: the particles restart at the estimate, the map is kept.
  dynamic_reconfigure::Reconfigure knobs;
  dynamic_reconfigure::IntParameter n;
  n.name = "num_particles";
  n.value = 150;
  knobs.request.config.ints.push_back(n);
  ASSERT_TRUE(ros::service::call("/slam/set_parameters", knobs));
  std::vector<geometry_msgs::PoseArray> particles;
  auto particles_sub = nh_.subscribe<geometry_msgs::PoseArray>(
      "particles", 10,
      [&](const geometry_msgs::PoseArray::ConstPtr& m) { particles.push_back(*m); });
  ASSERT_TRUE(
      ebslam_ros_test::spinUntil([&] { return particles_sub.getNumPublishers() > 0; }, 20.0));
  ros::WallDuration(0.3).sleep();
  feed(1.0, 2.0, t0);
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !particles.empty(); }, 10.0));
  EXPECT_EQ(particles.back().poses.size(), 150u);
  expectNearTruth(t0, 0.05, 3.0 * M_PI / 180.0);

  // reset: the filter starts again at ~initial_pose with an empty map with the next events,
  // which may continue the stream's time.
  ASSERT_TRUE(ros::service::call("reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
  ASSERT_TRUE(ros::service::call("save_map", save));
  EXPECT_FALSE(save.response.success);  // no map until events arrive
  // The first pose after the reset: ~initial_pose moved by the diffusion of one message only.
  t0 = g_next_t;
  ASSERT_TRUE(publishAndAwait(message(0, kEventsPerMessage, t0)));
  const Eigen::Isometry3d first = fromMsg(poses_.back().pose.pose);
  EXPECT_LT((first.translation() - initialBase().translation()).norm(), 0.01);
  EXPECT_LT(Eigen::AngleAxisd(first.rotation() * initialBase().rotation().transpose()).angle(),
            0.01);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_slam3d_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
