// Calibrates the D-eDVS (thesis 8.2, eq. 8.4-8.6) from a pulsed-LED calibration run: extracts
// the LED from the eDVS events by its known frequency, pairs it with its depth-camera pixel and
// depth per depth frame, solves eq. 8.5 with Ceres and writes the sensors (R, t, eDVS
// intrinsics and distortion) as the sensors.yaml the fusion reads (readDedvsSensors).
//
// The run directory's led_depth.txt comes from the simulator; a real rig is calibrated from its
// recorded bag with `rosrun ebslam_ros dedvs_calibrate_bag --bag FILE` (finds the LED in the
// colour frames too). A run directory holds:
//   events.bin     eDVS events (dedvs_io.h format)
//   led_depth.txt  one line per depth frame with the LED: `t_s u v depth_m x y z` (t on the
//                  event clock [s], depth pixel [px], depth [m], true LED point in the depth
//                  optical frame [m] or nan)
//   sensors.yaml   the depth camera and eDVS size (and, for a simulated run, the true
//                  calibration the errors are reported against)
//
// Examples:
//   ebslam_dedvs_calibrate --simulate-led out/led --seed 3 --outlier-fraction 0.2
//     --output calib.yaml                       (simulate a run into out/led, then calibrate)
//   ebslam_dedvs_calibrate --run out/led --output calib.yaml
//   ebslam_dedvs_calibrate --table-seeds 5      (the results table: seeds 1-5, 0 and 20 %
//                                                 outlier events, nothing written)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ebslam/calibration/dedvs_calibration.h"
#include "ebslam/simulation/dedvs_io.h"

namespace {

struct CalibrationInput {
  std::vector<ebslam::Event> events;
  std::vector<ebslam::DepthLedObservation> depth;
  ebslam::DedvsSensors sensors;
};

void writeRun(const std::string& directory, const ebslam::LedCalibrationRun& run) {
  namespace fs = std::filesystem;
  fs::create_directories(directory);
  std::vector<ebslam::TrueDepthEvent> events(run.events.size());
  for (std::size_t i = 0; i < run.events.size(); ++i) {
    events[i].event = run.events[i];
    events[i].depth_m = std::numeric_limits<float>::quiet_NaN();
  }
  ebslam::writeTrueDepthEvents((fs::path(directory) / "events.bin").string(), events,
                               run.truth.edvs.width, run.truth.edvs.height);
  std::ofstream out((fs::path(directory) / "led_depth.txt").string());
  if (!out) throw std::runtime_error("cannot write led_depth.txt in " + directory);
  out << "# t_s u v depth_m x y z\n";
  char line[256];
  for (const ebslam::DepthLedObservation& o : run.depth_observations) {
    std::snprintf(line, sizeof(line), "%.6f %.4f %.4f %.5f %.6f %.6f %.6f\n", o.t_s, o.pixel.x(),
                  o.pixel.y(), o.depth_m, o.true_point.x(), o.true_point.y(), o.true_point.z());
    out << line;
  }
  ebslam::writeDedvsSensors((fs::path(directory) / "sensors.yaml").string(), run.truth);
}

CalibrationInput readRun(const std::string& directory) {
  namespace fs = std::filesystem;
  CalibrationInput input;
  for (const ebslam::TrueDepthEvent& e :
       ebslam::readTrueDepthEvents((fs::path(directory) / "events.bin").string())) {
    input.events.push_back(e.event);
  }
  std::ifstream in((fs::path(directory) / "led_depth.txt").string());
  if (!in) throw std::runtime_error("missing led_depth.txt in " + directory);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    ebslam::DepthLedObservation o;
    std::string x, y, z;
    if (!(fields >> o.t_s >> o.pixel.x() >> o.pixel.y() >> o.depth_m >> x >> y >> z)) {
      throw std::runtime_error("malformed line in led_depth.txt: " + line);
    }
    o.true_point = Eigen::Vector3d(std::stod(x), std::stod(y), std::stod(z));
    input.depth.push_back(o);
  }
  input.sensors = ebslam::readDedvsSensors((fs::path(directory) / "sensors.yaml").string());
  return input;
}

