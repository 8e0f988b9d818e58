#include "ebslam/calibration/dedvs_calibration.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Checkerboard texture: `squares` x `squares` squares of 16 texels, dark and light, with the
// middle 3 x 3 squares light (the LED's surround: uniform, so that the LED's spot looks the
// same on all sides).
cv::Mat checkerboard(int squares) {
  constexpr int kTexels = 16;
  cv::Mat texture(squares * kTexels, squares * kTexels, CV_32FC1);
  const int middle = squares / 2;
  for (int row = 0; row < texture.rows; ++row) {
    for (int col = 0; col < texture.cols; ++col) {
      const int sr = row / kTexels, sc = col / kTexels;
      const bool light =
          (sr + sc) % 2 == 0 || (std::abs(sr - middle) <= 1 && std::abs(sc - middle) <= 1);
      texture.at<float>(row, col) = light ? 0.7f : 0.3f;  // low contrast: fewer plate events
    }
  }
  return texture;
}

// Depth of the surface at `pixel` from the measured depth around it: least-squares plane
// 1/z = a (col - u) + b (row - v) + c over the valid pixels within `radius` (exact for planar
// surfaces), evaluated at the pixel. std::nullopt with fewer than 10 valid pixels.
std::optional<double> planeDepthAt(const cv::Mat& depth_mm, const Eigen::Vector2d& pixel,
                                   double radius) {
  const int r = static_cast<int>(std::ceil(radius));
  const int cx = static_cast<int>(std::lround(pixel.x()));
  const int cy = static_cast<int>(std::lround(pixel.y()));
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  int count = 0;
  for (int row = std::max(0, cy - r); row <= std::min(depth_mm.rows - 1, cy + r); ++row) {
    for (int col = std::max(0, cx - r); col <= std::min(depth_mm.cols - 1, cx + r); ++col) {
      const Eigen::Vector2d offset = Eigen::Vector2d(col, row) - pixel;
      if (offset.norm() > radius) continue;
      const std::uint16_t mm = depth_mm.at<std::uint16_t>(row, col);
      if (mm == 0) continue;
      const Eigen::Vector3d a(offset.x(), offset.y(), 1.0);
      normal += a * a.transpose();
      rhs += a * (1000.0 / mm);
      ++count;
    }
  }
  if (count < 10) return std::nullopt;
  const Eigen::Vector3d solution = normal.ldlt().solve(rhs);
  if (!solution.allFinite() || !(solution.z() > 0.0)) return std::nullopt;
  return 1.0 / solution.z();
}

}  // namespace

void LedCalibrationRunConfig::validate() const {
  simulator.validate();
  require(std::isfinite(led_frequency_hz) && led_frequency_hz > 0.0 && led_frequency_hz <= 5000.0,
          "LedCalibrationRunConfig: led_frequency_hz must lie in (0, 5000]");
  require(std::isfinite(led_radius_m) && led_radius_m >= 0.0 && std::isfinite(led_on_intensity) &&
              led_on_intensity > 0.0,
          "LedCalibrationRunConfig: led_radius_m must be >= 0 and led_on_intensity > 0");
  require(poses >= 2 && poses <= 100000, "LedCalibrationRunConfig: poses must lie in [2, 1e5]");
  require(std::isfinite(move_s) && move_s > 0.0 && std::isfinite(rest_s) && rest_s > 0.0,
          "LedCalibrationRunConfig: move_s and rest_s must be positive");
  require(std::isfinite(min_depth_m) && min_depth_m > 0.0 && std::isfinite(max_depth_m) &&
              max_depth_m >= min_depth_m,
          "LedCalibrationRunConfig: need 0 < min_depth_m <= max_depth_m");
  require(std::isfinite(max_tilt_deg) && max_tilt_deg >= 0.0 && max_tilt_deg < 80.0,
          "LedCalibrationRunConfig: max_tilt_deg must lie in [0, 80)");
  require(corner_pose_fraction >= 0.0 && corner_pose_fraction <= 1.0 &&
              corner_size_fraction > 0.0 && corner_size_fraction <= 0.5,
          "LedCalibrationRunConfig: corner_pose_fraction must lie in [0, 1] and "
          "corner_size_fraction in (0, 0.5]");
  require(squares >= 1 && squares % 2 == 1 && squares <= 101,
          "LedCalibrationRunConfig: squares must be odd, in [1, 101]");
  require(std::isfinite(square_size_m) && square_size_m > 0.0,
          "LedCalibrationRunConfig: square_size_m must be positive");
  require(std::isfinite(border_margin_px) && border_margin_px >= 0.0 &&
              2.0 * border_margin_px < simulator.edvs.width - 1 &&
              2.0 * border_margin_px < simulator.edvs.height - 1,
          "LedCalibrationRunConfig: border_margin_px must be >= 0 and leave part of the sensor");
  require(std::isfinite(led_pixel_noise_px) && led_pixel_noise_px >= 0.0,
          "LedCalibrationRunConfig: led_pixel_noise_px must be >= 0");
  require(std::isfinite(depth_fit_radius_px) && depth_fit_radius_px >= 2.0,
          "LedCalibrationRunConfig: depth_fit_radius_px must be >= 2");
  require(outlier_event_fraction >= 0.0 && outlier_event_fraction <= 0.9,
          "LedCalibrationRunConfig: outlier_event_fraction must lie in [0, 0.9]");
}

