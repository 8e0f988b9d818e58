// Calibrates the D-eDVS (thesis 8.2, eq. 8.4-8.6) from a recorded bag: the user moves the plate
// with the blinking LED in front of the rig, resting it for half a second at each pose, while
// record.launch records the eDVS events, the colour image, the registered depth image and its
// camera_info. The LED is found in the events (its known frequency) and in the colour frames
// (the pixel blinking at that frequency from frame to frame), its depth in the registered depth
// image; the poses are paired in time and eq. 8.5 is solved. Writes the sensors.yaml the fusion
// reads (DepthEventFusion's dedvs_calibration).
//
//   rosrun ebslam_ros dedvs_calibrate_bag --bag calib.bag --led-frequency 250 --output sensors.yaml
//   rosrun ebslam_ros dedvs_calibrate_bag --simulate sim.bag --seed 3 --outlier-fraction 0.2
//     --truth-output truth.yaml        (a simulated calibration bag with the real topics)
//   rosrun ebslam_ros dedvs_calibrate_bag --bag sim.bag --truth truth.yaml   (errors vs. truth)
//   rosrun ebslam_ros dedvs_calibrate_bag --table-seeds 5 --outlier-fraction 0.2
//     (simulate, calibrate and compare seeds 1-5 through bags; a markdown table)
// Exit status: 0 calibrated, 3 calibration failed (the reason is printed), 1 error, 2 usage.

#include <unistd.h>
#include <CLI/CLI.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "ebslam/simulation/dedvs_io.h"
#include "ebslam_ros/calibration_bag.h"