struct Outcome {
  std::size_t correspondences = 0;
  ebslam::DedvsCalibrationResult result;
  ebslam::ExtrinsicError error;
  double led_error_median_px = std::numeric_limits<double>::quiet_NaN();
  double led_error_p90_px = std::numeric_limits<double>::quiet_NaN();
};

Outcome calibrate(const CalibrationInput& input, double led_frequency_hz) {
  ebslam::LedExtractionConfig extraction;
  extraction.led_frequency_hz = led_frequency_hz;
  extraction.width = input.sensors.edvs.width;
  extraction.height = input.sensors.edvs.height;
  const std::vector<ebslam::LedCorrespondence> correspondences =
      ebslam::collectLedCorrespondences(input.events, input.depth, extraction);
  Outcome outcome;
  outcome.correspondences = correspondences.size();
  // LED extraction error against the true LED point, when the run has it.
  std::vector<double> errors;
  for (const ebslam::DepthLedObservation& o : input.depth) {
    if (!o.true_point.allFinite()) continue;
    const std::optional<ebslam::LedObservation> led =
        ebslam::extractLed(input.events, o.t_s, extraction);
    const std::optional<Eigen::Vector2d> truth =
        input.sensors.edvs.project(input.sensors.depth_from_edvs.inverse() * o.true_point);
    if (led && truth) errors.push_back((led->pixel - *truth).norm());
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    outcome.led_error_median_px = errors[errors.size() / 2];
    outcome.led_error_p90_px = errors[errors.size() * 9 / 10];
  }
  outcome.result = ebslam::calibrateDedvs(correspondences, input.sensors);
  outcome.error =
      ebslam::extrinsicError(outcome.result.sensors.depth_from_edvs, input.sensors.depth_from_edvs);
  return outcome;
}

