#include "pose_node_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <cmath>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

void loadPoseNodeConfig(const ros::NodeHandle& nh, PoseNodeConfig& config) {
  config.map_frame = param<std::string>(nh, "map_frame", config.map_frame);
  config.odom_frame = param<std::string>(nh, "odom_frame", config.odom_frame);
  config.base_frame = param<std::string>(nh, "base_frame", config.base_frame);
  config.sensor_frame = param<std::string>(nh, "sensor_frame", config.sensor_frame);
  config.odom_from_tf = param<bool>(nh, "odom_from_tf", config.odom_from_tf);
  config.mount_from_tf = param<bool>(nh, "mount_from_tf", config.mount_from_tf);
  config.mount_xyz = triple(nh, "mount_xyz", config.mount_xyz);
  config.mount_rpy = triple(nh, "mount_rpy", config.mount_rpy);
  config.publish_tf = param<bool>(nh, "publish_tf", config.publish_tf);
  config.path_length = param<int>(nh, "path_length", config.path_length);
  config.queue_size = param<int>(nh, "queue_size", config.queue_size);
  config.max_backward_s = param<double>(nh, "max_backward", config.max_backward_s);
  config.gap_warning_s = param<double>(nh, "gap_warning", config.gap_warning_s);
  config.max_events_per_update =
      param<int>(nh, "max_events_per_update", config.max_events_per_update);
  requireFrame(nh, "map_frame", config.map_frame);
  requireFrame(nh, "odom_frame", config.odom_frame);
  requireFrame(nh, "base_frame", config.base_frame);
  requireFrame(nh, "sensor_frame", config.sensor_frame);
  if (config.map_frame == config.odom_frame || config.odom_frame == config.base_frame ||
      config.base_frame == config.sensor_frame || config.map_frame == config.base_frame ||
      config.map_frame == config.sensor_frame || config.odom_frame == config.sensor_frame) {
    fail(nh, "map_frame", "odom_frame, base_frame and sensor_frame must be four different frames");
  }
  if (config.path_length < 1) fail(nh, "path_length", "must be at least 1");
  if (config.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  if (!std::isfinite(config.max_backward_s) || config.max_backward_s < 0.0) {
    fail(nh, "max_backward", "must be a non-negative number of seconds");
  }
  requirePositive(config.gap_warning_s, nh, "gap_warning");
  if (config.max_events_per_update < 1000) fail(nh, "max_events_per_update", "must be >= 1000");
}

}  // namespace ebslam_ros
