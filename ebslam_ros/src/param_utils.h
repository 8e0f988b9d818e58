#pragma once
// What the ebslam_ros nodelets' parameter loaders (<nodelet>_params.cpp) share beyond
// ebslam_ros_common/ros_param_helpers.h: lists, frames, topic lists and the core's validate().
// Every function throws std::invalid_argument naming the fully resolved parameter.

#include <ros/node_handle.h>

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace ebslam_ros {

[[noreturn]] void fail(const ros::NodeHandle& nh, const std::string& name, const std::string& why);

/// A list of three finite numbers, or `default_value` where the parameter is not set.
std::array<double, 3> triple(const ros::NodeHandle& nh, const std::string& name,
                             const std::array<double, 3>& default_value);

/// A tf2 frame name: not empty, no leading '/'.
void requireFrame(const ros::NodeHandle& nh, const std::string& name, const std::string& frame);

/// Space-separated topic names, relative ones resolved in the node's namespace (the parent of
/// its private one).
std::vector<std::string> topicList(const ros::NodeHandle& nh, const std::string& name);

/// Runs a core validate() and names the node's parameter namespace in its message.
template <typename Config>
void validateCore(const ros::NodeHandle& nh, const Config& config) {
  try {
    config.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument("parameters of " + nh.getNamespace() + ": " + error.what());
  }
}

}  // namespace ebslam_ros
