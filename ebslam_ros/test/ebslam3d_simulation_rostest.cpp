// rostest of launch/ebslam3d_simulation.launch (ebslam3d_simulation.test): RgbdEventSimulator ->
// DepthEventFusion -> EventSlam3d on test/data/sample_session/freiburg1_xyz_excerpt.txt. The
// test relays the simulator's events to the fusion (the launch's fusion_input argument), so the
// simulation starts only once this program listens to every topic. Asserts: poses on
// /ebslam3d/pose in `map`, one per depth-event message with a depth (at least 95 % of them
// received), each stamped with the time of that message's last event with a depth, increasing; the
// depth-event messages carry the input messages' stamps; ground truth in `world`; and the position
// RMSE of the estimated eDVS path against the simulator's truth (after the alignment of
// eq. 8.16-8.19) below a bound. Every wait is for a message, with generous wall-time limits.
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/events/trajectory_evaluation.h>
#include <ebslam/simulation/dedvs_io.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/conversions.h"
#include "rostest_util.h"

namespace {

// Position RMSE bound [m] of the default set on this excerpt (the experiment tool measures
// 1.8-2.0 cm on the first 5 s of freiburg1_xyz, seed 1).
constexpr double kMaxRmseM = 0.035;

ebslam::StampedPose toStamped(double t_s, const Eigen::Isometry3d& t) {
  ebslam::StampedPose p;
  p.t_s = t_s;
  p.position = t.translation();
  p.orientation = Eigen::Quaterniond(t.rotation());
  return p;
}

struct Recorder {
  std::mutex mutex;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
  std::vector<geometry_msgs::PoseStamped> truth;
  std::set<std::int64_t> input_stamps_us;   // /dedvs/events header stamps
  std::set<std::int64_t> depth_stamps_us;   // /dedvs/depth_events header stamps
  std::set<std::int64_t> expected_pose_us;  // last event with a depth per depth-event message
  std::int64_t last_expected_us = -1;
  std::size_t input_messages = 0, depth_messages = 0, depth_events = 0, with_depth = 0;
  std::string depth_frame;
};

}  // namespace

