// Runs the ebslam_ros/EventSimulator nodelet as a standalone node; without parameters it
// simulates the demo's excerpt of freiburg2_pioneer_360 in real time.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "event_simulator", "ebslam_ros/EventSimulator");
}
