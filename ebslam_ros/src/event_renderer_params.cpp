#include "event_renderer_params.h"

#include <utility>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

EventRendererConfig loadEventRendererConfig(const ros::NodeHandle& nh) {
  EventRendererConfig c;
  c.publish_rate_hz = param<double>(nh, "publish_rate", c.publish_rate_hz);
  c.accumulation_time_s = param<double>(nh, "accumulation_time", c.accumulation_time_s);
  requirePositive(c.publish_rate_hz, nh, "publish_rate");
  requirePositive(c.accumulation_time_s, nh, "accumulation_time");
  c.queue_size = param<int>(nh, "queue_size", c.queue_size);
  if (c.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  for (const auto& [name, colour] :
       {std::pair<const char*, std::array<int, 3>*>{"on_colour", &c.on_rgb},
        {"off_colour", &c.off_rgb}}) {
    const std::array<double, 3> value =
        triple(nh, name, {double((*colour)[0]), double((*colour)[1]), double((*colour)[2])});
    for (int k = 0; k < 3; ++k) {
      if (value[k] < 0.0 || value[k] > 255.0) fail(nh, name, "must hold three values in 0..255");
      (*colour)[k] = static_cast<int>(value[k]);
    }
  }
  return c;
}

}  // namespace ebslam_ros
