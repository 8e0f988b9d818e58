// rostest of launch/playback.launch slam:=ebslam3d (ebslam3d_playback.test) on the shipped D-eDVS
// session (test/data/dedvs_session/dedvs_session.bag): rosbag play -> DepthEventFusion ->
// EventSlam3d. First the offline reference: the same bag's events and depth frames through the
// EB-SLAM-3D core as ebslam_experiment_ebslam3d runs it (ebslam_ros/dedvs_session.h); the bag
// starts only once this program subscribes (start_when_subscribed). Asserts, identifying
// messages by header.stamp: one depth-event message per event message with its stamp; a pose
// per depth-event message with a depth (at least 95 % of them), stamped with its last event with
// a depth, in `map`, increasing; map messages in `map`; the REP 105 tree map -> odom -> base_link
// -> edvs_optical_frame -> camera_rgb_optical_frame; the position RMSE of the eDVS path against
// the bag's ground truth within 1.5x of the offline reference's.
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/events/trajectory_evaluation.h>
#include <ebslam/simulation/dedvs_io.h>
#include <ebslam/slam/ebslam3d.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/conversions.h"
#include "ebslam_ros/dedvs_session.h"
#include "rostest_util.h"

namespace {

// The ROS run may be this much worse than the offline core on the same events: its fusion
// associates frames per message (waiting for the next frame up to a wall-time limit) and its
// filter runs per message instead of per 10 ms chunk.
constexpr double kMaxRmseRatio = 1.5;

// The node's configuration: config/ebslam3d.yaml (the core's default preset) with the launch
// file's focal length (the calibration's edvs_focal_px) and seed 1.
ebslam::Ebslam3dConfig nodeConfig(const ebslam::DedvsSensors& sensors) {
  ebslam::Ebslam3dConfig config = ebslam::Ebslam3dConfig::defaults();
  config.focal_px = sensors.edvs.focal_px;
  config.seed = 1;
  return config;
}

struct Recorder {
  std::mutex mutex;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
  std::vector<geometry_msgs::PoseStamped> truth;
  std::set<std::int64_t> input_stamps_us, depth_stamps_us, expected_pose_us;
  std::int64_t last_expected_us = -1;
  std::size_t input_messages = 0, depth_messages = 0, depth_events = 0, with_depth = 0;
  std::size_t map_messages = 0, map_points = 0;
  std::set<std::string> depth_frames, map_frames;
  std::map<std::string, std::string> parent_of;  // child -> parent, /tf and /tf_static
  std::set<std::string> tf_conflicts;
};

}  // namespace

