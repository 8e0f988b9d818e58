// Runs the ebslam_ros/EventRenderer nodelet as a standalone node.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "event_renderer", "ebslam_ros/EventRenderer");
}
