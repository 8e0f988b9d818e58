// Runs the ebslam_ros/DepthEventFusion nodelet as a standalone node (~calibration required).
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "depth_event_fusion", "ebslam_ros/DepthEventFusion");
}