namespace {

struct Comparison {
  double rotation_deg = 0.0;
  double translation_mm = 0.0;
  double focal_px = 0.0;
  double centre_px = 0.0;
  /// Largest difference between the fitted and the true lens distortion over the sensor: the
  /// displacement of an undistorted point [px].
  double distortion_px = 0.0;
};

Comparison compare(const ebslam::DedvsSensors& fitted, const ebslam::DedvsSensors& truth) {
  Comparison c;
  const ebslam::ExtrinsicError e =
      ebslam::extrinsicError(fitted.depth_from_edvs, truth.depth_from_edvs);
  c.rotation_deg = e.rotation_deg;
  c.translation_mm = e.translation_mm;
  c.focal_px = fitted.edvs.focal_px - truth.edvs.focal_px;
  c.centre_px = (fitted.edvs.principal_point - truth.edvs.principal_point).norm();
  // Distortion alone: the same ray through both models with the true focal length and centre.
  ebslam::CameraModel a = fitted.edvs, b = truth.edvs;
  a.focal_px = b.focal_px;
  a.principal_point = b.principal_point;
  for (int y = 0; y < b.height; y += 4) {
    for (int x = 0; x < b.width; x += 4) {
      const auto ray = b.backprojectRay(Eigen::Vector2d(x, y));
      if (!ray) continue;
      const auto pa = a.project(*ray);
      if (pa) c.distortion_px = std::max(c.distortion_px, (*pa - Eigen::Vector2d(x, y)).norm());
    }
  }
  return c;
}

void printResult(const ebslam_ros::BagCalibration& calibration) {
  const ebslam::LedPairing& p = calibration.pairing;
  std::printf("read %zu events and %zu RGB-D frames (%.2f frames/s)\n", calibration.events,
              calibration.frames, calibration.frame_rate_hz);
  std::printf("%zu still poses: LED found in the colour frames in %zu", p.segments,
              p.rgbd_status[0]);
  for (std::size_t s = 1; s < ebslam::kRgbdLedStatusCount; ++s) {
    if (p.rgbd_status[s] > 0) {
      std::printf(", %s in %zu", ebslam::toString(static_cast<ebslam::RgbdLedStatus>(s)),
                  p.rgbd_status[s]);
    }
  }
  std::printf("; not in the eDVS events in %zu, rest too short for the eDVS in %zu\n",
              p.edvs_missing, p.too_short_for_edvs);
  if (calibration.measured_clock_offset_s) {
    std::printf("measured depth camera clock offset: %.4f s\n",
                *calibration.measured_clock_offset_s);
  }
  std::printf("usable poses: %zu\n", p.correspondences.size());
  if (!calibration.result) return;
  const ebslam::DedvsCalibrationResult& r = *calibration.result;
  const ebslam::CameraModel& e = r.sensors.edvs;
  const Eigen::Vector3d t = r.sensors.depth_from_edvs.translation();
  std::printf("status: %s; %zu of %zu poses inliers, %d iterations\n", ebslam::toString(r.status),
              r.inliers, p.correspondences.size(), r.iterations);
  std::printf("reprojection RMSE %.3f px (inliers), %.3f px (all poses)\n", r.rmse_px,
              r.rmse_all_px);
  std::printf("depth_from_edvs t = (%.5f, %.5f, %.5f) m\n", t.x(), t.y(), t.z());
  std::printf("eDVS f = %.3f px, c = (%.3f, %.3f) px, kappa1 = %.3e, kappa2 = %.3e\n", e.focal_px,
              e.principal_point.x(), e.principal_point.y(), e.kappa1, e.kappa2);
  if (r.uncertainty) {
    const ebslam::CalibrationUncertainty& u = *r.uncertainty;
    std::printf(
        "standard deviations (solver covariance): rotation %.3f deg (about x, y, z: %.3f, %.3f, "
        "%.3f), translation (%.2f, %.2f, %.2f) mm, f %.2f px, c (%.2f, %.2f) px; rotation / "
        "centre correlation %.2f\n",
        u.rotation_std_deg, u.rotation_axes_std_deg.x(), u.rotation_axes_std_deg.y(),
        u.rotation_axes_std_deg.z(), u.translation_std_mm.x(), u.translation_std_mm.y(),
        u.translation_std_mm.z(), u.focal_std_px, u.principal_point_std_px.x(),
        u.principal_point_std_px.y(), u.rotation_principal_point_correlation);
  } else {
    std::printf("standard deviations: none (the covariance is singular)\n");
  }
  const ebslam::LedPoseCoverage& k = calibration.coverage;
  std::printf(
      "LED in the eDVS image's corners in %zu of %zu poses (top-left %zu, top-right %zu, "
      "bottom-left %zu, bottom-right %zu); depth %.2f-%.2f m\n",
      k.corners[0] + k.corners[1] + k.corners[2] + k.corners[3], k.poses, k.corners[0],
      k.corners[1], k.corners[2], k.corners[3], k.min_depth_m, k.max_depth_m);
  if (!calibration.pose_advice.empty()) {
    std::printf("WARNING: %s\n", calibration.pose_advice.c_str());
  }
}

ebslam::LedCalibrationRunConfig runConfig(std::uint64_t seed, double outlier_fraction, int poses,
                                          double rest_s, double move_s, double led_frequency,
                                          double corner_fraction) {
  ebslam::LedCalibrationRunConfig config;
  config.corner_pose_fraction = corner_fraction;
  config.seed = seed;
  config.simulator.seed = seed;
  config.simulator.events.seed = seed;
  config.outlier_event_fraction = outlier_fraction;
  config.poses = poses;
  config.rest_s = rest_s;
  config.move_s = move_s;
  config.led_frequency_hz = led_frequency;
  return config;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Calibrate the D-eDVS (eq. 8.4-8.6) from a recorded bag with a blinking LED"};
  std::string bag, simulate, output, truth_path, truth_output, compression = "lz4";
  ebslam_ros::BagCalibrationOptions options;
  double outlier_fraction = 0.0;
  std::uint64_t seed = 1;
  int poses = 250, table_seeds = 0, first_seed = 1;
  double rest_s = 0.25, move_s = 0.05;
  double corner_fraction = ebslam::LedCalibrationRunConfig{}.corner_pose_fraction;
  auto* bag_option =
      app.add_option("--bag", bag, "calibration bag to read")->check(CLI::ExistingFile);
  auto* simulate_option =
      app.add_option("--simulate", simulate, "write a simulated calibration bag to this file");
  auto* table_option =
      app.add_option("--table-seeds", table_seeds,
                     "simulate seeds 1..N into bags, calibrate from them, print a markdown table");
  app.add_option("--first-seed", first_seed, "first seed of --table-seeds")->capture_default_str();
  bag_option->excludes(simulate_option)->excludes(table_option);
  simulate_option->excludes(table_option);
  app.add_option("--output", output, "sensors.yaml to write (the fusion's calibration)");
  app.add_option("--truth", truth_path, "sensors.yaml of the simulated truth to compare with")
      ->check(CLI::ExistingFile);
  app.add_option("--led-frequency", options.led_frequency_hz, "LED frequency [Hz]")
      ->capture_default_str();
  app.add_option("--depth-clock-offset", options.depth_clock_offset_s,
                 "depth camera clock offset: event time = frame stamp - offset [s]")
      ->capture_default_str();
  app.add_flag("--measure-clock-offset", options.measure_clock_offset,
               "measure the depth camera clock offset from the plate's motion instead");
  app.add_option("--events-topic", options.topics.events)->capture_default_str();
  app.add_option("--colour-topic", options.topics.colour)->capture_default_str();
  app.add_option("--depth-topic", options.topics.depth)->capture_default_str();
  app.add_option("--camera-info-topic", options.topics.camera_info)->capture_default_str();
  app.add_option("--min-poses", options.solve.min_correspondences, "fewer usable poses: fail")
      ->capture_default_str();
  app.add_option("--seed", seed, "simulation seed (--simulate)")->capture_default_str();
  std::string event_camera = "edvs128";
  app.add_option("--event-camera", event_camera,
                 "simulation: event sensor (edvs128, davis240, davis346, vga, hd720: the eDVS "
                 "lens scaled to that size)")
      ->capture_default_str();
  app.add_option("--outlier-fraction", outlier_fraction,
                 "simulation: fraction of outlier events in the stream")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.9));
  app.add_option("--poses", poses, "simulation: plate poses")->capture_default_str();
  app.add_option("--rest", rest_s, "simulation: rest per pose [s]")->capture_default_str();
  app.add_option("--move", move_s, "simulation: move between poses [s]")->capture_default_str();
  app.add_option("--corner-fraction", corner_fraction,
                 "simulation: share of the poses with the LED in an eDVS image corner")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--max-rotation-std", options.max_rotation_std_deg,
                 "warn with pose advice above this rotation standard deviation [deg]")
      ->capture_default_str();
  app.add_option("--truth-output", truth_output, "simulation: write the true sensors.yaml here");
  app.add_option("--compression", compression, "simulation: bag compression")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "lz4", "bz2"}));
  CLI11_PARSE(app, argc, argv);
  try {
    if (table_seeds > 0) {
      std::printf(
          "| outlier events | seed | usable poses | rotation error [deg] | translation error [mm] "
          "| rotation std [deg] | focal error [px] | centre error [px] | distortion error [px] "
          "| reprojection RMSE [px] | corner poses | status |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
      const std::string path = (std::filesystem::temp_directory_path() /
                                ("dedvs_calibration_" + std::to_string(::getpid()) + ".bag"))
                                   .string();
      int failures = 0;
      for (int s = first_seed; s < first_seed + table_seeds; ++s) {
        ebslam_ros::SimulatedCalibrationBagOptions sim;
        sim.run = runConfig(static_cast<std::uint64_t>(s), outlier_fraction, poses, rest_s, move_s,
                            options.led_frequency_hz, corner_fraction);
        sim.run.simulator.edvs = ebslam::CameraModel::preset(event_camera, sim.run.simulator.edvs);
        sim.compression = "none";
        const ebslam_ros::SimulatedCalibrationBag written =
            ebslam_ros::writeSimulatedCalibrationBag(path, sim);
        const ebslam_ros::BagCalibration calibration = ebslam_ros::calibrateFromBag(path, options);
        std::filesystem::remove(path);
        if (!calibration.result) {
          std::printf("| %.0f %% | %d | %zu | | | | | | | | | %s |\n", 100.0 * outlier_fraction, s,
                      calibration.pairing.correspondences.size(), calibration.problem.c_str());
          ++failures;
          continue;
        }
        const Comparison c = compare(calibration.result->sensors, written.truth);
        const auto& u = calibration.result->uncertainty;
        char rotation_std[32] = "singular";
        if (u) std::snprintf(rotation_std, sizeof(rotation_std), "%.4f", u->rotation_std_deg);
        const std::array<std::size_t, 4>& k = calibration.coverage.corners;
        std::printf(
            "| %.0f %% | %d | %zu | %.4f | %.3f | %s | %.3f | %.3f | %.3f | %.3f | %zu | %s%s |\n",
            100.0 * outlier_fraction, s, calibration.pairing.correspondences.size(), c.rotation_deg,
            c.translation_mm, rotation_std, c.focal_px, c.centre_px, c.distortion_px,
            calibration.result->rmse_px, k[0] + k[1] + k[2] + k[3],
            ebslam::toString(calibration.result->status),
            calibration.pose_advice.empty() ? "" : ", pose advice");
        std::fflush(stdout);
      }
      return failures == 0 ? 0 : 3;
    }
    if (!simulate.empty()) {
      ebslam_ros::SimulatedCalibrationBagOptions sim;
      sim.run = runConfig(seed, outlier_fraction, poses, rest_s, move_s, options.led_frequency_hz,
                          corner_fraction);
      sim.run.simulator.edvs = ebslam::CameraModel::preset(event_camera, sim.run.simulator.edvs);
      sim.compression = compression;
      const ebslam_ros::SimulatedCalibrationBag written =
          ebslam_ros::writeSimulatedCalibrationBag(simulate, sim);
      std::printf("wrote %s: %.1f s, %zu events (%zu outliers), %zu RGB-D frames\n",
                  simulate.c_str(), written.duration_s, written.events, written.outlier_events,
                  written.frames);
      if (!truth_output.empty()) ebslam::writeDedvsSensors(truth_output, written.truth);
      return 0;
    }
    if (bag.empty()) {
      std::fprintf(stderr, "dedvs_calibrate_bag: give --bag, --simulate or --table-seeds\n");
      return 2;
    }
    const ebslam_ros::BagCalibration calibration = ebslam_ros::calibrateFromBag(bag, options);
    printResult(calibration);
    if (calibration.result && !truth_path.empty()) {
      const ebslam::DedvsSensors truth = ebslam::readDedvsSensors(truth_path);
      const Comparison c = compare(calibration.result->sensors, truth);
      std::printf(
          "against %s: rotation %.4f deg, translation %.3f mm, focal %.3f px, centre %.3f px, "
          "distortion %.3f px\n",
          truth_path.c_str(), c.rotation_deg, c.translation_mm, c.focal_px, c.centre_px,
          c.distortion_px);
    }
    if (!calibration.problem.empty()) {
      std::fprintf(stderr, "dedvs_calibrate_bag: calibration failed: %s\n",
                   calibration.problem.c_str());
      return 3;
    }
    if (!output.empty()) {
      ebslam::writeDedvsSensors(output, calibration.result->sensors);
      std::printf("wrote %s\n", output.c_str());
    }
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "dedvs_calibrate_bag: %s\n", error.what());
    return 1;
  }
}
