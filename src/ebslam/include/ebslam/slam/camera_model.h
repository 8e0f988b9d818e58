#pragma once

// Camera model of an event camera: the eDVS' of the thesis (6.2.1, eq. 6.1-6.3) and the lenses of
// sensor_msgs/CameraInfo (plumb_bob, equidistant) for any sensor size.
//
// Frames and units: a point in the camera frame has x to the right, y down and z along the
// optical axis (metres). Pixel coordinates are continuous with the centre of pixel (x, y) at
// (x, y) (OpenCV convention), so an event's integer coordinates can be used directly and the
// sensor spans [-0.5, width - 0.5) x [-0.5, height - 0.5). The principal point of a centred
// 128 x 128 sensor is therefore (63.5, 63.5).

#include <array>
#include <optional>
#include <string>

#include <Eigen/Core>

namespace ebslam {

/// Which way the polynomial L(r) = 1 + kappa1 r + kappa2 r^2 of the thesis is applied. The
/// thesis states it both ways: eq. 6.3 distorts (e = c + (e_u - c) L(|e_u - c|)), eq. 8.1/8.3
/// undistort (e_u = c + (e - c) L(|e - c|), as in CeilingCamera). Same kappas, different lens.
enum class DistortionModel {
  kDistortEq63,    ///< L applied to the undistorted radius gives the distorted position
  kUndistortEq83,  ///< L applied to the distorted (event) radius gives the undistorted position
  /// Eq. 8.1 as printed (the D-eDVS' eDVS model): e = c + s / L(|s|) with s = e_u - c, the
  /// undistorted offset; closed form both ways (the inverse solves a quadratic in the radius).
  kDivideEq81,
  /// ROS/OpenCV "plumb_bob" (Brown-Conrady) on normalised coordinates (x, y) = (p_x, p_y) / p_z:
  /// lens_coefficients (k1, k2, p1, p2, k3), r^2 = x^2 + y^2,
  ///   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2), y_d likewise;
  /// e = c + (f x_d, f_y y_d). kappa1/kappa2 are unused.
  kPlumbBob,
  /// ROS "equidistant" = OpenCV fisheye: lens_coefficients (k1, k2, k3, k4), theta = atan(r),
  ///   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
  ///   (x_d, y_d) = (x, y) theta_d / r. kappa1/kappa2 are unused.
  kEquidistant,
};

/// Pinhole projection (eq. 6.1) followed by the two-parameter radial distortion of eq. 6.3:
///   e_u = c + f (p_x, p_y) / p_z                       (undistorted, eq. 6.1)
///   e   = c + (e_u - c) (1 + kappa1 r + kappa2 r^2),   r = |e_u - c| [pixels]   (eq. 6.3)
/// kappa1 < 0 is barrel distortion. Event coordinates are distorted coordinates. With
/// DistortionModel::kUndistortEq83 the polynomial maps the other way (eq. 8.3). kPlumbBob and
/// kEquidistant are the lenses of sensor_msgs/CameraInfo (conversions in ebslam_ros).
/// Non-square pixels: focal_y_px (f_y) scales the rows, focal_px (f_x) the columns.
struct CameraModel {
  int width = 128;   ///< sensor columns [pixels], S for the eDVS
  int height = 128;  ///< sensor rows [pixels]
  /// Focal length [pixels]. Default: the thesis' floor-robot setup (6.5.3) has one pixel
  /// covering W_trig = D / f = 0.03 m on a ceiling D = 2.59 m away (eq. 6.5), f = 2.59 / 0.03.
  double focal_px = 2.59 / 0.03;
  Eigen::Vector2d principal_point{63.5, 63.5};  ///< c [pixels], sensor centre by default
  double kappa1 = 0.0;  ///< linear radial distortion coefficient [1/pixel] (eq. 6.3)
  double kappa2 = 0.0;  ///< quadratic radial distortion coefficient [1/pixel^2] (eq. 6.3)
  DistortionModel distortion_model = DistortionModel::kDistortEq63;
  /// f_y [pixels] of non-square pixels; 0 = focal_px. Quantities that need one focal length
  /// (W_trig, splat sizes) use focal_px.
  double focal_y_px = 0.0;
  /// Coefficients of kPlumbBob (k1, k2, p1, p2, k3) and kEquidistant (k1, k2, k3, k4, unused).
  std::array<double, 5> lens_coefficients{};

