#include "ebslam/slam/undistortion_table.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>

namespace ebslam {

UndistortionTable::UndistortionTable(const CameraModel& camera) : camera_(camera) {
  camera_.validate();
  rays_.resize(static_cast<std::size_t>(camera_.width) * camera_.height);
  for (int y = 0; y < camera_.height; ++y) {
    for (int x = 0; x < camera_.width; ++x) {
      const std::optional<Eigen::Vector3d> ray = camera_.backprojectRay(Eigen::Vector2d(x, y));
      if (!ray) {
        throw std::invalid_argument("UndistortionTable: pixel (" + std::to_string(x) + ", " +
                                    std::to_string(y) + ") cannot be undistorted");
      }
      rays_[static_cast<std::size_t>(y) * camera_.width + x] = ray->head<2>().cast<float>();
      max_radius_ = std::max(max_radius_, ray->head<2>().norm());
    }
  }
}

}  // namespace ebslam