TEST(Ebslam3dSimulation, PosesInMapWithInputStampsTrackTheGroundTruth) {
  ros::NodeHandle nh;
  Recorder rec;
  ros::Publisher relay = nh.advertise<ebslam_msgs::EventArray>("/test/events", 1000);
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "/ebslam3d/pose", 10000, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        rec.poses.push_back(*m);
      });
  ros::Subscriber truth_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/dedvs/ground_truth/pose", 10000, [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        rec.truth.push_back(*m);
      });
  ros::Subscriber depth_sub = nh.subscribe<ebslam_msgs::DepthEventArray>(
      "/dedvs/depth_events", 10000, [&](const ebslam_msgs::DepthEventArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        ++rec.depth_messages;
        rec.depth_frame = m->header.frame_id;
        rec.depth_stamps_us.insert(ebslam_msgs::toMicroseconds(m->header.stamp));
        rec.depth_events += m->events.size();
        std::int64_t last = -1;
        for (const ebslam_msgs::DepthEvent& e : m->events) {
          if (std::isfinite(e.point.x) && std::isfinite(e.point.y) && std::isfinite(e.point.z)) {
            last = ebslam_msgs::toMicroseconds(e.ts);
            ++rec.with_depth;
          }
        }
        if (last >= 0) {
          rec.expected_pose_us.insert(last);
          rec.last_expected_us = std::max(rec.last_expected_us, last);
        }
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();
  // Everything is subscribed; the fusion listens to the relay: start the simulation.
  const ros::WallTime ready_deadline = ros::WallTime::now() + ros::WallDuration(120.0);
  while (ros::ok() &&
         (relay.getNumSubscribers() == 0 || pose_sub.getNumPublishers() == 0 ||
          truth_sub.getNumPublishers() == 0 || depth_sub.getNumPublishers() == 0) &&
         ros::WallTime::now() < ready_deadline) {
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_GT(relay.getNumSubscribers(), 0u) << "the fusion does not listen to /test/events";
  ros::Subscriber input_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "/dedvs/events", 10000, [&](const ebslam_msgs::EventArray::ConstPtr& m) {
        {
          std::lock_guard<std::mutex> lock(rec.mutex);
          ++rec.input_messages;
          rec.input_stamps_us.insert(ebslam_msgs::toMicroseconds(m->header.stamp));
        }
        relay.publish(m);
      });

  // The simulation ends at the excerpt's end: the last ground-truth pose is stamped there.
  const ebslam::Trajectory excerpt = ebslam::readTumTrajectory(EXCERPT);
  const double duration_s = excerpt.back().t_s - excerpt.front().t_s;
  auto simulationDone = [&] {
    std::lock_guard<std::mutex> lock(rec.mutex);
    return rec.truth.size() > 1 && (rec.truth.back().header.stamp.toSec() -
                                    rec.truth.front().header.stamp.toSec()) >= duration_s - 0.02;
  };
  const ros::WallTime sim_deadline = ros::WallTime::now() + ros::WallDuration(600.0);
  while (ros::ok() && !simulationDone() && ros::WallTime::now() < sim_deadline) {
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(simulationDone()) << "the simulation did not reach the excerpt's end";
  // Then the fusion and the SLAM drain their queues: wait for the pose of the last message.
  auto drained = [&] {
    std::lock_guard<std::mutex> lock(rec.mutex);
    return rec.depth_messages >= rec.input_messages && !rec.poses.empty() &&
           ebslam_msgs::toMicroseconds(rec.poses.back().header.stamp) >= rec.last_expected_us;
  };
  const ros::WallTime drain_deadline = ros::WallTime::now() + ros::WallDuration(300.0);
  while (ros::ok() && !drained() && ros::WallTime::now() < drain_deadline) {
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(drained()) << "the last depth-event message got no pose";
  spinner.stop();

  std::lock_guard<std::mutex> lock(rec.mutex);
  EXPECT_EQ(rec.depth_frame, "edvs_optical_frame");
  // The fusion keeps the input stamps, one output per input message.
  EXPECT_EQ(rec.depth_messages, rec.input_messages);
  EXPECT_EQ(rec.depth_stamps_us, rec.input_stamps_us);
  // Most events get a depth (the fusion's share on these runs is about 70 %).
  EXPECT_GT(rec.with_depth, rec.depth_events / 2);

  // One pose per depth-event message with a depth, stamped with its last such event, in `map`,
  // increasing.
  // (A subscriber on a loaded machine may lose a few of a burst; the node keeps 1000.)
  EXPECT_LE(rec.poses.size(), rec.expected_pose_us.size());
  EXPECT_GE(rec.poses.size(), rec.expected_pose_us.size() * 95 / 100);
  EXPECT_GT(rec.poses.size(), static_cast<std::size_t>(80.0 * duration_s));  // 100 Hz messages
  std::size_t not_input = 0, not_increasing = 0;
  for (std::size_t i = 0; i < rec.poses.size(); ++i) {
    EXPECT_EQ(rec.poses[i].header.frame_id, "map");
    const std::int64_t t = ebslam_msgs::toMicroseconds(rec.poses[i].header.stamp);
    not_input += rec.expected_pose_us.count(t) == 0;
    if (i > 0) not_increasing += rec.poses[i].header.stamp <= rec.poses[i - 1].header.stamp;
  }
  EXPECT_EQ(not_input, 0u) << "pose stamps that are no message's last event with a depth";
  EXPECT_EQ(not_increasing, 0u);
  for (const geometry_msgs::PoseStamped& t : rec.truth) EXPECT_EQ(t.header.frame_id, "world");

  // Trajectory error of the eDVS: estimate = base_link * mount in map, truth = rig (depth
  // optical frame) * depth_from_edvs in world.
  const ebslam::DedvsSensors sensors = ebslam::readDedvsSensors(CALIBRATION);
  ebslam::Trajectory estimate, truth;
  // base_link -> eDVS of config/ebslam3d.yaml (the launch file's parameters).
  const Eigen::Isometry3d mount = ebslam_ros::readMountFromParams(EBSLAM3D_CONFIG);
  for (const auto& p : rec.poses) {
    estimate.push_back(
        toStamped(p.header.stamp.toSec(), ebslam_ros_test::toIsometry(p.pose.pose) * mount));
  }
  for (const auto& t : rec.truth) {
    truth.push_back(toStamped(t.header.stamp.toSec(),
                              ebslam_ros_test::toIsometry(t.pose) * sensors.depth_from_edvs));
  }
  ebslam::TrajectoryEvaluationConfig config;
  config.max_time_offset_s = 0.05;
  const ebslam::TrajectoryEvaluation eval = ebslam::evaluateTrajectory(estimate, truth, config);
  std::printf(
      "ebslam3d_simulation: %zu input messages, %zu events (%zu with depth), %zu poses, "
      "%zu ground-truth poses; position RMSE %.2f cm (max %.2f cm), rotation RMSE %.2f deg, "
      "time offset %.1f ms\n",
      rec.input_messages, rec.depth_events, rec.with_depth, rec.poses.size(), rec.truth.size(),
      100.0 * eval.position_rmse_m, 100.0 * eval.position_max_m, eval.rotation_rmse_deg,
      1e3 * eval.alignment.time_offset_s);
  EXPECT_LT(eval.position_rmse_m, kMaxRmseM);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "ebslam3d_simulation_rostest");
  return RUN_ALL_TESTS();
}