void printOutcome(const Outcome& o, const ebslam::DedvsSensors& truth) {
  const ebslam::DedvsCalibrationResult& r = o.result;
  const ebslam::CameraModel& e = r.sensors.edvs;
  std::printf("status: %s; %zu correspondences, %zu inliers, %d iterations\n",
              ebslam::toString(r.status), o.correspondences, r.inliers, r.iterations);
  std::printf("reprojection RMSE %.3f px (inliers), %.3f px (all)\n", r.rmse_px, r.rmse_all_px);
  std::printf("LED extraction error against the truth: median %.3f px, 90 %% %.3f px\n",
              o.led_error_median_px, o.led_error_p90_px);
  const Eigen::Vector3d t = r.sensors.depth_from_edvs.translation();
  std::printf("depth_from_edvs t = (%.5f, %.5f, %.5f) m\n", t.x(), t.y(), t.z());
  std::printf("eDVS f = %.3f px, c = (%.3f, %.3f) px, kappa1 = %.3e, kappa2 = %.3e\n", e.focal_px,
              e.principal_point.x(), e.principal_point.y(), e.kappa1, e.kappa2);
  std::printf(
      "against the file's sensors (the simulated truth): translation %.3f mm, rotation %.4f deg, "
      "focal %.3f px, centre %.3f px\n",
      o.error.translation_mm, o.error.rotation_deg, e.focal_px - truth.edvs.focal_px,
      (e.principal_point - truth.edvs.principal_point).norm());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Calibrate the D-eDVS (eq. 8.4-8.6) from a pulsed-LED calibration run"};
  std::string run_dir, simulate_dir, output;
  double outlier_fraction = 0.0, led_frequency = 250.0;
  std::uint64_t seed = 1;
  ebslam::LedCalibrationRunConfig defaults;
  int poses = defaults.poses, table_seeds = 0;
  double rest_s = defaults.rest_s, move_s = defaults.move_s;
  double min_depth = defaults.min_depth_m, max_depth = defaults.max_depth_m;
  auto* run_option = app.add_option("--run", run_dir, "calibration run directory (see above)")
                         ->check(CLI::ExistingDirectory);
  auto* simulate_option =
      app.add_option("--simulate-led", simulate_dir,
                     "simulate a calibration run into this directory first, then calibrate");
  auto* table_option =
      app.add_option("--table-seeds", table_seeds,
                     "simulate seeds 1..N with 0 and 20 % outlier events, print a markdown table");
  run_option->excludes(simulate_option)->excludes(table_option);
  simulate_option->excludes(table_option);
  app.add_option("--output", output, "sensors.yaml to write (the fusion's calibration)");
  app.add_option("--seed", seed, "simulation seed (--simulate-led)")->capture_default_str();
  app.add_option("--outlier-fraction", outlier_fraction,
                 "fraction of outlier events added to the simulated stream (--simulate-led)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.9));
  app.add_option("--poses", poses, "plate poses of a simulated run")->capture_default_str();
  app.add_option("--led-frequency", led_frequency, "LED frequency [Hz]")->capture_default_str();
  app.add_option("--rest", rest_s, "simulated plate: rest per pose [s]")->capture_default_str();
  app.add_option("--move", move_s, "simulated plate: move between poses [s]")
      ->capture_default_str();
  app.add_option("--min-depth", min_depth, "simulated plate: nearest LED depth [m]")
      ->capture_default_str();
  app.add_option("--max-depth", max_depth, "simulated plate: farthest LED depth [m]")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    if (table_seeds > 0) {
      std::printf(
          "| outlier events | seed | correspondences | translation error [mm] | rotation error "
          "[deg] | eDVS centre error [px] | reprojection RMSE [px] | LED error median / 90 %% [px] "
          "| "
          "status |\n|---|---|---|---|---|---|---|---|---|\n");
      for (double fraction : {0.0, 0.2}) {
        for (int s = 1; s <= table_seeds; ++s) {
          ebslam::LedCalibrationRunConfig config;
          config.seed = static_cast<std::uint64_t>(s);
          config.simulator.seed = config.seed;
          config.simulator.events.seed = config.seed;
          config.poses = poses;
          config.rest_s = rest_s;
          config.move_s = move_s;
          config.min_depth_m = min_depth;
          config.max_depth_m = max_depth;
          config.rest_s = rest_s;
          config.move_s = move_s;
          config.min_depth_m = min_depth;
          config.max_depth_m = max_depth;
          config.led_frequency_hz = led_frequency;
          config.outlier_event_fraction = fraction;
          const ebslam::LedCalibrationRun run = ebslam::simulateLedCalibrationRun(config);
          const Outcome o =
              calibrate({run.events, run.depth_observations, run.truth}, led_frequency);
          std::printf(
              "| %.0f %% | %d | %zu | %.3f | %.4f | %.2f | %.3f | %.2f / %.2f | %s |\n",
              100.0 * fraction, s, o.correspondences, o.error.translation_mm, o.error.rotation_deg,
              (o.result.sensors.edvs.principal_point - run.truth.edvs.principal_point).norm(),
              o.result.rmse_px, o.led_error_median_px, o.led_error_p90_px,
              ebslam::toString(o.result.status));
          std::fflush(stdout);
        }
      }
      return 0;
    }
    CalibrationInput input;
    if (!simulate_dir.empty()) {
      ebslam::LedCalibrationRunConfig config;
      config.seed = seed;
      config.simulator.seed = seed;
      config.simulator.events.seed = seed;
      config.poses = poses;
      config.rest_s = rest_s;
      config.move_s = move_s;
      config.min_depth_m = min_depth;
      config.max_depth_m = max_depth;
      config.led_frequency_hz = led_frequency;
      config.outlier_event_fraction = outlier_fraction;
      const ebslam::LedCalibrationRun run = ebslam::simulateLedCalibrationRun(config);
      writeRun(simulate_dir, run);
      std::printf("simulated %.2f s: %zu events (%zu outliers), %zu depth frames with the LED\n",
                  run.duration_s, run.events.size(), run.outlier_events,
                  run.depth_observations.size());
      run_dir = simulate_dir;
    }
    if (run_dir.empty()) {
      std::fprintf(stderr, "dedvs_calibrate: give --run, --simulate-led or --table-seeds\n");
      return 2;
    }
    input = readRun(run_dir);
    const Outcome outcome = calibrate(input, led_frequency);
    printOutcome(outcome, input.sensors);
    if (!output.empty()) ebslam::writeDedvsSensors(output, outcome.result.sensors);
    return outcome.result.status == ebslam::CalibrationStatus::kOk ? 0 : 3;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "dedvs_calibrate: %s\n", error.what());
    return 1;
  }
}
