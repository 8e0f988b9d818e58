#include "ebslam/simulation/simulator_scenes.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Bilinear lookup with wrap-around; texel (c, r) covers [c, c + 1) x [r, r + 1).
float sampleWrapped(const cv::Mat& texture, double u, double v) {
  const double x = u - 0.5;
  const double y = v - 0.5;
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  const float ax = static_cast<float>(x - fx);
  const float ay = static_cast<float>(y - fy);
  auto wrap = [](long long i, int n) {
    const long long m = i % n;
    return static_cast<int>(m < 0 ? m + n : m);
  };
  const int x0 = wrap(static_cast<long long>(fx), texture.cols);
  const int y0 = wrap(static_cast<long long>(fy), texture.rows);
  const int x1 = x0 + 1 == texture.cols ? 0 : x0 + 1;
  const int y1 = y0 + 1 == texture.rows ? 0 : y0 + 1;
  const float* row0 = texture.ptr<float>(y0);
  const float* row1 = texture.ptr<float>(y1);
  const float top = row0[x0] + ax * (row0[x1] - row0[x0]);
  const float bottom = row1[x0] + ax * (row1[x1] - row1[x0]);
  return top + ay * (bottom - top);
}

}  // namespace

Pose2 floorPoseToSe2(const StampedPose& pose) {
  const Eigen::Vector3d x_axis = pose.orientation.normalized() * Eigen::Vector3d::UnitX();
  return {pose.position.x(), pose.position.y(), std::atan2(x_axis.y(), x_axis.x())};
}

StampedPose se2ToFloorPose(double t_s, double x, double y, double theta) {
  StampedPose pose;
  pose.t_s = t_s;
  pose.position = Eigen::Vector3d(x, y, 0.0);
  pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
  return pose;
}

Trajectory makeFloorRobotTrajectory(const Trajectory& mocap_trajectory,
                                    const FloorRobotTrajectoryConfig& config) {
  require(mocap_trajectory.size() >= 2,
          "makeFloorRobotTrajectory: the trajectory needs at least two poses");
  validateTrajectory(mocap_trajectory, "makeFloorRobotTrajectory: input");
  require(std::isfinite(config.smoothing_half_window_s) && config.smoothing_half_window_s >= 0.0,
          "makeFloorRobotTrajectory: smoothing_half_window_s must be >= 0");
  require(std::isfinite(config.resample_interval_s) && config.resample_interval_s >= 0.0,
          "makeFloorRobotTrajectory: resample_interval_s must be >= 0");

  // Floor normal: the world axis with the least position variance.
  const std::size_t n = mocap_trajectory.size();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const StampedPose& pose : mocap_trajectory) mean += pose.position;
  mean /= static_cast<double>(n);
  Eigen::Vector3d variance = Eigen::Vector3d::Zero();
  for (const StampedPose& pose : mocap_trajectory) {
    variance += (pose.position - mean).cwiseAbs2();
  }
  int normal_axis = 0;
  variance.minCoeff(&normal_axis);
  // In-plane axes in cyclic order keep the frame right-handed (normal axis = up).
  const int axis_a = (normal_axis + 1) % 3;
  const int axis_b = (normal_axis + 2) % 3;

  std::vector<double> times(n);
  std::vector<double> xs(n);
  std::vector<double> ys(n);
  std::vector<double> yaws(n);
  for (std::size_t i = 0; i < n; ++i) {
    const StampedPose& pose = mocap_trajectory[i];
    const Eigen::Vector3d optical_axis = pose.orientation.normalized() * Eigen::Vector3d::UnitZ();
    const double a = optical_axis[axis_a];
    const double b = optical_axis[axis_b];
    if (std::hypot(a, b) < 0.3) {
      throw std::invalid_argument(
          "makeFloorRobotTrajectory: optical axis nearly vertical at pose " + std::to_string(i) +
          " (not a forward-looking floor-robot camera)");
    }
    times[i] = pose.t_s;
    xs[i] = pose.position[axis_a];
    ys[i] = pose.position[axis_b];
    double yaw = std::atan2(b, a);
    if (i > 0) {  // unwrap
      while (yaw - yaws[i - 1] > kPi) yaw -= 2.0 * kPi;
      while (yaw - yaws[i - 1] < -kPi) yaw += 2.0 * kPi;
    }
    yaws[i] = yaw;
  }

  // Centred moving average over a time window (samples may be irregular).
  if (config.smoothing_half_window_s > 0.0) {
    std::vector<double> sx(n);
    std::vector<double> sy(n);
    std::vector<double> syaw(n);
    std::size_t lo = 0;
    std::size_t hi = 0;
    double sum_x = 0.0;
    double sum_y = 0.0;
    double sum_yaw = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      while (hi < n && times[hi] <= times[i] + config.smoothing_half_window_s) {
        sum_x += xs[hi];
        sum_y += ys[hi];
        sum_yaw += yaws[hi];
        ++hi;
      }
      while (times[lo] < times[i] - config.smoothing_half_window_s) {
        sum_x -= xs[lo];
        sum_y -= ys[lo];
        sum_yaw -= yaws[lo];
        ++lo;
      }
      const double count = static_cast<double>(hi - lo);
      sx[i] = sum_x / count;
      sy[i] = sum_y / count;
      syaw[i] = sum_yaw / count;
    }
    xs.swap(sx);
    ys.swap(sy);
    yaws.swap(syaw);
  }

  const double t_offset = config.start_at_zero ? times.front() : 0.0;
  const double x_offset = config.start_at_origin ? xs.front() : 0.0;
  const double y_offset = config.start_at_origin ? ys.front() : 0.0;
  Trajectory result;
  auto append = [&](double t, double x, double y, double yaw) {
    result.push_back(se2ToFloorPose(t - t_offset, x - x_offset, y - y_offset, yaw));
  };
  if (config.resample_interval_s <= 0.0) {
    for (std::size_t i = 0; i < n; ++i) append(times[i], xs[i], ys[i], yaws[i]);
    return result;
  }
  const double duration = times.back() - times.front();
  const auto steps = static_cast<std::size_t>(std::floor(duration / config.resample_interval_s));
  std::size_t k = 0;
  double last_t = times.front();
  for (std::size_t step = 0; step <= steps; ++step) {
    const double t = times.front() + static_cast<double>(step) * config.resample_interval_s;
    last_t = t;
    while (k + 2 < n && times[k + 1] <= t) ++k;
    const double s = std::clamp((t - times[k]) / (times[k + 1] - times[k]), 0.0, 1.0);
    append(t, xs[k] + s * (xs[k + 1] - xs[k]), ys[k] + s * (ys[k + 1] - ys[k]),
           yaws[k] + s * (yaws[k + 1] - yaws[k]));
  }
  if (times.back() - last_t > 1e-9) {
    append(times.back(), xs.back(), ys.back(), yaws.back());
  }
  return result;
}

