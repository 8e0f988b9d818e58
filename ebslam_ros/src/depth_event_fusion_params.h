#pragma once
// Parameters of the DepthEventFusion nodelet.

#include <ros/node_handle.h>

#include <ebslam/slam/dedvs_fusion.h>

#include <string>

namespace ebslam_ros {

/// Configuration of the DepthEventFusion nodelet (D-eDVS depth for every event, thesis 8.2).
struct DepthEventFusionNodeConfig {
  /// ~calibration (required): sensors yaml (ebslam/slam/dedvs_sensors.h readDedvsSensors format:
  /// eDVS intrinsics and distortion, depth intrinsics, depth_from_edvs, depth clock offset, frame
  /// rate)
  std::string calibration;
  ebslam::DedvsSensors sensors;      ///< read from ~calibration
  ebslam::DepthFusionConfig fusion;  ///< ~min_depth, ~max_depth [m], ~max_frame_age [s],
                                     ///< ~max_surface_jump_ratio, ~frames_kept
  bool edvs_camera_info = false;     ///< ~edvs_camera_info: event camera size, f, centre and
                                     ///< lens from `camera_info` (zero D: the kappas stay)
  std::string edvs_frame = "edvs_optical_frame";           ///< ~edvs_frame
  std::string depth_frame = "camera_depth_optical_frame";  ///< ~depth_frame
  bool publish_tf = true;  ///< ~publish_tf: static tf of the calibration's depth_from_edvs
  /// ~tf_parent: "depth" (~depth_frame -> ~edvs_frame) or "edvs" (~edvs_frame -> ~depth_frame,
  /// when the eDVS frame has a parent already, e.g. EventSlam3d's base_link)
  std::string tf_parent = "depth";
  /// ~max_wait: longest wall time an EventArray newer than the latest depth frame waits for the
  /// next (nearer) frame [s]
  double max_wait_s = 0.2;
  int queue_size = 100;  ///< ~queue_size: subscriber queues [messages]
};

DepthEventFusionNodeConfig loadDepthEventFusionNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
