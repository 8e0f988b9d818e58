#pragma once
// The ground truth of the simulator nodelets (EventSimulator, RgbdEventSimulator,
// ClosedLoopSimulator): the pose on `ground_truth/pose`, the tf map_frame -> ground_truth_frame,
// and the last `path_length` poses on `ground_truth/path` (latched, only while subscribed).

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <ebslam/events/trajectory.h>

#include <cstddef>
#include <deque>
#include <string>

namespace ebslam_ros {

class GroundTruthPublisher {
 public:
  /// Advertises `ground_truth/pose` and `ground_truth/path` in `nh`'s namespace.
  GroundTruthPublisher(ros::NodeHandle& nh, std::string map_frame, std::string ground_truth_frame,
                       std::size_t path_length);

  /// Publishes `pose` (ground_truth_frame -> map_frame) at `stamp`; the path too when `path_due`
  /// and someone listens (the callers throttle it: the path grows with every pose).
  void publish(const ebslam::StampedPose& pose, const ros::Time& stamp, bool path_due);

  /// Publishes the static transform map_frame -> `frame` at `start` projected on the floor (x, y
  /// and the yaw of the body's x axis; z = 0): the frame an estimator starting at its own origin
  /// shares with the ground truth.
  void publishAlignedFrame(const ebslam::StampedPose& start, const std::string& frame);

 private:
  std::string map_frame_, ground_truth_frame_;
  std::size_t path_length_;
  std::deque<geometry_msgs::PoseStamped> path_;
  ros::Publisher pose_pub_, path_pub_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
};

}  // namespace ebslam_ros
