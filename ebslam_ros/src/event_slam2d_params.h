#pragma once
// Parameters of the EventSlam2d nodelet (EB-SLAM-2D, thesis 7).

#include <ros/node_handle.h>

#include <ebslam/slam/ebslam2d.h>

#include "pose_filter_params.h"

namespace ebslam_ros {

struct EventSlam2dNodeConfig {
  PoseFilterNodeConfig node;
  /// plus ~cell_size, ~map_size, ~splat_sigma, ~splat (expected_pose|all_particles),
  /// ~normalisation_step, ~normalisation_prior
  ebslam::Ebslam2dConfig slam;
  double map_publish_period_s = 1.0;  ///< ~map_publish_period: `map` at most this often [s]
  /// ~map_period_on_stamps: count ~map_publish_period in event time (the stamps) instead of
  /// wall time: maps at the same points of the data at any pace (exploration in lockstep).
  bool map_period_on_stamps = false;
};
EventSlam2dNodeConfig loadEventSlam2dNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
