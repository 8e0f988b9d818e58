#include "ebslam/slam/camera_model.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Radial distortion factor of eq. 6.3 at undistorted radius r [pixels].
double distortionFactor(const CameraModel& camera, double r) {
  return 1.0 + camera.kappa1 * r + camera.kappa2 * r * r;
}

// Largest distance of a sensor corner from the principal point [pixels].
double maxSensorRadius(const CameraModel& camera) {
  const double dx = std::max(std::abs(-0.5 - camera.principal_point.x()),
                             std::abs(camera.width - 0.5 - camera.principal_point.x()));
  const double dy = std::max(std::abs(-0.5 - camera.principal_point.y()),
                             std::abs(camera.height - 0.5 - camera.principal_point.y()));
  return std::hypot(dx, dy);
}

}  // namespace

double CameraModel::focalFromOpeningAngle(double alpha_fov_rad, int sensor_size) {
  if (!(alpha_fov_rad > 0.0 && alpha_fov_rad < kPi)) {
    throw std::invalid_argument("focalFromOpeningAngle: opening angle must lie in (0, pi) rad");
  }
  if (sensor_size <= 0) {
    throw std::invalid_argument("focalFromOpeningAngle: sensor size must be positive");
  }
  return sensor_size / std::tan(0.5 * alpha_fov_rad);
}

void CameraModel::validate() const {
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535) {
    throw std::invalid_argument("CameraModel: width and height must lie in [1, 65535] pixels");
  }
  if (!(std::isfinite(focal_px) && focal_px > 0.0)) {
    throw std::invalid_argument("CameraModel: focal_px must be positive and finite");
  }
  if (!principal_point.allFinite() || !std::isfinite(kappa1) || !std::isfinite(kappa2)) {
    throw std::invalid_argument("CameraModel: principal point and distortion must be finite");
  }
  // r L(r) = r (1 + k1 r + k2 r^2) must increase over the radii in use, otherwise its inverse
  // is ambiguous: d (r L(r)) / dr = 1 + 2 k1 r + 3 k2 r^2 > 0 on a fine grid. Radii in use:
  // eq. 6.3 maps undistorted radii until the image reaches the sensor corner; eq. 8.3 maps the
  // sensor's own (distorted) radii.
  const double sensor_radius = maxSensorRadius(*this);
  const double r_max = 2.0 * sensor_radius;
  for (int i = 0; i <= 1000; ++i) {
    const double r = r_max * i / 1000.0;
    if (1.0 + 2.0 * kappa1 * r + 3.0 * kappa2 * r * r <= 0.0) {
      throw std::invalid_argument(
          "CameraModel: radial distortion (kappa1, kappa2) is not monotonic inside the sensor");
    }
    if (distortion_model == DistortionModel::kDivideEq81) {
      // r / L(r) must increase with r (derivative (1 - k2 r^2) / L^2) with L > 0.
      if (distortionFactor(*this, r) <= 0.0 || 1.0 - kappa2 * r * r <= 0.0) {
        throw std::invalid_argument(
            "CameraModel: eq. 8.1 distortion (kappa1, kappa2) is not monotonic inside the sensor");
      }
      if (r / distortionFactor(*this, r) >= sensor_radius) break;
      continue;
    }
    const double covered =
        distortion_model == DistortionModel::kDistortEq63 ? r * distortionFactor(*this, r) : r;
    if (covered >= sensor_radius) break;
  }
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p_camera) const {
  if (!(p_camera.z() > 0.0) || !p_camera.allFinite()) {
    return std::nullopt;
  }
  const Eigen::Vector2d undistorted =
      principal_point + focal_px * p_camera.head<2>() / p_camera.z();  // eq. 6.1
  return distort(undistorted);
}

namespace {

// Solves r L(r) = target for r >= 0 by Newton's method from r = target; std::nullopt outside
// the monotonic range of r L(r).
std::optional<double> invertRadius(const CameraModel& camera, double target) {
  if (target == 0.0 || (camera.kappa1 == 0.0 && camera.kappa2 == 0.0)) return target;
  double r = target;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double g = r * distortionFactor(camera, r) - target;
    const double dg = 1.0 + 2.0 * camera.kappa1 * r + 3.0 * camera.kappa2 * r * r;
    if (dg <= 0.0) return std::nullopt;
    const double step = g / dg;
    r -= step;
    if (r < 0.0) return std::nullopt;
    if (std::abs(step) < 1e-12 * (1.0 + target)) break;
  }
  if (std::abs(r * distortionFactor(camera, r) - target) > 1e-9 * (1.0 + target)) {
    return std::nullopt;
  }
  return r;
}

}  // namespace

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& undistorted_px) const {
  const Eigen::Vector2d d = undistorted_px - principal_point;
  const double r = d.norm();
  if (distortion_model == DistortionModel::kDistortEq63) {
    return principal_point + d * distortionFactor(*this, r);  // eq. 6.3
  }
  if (distortion_model == DistortionModel::kDivideEq81) {
    const double factor = distortionFactor(*this, r);
    if (!(factor > 0.0)) return undistorted_px;
    return principal_point + d / factor;  // eq. 8.1
  }
  const std::optional<double> rd = invertRadius(*this, r);  // inverse of eq. 8.3
  if (!rd || r == 0.0) return undistorted_px;
  return principal_point + d * (*rd / r);
}

std::optional<Eigen::Vector2d> CameraModel::undistort(const Eigen::Vector2d& distorted_px) const {
  const Eigen::Vector2d d = distorted_px - principal_point;
  const double rd = d.norm();
  if (distortion_model == DistortionModel::kUndistortEq83) {
    return principal_point + d * distortionFactor(*this, rd);  // eq. 8.3
  }
  if (distortion_model == DistortionModel::kDivideEq81) {
    // Inverse of eq. 8.1: r_d (1 + k1 r + k2 r^2) = r, the root continuous with r = r_d at 0,
    // r = 2 r_d / ((1 - k1 r_d) + sqrt((1 - k1 r_d)^2 - 4 k2 r_d^2)).
    if (rd == 0.0) return distorted_px;
    const double a = 1.0 - kappa1 * rd;
    const double discriminant = a * a - 4.0 * kappa2 * rd * rd;
    if (discriminant < 0.0 || a + std::sqrt(discriminant) <= 0.0) return std::nullopt;
    const double r = 2.0 * rd / (a + std::sqrt(discriminant));
    if (!(r > 0.0) || 1.0 - kappa2 * r * r <= 0.0) return std::nullopt;
    return principal_point + d * (r / rd);
  }
  const std::optional<double> r = invertRadius(*this, rd);  // inverse of eq. 6.3
  if (!r) return std::nullopt;
  if (rd == 0.0) return distorted_px;
  return principal_point + d * (*r / rd);
}

std::optional<Eigen::Vector3d> CameraModel::backprojectRay(const Eigen::Vector2d& pixel) const {
  const std::optional<Eigen::Vector2d> undistorted = undistort(pixel);
  if (!undistorted) {
    return std::nullopt;
  }
  const Eigen::Vector2d xy = (*undistorted - principal_point) / focal_px;
  return Eigen::Vector3d(xy.x(), xy.y(), 1.0);
}

}  // namespace ebslam