namespace {

// Pixels of the depth camera at least `margin` pixels inside its border.
struct DepthView {
  const PinholeCamera& camera;
  double margin;

  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {camera.fx * p.x() / p.z() + camera.cx, camera.fy * p.y() / p.z() + camera.cy};
  }
  bool inside(const Eigen::Vector2d& u) const {
    return u.x() >= margin && u.y() >= margin && u.x() <= camera.width - 1 - margin &&
           u.y() <= camera.height - 1 - margin;
  }
};

// The checkerboard plate (plane 0, in its own frame) and the LED at its centre.
Scene calibrationPlate(const LedCalibrationRunConfig& config) {
  const double side = config.squares * config.square_size_m;
  TexturedPlane plate;
  plate.texture = checkerboard(config.squares);
  plate.size_m = Eigen::Vector2d(side, side);
  plate.metres_per_texel = config.square_size_m / 16.0;
  plate.repeat = false;
  Scene scene;
  scene.planes.push_back(plate);
  scene.background_intensity = 0.5;
  return scene;
}

// A depth-frame point of the LED for plate pose k: at a random eDVS pixel (a share of the poses
// in the image's corners, where rotation and principal point differ most and the distortion is
// largest, the corners in turn; the others anywhere) and depth, seen by the depth camera too.
Eigen::Vector3d randomLedPoint(const LedCalibrationRunConfig& config, const DepthView& view, int k,
                               std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const DedvsSimulatorConfig& sim = config.simulator;
  const CameraModel& edvs = sim.edvs;
  const double m = config.border_margin_px;
  // Pose k is a corner pose when the running count of corner poses steps at k (spread evenly).
  const double share = config.corner_pose_fraction;
  const int corner_poses_before = static_cast<int>(std::floor(k * share + 1e-9));
  const bool corner_pose =
      static_cast<int>(std::floor((k + 1) * share + 1e-9)) > corner_poses_before;
  const int corner = corner_poses_before % 4;  // top-left, top-right, bottom-left, bottom-right
  const double corner_w = config.corner_size_fraction * edvs.width;
  const double corner_h = config.corner_size_fraction * edvs.height;
  for (int attempt = 0; attempt <= 10000; ++attempt) {
    Eigen::Vector2d v(m + unit(rng) * (edvs.width - 1 - 2 * m),
                      m + unit(rng) * (edvs.height - 1 - 2 * m));
    if (corner_pose) {
      const double dx = unit(rng) * std::max(0.0, corner_w - m);
      const double dy = unit(rng) * std::max(0.0, corner_h - m);
      v.x() = corner % 2 == 0 ? m + dx : edvs.width - 1 - m - dx;
      v.y() = corner < 2 ? m + dy : edvs.height - 1 - m - dy;
    }
    const double z = config.min_depth_m + unit(rng) * (config.max_depth_m - config.min_depth_m);
    const std::optional<Eigen::Vector3d> ray = edvs.backprojectRay(v);
    if (!ray) continue;
    const Eigen::Vector3d ray_depth = sim.depth_from_edvs.linear() * *ray;
    if (!(ray_depth.z() > 0.0)) continue;
    const double lambda = (z - sim.depth_from_edvs.translation().z()) / ray_depth.z();
    if (!(lambda > 0.0)) continue;
    const Eigen::Vector3d led_depth = sim.depth_from_edvs * (lambda * *ray);
    if (view.inside(view.project(led_depth))) return led_depth;
  }
  throw std::invalid_argument(
      "simulateLedCalibrationRun: the eDVS and depth views do not overlap at these depths");
}

