#include "ebslam/slam/camera_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

// The CameraInfo lenses on normalised coordinates (x, y) = (p_x, p_y) / p_z.
Eigen::Vector2d distortNormalised(const CameraModel& camera, const Eigen::Vector2d& n) {
  const auto& k = camera.lens_coefficients;
  const double x = n.x(), y = n.y();
  const double r2 = x * x + y * y;
  if (camera.distortion_model == DistortionModel::kEquidistant) {
    const double r = std::sqrt(r2);
    if (r == 0.0) return n;
    const double theta = std::atan(r);
    const double t2 = theta * theta;
    const double theta_d = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    return n * (theta_d / r);
  }
  const double radial = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
  return {x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x),
          y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y};
}

// Inverse of distortNormalised: Newton's method on theta (equidistant) or on (x, y) (plumb_bob)
// from the distorted position; std::nullopt without a converged solution in the lens' valid
// range (theta < pi / 2; plumb_bob's radial polynomial increasing).
std::optional<Eigen::Vector2d> undistortNormalised(const CameraModel& camera,
                                                   const Eigen::Vector2d& nd) {
  const auto& k = camera.lens_coefficients;
  if (!nd.allFinite()) return std::nullopt;
  if (camera.distortion_model == DistortionModel::kEquidistant) {
    const double theta_d = nd.norm();
    if (theta_d == 0.0) return nd;
    double theta = std::min(theta_d, 1.5);
    for (int iteration = 0; iteration < 50; ++iteration) {
      const double t2 = theta * theta;
      const double g =
          theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d;
      const double dg =
          1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
      if (!(dg > 0.0)) return std::nullopt;
      const double step = g / dg;
      theta -= step;
      if (!(theta > 0.0) || theta >= 0.5 * kPi) return std::nullopt;
      if (std::abs(step) < 1e-14) break;
    }
    const double t2 = theta * theta;
    if (std::abs(theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d) >
        1e-10 * (1.0 + theta_d)) {
      return std::nullopt;
    }
    return nd * (std::tan(theta) / theta_d);
  }
  Eigen::Vector2d n = nd;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double x = n.x(), y = n.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
    const double g = 2.0 * k[0] + r2 * (4.0 * k[1] + r2 * 6.0 * k[4]);  // d radial / d(r^2) * 2
    // Jacobian [[a, b], [b, d]] of the distortion (symmetric).
    const double a = radial + g * x * x + 2.0 * k[2] * y + 6.0 * k[3] * x;
    const double b = g * x * y + 2.0 * k[2] * x + 2.0 * k[3] * y;
    const double d = radial + g * y * y + 6.0 * k[2] * y + 2.0 * k[3] * x;
    const Eigen::Vector2d residual = distortNormalised(camera, n) - nd;
    const double det = a * d - b * b;
    if (!(det > 0.0)) return std::nullopt;
    const Eigen::Vector2d step((d * residual.x() - b * residual.y()) / det,
                               (a * residual.y() - b * residual.x()) / det);
    n -= step;
    if (!n.allFinite()) return std::nullopt;
    if (step.norm() < 1e-14 * (1.0 + n.norm())) break;
  }
  if ((distortNormalised(camera, n) - nd).norm() > 1e-10 * (1.0 + nd.norm())) return std::nullopt;
  // The radial polynomial r (1 + k1 r^2 + k2 r^4 + k3 r^6) must still increase at the solution,
  // otherwise it is the fold's far branch.
  const double r2 = n.squaredNorm();
  if (!(1.0 + r2 * (3.0 * k[0] + r2 * (5.0 * k[1] + r2 * 7.0 * k[4])) > 0.0)) return std::nullopt;
  return n;
}

}  // namespace

bool CameraModel::isSquarePinhole() const {
  if (fy() != focal_px) return false;
  if (hasOpenCvLens()) {
    return std::all_of(lens_coefficients.begin(), lens_coefficients.end(),
                       [](double c) { return c == 0.0; });
  }
  return kappa1 == 0.0 && kappa2 == 0.0;
}

