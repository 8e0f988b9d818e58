#pragma once

// Per-pixel undistortion of an event camera, built once: every event is a pixel index, so the
// cores look its viewing ray up instead of inverting the lens per event.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "ebslam/slam/camera_model.h"

namespace ebslam {

/// The undistorted viewing ray through the centre of each pixel of a CameraModel, as normalised
/// image coordinates (x / z, y / z) in the camera frame (x right, y down, z along the optical
/// axis), so the ray is (x, y, 1). Immutable after construction; building costs one lens
/// inversion per pixel (about 1 ms per 100k pixels).
class UndistortionTable {
 public:
  /// Throws std::invalid_argument if the camera is invalid (CameraModel::validate) or a pixel
  /// of the sensor cannot be undistorted.
  explicit UndistortionTable(const CameraModel& camera);

  const CameraModel& camera() const { return camera_; }
  int width() const { return camera_.width; }
  int height() const { return camera_.height; }
  /// Normalised coordinates of pixel index y * width + x.
  const Eigen::Vector2f& normalised(std::size_t index) const { return rays_[index]; }
  /// Normalised coordinates of pixel (x, y); x in [0, width), y in [0, height) (not checked).
  const Eigen::Vector2f& normalised(int x, int y) const {
    return rays_[static_cast<std::size_t>(y) * camera_.width + x];
  }
  /// The ray (x, y, 1) through pixel (x, y) in double precision (not checked).
  Eigen::Vector3d ray(int x, int y) const {
    const Eigen::Vector2f& n = normalised(x, y);
    return {n.x(), n.y(), 1.0};
  }
  /// Largest distance of a pixel's ray from the optical axis at z = 1 [-].
  double maxRadius() const { return max_radius_; }

 private:
  CameraModel camera_;
  std::vector<Eigen::Vector2f> rays_;
  double max_radius_ = 0.0;
};

}  // namespace ebslam
