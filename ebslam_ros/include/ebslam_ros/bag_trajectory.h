#pragma once
// Pose topics recorded in a bag -> TUM trajectories, so that ebslam_evaluate_trajectory scores
// what the nodes published (tool: ebslam_ros bag_to_tum).

#include <ebslam/events/trajectory.h>

#include <cstddef>
#include <string>

namespace ebslam_ros {

struct BagTrajectory {
  ebslam::Trajectory trajectory;  ///< poses by header.stamp [s], strictly increasing
  std::string frame_id;           ///< header.frame_id of the first pose
  std::size_t messages = 0;       ///< pose messages on the topic
  std::size_t dropped = 0;        ///< poses dropped: stamp not after its predecessor's
};

/// Reads geometry_msgs/PoseStamped, PoseWithCovarianceStamped, nav_msgs/Odometry or
/// TransformStamped messages of `topic` in bag order, keyed by header.stamp. A pose whose stamp
/// is not after the previous kept one is dropped and counted (a filter restart, a bag loop).
/// Throws std::runtime_error for an unreadable bag, a topic that is not in the bag, an
/// unsupported type, or messages in different frames.
BagTrajectory readBagTrajectory(const std::string& bag_path, const std::string& topic);

}  // namespace ebslam_ros
