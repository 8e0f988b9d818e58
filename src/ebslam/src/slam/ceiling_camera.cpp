#include "ebslam/slam/ceiling_camera.h"

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
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  offset_x_.resize(n);
  offset_y_.resize(n);
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const std::optional<Eigen::Vector3d> ray = camera_.backprojectRay(Eigen::Vector2d(x, y));
      if (!ray) {
        throw std::invalid_argument("CeilingCamera: pixel (" + std::to_string(x) + ", " +
                                    std::to_string(y) + ") cannot be undistorted");
      }
      const Eigen::Vector2d p = ray->head<2>() * ceiling_distance_m;  // ray scaled to z = D
      const std::size_t i = static_cast<std::size_t>(y) * camera.width + x;
      offset_x_[i] = static_cast<float>(p.x());
      offset_y_[i] = static_cast<float>(p.y());
      footprint_radius_m_ = std::max(footprint_radius_m_, p.norm());
    }
  }
}

Eigen::Vector2d CeilingCamera::project(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d undistorted = camera_.principal_point + p / wTrig();  // eq. 6.1, z = D
  return camera_.distort(undistorted);                                        // eq. 6.3
}

}  // namespace ebslam
