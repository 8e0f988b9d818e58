// Writes a pose topic of a bag as a TUM trajectory, e.g.
//   rosrun ebslam_ros bag_to_tum run.bag /slam/pose slam.tum
//   ebslam_evaluate_trajectory --no-time-offset slam.tum groundtruth.tum
// Exit status: 0 success, 1 usage or input error.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "ebslam_ros/bag_trajectory.h"

int main(int argc, char** argv) {
  CLI::App app{
      "Pose topic of a bag (PoseStamped, PoseWithCovarianceStamped, Odometry, "
      "TransformStamped) -> TUM trajectory (stamp x y z qx qy qz qw)"};
  std::string bag, topic, output;
  app.add_option("bag", bag, "input bag")->required()->check(CLI::ExistingFile);
  app.add_option("topic", topic, "pose topic")->required();
  app.add_option("output", output, "output TUM file")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const ebslam_ros::BagTrajectory t = ebslam_ros::readBagTrajectory(bag, topic);
    ebslam::writeTumTrajectory(output, t.trajectory);
    std::printf("%zu poses in frame '%s' written to %s", t.trajectory.size(), t.frame_id.c_str(),
                output.c_str());
    if (t.dropped > 0) std::printf(" (%zu dropped: stamp not after the previous one)", t.dropped);
    std::printf("\n");
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bag_to_tum: %s\n", error.what());
    return 1;
  }
  return 0;
}
