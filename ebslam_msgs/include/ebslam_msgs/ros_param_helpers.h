#pragma once
// Parameter reading and checks shared by the ROS packages' ros_params.cpp (every ROS package of
// the workspace depends on ebslam_msgs). A failed check throws std::invalid_argument naming the
// fully resolved parameter.

#include <ros/node_handle.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam_msgs {

/// The parameter `name` of `nh`, or `default_value` where it is not set.
template <typename T>
T param(const ros::NodeHandle& nh, const std::string& name, const T& default_value) {
  T value;
  nh.param<T>(name, value, default_value);
  return value;
}

/// Throws std::invalid_argument: parameter <resolved name> <why>.
[[noreturn]] inline void failParam(const ros::NodeHandle& nh, const std::string& name,
                                   const std::string& why) {
  throw std::invalid_argument("parameter " + nh.resolveName(name) + " " + why);
}

/// Throws std::invalid_argument unless `value` is finite and > 0.
inline void requirePositive(double value, const ros::NodeHandle& nh, const std::string& name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument("parameter " + nh.resolveName(name) + " = " +
                                std::to_string(value) + " must be a positive number");
  }
}

}  // namespace ebslam_msgs
