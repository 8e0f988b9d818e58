// Scores EB-SLAM-3D on a recorded D-eDVS session (ebslam_ros/dedvs_session.h): the offline core
// on the bag's events and depth frames (as ebslam_experiment_ebslam3d), and with --poses the
// poses the ROS pipeline published (a bag of /ebslam3d/pose, e.g. recorded during
// playback.launch slam:=ebslam3d), both against the session's ground truth (eDVS optical frame).
// The published poses are base_link's: the eDVS pose is base_link * mount, the mounting of the
// EventSlam3d parameter file (--slam-config, default the package's config/ebslam3d.yaml).
//   rosrun ebslam_ros dedvs_session_eval --session test/data/dedvs_session/dedvs_session.bag
//     --calibration ebslam_ros/config/dedvs_sensors.yaml --poses out.bag
// Prints one line per scored trajectory (position RMSE: the shipped session's 4.5 s path is nearly
// straight, so the alignment's rotation, fitted to positions, is too loose to score orientation);
// exit status 0, 1 on an input error.
#include <ros/package.h>

#include <CLI/CLI.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "ebslam_ros/bag_trajectory.h"
#include "ebslam_ros/conversions.h"
#include "ebslam_ros/dedvs_session.h"

int main(int argc, char** argv) {
  CLI::App app{"EB-SLAM-3D on a D-eDVS session bag: offline core and published poses"};
  std::string session_bag, calibration, poses_bag, pose_topic = "/ebslam3d/pose";
  std::string estimate_out;
  std::uint64_t seed = 1;
  std::string slam_config = ros::package::getPath("ebslam_ros") + "/config/ebslam3d.yaml";
  bool offline = true;
  app.add_option("--session", session_bag, "the session bag (events, depth, ground truth)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--calibration", calibration, "D-eDVS sensors.yaml (ebslam/slam/dedvs_sensors.h)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--poses", poses_bag, "bag of the published poses")->check(CLI::ExistingFile);
  app.add_option("--pose-topic", pose_topic, "pose topic in --poses")->capture_default_str();
  app.add_option("--seed", seed, "filter seed of the offline run")->capture_default_str();
  app.add_option("--slam-config", slam_config,
                 "EventSlam3d parameter file whose mount_xyz, mount_rpy give base_link -> eDVS")
      ->capture_default_str();
  app.add_flag("!--no-offline", offline, "score the published poses only");
  app.add_option("--estimate", estimate_out, "the published eDVS path as a TUM file");
  CLI11_PARSE(app, argc, argv);
  try {
    const ebslam_ros::DedvsSession session = ebslam_ros::readDedvsSession(session_bag);
    const ebslam::DedvsSensors sensors = ebslam::readDedvsSensors(calibration);
    if (offline) {
      ebslam::Ebslam3dConfig config = ebslam::Ebslam3dConfig::defaults();
      config.focal_px = sensors.edvs.focal_px;
      config.seed = seed;
      const ebslam_ros::OfflineEbslam3dRun run =
          ebslam_ros::runOfflineEbslam3d(session, sensors, {}, config);
      const ebslam::TrajectoryEvaluation eval =
          ebslam_ros::evaluateEdvsTrajectory(run.estimate, session.ground_truth);
      std::printf(
          "offline core: %zu events (%zu with depth), %zu poses: position RMSE %.2f cm (max "
          "%.2f cm)\n",
          session.events.size(), run.events_with_depth, run.estimate.size(),
          100.0 * eval.position_rmse_m, 100.0 * eval.position_max_m);
    }
    if (!poses_bag.empty()) {
      const ebslam_ros::BagTrajectory base = ebslam_ros::readBagTrajectory(poses_bag, pose_topic);
      const Eigen::Isometry3d mount = ebslam_ros::readMountFromParams(slam_config);
      const Eigen::Quaterniond mount_rotation(mount.rotation());
      ebslam::Trajectory estimate = base.trajectory;
      for (ebslam::StampedPose& p : estimate) {
        p.position += p.orientation * mount.translation();
        p.orientation = (p.orientation * mount_rotation).normalized();
      }
      if (!estimate_out.empty()) ebslam::writeTumTrajectory(estimate_out, estimate);
      const ebslam::TrajectoryEvaluation eval =
          ebslam_ros::evaluateEdvsTrajectory(estimate, session.ground_truth);
      std::printf("published (%s, %zu poses): position RMSE %.2f cm (max %.2f cm)\n",
                  pose_topic.c_str(), estimate.size(), 100.0 * eval.position_rmse_m,
                  100.0 * eval.position_max_m);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "dedvs_session_eval: %s\n", error.what());
    return 1;
  }
  return 0;
}
