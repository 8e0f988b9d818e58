#include "param_utils.h"

#include <ebslam_ros_common/ros_param_helpers.h>
#include <ros/names.h>

#include <cmath>
#include <sstream>

namespace ebslam_ros {

using ebslam_ros_common::param;

[[noreturn]] void fail(const ros::NodeHandle& nh, const std::string& name, const std::string& why) {
  ebslam_ros_common::failParam(nh, name, why);
}

std::array<double, 3> triple(const ros::NodeHandle& nh, const std::string& name,
                             const std::array<double, 3>& default_value) {
  std::vector<double> values;
  ebslam_ros_common::markParamRead(nh, name);
  if (!nh.getParam(name, values)) {
    if (nh.hasParam(name)) fail(nh, name, "must be a list of three numbers");
    return default_value;
  }
  if (values.size() != 3) fail(nh, name, "must be a list of three numbers");
  for (double v : values) {
    if (!std::isfinite(v)) fail(nh, name, "must hold finite numbers");
  }
  return {values[0], values[1], values[2]};
}

void requireFrame(const ros::NodeHandle& nh, const std::string& name, const std::string& frame) {
  if (frame.empty()) fail(nh, name, "is empty");
  if (frame.front() == '/') fail(nh, name, "= '" + frame + "' must not start with '/' (tf2)");
}

std::vector<std::string> topicList(const ros::NodeHandle& nh, const std::string& name) {
  std::istringstream words(param<std::string>(nh, name, ""));
  const std::string node_namespace = ros::names::parentNamespace(nh.getNamespace());
  std::vector<std::string> topics;
  for (std::string topic; words >> topic;) {
    try {
      topics.push_back(ros::names::resolve(node_namespace, topic, false));
    } catch (const ros::InvalidNameException& error) {
      fail(nh, name, "'" + topic + "' is not a valid topic name (" + error.what() + ")");
    }
  }
  return topics;
}

}  // namespace ebslam_ros
