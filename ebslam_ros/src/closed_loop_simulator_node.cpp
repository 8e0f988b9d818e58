// Runs the ebslam_ros/ClosedLoopSimulator nodelet as a standalone node; without parameters it
// simulates the office floor plan in real time.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "closed_loop_simulator",
                                "ebslam_ros/ClosedLoopSimulator");
}
