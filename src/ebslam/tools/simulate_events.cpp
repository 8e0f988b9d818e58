// Simulates eDVS events of the floor-robot scenario (thesis 6.5.3): a robot drives along a
// motion-capture trajectory (TUM format, e.g. the TUM freiburg2_pioneer runs) with the sensor
// looking up at a textured ceiling 2.59 m above. Writes the events (project binary format, or
// text for a .txt path), the ground-truth camera trajectory (TUM format, same clock as the
// events: seconds since the trajectory start) and optionally the known ceiling map for EB-PF.
//
// Example (one line):
//   ebslam_simulate_events --trajectory rgbd_dataset_freiburg2_pioneer_360-groundtruth.txt
//     --texture lines --seed 3 --events out/pioneer_360.ebe --groundtruth out/pioneer_360.tum
//     --map out/pioneer_360_map

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ebslam/events/event_io.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"

namespace {

struct Options {
  std::string trajectory_path;
  bool raw_camera_poses = false;
  std::string texture = "lines";
  double metres_per_texel = 0.01;
  double ceiling_height_m = ebslam::kThesisCeilingHeightM;
  double t_begin_s = 0.0;
  double t_end_s = -1.0;
  std::string events_path;
  std::string groundtruth_path;
  std::string map_prefix;
  double map_metres_per_pixel = 0.01;
  double smoothing_half_window_s = 0.05;
};

int run(const Options& options, ebslam::SimulatorConfig config,
        ebslam::LinesAndCirclesConfig lines) {
  config.validate();
  const ebslam::Trajectory input = ebslam::readTumTrajectory(options.trajectory_path);
  if (input.size() < 2) {
    throw std::invalid_argument("trajectory file " + options.trajectory_path +
                                " holds fewer than two poses");
  }
  ebslam::Trajectory camera_path;
  if (options.raw_camera_poses) {
    camera_path = input;
  } else {
    ebslam::FloorRobotTrajectoryConfig floor_config;
    floor_config.smoothing_half_window_s = options.smoothing_half_window_s;
    camera_path = ebslam::makeFloorRobotTrajectory(input, floor_config);
  }
  const double t0 = camera_path.front().t_s;
  const double t_begin = t0 + options.t_begin_s;
  const double t_end = options.t_end_s < 0.0 ? camera_path.back().t_s : t0 + options.t_end_s;
  if (!(t_begin < t_end) || t_end > camera_path.back().t_s) {
    throw std::invalid_argument("time range [" + std::to_string(options.t_begin_s) + ", " +
                                std::to_string(options.t_end_s) +
                                "] s is empty or beyond the trajectory (" +
                                std::to_string(camera_path.back().t_s - t0) + " s long)");
  }

  const ebslam::FloorRegion region =
      ebslam::visibleCeilingRegion(camera_path, config.camera, options.ceiling_height_m);
  ebslam::Scene scene;
  if (options.texture == "lines") {
    scene = ebslam::makeLinesCeilingScene(region, options.metres_per_texel, lines,
                                          options.ceiling_height_m);
  } else {
    const cv::Mat texture = cv::imread(options.texture, cv::IMREAD_UNCHANGED);
    if (texture.empty()) {
      throw std::runtime_error("cannot read texture image " + options.texture);
    }
    scene = ebslam::makeCeilingScene(texture, region, options.metres_per_texel,
                                     options.ceiling_height_m);
  }

  const ebslam::SensorSize sensor{static_cast<std::uint32_t>(config.camera.width),
                                  static_cast<std::uint32_t>(config.camera.height)};
  ebslam::EventFileWriter writer(options.events_path, sensor,
                                 ebslam::eventFileFormatFromExtension(options.events_path));
  const ebslam::EventSimulator simulator(config);
  const auto start = std::chrono::steady_clock::now();
  const ebslam::SimulationResult result =
      simulator.simulate(scene, camera_path, t_begin, t_end,
                         [&writer](const ebslam::EventVector& events) { writer.write(events); });
  writer.close();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ebslam::writeTumTrajectory(options.groundtruth_path, result.ground_truth);

  double distance_m = 0.0;
  double rotation_rad = 0.0;
  for (std::size_t i = 1; i < result.ground_truth.size(); ++i) {
    distance_m += (result.ground_truth[i].position - result.ground_truth[i - 1].position).norm();
    rotation_rad +=
        result.ground_truth[i].orientation.angularDistance(result.ground_truth[i - 1].orientation);
  }
  const double duration_s = t_end - t_begin;
  const std::size_t total = result.signal_events + result.noise_events;
  std::printf("simulated %.3f s (%.2f m, %.2f rad) in %.3f s wall: %.2f x real time\n", duration_s,
              distance_m, rotation_rad, wall_s, duration_s / wall_s);
  std::printf("events: %zu (%zu signal, %zu noise), %.0f events/s simulated, %zu renders\n", total,
              result.signal_events, result.noise_events, total / duration_s, result.render_steps);
  if (distance_m > 0.0) {
    // Eq. 6.6 read backwards, counting all signal events as translation-caused (an upper bound
    // for G0 when the path also turns).
    const double d = options.ceiling_height_m;
    std::printf("signal events per metre: %.0f (G0 <= %.0f by eq. 6.6 with D = %.2f m)\n",
                result.signal_events / distance_m,
                result.signal_events * d / (distance_m * config.camera.focal_px), d);
  }

  if (!options.map_prefix.empty()) {
    ebslam::CeilingMapConfig map_config;
    map_config.metres_per_pixel = options.map_metres_per_pixel;
    map_config.blur_sigma_m = 0.5 * config.camera.triggerDistance(options.ceiling_height_m);
    const ebslam::CeilingMap map = ebslam::renderCeilingMap(scene, region, map_config);
    cv::Mat intensity;
    map.intensity.convertTo(intensity, CV_8U, 255.0);
    if (!cv::imwrite(options.map_prefix + "_edges.png", map.edges) ||
        !cv::imwrite(options.map_prefix + "_intensity.png", intensity)) {
      throw std::runtime_error("cannot write map images " + options.map_prefix + "_*.png");
    }
    std::ofstream meta(options.map_prefix + ".yaml");
    meta.precision(12);
    meta << "# Ceiling map for EB-PF: pixel (col, row) has its centre at world\n"
         << "# (origin_x + col * res, origin_y + row * res) (row grows with world y).\n"
         << "edges: " << options.map_prefix + "_edges.png\n"
         << "intensity: " << options.map_prefix + "_intensity.png\n"
         << "resolution_m: " << map.metres_per_pixel << "\n"
         << "origin_x_m: " << map.origin_m.x() << "\n"
         << "origin_y_m: " << map.origin_m.y() << "\n"
         << "ceiling_height_m: " << options.ceiling_height_m << "\n"
         << "focal_px: " << config.camera.focal_px << "\n"
         << "principal_point_px: [" << config.camera.principal_point.x() << ", "
         << config.camera.principal_point.y() << "]\n"
         << "kappa: [" << config.camera.kappa1 << ", " << config.camera.kappa2 << "]\n"
         << "distortion_model: "
         << (config.camera.distortion_model == ebslam::DistortionModel::kDistortEq63 ? "eq6.3"
                                                                                     : "eq8.3")
         << "\n"
         << "seed: " << config.events.seed << "\n";
    if (!meta) throw std::runtime_error("cannot write " + options.map_prefix + ".yaml");
    std::printf("ceiling map: %dx%d pixels at %.3f m, origin (%.3f, %.3f) m -> %s_*.png\n",
                map.edges.cols, map.edges.rows, map.metres_per_pixel, map.origin_m.x(),
                map.origin_m.y(), options.map_prefix.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Simulate eDVS events of a floor robot looking up at a textured ceiling (thesis 6.5.3)"};
  Options options;
  ebslam::SimulatorConfig config;
  ebslam::LinesAndCirclesConfig lines;
  app.add_option("--trajectory", options.trajectory_path,
                 "TUM trajectory; by default a motion-capture run of a forward-looking camera "
                 "on a floor robot (x, y and yaw are kept, see makeFloorRobotTrajectory)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_flag("--raw-camera-poses", options.raw_camera_poses,
               "use the trajectory as eDVS camera poses (camera -> world, z up to the ceiling)");
  app.add_option("--smoothing", options.smoothing_half_window_s,
                 "half-width of the moving average over x, y, yaw of the mocap poses [s]")
      ->capture_default_str();
  app.add_option("--texture", options.texture,
                 "ceiling texture: an image file (tiled) or 'lines' for random lines and circles")
      ->capture_default_str();
  app.add_option("--texture-mpt", options.metres_per_texel, "texel size on the ceiling [m]")
      ->capture_default_str();
  app.add_option("--texture-seed", lines.seed, "seed of the procedural texture")
      ->capture_default_str();
  app.add_option("--line-intensity", lines.foreground,
                 "intensity of the procedural lines and circles in [0, 1] (ceiling: " +
                     std::to_string(lines.background) + ")")
      ->capture_default_str();
  app.add_option("--ceiling-height", options.ceiling_height_m, "ceiling above the sensor [m]")
      ->capture_default_str();
  app.add_option("--t-begin", options.t_begin_s, "start, seconds after the trajectory start")
      ->capture_default_str();
  app.add_option("--t-end", options.t_end_s,
                 "end, seconds after the trajectory start (negative: trajectory end)")
      ->capture_default_str();
  app.add_option("--seed", config.events.seed, "seed of mismatch, initial levels and noise")
      ->capture_default_str();
  app.add_option("--contrast", config.events.contrast_threshold_on,
                 "ON and OFF contrast threshold [log intensity]")
      ->capture_default_str();
  app.add_option("--mismatch", config.events.threshold_mismatch_sigma,
                 "per-pixel threshold standard deviation [log intensity]")
      ->capture_default_str();
  app.add_option("--refractory-us", config.events.refractory_period_us, "refractory period [us]")
      ->capture_default_str();
  app.add_option("--noise-rate", config.events.noise_rate_hz_per_pixel,
                 "background noise events per pixel and second")
      ->capture_default_str();
  app.add_option("--noise-log-sigma", config.events.noise_rate_log_sigma,
                 "spread of the noise rate across pixels: std. dev. of its natural log")
      ->capture_default_str();
  app.add_option("--hot-pixel-fraction", config.events.hot_pixel_fraction,
                 "fraction of hot pixels [0, 1]")
      ->capture_default_str();
  app.add_option("--hot-pixel-rate", config.events.hot_pixel_rate_hz,
                 "noise rate of a hot pixel [Hz]")
      ->capture_default_str();
  app.add_option("--render-rate", config.render_rate_hz, "minimum render rate [Hz]")
      ->capture_default_str();
  app.add_option("--max-step-px", config.max_step_motion_px,
                 "largest image motion between renders [pixels]")
      ->capture_default_str();
  app.add_option("--supersampling", config.supersampling, "samples per pixel and axis")
      ->capture_default_str();
  app.add_option("--focal", config.camera.focal_px, "focal length [pixels]")->capture_default_str();
  app.add_option("--kappa1", config.camera.kappa1, "radial distortion, eq. 6.3 [1/pixel]")
      ->capture_default_str();
  app.add_option("--kappa2", config.camera.kappa2, "radial distortion, eq. 6.3 [1/pixel^2]")
      ->capture_default_str();
  app.add_flag(
      "--distortion-eq83",
      [&config](std::int64_t) {
        config.camera.distortion_model = ebslam::DistortionModel::kUndistortEq83;
      },
      "apply kappa1/kappa2 as in eq. 8.3 (polynomial undistorts event coordinates, as "
      "CeilingCamera) instead of eq. 6.3");
  app.add_option("--groundtruth-rate", config.ground_truth_rate_hz,
                 "rate of the ground-truth poses [Hz]")
      ->capture_default_str();
  app.add_option("--events", options.events_path,
                 "output event file (binary; text if it ends in .txt)")
      ->required();
  app.add_option("--groundtruth", options.groundtruth_path,
                 "output ground-truth camera trajectory (TUM)")
      ->required();
  app.add_option("--map", options.map_prefix,
                 "also write the known ceiling map: PREFIX_edges.png (Canny), "
                 "PREFIX_intensity.png and PREFIX.yaml");
  app.add_option("--map-resolution", options.map_metres_per_pixel, "map pixel size [m]")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  config.events.contrast_threshold_off = config.events.contrast_threshold_on;
  try {
    return run(options, config, lines);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "ebslam_simulate_events: %s\n", error.what());
    return 1;
  }
}
