#pragma once
// The body of every ebslam_ros node: loads the nodelet of the same function into this process
// (same topics, parameters and remappings as the nodelet).
#include <nodelet/loader.h>
#include <ros/ros.h>

#include <string>

namespace ebslam_ros {

inline int runNodelet(int argc, char** argv, const std::string& node_name,
                      const std::string& nodelet_type) {
  ros::init(argc, argv, node_name);
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv;
  if (!loader.load(ros::this_node::getName(), nodelet_type, remappings, nodelet_argv)) {
    ROS_FATAL("could not load nodelet %s", nodelet_type.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}

}  // namespace ebslam_ros
