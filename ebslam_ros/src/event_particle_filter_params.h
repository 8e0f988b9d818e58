#pragma once
// Parameters of the EventParticleFilter nodelet (EB-PF, thesis 6).

#include <ros/node_handle.h>

#include <ebslam/slam/ebpf.h>

#include <string>

#include "pose_filter_params.h"

namespace ebslam_ros {

struct EventParticleFilterNodeConfig {
  PoseFilterNodeConfig node;
  ebslam::EbpfConfig filter;  ///< plus ~gamma (sensor model sigma [W_trig])
  std::string map_yaml;       ///< ~map: ceiling map yaml (map_server style or simulator's)
};
EventParticleFilterNodeConfig loadEventParticleFilterNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
