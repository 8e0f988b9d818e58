// Runs one dasp_ros nodelet (NODELET_TYPE, set by CMake) as a standalone node: same topics,
// parameters and services as the nodelet loaded into a manager.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, NODE_NAME);
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv;
  if (!loader.load(ros::this_node::getName(), NODELET_TYPE, remappings, nodelet_argv)) {
    ROS_FATAL("could not load nodelet %s", NODELET_TYPE);
    return 1;
  }
  ros::spin();
  return 0;
}
