#include "event_slam2d_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <string>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

EventSlam2dNodeConfig loadEventSlam2dNodeConfig(const ros::NodeHandle& nh) {
  EventSlam2dNodeConfig config;
  config.node = loadPoseFilterNodeConfig(nh);
  if (config.node.initial_pose_unknown) {
    // EB-SLAM-2D's map frame is where it starts: there is no map to search.
    fail(nh, "initial_pose", "= \"unknown\" needs a known map (EventParticleFilter)");
  }
  ebslam::Ebslam2dConfig& s = config.slam;
  s.filter = loadEventFilterConfig(nh, s.filter);
  s.noise_aware_diffusion = param<bool>(nh, "noise_aware_diffusion", s.noise_aware_diffusion);
  s.cell_size_wtrig = param<double>(nh, "cell_size", s.cell_size_wtrig);
  s.map_size_m = param<double>(nh, "map_size", s.map_size_m);
  s.splat_sigma_wtrig = param<double>(nh, "splat_sigma", s.splat_sigma_wtrig);
  s.normalisation_step_px = param<double>(nh, "normalisation_step", s.normalisation_step_px);
  s.normalisation_prior_px = param<double>(nh, "normalisation_prior", s.normalisation_prior_px);
  const std::string splat = param<std::string>(nh, "splat", "expected_pose");
  if (splat == "expected_pose") {
    s.splat = ebslam::OccurrenceSplat::kExpectedPose;
  } else if (splat == "all_particles") {
    s.splat = ebslam::OccurrenceSplat::kAllParticles;
  } else {
    fail(nh, "splat", "= '" + splat + "' is not one of expected_pose, all_particles");
  }
  validateCore(nh, s);
  config.map_publish_period_s =
      param<double>(nh, "map_publish_period", config.map_publish_period_s);
  requirePositive(config.map_publish_period_s, nh, "map_publish_period");
  config.map_period_on_stamps =
      param<bool>(nh, "map_period_on_stamps", config.map_period_on_stamps);
  return config;
}

}  // namespace ebslam_ros
