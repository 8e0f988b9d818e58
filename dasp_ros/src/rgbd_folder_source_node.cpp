// Runs the dasp_ros/RgbdFolderSource nodelet as a standalone node (same topics and parameters).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "rgbd_folder_source");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv;
  if (!loader.load(ros::this_node::getName(), "dasp_ros/RgbdFolderSource", remappings,
                   nodelet_argv)) {
    ROS_FATAL("could not load nodelet dasp_ros/RgbdFolderSource");
    return 1;
  }
  ros::spin();
  return 0;
}
