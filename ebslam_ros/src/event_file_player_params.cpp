#include "event_file_player_params.h"

#include <cstdint>
#include <stdexcept>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

EventFilePlayerConfig loadEventFilePlayerConfig(const ros::NodeHandle& nh) {
  EventFilePlayerConfig config;
  config.file = param<std::string>(nh, "file", config.file);
  const std::string format = param<std::string>(nh, "format", "");
  const int width = param<int>(nh, "width", 0);
  const int height = param<int>(nh, "height", 0);
  config.frame_id = param<std::string>(nh, "frame_id", config.frame_id);
  config.publish_rate_hz = param<double>(nh, "publish_rate", config.publish_rate_hz);
  config.speed = param<double>(nh, "speed", config.speed);
  config.loop = param<bool>(nh, "loop", config.loop);
  config.max_gap_s = param<double>(nh, "max_gap", config.max_gap_s);
  config.wait_for_subscribers =
      param<bool>(nh, "wait_for_subscribers", config.wait_for_subscribers);

  if (config.file.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("file") + " is not set");
  }
  if (!format.empty()) {
    config.format = ebslam::parseEventFileFormat(format);
    if (!config.format) {
      throw std::invalid_argument("parameter " + nh.resolveName("format") + " = '" + format +
                                  "' is not one of binary, text, rpg");
    }
  }
  if (width < 0 || height < 0 || (width == 0) != (height == 0) || width > 65535 || height > 65535) {
    throw std::invalid_argument("parameters " + nh.resolveName("width") + ", " +
                                nh.resolveName("height") +
                                " must both be 0 (from the file) or both in 1..65535");
  }
  if (width > 0) {
    config.sensor =
        ebslam::SensorSize{static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
  }
  if (config.frame_id.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("frame_id") + " is empty");
  }
  requirePositive(config.publish_rate_hz, nh, "publish_rate");
  requirePositive(config.speed, nh, "speed");
  requirePositive(config.max_gap_s, nh, "max_gap");
  return config;
}

}  // namespace ebslam_ros
