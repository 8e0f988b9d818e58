#include "event_particle_filter_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;

EventParticleFilterNodeConfig loadEventParticleFilterNodeConfig(const ros::NodeHandle& nh) {
  EventParticleFilterNodeConfig config;
  config.node = loadPoseFilterNodeConfig(nh);
  config.filter.filter = loadEventFilterConfig(nh, config.filter.filter);
  config.filter.gamma = param<double>(nh, "gamma", config.filter.gamma);
  validateCore(nh, config.filter);
  config.map_yaml = param<std::string>(nh, "map", config.map_yaml);
  if (config.map_yaml.empty()) fail(nh, "map", "is not set (a ceiling map yaml)");
  return config;
}

}  // namespace ebslam_ros
