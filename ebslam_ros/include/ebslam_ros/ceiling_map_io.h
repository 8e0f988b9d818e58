#pragma once
// Ceiling maps on disk (ROS-free): the known edge map EB-PF localises on and the map EB-SLAM
// saves. Reads map_server's yaml layout and ebslam_simulate_events --map's; the result is in the
// core's convention (makeEdgeLikelihoodMap): pixel (c, r) has its centre at origin_centre_m +
// (c, r) * resolution_m. Layouts: docs/ros_nodes_notes.md#ceiling-maps

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>

namespace ebslam_ros {

struct CeilingEdgeMap {
  cv::Mat edges;  ///< CV_8UC1, 255 on edges, rows growing with map y
  double resolution_m = 0.0;
  Eigen::Vector2d origin_centre_m{0.0, 0.0};  ///< map (x, y) of the centre of pixel (0, 0)
};

/// Throws std::runtime_error naming the file and the reason (missing file or key, unreadable
/// or wrongly formatted image, non-zero yaw, no edge pixel).
CeilingEdgeMap loadCeilingMap(const std::string& yaml_path);

/// Writes `image` (CV_8UC1, row r = map y origin + r res, i.e. the core's orientation) as
/// <prefix>.png flipped to map_server's orientation and <prefix>.yaml in map_server's layout;
/// `origin_corner_m` is the map (x, y) of the corner of cell (0, 0). Throws std::runtime_error.
void saveMapServerMap(const std::string& prefix, const cv::Mat& image, double resolution_m,
                      const Eigen::Vector2d& origin_corner_m);

}  // namespace ebslam_ros