TEST(Ebslam3dPlayback, PosesMapAndFramesTrackTheGroundTruthLikeTheOfflineCore) {
  // The offline reference on the same events.
  const ebslam_ros::DedvsSession session = ebslam_ros::readDedvsSession(SESSION_BAG);
  const ebslam::DedvsSensors sensors = ebslam::readDedvsSensors(CALIBRATION);
  const ebslam_ros::OfflineEbslam3dRun offline =
      ebslam_ros::runOfflineEbslam3d(session, sensors, {}, nodeConfig(sensors));
  const ebslam::TrajectoryEvaluation offline_eval =
      ebslam_ros::evaluateEdvsTrajectory(offline.estimate, session.ground_truth);
  std::printf("offline core: %zu events (%zu with depth), %zu poses, position RMSE %.2f cm\n",
              session.events.size(), offline.events_with_depth, offline.estimate.size(),
              100.0 * offline_eval.position_rmse_m);

  ros::NodeHandle nh;
  Recorder rec;
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  auto on_tf = [&](const tf2_msgs::TFMessage::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(rec.mutex);
    for (const geometry_msgs::TransformStamped& t : m->transforms) {
      auto it = rec.parent_of.find(t.child_frame_id);
      if (it != rec.parent_of.end() && it->second != t.header.frame_id) {
        rec.tf_conflicts.insert(t.child_frame_id);
      }
      rec.parent_of[t.child_frame_id] = t.header.frame_id;
    }
  };
  ros::Subscriber tf_sub = nh.subscribe<tf2_msgs::TFMessage>("/tf", 1000, on_tf);
  ros::Subscriber tf_static_sub = nh.subscribe<tf2_msgs::TFMessage>("/tf_static", 100, on_tf);
  ros::Subscriber input_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "/edvs/events", 10000, [&](const ebslam_msgs::EventArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        ++rec.input_messages;
        rec.input_stamps_us.insert(ebslam_msgs::toMicroseconds(m->header.stamp));
      });
  ros::Subscriber depth_sub = nh.subscribe<ebslam_msgs::DepthEventArray>(
      "/dedvs/depth_events", 10000, [&](const ebslam_msgs::DepthEventArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        ++rec.depth_messages;
        rec.depth_frames.insert(m->header.frame_id);
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
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "/ebslam3d/pose", 10000, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        rec.poses.push_back(*m);
      });
  ros::Subscriber map_sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "/ebslam3d/map", 10, [&](const sensor_msgs::PointCloud2::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        ++rec.map_messages;
        rec.map_frames.insert(m->header.frame_id);
        rec.map_points = static_cast<std::size_t>(m->width) * m->height;
      });
  ros::Subscriber truth_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/ground_truth/pose", 10000, [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(rec.mutex);
        rec.truth.push_back(*m);
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();

  // The bag has played when its last ground-truth pose has arrived.
  const double last_truth_s = session.ground_truth.back().t_s;
  auto played = [&] {
    std::lock_guard<std::mutex> lock(rec.mutex);
    return !rec.truth.empty() && rec.truth.back().header.stamp.toSec() >= last_truth_s - 1e-6;
  };
  const ros::WallTime play_deadline = ros::WallTime::now() + ros::WallDuration(300.0);
  while (ros::ok() && !played() && ros::WallTime::now() < play_deadline) {
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(played()) << "the bag did not play to its end";
  // Then the fusion and the SLAM drain their queues: wait for the pose of the last message, and
  // for a map published after it (the map comes every ~map_publish_period of wall time).
  std::size_t maps_at_end = 0;
  {
    std::lock_guard<std::mutex> lock(rec.mutex);
    maps_at_end = rec.map_messages;
  }
  auto drained = [&] {
    std::lock_guard<std::mutex> lock(rec.mutex);
    return rec.depth_messages >= session.event_messages && !rec.poses.empty() &&
           ebslam_msgs::toMicroseconds(rec.poses.back().header.stamp) >= rec.last_expected_us &&
           rec.map_messages > maps_at_end;
  };
  const ros::WallTime drain_deadline = ros::WallTime::now() + ros::WallDuration(120.0);
  while (ros::ok() && !drained() && ros::WallTime::now() < drain_deadline) {
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_TRUE(drained()) << "the last depth-event message got no pose, or no map came after it";
  // The whole rig in one REP 105 tree (tf2 chains map -> ... -> camera_rgb_optical_frame).
  std::string tf_error;
  EXPECT_TRUE(tf_buffer.canTransform("map", "camera_rgb_optical_frame", ros::Time(0), &tf_error))
      << tf_error;
  // The rig's transform is the calibration's: eDVS-frame points into the depth camera's frame.
  if (tf_buffer.canTransform("camera_rgb_optical_frame", "edvs_optical_frame", ros::Time(0))) {
    const geometry_msgs::TransformStamped rig =
        tf_buffer.lookupTransform("camera_rgb_optical_frame", "edvs_optical_frame", ros::Time(0));
    const Eigen::Vector3d t = sensors.depth_from_edvs.translation();
    EXPECT_NEAR(rig.transform.translation.x, t.x(), 1e-6);
    EXPECT_NEAR(rig.transform.translation.y, t.y(), 1e-6);
    EXPECT_NEAR(rig.transform.translation.z, t.z(), 1e-6);
    const Eigen::Quaterniond q(sensors.depth_from_edvs.rotation());
    const Eigen::Quaterniond r(rig.transform.rotation.w, rig.transform.rotation.x,
                               rig.transform.rotation.y, rig.transform.rotation.z);
    EXPECT_LT(q.angularDistance(r), 1e-6);
  }
  spinner.stop();

  std::lock_guard<std::mutex> lock(rec.mutex);
  // The fusion: one output per bag message, with its stamp, in the eDVS frame.
  EXPECT_EQ(rec.input_messages, session.event_messages);
  EXPECT_EQ(rec.depth_messages, rec.input_messages);
  EXPECT_EQ(rec.depth_stamps_us, rec.input_stamps_us);
  EXPECT_EQ(rec.depth_frames, std::set<std::string>{"edvs_optical_frame"});
  EXPECT_GT(rec.with_depth, rec.depth_events / 2);

  // Poses at the event messages' batches: one per depth-event message with a depth, stamped with
  // its last event with a depth, in `map`, increasing (a loaded machine may lose a few of a
  // burst in the subscriber queue).
  EXPECT_LE(rec.poses.size(), rec.expected_pose_us.size());
  EXPECT_GE(rec.poses.size(), rec.expected_pose_us.size() * 95 / 100);
  std::size_t not_batch = 0, not_increasing = 0, not_map = 0;
  for (std::size_t i = 0; i < rec.poses.size(); ++i) {
    not_map += rec.poses[i].header.frame_id != "map";
    not_batch +=
        rec.expected_pose_us.count(ebslam_msgs::toMicroseconds(rec.poses[i].header.stamp)) == 0;
    if (i > 0) not_increasing += rec.poses[i].header.stamp <= rec.poses[i - 1].header.stamp;
  }
  EXPECT_EQ(not_map, 0u);
  EXPECT_EQ(not_batch, 0u) << "pose stamps that are no message's last event with a depth";
  EXPECT_EQ(not_increasing, 0u);

  // The voxel map, in `map`.
  EXPECT_GT(rec.map_messages, 0u);
  EXPECT_EQ(rec.map_frames, std::set<std::string>{"map"});
  EXPECT_GT(rec.map_points, 100u);

  // REP 105: map -> odom -> base_link -> edvs_optical_frame -> camera_rgb_optical_frame, each
  // frame with one parent.
  EXPECT_EQ(rec.parent_of["odom"], "map");
  EXPECT_EQ(rec.parent_of["base_link"], "odom");
  EXPECT_EQ(rec.parent_of["edvs_optical_frame"], "base_link");
  EXPECT_EQ(rec.parent_of["camera_rgb_optical_frame"], "edvs_optical_frame");
  EXPECT_TRUE(rec.tf_conflicts.empty())
      << "a frame with two parents: " << *rec.tf_conflicts.begin();

  // The eDVS path (base_link * mount) against the bag's ground truth, scored as the offline one.
  ebslam::Trajectory estimate;
  // base_link -> eDVS of config/ebslam3d.yaml (the launch file's parameters).
  const Eigen::Isometry3d mount = ebslam_ros::readMountFromParams(EBSLAM3D_CONFIG);
  for (const auto& p : rec.poses) {
    const Eigen::Isometry3d t = ebslam_ros_test::toIsometry(p.pose.pose) * mount;
    ebslam::StampedPose s;
    s.t_s = p.header.stamp.toSec();
    s.position = t.translation();
    s.orientation = Eigen::Quaterniond(t.rotation());
    estimate.push_back(s);
  }
  ASSERT_GE(estimate.size(), 3u);
  const ebslam::TrajectoryEvaluation eval =
      ebslam_ros::evaluateEdvsTrajectory(estimate, session.ground_truth);
  std::printf(
      "ebslam3d_playback: %zu event messages, %zu events (%zu with depth), %zu poses of %zu "
      "batches, %zu maps; position RMSE %.2f cm ROS, %.2f cm offline core (ratio %.2f, bound "
      "%.1f); rotation RMSE %.2f deg ROS, %.2f deg offline\n",
      rec.input_messages, rec.depth_events, rec.with_depth, rec.poses.size(),
      rec.expected_pose_us.size(), rec.map_messages, 100.0 * eval.position_rmse_m,
      100.0 * offline_eval.position_rmse_m, eval.position_rmse_m / offline_eval.position_rmse_m,
      kMaxRmseRatio, eval.rotation_rmse_deg, offline_eval.rotation_rmse_deg);
  EXPECT_LE(eval.position_rmse_m, kMaxRmseRatio * offline_eval.position_rmse_m);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "ebslam3d_playback_rostest");
  return RUN_ALL_TESTS();
}
