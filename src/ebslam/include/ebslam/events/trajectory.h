#pragma once

// Timestamped 6-DoF trajectories in the TUM RGB-D benchmark format, shared by the simulator,
// the filters and the evaluation.
//
// TUM format: one pose per line `timestamp tx ty tz qx qy qz qw`; timestamp in seconds,
// position in metres, orientation as a unit quaternion (x, y, z, w). The pose maps body
// coordinates into world coordinates: p_world = orientation * p_body + position.
// Lines starting with '#' and blank lines are ignored.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/pose.h"

namespace ebslam {

/// One pose of a body in the world frame (position: body origin in world [m], orientation: body ->
/// world) at a time.
struct StampedPose : Pose3 {
  double t_s = 0.0;  ///< timestamp [s]

  /// The pose of a rigid transform at time t_s (orientation normalised).
  static StampedPose fromIsometry(double t_s, const Eigen::Isometry3d& transform) {
    StampedPose stamped;
    stamped.t_s = t_s;
    stamped.position = transform.translation();
    stamped.orientation = Eigen::Quaterniond(transform.linear()).normalized();
    return stamped;
  }
};

/// Poses with strictly increasing timestamps.
using Trajectory = std::vector<StampedPose>;

/// How readTumTrajectory treats lines whose timestamp equals the previous one. The TUM
/// ground-truth files round times to 0.1 ms and contain a few such repeats
/// (freiburg2_pioneer_360 has 3).
enum class DuplicateTimestampPolicy {
  kKeepFirst,  ///< drop the later pose (default)
  kThrow,      ///< std::runtime_error like any other non-increasing time
};

/// Reads a TUM trajectory. Quaternions are normalised (a norm differing from 1 by more than
/// 0.01 is malformed). Throws std::runtime_error naming file:line for a line that does not
/// hold 8 finite numbers, a malformed quaternion, or a timestamp below the previous one, and
/// std::runtime_error if the file cannot be opened. An empty file gives an empty trajectory.
Trajectory readTumTrajectory(const std::string& path, DuplicateTimestampPolicy duplicates =
                                                          DuplicateTimestampPolicy::kKeepFirst);

/// Writes a TUM trajectory (timestamps with 9 decimals, positions/quaternions with 9).
/// Throws std::runtime_error on I/O failure, std::invalid_argument for non-finite values.
void writeTumTrajectory(const std::string& path, const Trajectory& trajectory);

/// Checks that times strictly increase and all values are finite with unit quaternions;
/// throws std::invalid_argument naming the first offending index (`what` names the trajectory).
void validateTrajectory(const Trajectory& trajectory, const std::string& what = "trajectory");

/// The pose at time t_s: linear interpolation of the position and slerp (shortest arc) of the
/// orientation between the two neighbouring poses. Exact at the stored timestamps.
/// Throws std::invalid_argument for an empty trajectory and std::out_of_range when t_s lies
/// outside [front().t_s, back().t_s]. O(log n).
StampedPose interpolatePose(const Trajectory& trajectory, double t_s);

}  // namespace ebslam
