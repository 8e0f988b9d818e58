// Runs the ebslam_ros/EventSlam3d nodelet as a standalone node.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "event_slam3d", "ebslam_ros/EventSlam3d");
}