CameraModel CameraModel::scaledTo(int new_width, int new_height) const {
  if (new_width <= 0 || new_height <= 0 || new_width > 65535 || new_height > 65535) {
    throw std::invalid_argument("CameraModel::scaledTo: width and height must lie in [1, 65535]");
  }
  const double s = static_cast<double>(new_width) / width;
  CameraModel out = *this;
  out.width = new_width;
  out.height = new_height;
  out.focal_px = focal_px * s;
  out.focal_y_px = focal_y_px * s;
  const Eigen::Vector2d old_centre(0.5 * (width - 1), 0.5 * (height - 1));
  const Eigen::Vector2d new_centre(0.5 * (new_width - 1), 0.5 * (new_height - 1));
  out.principal_point = new_centre + (principal_point - old_centre) * s;
  out.kappa1 = kappa1 / s;        // [1/pixel]
  out.kappa2 = kappa2 / (s * s);  // [1/pixel^2]
  return out;
}

CameraModel CameraModel::preset(const std::string& name, const CameraModel& lens) {
  static const std::pair<const char*, std::pair<int, int>> kPresets[] = {{"edvs128", {128, 128}},
                                                                         {"davis240", {240, 180}},
                                                                         {"davis346", {346, 260}},
                                                                         {"vga", {640, 480}},
                                                                         {"hd720", {1280, 720}}};
  std::string names;
  for (const auto& [preset_name, size] : kPresets) {
    if (name == preset_name) return lens.scaledTo(size.first, size.second);
    names += std::string(names.empty() ? "" : ", ") + preset_name;
  }
  throw std::invalid_argument("CameraModel::preset: unknown sensor '" + name +
                              "' (known: " + names + ")");
}

CameraModel CameraModel::preset(const std::string& name) { return preset(name, CameraModel{}); }

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
  if (!principal_point.allFinite() || !std::isfinite(kappa1) || !std::isfinite(kappa2) ||
      !std::all_of(lens_coefficients.begin(), lens_coefficients.end(),
                   [](double c) { return std::isfinite(c); })) {
    throw std::invalid_argument("CameraModel: principal point and distortion must be finite");
  }
  if (!(std::isfinite(focal_y_px) && focal_y_px >= 0.0)) {
    throw std::invalid_argument("CameraModel: focal_y_px must be positive (or 0 = focal_px)");
  }
  if (hasOpenCvLens()) {
    // Every pixel on the sensor's border must undistort (inside, the lens is monotonic
    // along each ray from the centre up to the border: checked by the Newton solution's
    // derivative test).
    for (int x = 0; x < width; ++x) {
      for (int y : {0, height - 1}) {
        if (!undistort(Eigen::Vector2d(x, y))) {
          throw std::invalid_argument(
              "CameraModel: the lens distortion cannot be inverted at pixel (" + std::to_string(x) +
              ", " + std::to_string(y) + ")");
        }
      }
    }
    for (int y = 0; y < height; ++y) {
      for (int x : {0, width - 1}) {
        if (!undistort(Eigen::Vector2d(x, y))) {
          throw std::invalid_argument(
              "CameraModel: the lens distortion cannot be inverted at pixel (" + std::to_string(x) +
              ", " + std::to_string(y) + ")");
        }
      }
    }
    return;
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
  const Eigen::Vector2d n = p_camera.head<2>() / p_camera.z();
  if (hasOpenCvLens()) {
    const Eigen::Vector2d nd = distortNormalised(*this, n);
    return Eigen::Vector2d(principal_point.x() + focal_px * nd.x(),
                           principal_point.y() + fy() * nd.y());
  }
  const Eigen::Vector2d undistorted(principal_point.x() + focal_px * n.x(),
                                    principal_point.y() + fy() * n.y());  // eq. 6.1
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
  if (hasOpenCvLens()) {
    const Eigen::Vector2d n((undistorted_px.x() - principal_point.x()) / focal_px,
                            (undistorted_px.y() - principal_point.y()) / fy());
    const Eigen::Vector2d nd = distortNormalised(*this, n);
    return {principal_point.x() + focal_px * nd.x(), principal_point.y() + fy() * nd.y()};
  }
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
  if (hasOpenCvLens()) {
    const Eigen::Vector2d nd((distorted_px.x() - principal_point.x()) / focal_px,
                             (distorted_px.y() - principal_point.y()) / fy());
    const std::optional<Eigen::Vector2d> n = undistortNormalised(*this, nd);
    if (!n) return std::nullopt;
    return Eigen::Vector2d(principal_point.x() + focal_px * n->x(),
                           principal_point.y() + fy() * n->y());
  }
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
  return Eigen::Vector3d((undistorted->x() - principal_point.x()) / focal_px,
                         (undistorted->y() - principal_point.y()) / fy(), 1.0);
}

}  // namespace ebslam
