// Runs the ebslam_ros/EventParticleFilter nodelet as a standalone node.
#include "ebslam_ros/nodelet_main.h"

int main(int argc, char** argv) {
  return ebslam_ros::runNodelet(argc, argv, "event_particle_filter",
                                "ebslam_ros/EventParticleFilter");
}
