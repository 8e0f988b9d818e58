// Runs the ebslam_ros/RgbdEventSimulator nodelet as a standalone node; without parameters it
// carries the D-eDVS along the repository's freiburg2_pioneer_360 excerpt in real time.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "rgbd_event_simulator",
                                "ebslam_ros/RgbdEventSimulator");
}