// Plate poses (world = depth optical frame), each held for rest_s after a move of move_s: the
// LED at randomLedPoint, the plate facing the rig (its normal along -z) tilted about its x and
// y axes.
Trajectory plateCalibrationPoses(const LedCalibrationRunConfig& config, const DepthView& view,
                                 const Eigen::Vector3d& led_on_plate, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double period_s = config.move_s + config.rest_s;
  Trajectory plate_poses;
  for (int k = 0; k < config.poses; ++k) {
    const Eigen::Vector3d led_depth = randomLedPoint(config, view, k, rng);
    const double tilt = config.max_tilt_deg * kPi / 180.0;
    const Eigen::Matrix3d rotation =
        (Eigen::AngleAxisd((2.0 * unit(rng) - 1.0) * tilt, Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd((2.0 * unit(rng) - 1.0) * tilt, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation;
    pose.translation() = led_depth - rotation * led_on_plate;
    plate_poses.push_back(StampedPose::fromIsometry(k * period_s, pose));
    plate_poses.push_back(StampedPose::fromIsometry(k * period_s + config.rest_s, pose));
  }
  return plate_poses;
}

// Outlier events: uniformly random pixel, polarity and time, merged into the time-sorted events.
void addOutlierEvents(const LedCalibrationRunConfig& config, std::mt19937_64& rng,
                      LedCalibrationRun& run) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const CameraModel& edvs = config.simulator.edvs;
  std::vector<Event>& events = run.events;
  const double fraction = config.outlier_event_fraction;
  run.outlier_events = static_cast<std::size_t>(
      std::llround(static_cast<double>(events.size()) * fraction / (1.0 - fraction)));
  const std::size_t simulated = events.size();
  const double duration_us = run.duration_s * 1e6;
  for (std::size_t k = 0; k < run.outlier_events; ++k) {
    Event e;
    e.t_us = static_cast<std::int64_t>(unit(rng) * duration_us);
    e.x = static_cast<std::uint16_t>(std::min<double>(edvs.width - 1, unit(rng) * edvs.width));
    e.y = static_cast<std::uint16_t>(std::min<double>(edvs.height - 1, unit(rng) * edvs.height));
    e.polarity = unit(rng) < 0.5;
    events.push_back(e);
  }
  std::sort(events.begin() + static_cast<std::ptrdiff_t>(simulated), events.end(),
            [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
  std::inplace_merge(events.begin(), events.begin() + static_cast<std::ptrdiff_t>(simulated),
                     events.end(), [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
}

}  // namespace

LedCalibrationRun simulateLedCalibrationRun(const LedCalibrationRunConfig& config,
                                            const DedvsSimulator::DepthSink& frame_sink) {
  config.validate();
  const DedvsSimulatorConfig& sim = config.simulator;
  const DedvsSimulator simulator(sim);
  std::mt19937_64 rng(config.seed);

  const Scene scene = calibrationPlate(config);
  const double side = config.squares * config.square_size_m;
  const Eigen::Vector3d led_on_plate(0.5 * side, 0.5 * side, 0.0);  // centre of the middle square
  BlinkingLed led;
  led.position = led_on_plate;
  led.plane_index = 0;
  led.frequency_hz = config.led_frequency_hz;
  led.radius_m = config.led_radius_m;
  led.on_intensity = config.led_on_intensity;

  const DepthView view{sim.depth.camera, config.border_margin_px};
  const Trajectory plate_poses = plateCalibrationPoses(config, view, led_on_plate, rng);
  const double duration = plate_poses.back().t_s;  // the last pose rests only
  MovingPlane moving;
  moving.plane_index = 0;
  moving.pose = plate_poses;
  Trajectory rig;  // the rig stands still at the world origin
  rig.push_back(StampedPose::fromIsometry(0.0, Eigen::Isometry3d::Identity()));
  rig.push_back(StampedPose::fromIsometry(duration, Eigen::Isometry3d::Identity()));

  LedCalibrationRun run;
  run.truth = sensorsOf(sim);
  run.duration_s = duration;
  std::vector<cv::Mat> frames;
  std::vector<double> frame_times;
  simulator.simulate(
      scene, rig, 0.0, duration,
      [&run](const std::vector<TrueDepthEvent>& batch) {
        for (const TrueDepthEvent& e : batch) run.events.push_back(e.event);
      },
      [&](const DepthFrame& frame) {
        if (frame_sink) frame_sink(frame);
        frames.push_back(frame.depth_mm);
        frame_times.push_back(frame.t_s);
      },
      {led}, {moving});

  // The LED in the depth camera: its true pixel plus tracking noise, the depth from the
  // measured plate surface around it.
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const Eigen::Vector3d point =
        interpolatePose(plate_poses, frame_times[f]).isometry() * led_on_plate;
    const double noise_x = gauss(rng), noise_y = gauss(rng);
    if (!(point.z() > 0.0)) continue;
    const Eigen::Vector2d pixel =
        view.project(point) + config.led_pixel_noise_px * Eigen::Vector2d(noise_x, noise_y);
    if (!view.inside(pixel)) continue;
    const std::optional<double> z = planeDepthAt(frames[f], pixel, config.depth_fit_radius_px);
    if (!z) continue;
    DepthLedObservation observation;
    observation.t_s = frame_times[f];
    observation.pixel = pixel;
    observation.depth_m = *z;
    observation.true_point = point;
    run.depth_observations.push_back(observation);
  }

  addOutlierEvents(config, rng, run);
  return run;
}

}  // namespace ebslam
