// Runs the ebslam_ros/EventFilePlayer nodelet as a standalone node (same topics and parameters).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "event_file_player");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv;
  if (!loader.load(ros::this_node::getName(), "ebslam_ros/EventFilePlayer", remappings,
                   nodelet_argv)) {
    ROS_FATAL("could not load nodelet ebslam_ros/EventFilePlayer");
    return 1;
  }
  ros::spin();
  return 0;
}