FloorRegion visibleCeilingRegion(const Trajectory& floor_trajectory, const CameraModel& camera,
                                 double ceiling_height_m, double margin_m) {
  require(!floor_trajectory.empty(), "visibleCeilingRegion: empty trajectory");
  require(std::isfinite(ceiling_height_m) && ceiling_height_m > 0.0,
          "visibleCeilingRegion: ceiling height must be positive");
  require(std::isfinite(margin_m) && margin_m >= 0.0, "visibleCeilingRegion: margin must be >= 0");
  camera.validate();
  double footprint_radius = 0.0;
  const Eigen::Vector2d corners[] = {{-0.5, -0.5},
                                     {camera.width - 0.5, -0.5},
                                     {-0.5, camera.height - 0.5},
                                     {camera.width - 0.5, camera.height - 0.5}};
  for (const Eigen::Vector2d& corner : corners) {
    if (const std::optional<Eigen::Vector3d> ray = camera.backprojectRay(corner)) {
      footprint_radius = std::max(footprint_radius, ray->head<2>().norm() * ceiling_height_m);
    }
  }
  FloorRegion region;
  region.min = floor_trajectory.front().position.head<2>();
  region.max = region.min;
  for (const StampedPose& pose : floor_trajectory) {
    require(pose.position.allFinite(), "visibleCeilingRegion: non-finite position");
    region.min = region.min.cwiseMin(pose.position.head<2>());
    region.max = region.max.cwiseMax(pose.position.head<2>());
  }
  const double grow = footprint_radius + margin_m;
  region.min.array() -= grow;
  region.max.array() += grow;
  return region;
}

