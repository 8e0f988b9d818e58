// Thin node wrapper: loads edvs_driver/EdvsDriverNodelet into this process.
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "edvs_driver");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string args(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "edvs_driver/EdvsDriverNodelet", remappings, args)) {
    ROS_FATAL("edvs_driver: could not load edvs_driver/EdvsDriverNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}
