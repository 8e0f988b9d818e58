#pragma once
// Parameters of the EventParticleFilter nodelet (EB-PF, thesis 6).

#include <ros/node_handle.h>

#include <ebslam/slam/ebpf.h>

#include <string>

#include "pose_filter_params.h"

namespace ebslam_ros {

struct EventParticleFilterNodeConfig {
  PoseFilterNodeConfig node;
  /// plus ~gamma (sensor model sigma [W_trig]) and the localisation parameters with AMCL's
  /// names where they match (~min_particles, ~max_particles, ~kld_err, ~kld_z,
  /// ~recovery_alpha_slow, ~recovery_alpha_fast, ~odom_alpha1..4; README.md lists them all)
  ebslam::EbpfConfig filter;
  std::string map_yaml;  ///< ~map: ceiling map yaml (map_server style or simulator's)
  /// ~use_odometry: odom -> base_link from tf moves the particles between event batches.
  bool use_odometry = false;
};
EventParticleFilterNodeConfig loadEventParticleFilterNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
