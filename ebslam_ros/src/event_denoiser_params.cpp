#include "event_denoiser_params.h"

#include <cmath>
#include <cstdint>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

ebslam::BackgroundActivityFilterConfig loadBackgroundActivityFilterConfig(
    const ros::NodeHandle& nh) {
  ebslam::BackgroundActivityFilterConfig c;
  const double window_s = param<double>(nh, "window", 1e-6 * static_cast<double>(c.window_us));
  requirePositive(window_s, nh, "window");
  if (window_s > 1000.0) fail(nh, "window", "must be at most 1000 s");
  c.window_us = static_cast<std::int64_t>(std::llround(window_s * 1e6));
  if (c.window_us < 1) fail(nh, "window", "must be at least 1 us");
  c.min_support = param<int>(nh, "min_support", c.min_support);
  if (c.min_support < 1 || c.min_support > 8) fail(nh, "min_support", "must be in 1..8");
  c.polarity_match = param<bool>(nh, "polarity_match", c.polarity_match);
  c.refractory_filter = param<bool>(nh, "refractory_filter", c.refractory_filter);
  const double refractory_s =
      param<double>(nh, "refractory_period", 1e-6 * static_cast<double>(c.refractory_period_us));
  if (!std::isfinite(refractory_s) || refractory_s < 0.0 || refractory_s > 1000.0) {
    fail(nh, "refractory_period", "must be a number of seconds in [0, 1000]");
  }
  c.refractory_period_us = static_cast<std::int64_t>(std::llround(refractory_s * 1e6));
  validateCore(nh, c);
  return c;
}

EventDenoiserNodeConfig loadEventDenoiserNodeConfig(const ros::NodeHandle& nh) {
  EventDenoiserNodeConfig config;
  config.filter = loadBackgroundActivityFilterConfig(nh);
  config.queue_size = param<int>(nh, "queue_size", config.queue_size);
  if (config.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  config.max_backward_s = param<double>(nh, "max_backward", config.max_backward_s);
  if (!std::isfinite(config.max_backward_s) || config.max_backward_s < 0.0) {
    fail(nh, "max_backward", "must be a non-negative number of seconds");
  }
  return config;
}

}  // namespace ebslam_ros