  double fx() const { return focal_px; }
  double fy() const { return focal_y_px > 0.0 ? focal_y_px : focal_px; }
  /// True for the lenses of sensor_msgs/CameraInfo (kPlumbBob, kEquidistant).
  bool hasOpenCvLens() const {
    return distortion_model == DistortionModel::kPlumbBob ||
           distortion_model == DistortionModel::kEquidistant;
  }
  /// True if the lens maps a point without distortion and with square pixels (f_y = f_x).
  bool isSquarePinhole() const;

  /// The same lens on a sensor of width x height pixels with the same horizontal field of view:
  /// f_x, f_y and the principal point's offset from the sensor centre scale by width /
  /// this->width, the pixel-unit kappas by its inverse powers (normalised lens coefficients are
  /// unchanged). Throws std::invalid_argument for a size outside [1, 65535].
  CameraModel scaledTo(int new_width, int new_height) const;
  /// Event-sensor sizes by name, with `lens` scaled to them (scaledTo): "edvs128" (128 x 128),
  /// "davis240" (240 x 180), "davis346" (346 x 260), "vga" (640 x 480: DVXplorer, Prophesee
  /// Gen3), "hd720" (1280 x 720: Prophesee IMX636). Throws std::invalid_argument for another
  /// name (the message lists the names).
  static CameraModel preset(const std::string& name, const CameraModel& lens);
  /// preset(name, CameraModel{}): the thesis' floor-robot lens.
  static CameraModel preset(const std::string& name);

  /// Focal length from the full opening angle alpha_fov [rad] with eq. 6.2 as printed,
  /// f = S / tan(alpha_fov / 2). (The usual pinhole relation is (S / 2) / tan(alpha_fov / 2);
  /// the thesis' formula is kept so that thesis parameters reproduce.)
  /// Throws std::invalid_argument unless 0 < alpha_fov < pi and size > 0.
  static double focalFromOpeningAngle(double alpha_fov_rad, int sensor_size = 128);

  /// Throws std::invalid_argument with the reason if a parameter is invalid (non-positive size
  /// or focal length, non-finite values, or a distortion that is not monotonic inside the
  /// sensor so that it cannot be inverted).
  void validate() const;

  /// World distance one pixel covers at depth D [m] (eq. 6.5): W_trig = D / f.
  double triggerDistance(double depth_m) const { return depth_m / focal_px; }

  /// Distorted pixel coordinates of a camera-frame point (eq. 6.1 + 6.3). std::nullopt for
  /// points at or behind the projection centre (p_z <= 0). The result may lie outside the
  /// sensor; see isInside().
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_camera) const;

  /// Undistorted -> distorted pixel coordinates (eq. 6.3; Newton inverse of eq. 8.3; the
  /// CameraInfo lenses on ((u - c_x) / f_x, (v - c_y) / f_y)).
  /// Returns the input unchanged if no monotonic solution exists (far outside the sensor).
  Eigen::Vector2d distort(const Eigen::Vector2d& undistorted_px) const;
  /// Distorted -> undistorted pixel coordinates: inverse of eq. 6.3 by Newton iteration on the
  /// radius (eq. 8.3 directly); Newton iteration for the CameraInfo lenses. std::nullopt if the
  /// position is beyond the range where the lens can be inverted.
  std::optional<Eigen::Vector2d> undistort(const Eigen::Vector2d& distorted_px) const;

  /// Direction of the viewing ray through a (distorted) pixel position in the camera frame,
  /// scaled to z = 1: ((u - c_x) / f, (v - c_y) / f, 1) after undistortion (eq. 6.32 / f).
  /// std::nullopt if the pixel cannot be undistorted.
  std::optional<Eigen::Vector3d> backprojectRay(const Eigen::Vector2d& pixel) const;

  /// True if a continuous pixel position rounds to a pixel of the sensor.
  bool isInside(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width - 0.5 &&
           pixel.y() < height - 0.5;
  }
};

}  // namespace ebslam
