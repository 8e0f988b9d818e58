#include "event_slam3d_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

ebslam::Ebslam3dConfig loadEbslam3dConfig(const ros::NodeHandle& nh,
                                          const ebslam::Ebslam3dConfig& defaults) {
  ebslam::Ebslam3dConfig c = defaults;
  c.num_particles = param<int>(nh, "num_particles", c.num_particles);
  c.batch_size = param<int>(nh, "batch_size", c.batch_size);
  c.resample_every = param<int>(nh, "resample_every", c.resample_every);
  c.event_share = param<double>(nh, "event_share", c.event_share);
  c.sigma_position_m = param<double>(nh, "sigma_position", c.sigma_position_m);
  c.sigma_rotation_rad = param<double>(nh, "sigma_rotation", c.sigma_rotation_rad);
  c.sigma_position_per_sqrt_s =
      param<double>(nh, "sigma_position_time", c.sigma_position_per_sqrt_s);
  c.sigma_rotation_per_sqrt_s =
      param<double>(nh, "sigma_rotation_time", c.sigma_rotation_per_sqrt_s);
  c.diffusion_min_scale = param<double>(nh, "diffusion_min_scale", c.diffusion_min_scale);
  c.diffusion_max_scale = param<double>(nh, "diffusion_max_scale", c.diffusion_max_scale);
  c.reference_angular_speed =
      param<double>(nh, "reference_angular_speed", c.reference_angular_speed);
  c.reference_linear_speed = param<double>(nh, "reference_linear_speed", c.reference_linear_speed);
  c.max_event_rate = param<double>(nh, "max_event_rate", c.max_event_rate);
  c.score_alpha = param<double>(nh, "score_alpha", c.score_alpha);
  c.voxel_size_m = param<double>(nh, "voxel_size", c.voxel_size_m);
  c.splat_lambda = param<double>(nh, "splat_lambda", c.splat_lambda);
  c.focal_px = param<double>(nh, "focal_px", c.focal_px);
  c.min_range_m = param<double>(nh, "min_range", c.min_range_m);
  c.max_range_m = param<double>(nh, "max_range", c.max_range_m);
  const double map_mb =
      param<double>(nh, "max_map_mb", static_cast<double>(c.max_map_bytes) / (1024.0 * 1024.0));
  if (!std::isfinite(map_mb) || map_mb < 0.0 || map_mb > 1024.0 * 1024.0) {
    fail(nh, "max_map_mb", "must be a number of MiB in [0, 1048576] (0 = unbounded)");
  }
  c.max_map_bytes = static_cast<std::size_t>(std::llround(map_mb * 1024.0 * 1024.0));
  const std::string splat = param<std::string>(
      nh, "splat",
      c.splat == ebslam::MapSplat3d::kAllParticles ? "all_particles" : "expected_pose");
  if (splat == "expected_pose") {
    c.splat = ebslam::MapSplat3d::kExpectedPose;
  } else if (splat == "all_particles") {
    c.splat = ebslam::MapSplat3d::kAllParticles;
  } else {
    fail(nh, "splat", "= '" + splat + "' is not one of expected_pose, all_particles");
  }
  const int seed = param<int>(nh, "seed", static_cast<int>(c.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  c.seed = static_cast<std::uint64_t>(seed);
  c.imu.gyro.noise_density = param<double>(nh, "gyro_noise_density", c.imu.gyro.noise_density);
  c.imu.gyro.bias_random_walk =
      param<double>(nh, "gyro_bias_random_walk", c.imu.gyro.bias_random_walk);
  c.imu.gyro.initial_bias_std = param<double>(nh, "gyro_initial_bias", c.imu.gyro.initial_bias_std);
  c.imu.sigma_rotation_per_sqrt_s =
      param<double>(nh, "imu_sigma_rotation_time", c.imu.sigma_rotation_per_sqrt_s);
  c.imu.bias_window_s = param<double>(nh, "imu_bias_window", c.imu.bias_window_s);
  c.imu.estimate_bias = param<bool>(nh, "imu_estimate_bias", c.imu.estimate_bias);
  // The core names its fields; name the parameters where the mapping is not obvious.
  requirePositive(c.voxel_size_m, nh, "voxel_size");
  requirePositive(c.splat_lambda, nh, "splat_lambda");
  requirePositive(c.focal_px, nh, "focal_px");
  if (!(c.min_range_m >= 0.0) || !std::isfinite(c.max_range_m) ||
      !(c.min_range_m < c.max_range_m)) {
    fail(nh, "min_range", "and ~max_range must satisfy 0 <= min_range < max_range [m]");
  }
  validateCore(nh, c);
  return c;
}

EventSlam3dNodeConfig loadEventSlam3dNodeConfig(const ros::NodeHandle& nh) {
  EventSlam3dNodeConfig config;
  // ~preset chooses the values the other parameters start from.
  const std::string preset = param<std::string>(nh, "preset", "default");
  ebslam::Ebslam3dConfig base;
  if (preset == "default") {
    base = ebslam::Ebslam3dConfig::defaults();
  } else if (preset == "fast") {
    base = ebslam::Ebslam3dConfig::fast();
  } else if (preset == "thesis") {
    base = ebslam::Ebslam3dConfig::thesis();
  } else {
    fail(nh, "preset", "= '" + preset + "' is not one of default, fast, thesis");
  }
  config.slam = loadEbslam3dConfig(nh, base);
  std::vector<double> start;
  ebslam_ros_common::markParamRead(nh, "initial_pose");
  if (nh.getParam("initial_pose", start)) {
    if (start.size() != 6) fail(nh, "initial_pose", "must be [x, y, z, roll, pitch, yaw]");
    for (double v : start) {
      if (!std::isfinite(v)) fail(nh, "initial_pose", "must hold finite numbers");
    }
    std::copy(start.begin(), start.end(), config.initial_pose.begin());
  } else if (nh.hasParam("initial_pose")) {
    fail(nh, "initial_pose", "must be a list [x, y, z, roll, pitch, yaw]");
  }
  loadPoseNodeConfig(nh, config);
  config.map_threshold = param<double>(nh, "map_threshold", config.map_threshold);
  config.map_publish_period_s =
      param<double>(nh, "map_publish_period", config.map_publish_period_s);
  config.map_file = param<std::string>(nh, "map_file", config.map_file);
  if (!std::isfinite(config.map_threshold) || config.map_threshold < 0.0) {
    fail(nh, "map_threshold", "must be a non-negative number");
  }
  requirePositive(config.map_publish_period_s, nh, "map_publish_period");
  config.use_imu = param<bool>(nh, "use_imu", config.use_imu);
  config.imu_rotation_from_tf =
      param<bool>(nh, "imu_rotation_from_tf", config.imu_rotation_from_tf);
  std::vector<double> rpy;
  ebslam_ros_common::markParamRead(nh, "imu_rpy");
  if (nh.getParam("imu_rpy", rpy)) {
    if (rpy.size() != 3) fail(nh, "imu_rpy", "must be [roll, pitch, yaw] in radians");
    for (double v : rpy) {
      if (!std::isfinite(v)) fail(nh, "imu_rpy", "must hold finite numbers");
    }
    std::copy(rpy.begin(), rpy.end(), config.imu_rpy.begin());
  } else if (nh.hasParam("imu_rpy")) {
    fail(nh, "imu_rpy", "must be a list [roll, pitch, yaw]");
  }
  config.imu_max_wait_s = param<double>(nh, "imu_max_wait", config.imu_max_wait_s);
  requirePositive(config.imu_max_wait_s, nh, "imu_max_wait");
  return config;
}

}  // namespace ebslam_ros
