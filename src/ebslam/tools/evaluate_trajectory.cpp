// Evaluates an estimated trajectory against ground truth (thesis 8.4, eq. 8.16-8.20): finds the
// best rigid alignment including a time offset, prints position and rotation RMSE and writes the
// per-pose errors as CSV (for tools/plot_trajectory.py), e.g.
//   ebslam_evaluate_trajectory estimate.txt groundtruth.txt --csv errors.csv
// Both files are TUM format (timestamp tx ty tz qx qy qz qw).

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "ebslam/events/trajectory.h"
#include "ebslam/events/trajectory_evaluation.h"

int main(int argc, char** argv) {
  CLI::App app{
      "Position and rotation RMSE of an estimated trajectory after the best rigid "
      "alignment with time offset (TUM format files)"};
  std::string estimate_path;
  std::string ground_truth_path;
  std::string csv_path;
  std::string aligned_path;
  std::string association = "interpolate";
  ebslam::TrajectoryEvaluationConfig config;
  bool no_time_offset = false;
  app.add_option("estimate", estimate_path, "estimated trajectory (TUM)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("groundtruth", ground_truth_path, "ground-truth trajectory (TUM)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--csv", csv_path, "write per-pose errors here (CSV)");
  app.add_option("--aligned", aligned_path, "write the aligned estimate here (TUM)");
  app.add_flag("--scale", config.estimate_scale, "also fit a scale (similarity alignment)");
  app.add_flag("--body-rotation", config.estimate_body_rotation,
               "also fit a constant rotation between the body frames (affects rotation error)");
  app.add_flag("--no-time-offset", no_time_offset, "do not search a time offset (t_a = 0)");
  app.add_option("--max-offset", config.max_time_offset_s, "time offset search range +- [s]")
      ->capture_default_str();
  app.add_option("--step", config.coarse_step_s, "coarse grid step of the offset search [s]")
      ->capture_default_str();
  app.add_option("--max-gap", config.max_association_gap_s,
                 "largest ground-truth gap to interpolate across / nearest-pose distance [s]")
      ->capture_default_str();
  app.add_option("--association", association,
                 "interpolate (ground truth interpolated at t + t_a) or nearest (thesis eq. 8.16)")
      ->check(CLI::IsMember({"interpolate", "nearest"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  config.estimate_time_offset = !no_time_offset;
  config.association = association == "nearest" ? ebslam::TimeAssociation::kNearest
                                                : ebslam::TimeAssociation::kInterpolate;
  try {
    const ebslam::Trajectory estimate = ebslam::readTumTrajectory(estimate_path);
    const ebslam::Trajectory ground_truth = ebslam::readTumTrajectory(ground_truth_path);
    const ebslam::TrajectoryEvaluation r =
        ebslam::evaluateTrajectory(estimate, ground_truth, config);
    const Eigen::AngleAxisd rotation(r.alignment.rotation);
    std::printf("poses            %zu estimated, %zu ground truth, %zu associated\n",
                r.estimated_poses, ground_truth.size(), r.errors.size());
    std::printf("time offset      %+.6f s (estimate time + offset = ground-truth time)\n",
                r.alignment.time_offset_s);
    std::printf("rotation         %.4f deg about (%.4f, %.4f, %.4f)\n",
                rotation.angle() * 180.0 / M_PI, rotation.axis().x(), rotation.axis().y(),
                rotation.axis().z());
    std::printf("translation      (%.4f, %.4f, %.4f) m\n", r.alignment.translation.x(),
                r.alignment.translation.y(), r.alignment.translation.z());
    std::printf("scale            %.6f%s\n", r.alignment.scale,
                config.estimate_scale ? "" : " (not estimated)");
    std::printf("position RMSE    %.4f m   (max %.4f m)\n", r.position_rmse_m, r.position_max_m);
    std::printf("rotation RMSE    %.4f deg (max %.4f deg)\n", r.rotation_rmse_deg,
                r.rotation_max_deg);
    if (!csv_path.empty()) ebslam::writeTrajectoryErrorsCsv(csv_path, r);
    if (!aligned_path.empty()) {
      ebslam::Trajectory aligned;
      aligned.reserve(estimate.size());
      for (const ebslam::StampedPose& p : estimate) aligned.push_back(r.alignment.apply(p));
      ebslam::writeTumTrajectory(aligned_path, aligned);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
