#include "dasp_ros/ros_params.h"

#include <cmath>
#include <stdexcept>

namespace dasp_ros {
namespace {

template <typename T>
T param(const ros::NodeHandle& nh, const std::string& name, const T& default_value) {
  T value;
  nh.param<T>(name, value, default_value);
  return value;
}

void requirePositive(double value, const ros::NodeHandle& nh, const std::string& name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument("parameter " + nh.resolveName(name) + " = " +
                                std::to_string(value) + " must be a positive number");
  }
}

}  // namespace

RgbdFolderSourceConfig loadRgbdFolderSourceConfig(const ros::NodeHandle& nh) {
  RgbdFolderSourceConfig config;
  config.folder = param<std::string>(nh, "folder", config.folder);
  config.rate_hz = param<double>(nh, "rate", config.rate_hz);
  config.loop = param<bool>(nh, "loop", config.loop);
  config.wait_for_subscribers =
      param<bool>(nh, "wait_for_subscribers", config.wait_for_subscribers);
  config.frame_id = param<std::string>(nh, "frame_id", config.frame_id);
  config.intrinsics.fx = static_cast<float>(param<double>(nh, "fx", config.intrinsics.fx));
  config.intrinsics.fy = static_cast<float>(param<double>(nh, "fy", config.intrinsics.fy));
  config.intrinsics.cx = static_cast<float>(param<double>(nh, "cx", config.intrinsics.cx));
  config.intrinsics.cy = static_cast<float>(param<double>(nh, "cy", config.intrinsics.cy));

  if (config.folder.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("folder") + " is not set");
  }
  if (config.frame_id.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("frame_id") + " is empty");
  }
  requirePositive(config.rate_hz, nh, "rate");
  requirePositive(config.intrinsics.fx, nh, "fx");
  requirePositive(config.intrinsics.fy, nh, "fy");
  if (!std::isfinite(config.intrinsics.cx) || !std::isfinite(config.intrinsics.cy)) {
    throw std::invalid_argument("parameters cx, cy must be finite");
  }
  return config;
}

}  // namespace dasp_ros
