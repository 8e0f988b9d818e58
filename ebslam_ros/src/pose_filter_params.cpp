#include "pose_filter_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "event_denoiser_params.h"
#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;

PoseFilterNodeConfig loadPoseFilterNodeConfig(const ros::NodeHandle& nh) {
  PoseFilterNodeConfig config;
  config.sensor = loadCeilingSensorConfig(nh);
  std::string start_text;
  if (nh.getParam("initial_pose", start_text)) {
    ebslam_ros_common::markParamRead(nh, "initial_pose");
    if (start_text != "unknown") {
      fail(nh, "initial_pose", "must be [x, y, theta] or \"unknown\" (not '" + start_text + "')");
    }
    config.initial_pose_unknown = true;
  } else {
    const std::array<double, 3> start = triple(nh, "initial_pose", {0.0, 0.0, 0.0});
    config.initial_pose = {start[0], start[1], start[2]};
  }
  loadPoseNodeConfig(nh, config);
  config.denoise = param<bool>(nh, "denoise", config.denoise);
  config.denoiser = loadBackgroundActivityFilterConfig(ros::NodeHandle(nh, "denoiser"));
  ebslam::EventRateLimiterConfig& rate = config.rate_limit;
  rate.max_rate_eps = param<double>(nh, "max_event_rate", rate.max_rate_eps);
  const double window_s =
      param<double>(nh, "rate_window", 1e-6 * static_cast<double>(rate.window_us));
  if (!std::isfinite(window_s)) fail(nh, "rate_window", "must be a number of seconds");
  rate.window_us = std::llround(std::clamp(window_s, -1.0, 10.0) * 1e6);
  const int rate_seed = param<int>(nh, "rate_seed", static_cast<int>(rate.seed));
  if (rate_seed < 0) fail(nh, "rate_seed", "must not be negative");
  rate.seed = static_cast<std::uint64_t>(rate_seed);
  validateCore(nh, rate);
  return config;
}

ebslam::EventFilterConfig loadEventFilterConfig(const ros::NodeHandle& nh,
                                                const ebslam::EventFilterConfig& defaults) {
  ebslam::EventFilterConfig f = defaults;
  f.num_particles = param<int>(nh, "num_particles", f.num_particles);
  f.batch_size = param<int>(nh, "batch_size", f.batch_size);
  f.resample_every = param<int>(nh, "resample_every", f.resample_every);
  f.beta = param<double>(nh, "beta", f.beta);
  f.g0 = param<double>(nh, "g0", f.g0);
  f.experimental.diffusion_scale =
      param<double>(nh, "diffusion_scale", f.experimental.diffusion_scale);
  f.initial_spread_m = param<double>(nh, "initial_spread", f.initial_spread_m);
  f.initial_spread_rad = param<double>(nh, "initial_spread_rad", f.initial_spread_rad);
  f.experimental.reset_scores_on_resample =
      param<bool>(nh, "reset_scores_on_resample", f.experimental.reset_scores_on_resample);
  f.experimental.adapt_g0 = param<bool>(nh, "adapt_g0", f.experimental.adapt_g0);
  f.latency_compensation_s = param<double>(nh, "latency_compensation", f.latency_compensation_s);
  const std::string estimate = param<std::string>(
      nh, "estimate", f.estimate == ebslam::PoseEstimateMode::kBestParticle ? "best" : "mean");
  if (estimate == "mean") {
    f.estimate = ebslam::PoseEstimateMode::kWeightedMean;
  } else if (estimate == "best") {
    f.estimate = ebslam::PoseEstimateMode::kBestParticle;
  } else {
    fail(nh, "estimate", "= '" + estimate + "' is not one of mean, best");
  }
  const int seed = param<int>(nh, "seed", static_cast<int>(f.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  f.seed = static_cast<std::uint64_t>(seed);
  validateCore(nh, f);
  return f;
}

}  // namespace ebslam_ros
