#include "depth_event_fusion_params.h"

#include <ebslam/slam/dedvs_sensors.h>

#include <cmath>
#include <exception>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

DepthEventFusionNodeConfig loadDepthEventFusionNodeConfig(const ros::NodeHandle& nh) {
  DepthEventFusionNodeConfig c;
  c.calibration = param<std::string>(nh, "calibration", c.calibration);
  if (c.calibration.empty()) {
    fail(nh, "calibration",
         "is not set (a D-eDVS sensors yaml, format in ebslam/slam/dedvs_sensors.h)");
  }
  try {
    c.sensors = ebslam::readDedvsSensors(c.calibration);
  } catch (const std::exception& error) {
    fail(nh, "calibration", "= '" + c.calibration + "' is unusable: " + error.what());
  }
  ebslam::DepthFusionConfig& f = c.fusion;
  f.min_depth_m = param<double>(nh, "min_depth", f.min_depth_m);
  f.max_depth_m = param<double>(nh, "max_depth", f.max_depth_m);
  f.max_frame_age_s = param<double>(nh, "max_frame_age", f.max_frame_age_s);
  f.max_surface_jump_ratio = param<double>(nh, "max_surface_jump_ratio", f.max_surface_jump_ratio);
  const int frames_kept = param<int>(nh, "frames_kept", static_cast<int>(f.frames_kept));
  if (frames_kept < 1 || frames_kept > 100) fail(nh, "frames_kept", "must be in 1..100");
  f.frames_kept = static_cast<std::size_t>(frames_kept);
  requirePositive(f.min_depth_m, nh, "min_depth");
  requirePositive(f.max_depth_m, nh, "max_depth");
  if (!(f.max_depth_m > f.min_depth_m)) fail(nh, "max_depth", "must exceed ~min_depth");
  requirePositive(f.max_frame_age_s, nh, "max_frame_age");
  requirePositive(f.max_surface_jump_ratio, nh, "max_surface_jump_ratio");
  validateCore(nh, f);
  c.edvs_camera_info = param<bool>(nh, "edvs_camera_info", c.edvs_camera_info);
  c.edvs_frame = param<std::string>(nh, "edvs_frame", c.edvs_frame);
  c.depth_frame = param<std::string>(nh, "depth_frame", c.depth_frame);
  requireFrame(nh, "edvs_frame", c.edvs_frame);
  requireFrame(nh, "depth_frame", c.depth_frame);
  if (c.edvs_frame == c.depth_frame) fail(nh, "edvs_frame", "must differ from ~depth_frame");
  c.publish_tf = param<bool>(nh, "publish_tf", c.publish_tf);
  c.tf_parent = param<std::string>(nh, "tf_parent", c.tf_parent);
  if (c.tf_parent != "depth" && c.tf_parent != "edvs") {
    fail(nh, "tf_parent", "must be 'depth' or 'edvs'");
  }
  c.max_wait_s = param<double>(nh, "max_wait", c.max_wait_s);
  if (!std::isfinite(c.max_wait_s) || c.max_wait_s < 0.0 || c.max_wait_s > 10.0) {
    fail(nh, "max_wait", "must be a number of seconds in [0, 10]");
  }
  c.queue_size = param<int>(nh, "queue_size", c.queue_size);
  if (c.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  return c;
}

}  // namespace ebslam_ros
