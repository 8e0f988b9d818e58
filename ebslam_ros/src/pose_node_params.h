#pragma once
// The parameters every pose-estimating nodelet shares (EventParticleFilter, EventSlam2d,
// EventSlam3d; pose_filter_nodelet_base.h): frames, sensor mounting, outputs and input checks.

#include <ros/node_handle.h>

#include <array>
#include <string>

namespace ebslam_ros {

/// Frames (REP 105: map -> odom -> base_link -> sensor_frame), mounting, outputs, input checks.
struct PoseNodeConfig {
  std::string map_frame = "map";                    ///< ~map_frame
  std::string odom_frame = "odom";                  ///< ~odom_frame
  std::string base_frame = "base_link";             ///< ~base_frame
  std::string sensor_frame = "edvs_optical_frame";  ///< ~sensor_frame: the events' frame
  /// ~odom_from_tf: map -> odom = pose * (odom -> base_link from tf, e.g. wheel odometry);
  /// false: the node publishes odom -> base_link as identity.
  bool odom_from_tf = false;
  /// ~mount_from_tf: base_link -> sensor_frame from tf; false: from ~mount_xyz, ~mount_rpy,
  /// published by the node as a static transform.
  bool mount_from_tf = false;
  std::array<double, 3> mount_xyz{0.0, 0.0, 0.0};  ///< ~mount_xyz [m]
  std::array<double, 3> mount_rpy{0.0, 0.0, 0.0};  ///< ~mount_rpy [rad] (fixed axes, as tf2)
  bool publish_tf = true;                          ///< ~publish_tf: map -> odom (-> base_link)
  int path_length = 10000;                         ///< ~path_length: poses kept on `path`
  int queue_size = 1000;                           ///< ~queue_size: event messages queued
  double max_backward_s = 0.001;  ///< ~max_backward: earlier events are clamped up to this [s]
  double gap_warning_s = 1.0;     ///< ~gap_warning: warn about pauses in the stream longer [s]
  /// ~max_events_per_update: events per filter call and pose (a huge message gives several).
  int max_events_per_update = 200000;
};

/// Reads and validates the fields of `config` from `private_nh` over their present values.
void loadPoseNodeConfig(const ros::NodeHandle& private_nh, PoseNodeConfig& config);

}  // namespace ebslam_ros
