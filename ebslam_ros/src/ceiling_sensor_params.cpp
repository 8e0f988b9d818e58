#include "ceiling_sensor_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& nh) {
  CeilingSensorConfig config;
  ebslam::CameraModel& c = config.camera;
  c.width = param<int>(nh, "camera/width", c.width);
  c.height = param<int>(nh, "camera/height", c.height);
  c.focal_px = param<double>(nh, "camera/focal_px", c.focal_px);
  c.principal_point.x() = param<double>(nh, "camera/cx", c.principal_point.x());
  c.principal_point.y() = param<double>(nh, "camera/cy", c.principal_point.y());
  c.kappa1 = param<double>(nh, "camera/kappa1", c.kappa1);
  c.kappa2 = param<double>(nh, "camera/kappa2", c.kappa2);
  config.ceiling_distance_m = param<double>(nh, "ceiling_distance", config.ceiling_distance_m);
  if (c.width < 1 || c.height < 1 || c.width > 65535 || c.height > 65535) {
    fail(nh, "camera/width", "and camera/height must be in 1..65535");
  }
  requirePositive(config.ceiling_distance_m, nh, "ceiling_distance");
  validateCore(nh, c);
  return config;
}

}  // namespace ebslam_ros
