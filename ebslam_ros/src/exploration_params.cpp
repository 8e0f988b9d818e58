#include "exploration_params.h"

#include <array>
#include <string>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

ExplorationNodeConfig loadExplorationNodeConfig(const ros::NodeHandle& nh) {
  ExplorationNodeConfig c;
  ebslam::ExplorationConfig& e = c.exploration;
  e.hex_spacing_m = param<double>(nh, "hex_spacing", e.hex_spacing_m);
  e.grid_extent_m = param<double>(nh, "grid_extent", e.grid_extent_m);
  e.robot_radius_m = param<double>(nh, "robot_radius", e.robot_radius_m);
  e.bump_cone_depth_m = param<double>(nh, "bump_cone_depth", e.bump_cone_depth_m);
  e.bump_cone_half_angle_rad =
      param<double>(nh, "bump_cone_half_angle", e.bump_cone_half_angle_rad);
  e.weight_z = param<double>(nh, "weight_z", e.weight_z);
  e.weight_e = param<double>(nh, "weight_e", e.weight_e);
  e.alpha = param<double>(nh, "alpha", e.alpha);
  e.planner_max_nodes = param<int>(nh, "planner_max_nodes", e.planner_max_nodes);
  e.planner_time_budget_s = param<double>(nh, "planner_time_budget", e.planner_time_budget_s);
  e.near_blocked_cost = param<double>(nh, "near_blocked_cost", e.near_blocked_cost);
  e.oscillation_window = param<int>(nh, "oscillation_window", e.oscillation_window);
  e.oscillation_max_cells = param<int>(nh, "oscillation_max_cells", e.oscillation_max_cells);
  e.commit_min_cells = param<int>(nh, "commit_min_cells", e.commit_min_cells);
  e.escape_blocked_cost = param<double>(nh, "escape_blocked_cost", e.escape_blocked_cost);
  e.min_path_cells = param<int>(nh, "min_path_cells", e.min_path_cells);
  e.max_path_cells = param<int>(nh, "max_path_cells", e.max_path_cells);
  e.waypoint_tolerance_m = param<double>(nh, "waypoint_tolerance", e.waypoint_tolerance_m);
  e.lookahead_m = param<double>(nh, "lookahead", e.lookahead_m);
  e.turn_in_place_rad = param<double>(nh, "turn_in_place", e.turn_in_place_rad);
  e.heading_gain = param<double>(nh, "heading_gain", e.heading_gain);
  e.max_speed_mps = param<double>(nh, "max_speed", e.max_speed_mps);
  e.max_turn_rate_rps = param<double>(nh, "max_turn_rate", e.max_turn_rate_rps);
  e.backout_time_s = param<double>(nh, "backout_time", e.backout_time_s);
  e.backout_speed_mps = param<double>(nh, "backout_speed", e.backout_speed_mps);
  e.max_bumps_in_a_row = param<int>(nh, "max_bumps_in_a_row", e.max_bumps_in_a_row);
  e.pose_timeout_s = param<double>(nh, "pose_timeout", e.pose_timeout_s);
  e.pose_jump_m = param<double>(nh, "pose_jump", e.pose_jump_m);
  e.pose_jump_rad = param<double>(nh, "pose_jump_rad", e.pose_jump_rad);
  validateCore(nh, e);
  const std::string planner = param<std::string>(nh, "planner", "gain");
  if (planner != "gain" && planner != "coverage") {
    fail(nh, "planner", "must be gain or coverage, not '" + planner + "'");
  }
  c.coverage_planner = planner == "coverage";
  ebslam::CoverageConfig& v = c.coverage;
  const auto real = [&](const char* name, double& value) {
    value = param<double>(nh, std::string("coverage/") + name, value);
  };
  const auto integer = [&](const char* name, int& value) {
    value = param<int>(nh, std::string("coverage/") + name, value);
  };
  real("cell", v.cell_m);
  real("grid_extent", v.grid_extent_m);
  real("robot_radius", v.robot_radius_m);
  real("lane_spacing", v.lane_spacing_m);
  real("lane_direction", v.lane_direction_rad);
  real("contact_block_radius", v.contact_block_radius_m);
  real("wall_half_length", v.wall_half_length_m);
  real("wall_depth", v.wall_depth_m);
  real("clearance_cost", v.clearance_cost);
  integer("clearance_cells", v.clearance_cells);
  real("max_speed", v.max_speed_mps);
  real("max_turn_rate", v.max_turn_rate_rps);
  real("heading_gain", v.heading_gain);
  real("turn_in_place", v.turn_in_place_rad);
  real("lookahead", v.lookahead_m);
  real("waypoint_tolerance", v.waypoint_tolerance_m);
  real("backout_time", v.backout_time_s);
  real("backout_speed", v.backout_speed_mps);
  real("side_bump_skip", v.side_bump_skip_m);
  integer("repeat_bumps", v.repeat_bumps);
  real("repeat_bump_radius", v.repeat_bump_radius_m);
  real("repeat_bump_window", v.repeat_bump_window_s);
  real("escape_turn_rate", v.escape_turn_rate_rps);
  real("escape_forward", v.escape_forward_m);
  integer("max_bumps_per_goal", v.max_bumps_per_goal);
  real("progress", v.progress_m);
  real("progress_timeout", v.progress_timeout_s);
  real("pose_timeout", v.pose_timeout_s);
  v.return_to_start = param<bool>(nh, "coverage/return_to_start", v.return_to_start);
  real("start_tolerance", v.start_tolerance_m);
  validateCore(nh, v);
  c.control_rate_hz = param<double>(nh, "control_rate", c.control_rate_hz);
  requirePositive(c.control_rate_hz, nh, "control_rate");
  if (c.control_rate_hz > 1000.0) fail(nh, "control_rate", "must be at most 1000 Hz");
  c.map_frame = param<std::string>(nh, "map_frame", c.map_frame);
  requireFrame(nh, "map_frame", c.map_frame);
  c.use_localisation_map = param<bool>(nh, "use_localisation_map", c.use_localisation_map);
  c.markers_period_s = param<double>(nh, "markers_period", c.markers_period_s);
  requirePositive(c.markers_period_s, nh, "markers_period");
  if (nh.hasParam("initial_pose")) {
    const std::array<double, 3> start = triple(nh, "initial_pose", {0.0, 0.0, 0.0});
    c.initial_pose = ebslam::Pose2{start[0], start[1], start[2]};
  } else {
    ebslam_ros_common::markParamRead(nh, "initial_pose");
  }
  return c;
}

}  // namespace ebslam_ros
