#pragma once
// Parameters of the Exploration nodelet.

#include <ros/node_handle.h>

#include <ebslam/events/pose.h>
#include <ebslam/slam/coverage.h>
#include <ebslam/slam/exploration.h>

#include <optional>
#include <string>

namespace ebslam_ros {

/// The Exploration nodelet (thesis 7.4): the explorer's parameters under their core names
/// (ebslam::ExplorationConfig, units in its comments: ~hex_spacing [m], ~grid_extent [m],
/// ~robot_radius [m], ~bump_cone_depth [m], ~bump_cone_half_angle [rad], ~weight_z, ~weight_e,
/// ~alpha, ~planner_max_nodes, ~planner_time_budget [s], ~near_blocked_cost, ~oscillation_window,
/// ~oscillation_max_cells, ~commit_min_cells, ~escape_blocked_cost,
/// ~min_path_cells, ~max_path_cells, ~waypoint_tolerance [m], ~lookahead [m], ~turn_in_place
/// [rad], ~heading_gain [1/s], ~max_speed [m/s], ~max_turn_rate [rad/s], ~backout_time [s],
/// ~backout_speed [m/s], ~max_bumps_in_a_row, ~pose_timeout [s], ~pose_jump [m],
/// ~pose_jump_rad [rad]), the coverage planner's under ~coverage/ (ebslam::CoverageConfig:
/// ~coverage/cell [m], ~coverage/grid_extent [m], ~coverage/robot_radius [m],
/// ~coverage/lane_spacing [m], ~coverage/lane_direction [rad], ~coverage/contact_block_radius [m],
/// ~coverage/wall_half_length [m], ~coverage/wall_depth [m], ~coverage/clearance_cost,
/// ~coverage/clearance_cells, ~coverage/max_speed [m/s], ~coverage/max_turn_rate [rad/s],
/// ~coverage/heading_gain [1/s], ~coverage/turn_in_place [rad], ~coverage/lookahead [m],
/// ~coverage/waypoint_tolerance [m], ~coverage/backout_time [s], ~coverage/backout_speed [m/s],
/// ~coverage/side_bump_skip [m], ~coverage/repeat_bumps, ~coverage/repeat_bump_radius [m],
/// ~coverage/repeat_bump_window [s], ~coverage/max_bumps_per_goal, ~coverage/progress [m],
/// ~coverage/progress_timeout [s], ~coverage/pose_timeout [s], ~coverage/return_to_start,
/// ~coverage/start_tolerance [m]) and the node's own.
struct ExplorationNodeConfig {
  /// ~planner: "gain" (thesis 7.4's information-gain planner, ebslam::Explorer) or "coverage"
  /// (boustrophedon lanes on a grid learned from bumps, ebslam::CoverageExplorer).
  bool coverage_planner = false;
  ebslam::ExplorationConfig exploration;
  ebslam::CoverageConfig coverage;
  double control_rate_hz = 20.0;  ///< ~control_rate: control steps and cmd_vel per second [Hz]
  std::string map_frame = "map";  ///< ~map_frame: frame of pose, Z map, plan and markers
  /// ~use_localisation_map: subscribe EB-SLAM's normalisation map (`map/normalisation`) for Z;
  /// false: Z stays 0 (only E and the bumps guide the robot).
  bool use_localisation_map = true;
  double markers_period_s = 1.0;  ///< ~markers_period: grid_markers while subscribed [s]
  /// ~initial_pose [x [m], y [m], yaw [rad]] in ~map_frame: the localisation's start pose (e.g.
  /// EventSlam2d's ~initial_pose), used from the first control step until the first `pose`
  /// arrives, as ebslam_explore starts from EB-SLAM's estimate before any event. Unset: the
  /// explorer stands still until the first pose.
  std::optional<ebslam::Pose2> initial_pose;
};
ExplorationNodeConfig loadExplorationNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
