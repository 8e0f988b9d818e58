// Runs the ebslam_ros/Exploration nodelet as a standalone node.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "exploration", "ebslam_ros/Exploration");
}
