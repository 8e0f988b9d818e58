#pragma once

// Path following shared by the floor robot's explorers (exploration.cpp, coverage.cpp): progress
// along a list of waypoints and a pure-pursuit heading controller. Internal to ebslam::slam.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Core>

#include "ebslam/events/pose.h"
#include "ebslam/slam/floor_robot.h"

namespace ebslam::path_following {

/// The nearest, by distance(j) [m], of the waypoints next .. next + window - 1 of the count there
/// are (next itself when next >= count): steering at a look-ahead point passes waypoints
/// without touching them, so progress skips to the nearest of the next few.
template <class Distance>
std::size_t nearestAhead(std::size_t next, std::size_t count, std::size_t window,
                         const Distance& distance) {
  if (next >= count) return next;
  std::size_t nearest = next;
  const std::size_t last = std::min(count, next + window);
  for (std::size_t j = next + 1; j < last; ++j) {
    if (distance(j) < distance(nearest)) nearest = j;
  }
  return nearest;
}

/// The farthest waypoint from next on (of count) whose distance(j) [m] is within lookahead_m;
/// next itself when the following one is already farther. Requires next < count.
template <class Distance>
std::size_t lookaheadTarget(std::size_t next, std::size_t count, double lookahead_m,
                            const Distance& distance) {
  std::size_t target = next;
  for (std::size_t j = next + 1; j < count; ++j) {
    if (distance(j) > lookahead_m) break;
    target = j;
  }
  return target;
}

/// Turns towards target (map frame [m]) at heading_gain x the heading error, clamped to
/// +-max_turn_rate_rps; drives at max_speed_mps x cos(error) once the error is below
/// turn_in_place_rad, else turns in place.
inline VelocityCommand steerTowards(const Pose2& pose, const Eigen::Vector2d& target,
                                    double heading_gain, double max_turn_rate_rps,
                                    double turn_in_place_rad, double max_speed_mps) {
  const Eigen::Vector2d to_target = target - Eigen::Vector2d(pose.x, pose.y);
  const double error = wrapAngle(std::atan2(to_target.y(), to_target.x()) - pose.theta);
  VelocityCommand command;
  command.omega_rps = std::clamp(heading_gain * error, -max_turn_rate_rps, max_turn_rate_rps);
  if (std::abs(error) < turn_in_place_rad) command.v_mps = max_speed_mps * std::cos(error);
  return command;
}

}  // namespace ebslam::path_following