Scene makeCeilingScene(const cv::Mat& texture, const FloorRegion& region, double metres_per_texel,
                       double ceiling_height_m) {
  require(!texture.empty(), "makeCeilingScene: texture is empty");
  require(region.min.allFinite() && region.max.allFinite() &&
              (region.max - region.min).minCoeff() > 0.0,
          "makeCeilingScene: region is empty");
  require(std::isfinite(metres_per_texel) && metres_per_texel > 0.0,
          "makeCeilingScene: metres_per_texel must be positive");
  require(std::isfinite(ceiling_height_m) && ceiling_height_m > 0.0,
          "makeCeilingScene: ceiling height must be positive");
  TexturedPlane ceiling;
  ceiling.pose = Eigen::Isometry3d::Identity();
  ceiling.pose.translation() = Eigen::Vector3d(region.min.x(), region.min.y(), ceiling_height_m);
  ceiling.size_m = region.max - region.min;
  ceiling.texture = textureFromImage(texture);
  ceiling.metres_per_texel = metres_per_texel;
  ceiling.repeat = true;
  Scene scene;
  scene.planes.push_back(ceiling);
  scene.background_intensity = 0.5;
  return scene;
}

cv::Mat makeLinesAndCirclesTexture(const LinesAndCirclesConfig& config) {
  require(config.width_px > 0 && config.height_px > 0,
          "makeLinesAndCirclesTexture: size must be positive");
  require(config.line_count >= 0 && config.circle_count >= 0,
          "makeLinesAndCirclesTexture: counts must be >= 0");
  require(config.stroke_width_px >= 1.0 && config.max_line_length_px > 0.0 &&
              config.min_circle_radius_px > 0.0 &&
              config.max_circle_radius_px >= config.min_circle_radius_px,
          "makeLinesAndCirclesTexture: invalid stroke, length or radius");
  require(config.background >= 0.0 && config.background <= 1.0 && config.foreground >= 0.0 &&
              config.foreground <= 1.0,
          "makeLinesAndCirclesTexture: intensities must lie in [0, 1]");
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat canvas(config.height_px, config.width_px, CV_8UC1,
                 cv::Scalar(std::lround(config.background * 255.0)));
  const cv::Scalar ink(static_cast<double>(std::lround(config.foreground * 255.0)));
  const int thickness = static_cast<int>(std::lround(config.stroke_width_px));
  // Drawing uses 4 fractional bits for sub-texel anti-aliased placement.
  constexpr int kShift = 4;
  constexpr double kScale = 1 << kShift;
  auto point = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(x * kScale)),
                     static_cast<int>(std::lround(y * kScale)));
  };
  for (int i = 0; i < config.line_count; ++i) {
    const double x = unit(rng) * config.width_px;
    const double y = unit(rng) * config.height_px;
    const double angle = unit(rng) * kPi;
    const double length = (0.25 + 0.75 * unit(rng)) * config.max_line_length_px;
    const double dx = 0.5 * length * std::cos(angle);
    const double dy = 0.5 * length * std::sin(angle);
    cv::line(canvas, point(x - dx, y - dy), point(x + dx, y + dy), ink, thickness, cv::LINE_AA,
             kShift);
  }
  for (int i = 0; i < config.circle_count; ++i) {
    const double x = unit(rng) * config.width_px;
    const double y = unit(rng) * config.height_px;
    const double radius = config.min_circle_radius_px +
                          unit(rng) * (config.max_circle_radius_px - config.min_circle_radius_px);
    cv::circle(canvas, point(x, y), static_cast<int>(std::lround(radius * kScale)), ink, thickness,
               cv::LINE_AA, kShift);
  }
  return textureFromImage(canvas);
}

