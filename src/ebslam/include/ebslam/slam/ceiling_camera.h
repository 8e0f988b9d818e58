#pragma once

// Upward-looking event camera under a flat ceiling (thesis 6.5.1): precomputed per-pixel
// ceiling offsets, so that mapping an event into the world is one rotation and translation.
//
// Frames (as in simulator_scenes.h): the camera frame has x along pixel columns, y along pixel
// rows and z along the optical axis, which points straight up to the ceiling at distance D. A
// planar pose p = (x, y, theta) places the camera in the world (map) frame as
// T_p(v) = (x, y, 0) + R_z(theta) v (eq. 6.33), so a ceiling point is handled by its 2D
// coordinates on the ceiling plane [m].

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "ebslam/slam/camera_model.h"

namespace ebslam {

class CeilingCamera {
 public:
  /// Throws std::invalid_argument for an invalid camera (CameraModel::validate), a
  /// non-positive or non-finite ceiling distance, or a pixel that cannot be undistorted.
  explicit CeilingCamera(const CameraModel& camera, double ceiling_distance_m = 2.59);

  const CameraModel& camera() const { return camera_; }
  double ceilingDistance() const { return ceiling_distance_m_; }
  int width() const { return camera_.width; }
  int height() const { return camera_.height; }
  /// W_trig = D / f: one pixel back-projected onto the ceiling [m] (eq. 6.5).
  double wTrig() const { return ceiling_distance_m_ / camera_.focal_px; }

  /// Ceiling offsets in the camera frame [m] of pixel index y * width + x: the undistorted ray
  /// through the pixel centre intersected with the ceiling (eq. 6.32-6.35 at lambda = D / f).
  const std::vector<float>& offsetX() const { return offset_x_; }
  const std::vector<float>& offsetY() const { return offset_y_; }
  /// Distorted pixel position of a ceiling point given in the camera frame [m] (eq. 6.1, 6.3);
  /// may lie outside the sensor (see inside()).
  Eigen::Vector2d project(const Eigen::Vector2d& ceiling_point_cam) const;
  bool inside(const Eigen::Vector2d& pixel) const { return camera_.isInside(pixel); }
  /// Largest distance of a ceiling point seen by the sensor from the optical axis [m].
  double footprintRadius() const { return footprint_radius_m_; }

 private:
  CameraModel camera_;
  double ceiling_distance_m_;
  std::vector<float> offset_x_;
  std::vector<float> offset_y_;
  double footprint_radius_m_ = 0.0;
};

}  // namespace ebslam
