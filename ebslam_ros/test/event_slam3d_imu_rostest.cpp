// rostest of the EventSlam3d nodelet with the gyro rotation prior (event_slam3d_imu.test):
// synthetic depth events of a sensor turning through the textured room of
// ebslam/simulation/synthetic_depth_events.h, and the readings of an IMU mounted on it
// (ebslam/simulation/imu_simulator.h; the IMU -> sensor rotation comes from tf). The poses must be
// those of the offline core fed the same messages and readings, near the path; bad IMU messages
// are counted and dropped with the node running on.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/simulation/imu_simulator.h>
#include <ebslam/simulation/synthetic_depth_events.h>
#include <ebslam/slam/ebslam3d.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"

#include "rostest_util.h"

namespace {

constexpr std::int64_t kT0 = 1700000000000000;  // event time of the path's start [us]
constexpr double kDurationS = 3.0;
constexpr std::size_t kEventsPerMessage = 400;

// The .test file's static tf edvs_optical_frame -> imu_link: 1.4 rad about (1, -3, 4).
Eigen::Quaterniond sensorFromImu() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(1.4, Eigen::Vector3d(1.0, -3.0, 4.0).normalized()));
}
// ~initial_pose and ~mount_xyz of the .test file (as event_slam3d_rostest.cpp).
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
Eigen::Isometry3d fromMsg(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
          .normalized()
          .toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

// At rest, then a pan of 0.8 rad and a tilt of 0.3 rad with 0.2 m sideways, at rest again.
ebslam::Trajectory testPath() {
  ebslam::Trajectory path;
  for (int k = 0; k <= 600; ++k) {
    const double t = kDurationS * k / 600.0;
    const double u = 0.5 * (1.0 - std::cos(M_PI * t / kDurationS));
    ebslam::StampedPose p;
    p.t_s = t;
    p.position = Eigen::Vector3d(0.2 * u, 0.0, 0.05 * u);
    p.orientation = Eigen::AngleAxisd(0.8 * u, Eigen::Vector3d::UnitY()) *
                    Eigen::AngleAxisd(0.3 * std::sin(M_PI * u), Eigen::Vector3d::UnitX());
    path.push_back(p);
  }
  return path;
}

struct Scene {
  ebslam::Trajectory path = testPath();
  ebslam::PointEventVector events;  // t_us from 0 at the path's start
  std::vector<ebslam::ImuReading> imu;
  Scene() {
    ebslam::SyntheticRoomConfig config;
    config.margin_m = 1.0;
    config.edges_per_square_m = 8;
    events = ebslam::simulateDepthEvents(ebslam::makeSyntheticRoom(path, config),
                                         ebslam::SyntheticDepthSensor{}, path, 0.0, kDurationS);
    ebslam::ImuSimulatorConfig imu_config;
    imu_config.body_from_imu = sensorFromImu();
    imu_config.seed = 4;
    imu = ebslam::simulateImu(path, 0.0, kDurationS, imu_config);
  }
  Eigen::Isometry3d truth(double t_s) const {
    const ebslam::StampedPose s = ebslam::interpolatePose(path, t_s);
    return initialBase() * mount() * s.isometry() * mount().inverse();
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

std::int64_t imuTime(const ebslam::ImuReading& r) {
  return kT0 + static_cast<std::int64_t>(std::llround(r.t_s * 1e6));
}

sensor_msgs::Imu imuMsg(const ebslam::ImuReading& r) {
  sensor_msgs::Imu m;
  m.header.stamp = ebslam_msgs::toRosTime(imuTime(r));
  m.header.frame_id = "imu_link";
  m.orientation_covariance[0] = -1.0;  // no orientation
  m.angular_velocity.x = r.gyro.x();
  m.angular_velocity.y = r.gyro.y();
  m.angular_velocity.z = r.gyro.z();
  m.linear_acceleration.x = r.accel.x();
  m.linear_acceleration.y = r.accel.y();
  m.linear_acceleration.z = r.accel.z();
  return m;
}

ebslam_msgs::DepthEventArray eventsMsg(std::size_t begin, std::size_t end) {
  ebslam_msgs::DepthEventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = msg.height = 128;
  for (std::size_t i = begin; i < end; ++i) {
    const ebslam::PointEvent& e = scene().events[i];
    ebslam_msgs::DepthEvent m;
    m.x = static_cast<std::uint16_t>(
        std::clamp(160.0 * e.point.x() / e.point.z() + 64.0, 0.0, 127.0));
    m.y = static_cast<std::uint16_t>(
        std::clamp(160.0 * e.point.y() / e.point.z() + 64.0, 0.0, 127.0));
    m.ts = ebslam_msgs::toRosTime(kT0 + e.t_us);
    m.depth = e.point.z();
    m.point.x = e.point.x();
    m.point.y = e.point.y();
    m.point.z = e.point.z();
    msg.events.push_back(m);
  }
  msg.header.stamp = msg.events.back().ts;
  return msg;
}

class EventSlam3dImuTest : public ::testing::Test {
 public:
  void SetUp() override {
    events_pub_ = nh_.advertise<ebslam_msgs::DepthEventArray>("depth_events", 100);
    imu_pub_ = nh_.advertise<sensor_msgs::Imu>("imu", 2000);
    pose_sub_ = nh_.subscribe("pose", 1000, &EventSlam3dImuTest::onPose, this);
    ebslam_ros_test::spinUntil(
        [&] { return events_pub_.getNumSubscribers() > 0 && imu_pub_.getNumSubscribers() > 0; },
        20.0);
    ASSERT_GT(imu_pub_.getNumSubscribers(), 0u) << "the nodelet did not subscribe to imu";
    ebslam_ros_test::spinUntil([&] { return pose_sub_.getNumPublishers() > 0; }, 20.0);
    ros::WallDuration(1.0).sleep();  // the node's tf listener receives the static IMU mount
  }
  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    poses_.push_back(*msg);
  }
  std::map<std::string, std::string> diagnostics() {
    std::map<std::string, std::string> values;
    diagnostic_msgs::DiagnosticArray latest;
    auto sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10,
        [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) { latest = *m; });
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
  ros::Publisher events_pub_, imu_pub_;
  ros::Subscriber pose_sub_;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
};

// Each event message goes out before the IMU readings that cover it (the node holds it until
// they arrive); a few bad IMU messages are mixed in. The poses equal the offline core's.
TEST_F(EventSlam3dImuTest, PosesEqualTheOfflineCoreWithTheGyroPrior) {
  const auto& events = scene().events;
  const auto& imu = scene().imu;
  ASSERT_GT(events.size(), 5000u);
  std::size_t next_imu = 0;
  std::vector<std::size_t> imu_sent_after;  // readings sent after message k (cumulative)
  std::size_t bad_sent = 0;
  for (std::size_t i = 0; i < events.size(); i += kEventsPerMessage) {
    const ebslam_msgs::DepthEventArray msg =
        eventsMsg(i, std::min(events.size(), i + kEventsPerMessage));
    events_pub_.publish(msg);
    const std::int64_t end_us = ebslam_msgs::toMicroseconds(msg.header.stamp);
    while (next_imu < imu.size()) {
      imu_pub_.publish(imuMsg(imu[next_imu]));
      const bool covers = imuTime(imu[next_imu]) >= end_us;
      ++next_imu;
      if (covers) break;
    }
    if (i / kEventsPerMessage == 10) {
      // Bad messages: NaN, a repeat of the last stamp, another frame, no angular velocity.
      sensor_msgs::Imu bad = imuMsg(imu[next_imu - 1]);
      bad.header.stamp = ebslam_msgs::toRosTime(imuTime(imu[next_imu - 1]) + 10);
      bad.angular_velocity.y = std::numeric_limits<double>::quiet_NaN();
      imu_pub_.publish(bad);
      bad = imuMsg(imu[next_imu - 1]);
      imu_pub_.publish(bad);
      bad.header.frame_id = "other_imu";
      bad.header.stamp = ebslam_msgs::toRosTime(imuTime(imu[next_imu - 1]) + 20);
      imu_pub_.publish(bad);
      bad = imuMsg(imu[next_imu - 1]);
      bad.header.stamp = ebslam_msgs::toRosTime(imuTime(imu[next_imu - 1]) + 30);
      bad.angular_velocity_covariance[0] = -1.0;
      imu_pub_.publish(bad);
      bad_sent += 4;
    }
    imu_sent_after.push_back(next_imu);
    ASSERT_TRUE(ebslam_ros_test::spinUntil(
        [&] { return !poses_.empty() && poses_.back().header.stamp == msg.header.stamp; }, 60.0))
        << "no pose stamped with the last event of message " << i / kEventsPerMessage;
  }
  // The offline core: the node's parameters, the IMU mounting, the same messages with the
  // readings up to the one covering each given first.
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
  c.max_event_rate = slam_nh.param("max_event_rate", c.max_event_rate);
  c.score_alpha = slam_nh.param("score_alpha", c.score_alpha);
  c.voxel_size_m = slam_nh.param("voxel_size", c.voxel_size_m);
  c.focal_px = slam_nh.param("focal_px", c.focal_px);
  c.diffusion_min_scale = slam_nh.param("diffusion_min_scale", c.diffusion_min_scale);
  c.diffusion_max_scale = slam_nh.param("diffusion_max_scale", c.diffusion_max_scale);
  c.reference_angular_speed = slam_nh.param("reference_angular_speed", c.reference_angular_speed);
  c.reference_linear_speed = slam_nh.param("reference_linear_speed", c.reference_linear_speed);
  c.imu.gyro.noise_density = slam_nh.param("gyro_noise_density", c.imu.gyro.noise_density);
  c.imu.gyro.bias_random_walk = slam_nh.param("gyro_bias_random_walk", c.imu.gyro.bias_random_walk);
  c.imu.gyro.initial_bias_std = slam_nh.param("gyro_initial_bias", c.imu.gyro.initial_bias_std);
  c.imu.sigma_rotation_per_sqrt_s =
      slam_nh.param("imu_sigma_rotation_time", c.imu.sigma_rotation_per_sqrt_s);
  c.imu.bias_window_s = slam_nh.param("imu_bias_window", c.imu.bias_window_s);
  c.imu.estimate_bias = slam_nh.param("imu_estimate_bias", c.imu.estimate_bias);
  c.imu.gyro.sensor_from_imu = sensorFromImu();
  ebslam::EventSlam3d offline(c, ebslam::Pose3::fromIsometry(initialBase() * mount()));
  std::size_t given = 0, k = 0;
  double worst_difference = 0.0, worst_error = 0.0, sum_sq = 0.0;
  for (std::size_t i = 0; i < events.size(); i += kEventsPerMessage, ++k) {
    for (; given < imu_sent_after[k]; ++given) {
      offline.addGyro(imuTime(imu[given]), imu[given].gyro);
    }
    ebslam::PointEventVector chunk;
    for (const auto& e : eventsMsg(i, std::min(events.size(), i + kEventsPerMessage)).events) {
      chunk.push_back(
          {ebslam_msgs::toMicroseconds(e.ts), Eigen::Vector3f(e.point.x, e.point.y, e.point.z)});
    }
    offline.process(chunk);
    ASSERT_LT(k, poses_.size());
    const Eigen::Isometry3d base = offline.estimate().isometry() * mount().inverse();
    const Eigen::Isometry3d node = fromMsg(poses_[k].pose.pose);
    worst_difference = std::max(worst_difference, (base.translation() - node.translation()).norm());
    worst_difference = std::max(
        worst_difference, Eigen::AngleAxisd(base.rotation() * node.rotation().transpose()).angle());
    const double t_s =
        1e-6 * static_cast<double>(ebslam_msgs::toMicroseconds(poses_[k].header.stamp) - kT0);
    const double error = (node.translation() - scene().truth(t_s).translation()).norm();
    worst_error = std::max(worst_error, error);
    sum_sq += error * error;
  }
  EXPECT_EQ(k, poses_.size());
  EXPECT_LT(worst_difference, 1e-6) << "node and offline core differ";
  EXPECT_GT(offline.gyroPredictedBatches(), 1000u);
  const double rmse = std::sqrt(sum_sq / static_cast<double>(k));
  std::cout << k << " poses, position RMSE " << rmse << " m, worst " << worst_error << " m\n";
  // The workspace's default preset (larger diffusion than the thesis set of event_slam3d.test):
  // measured 4.3 cm on this path.
  EXPECT_LT(rmse, 0.06);
  EXPECT_LT(worst_error, 0.1);
  const auto values = diagnostics();
  ASSERT_TRUE(values.count("IMU samples rejected"));
  EXPECT_EQ(std::stoul(values.at("IMU samples rejected")), bad_sent);
  EXPECT_EQ(std::stoul(values.at("IMU samples")), imu.size());
  EXPECT_EQ(std::stoul(values.at("events processed without IMU cover")), 0u);
  EXPECT_GT(std::stoul(values.at("batches rotated by the gyro")), 1000u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_slam3d_imu_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