CeilingMap renderCeilingMap(const Scene& scene, const FloorRegion& region,
                            const CeilingMapConfig& config) {
  require(std::isfinite(config.metres_per_pixel) && config.metres_per_pixel > 0.0,
          "renderCeilingMap: metres_per_pixel must be positive");
  require(std::isfinite(config.blur_sigma_m) && config.blur_sigma_m >= 0.0,
          "renderCeilingMap: blur_sigma_m must be >= 0");
  require(region.min.allFinite() && region.max.allFinite() &&
              (region.max - region.min).minCoeff() > 0.0,
          "renderCeilingMap: region is empty");
  const TexturedPlane* ceiling = nullptr;
  for (const TexturedPlane& plane : scene.planes) {
    plane.validate();
    if (std::abs(plane.pose.linear().col(2).z()) > 1.0 - 1e-9) {
      ceiling = &plane;
      break;
    }
  }
  require(ceiling != nullptr, "renderCeilingMap: the scene has no horizontal plane");
  const double extent = (region.max - region.min).maxCoeff() / config.metres_per_pixel;
  require(extent < 20000.0, "renderCeilingMap: map would exceed 20000 pixels per side");

  cv::Mat texture = textureFromImage(ceiling->texture);
  const double sigma_texels = config.blur_sigma_m / ceiling->metres_per_texel;
  if (sigma_texels > 0.2) {
    const int pad = static_cast<int>(std::ceil(4.0 * sigma_texels)) + 1;
    if (pad < texture.cols && pad < texture.rows) {
      cv::Mat padded;
      cv::copyMakeBorder(texture, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
      cv::GaussianBlur(padded, padded, cv::Size(), sigma_texels, sigma_texels, cv::BORDER_REFLECT);
      texture = padded(cv::Rect(pad, pad, texture.cols, texture.rows)).clone();
    } else {
      cv::GaussianBlur(texture, texture, cv::Size(), sigma_texels, sigma_texels,
                       cv::BORDER_REPLICATE);
    }
  }

  CeilingMap map;
  map.metres_per_pixel = config.metres_per_pixel;
  // Pixel (col, row) covers region.min + [col, col + 1) * res: its centre is the origin below.
  map.origin_m = region.min + Eigen::Vector2d::Constant(0.5 * config.metres_per_pixel);
  const int cols =
      static_cast<int>(std::ceil((region.max.x() - region.min.x()) / config.metres_per_pixel));
  const int rows =
      static_cast<int>(std::ceil((region.max.y() - region.min.y()) / config.metres_per_pixel));
  map.intensity.create(rows, cols, CV_32FC1);
  const Eigen::Vector3d origin = ceiling->pose.translation();
  const Eigen::Vector3d axis_u = ceiling->pose.linear().col(0);
  const Eigen::Vector3d axis_v = ceiling->pose.linear().col(1);
  const double inv_mpt = 1.0 / ceiling->metres_per_texel;
  const double extent_u =
      ceiling->repeat ? ceiling->size_m.x()
                      : std::min(ceiling->size_m.x(), texture.cols * ceiling->metres_per_texel);
  const double extent_v =
      ceiling->repeat ? ceiling->size_m.y()
                      : std::min(ceiling->size_m.y(), texture.rows * ceiling->metres_per_texel);
  for (int row = 0; row < rows; ++row) {
    float* out = map.intensity.ptr<float>(row);
    for (int col = 0; col < cols; ++col) {
      const Eigen::Vector3d world(region.min.x() + (col + 0.5) * config.metres_per_pixel,
                                  region.min.y() + (row + 0.5) * config.metres_per_pixel,
                                  origin.z());
      const double u = axis_u.dot(world - origin);
      const double v = axis_v.dot(world - origin);
      if (u < 0.0 || v < 0.0 || u > extent_u || v > extent_v) {
        out[col] = static_cast<float>(scene.background_intensity);
      } else {
        out[col] = sampleWrapped(texture, u * inv_mpt, v * inv_mpt);
      }
    }
  }
  cv::Mat grey;
  map.intensity.convertTo(grey, CV_8U, 255.0);
  cv::Canny(grey, map.edges, config.canny_low, config.canny_high, 3, true);
  return map;
}

Scene makeLinesCeilingScene(const FloorRegion& region, double metres_per_texel,
                            LinesAndCirclesConfig lines, double ceiling_height_m) {
  if (!(metres_per_texel > 0.0)) {
    throw std::invalid_argument("makeLinesCeilingScene: metres_per_texel must be positive");
  }
  if (!(region.max.x() > region.min.x() && region.max.y() > region.min.y())) {
    throw std::invalid_argument("makeLinesCeilingScene: empty region");
  }
  const LinesAndCirclesConfig defaults;
  const double default_area = static_cast<double>(defaults.width_px) * defaults.height_px;
  lines.width_px =
      static_cast<int>(std::ceil((region.max.x() - region.min.x()) / metres_per_texel));
  lines.height_px =
      static_cast<int>(std::ceil((region.max.y() - region.min.y()) / metres_per_texel));
  const double area_ratio = static_cast<double>(lines.width_px) * lines.height_px / default_area;
  lines.line_count = static_cast<int>(std::lround(lines.line_count * area_ratio));
  lines.circle_count = static_cast<int>(std::lround(lines.circle_count * area_ratio));
  return makeCeilingScene(makeLinesAndCirclesTexture(lines), region, metres_per_texel,
                          ceiling_height_m);
}

}  // namespace ebslam
