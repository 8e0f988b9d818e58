#include "ebslam/slam/ceiling_camera.h"

#include "ebslam/slam/undistortion_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

CeilingCamera::CeilingCamera(const CameraModel& camera, double ceiling_distance_m)
    : camera_(camera), ceiling_distance_m_(ceiling_distance_m) {
  camera_.validate();
  if (!(ceiling_distance_m > 0.0) || !std::isfinite(ceiling_distance_m)) {
    throw std::invalid_argument("CeilingCamera: ceiling distance must be positive and finite");
  }
  const UndistortionTable table(camera_);  // throws for a pixel without a ray
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  offset_x_.resize(n);
  offset_y_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // The ray (x, y, 1) scaled to z = D.
    const Eigen::Vector2d p = table.normalised(i).cast<double>() * ceiling_distance_m;
    offset_x_[i] = static_cast<float>(p.x());
    offset_y_[i] = static_cast<float>(p.y());
    footprint_radius_m_ = std::max(footprint_radius_m_, p.norm());
  }
}

Eigen::Vector2d CeilingCamera::project(const Eigen::Vector2d& p) const {
  // eq. 6.1 at z = D, then eq. 6.3 (or the camera's lens).
  const std::optional<Eigen::Vector2d> pixel =
      camera_.project(Eigen::Vector3d(p.x(), p.y(), ceiling_distance_m_));
  return *pixel;  // z = D > 0: always projects
}

}  // namespace ebslam
