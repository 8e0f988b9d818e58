#pragma once

// Autonomous exploration with EB-SLAM (thesis 7.4): a floor robot with a bump ring explores an
// unknown room, localised only by EB-SLAM-2D. Hex-grid maps Z (eq. 7.7) and E and blocked cells,
// the information gain of eq. 7.8-7.10, a best-first search by gain per path length, replanning
// and a path-following controller. Frames: EB-SLAM's map frame (x, y [m], theta [rad]); the robot
// pose is the eDVS' planar pose (sensor at the robot's centre).
// Details: docs/ebslam_core.md#exploration

#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ebslam/slam/floor_robot.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam {

/// Hexagonal grid ("pointy-top" hexagons in odd-row offset layout): cell centres spaced by
/// `spacing_m` along rows, rows sqrt(3)/2 spacing apart, covering a square of side extent_m
/// centred on `centre`. A point belongs to the cell with the nearest centre.
class HexGrid {
 public:
  HexGrid() = default;
  /// Throws std::invalid_argument for a non-positive spacing or extent, or more than 4e6 cells.
  HexGrid(double spacing_m, const Eigen::Vector2d& centre, double extent_m);

  int size() const { return cols_ * rows_; }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  double spacing() const { return spacing_; }
  Eigen::Vector2d centre(int cell) const;
  /// Cell containing p; nullopt outside the grid.
  std::optional<int> cellAt(const Eigen::Vector2d& p) const;
  /// The six neighbours (-1 where the grid ends), counter-clockwise from +x.
  const std::array<int, 6>& neighbours(int cell) const { return neighbours_[cell]; }

 private:
  double spacing_ = 0.0;
  double row_height_ = 0.0;
  Eigen::Vector2d origin_{0.0, 0.0};  // centre of cell (0, 0)
  int cols_ = 0;
  int rows_ = 0;
  std::vector<std::array<int, 6>> neighbours_;
};

struct ExplorationConfig {
  double hex_spacing_m = 0.15;  ///< distance between neighbouring cell centres [m]
  double grid_extent_m = 12.0;  ///< side of the square grid centred on the start [m]
  /// Cells whose centre lies within this distance of the robot are covered (E += 1) [m]; the
  /// robot's radius.
  double robot_radius_m = 0.15;
  /// After a bump, the cells in a cone around the contact direction are blocked: centres within
  /// robot_radius_m + bump_cone_depth_m [m] and the half angle [rad].
  /// docs/ebslam_core.md#exploration
  double bump_cone_depth_m = 0.3;
  double bump_cone_half_angle_rad = 1.05;
  /// Gain (eq. 7.9, 7.10): weights and slope; the thesis' values.
  double weight_z = 1.0;
  double weight_e = 1.0;
  double alpha = 10.0;
  /// Best-first search budget: expanded cells and CPU time [s].
  int planner_max_nodes = 3000;
  double planner_time_budget_s = 0.005;
  /// Extra path cost [cells] of stepping onto a cell next to a blocked cell (its centre lies
  /// within about a robot radius of an obstacle): paths keep clear of obstacles where that is
  /// cheap, yet still pass a gap the body fits when the gain beyond it pays for the detour
  /// (0: no preference). A hard avoidance would trap the robot in a pocket whose mouth is narrow.
  double near_blocked_cost = 2.0;
  /// Oscillation: when the last oscillation_window cell changes of the robot visited at most
  /// oscillation_max_cells distinct cells, it is going round in a loop; it then commits to a
  /// plan of at least commit_min_cells cells that ends outside the loop and keeps it until
  /// driven (a bump still backs out and replans, committed). 0 cells: no detection.
  int oscillation_window = 30;
  int oscillation_max_cells = 7;
  int commit_min_cells = 8;
  /// Path cost [cells] of crossing a blocked cell when a committed plan cannot leave the loop
  /// otherwise: cone cells are guesses around a contact, so a robot walled in
  /// by its own cones tries the cheapest way past them (a real obstacle bumps it again).
  double escape_blocked_cost = 20.0;
  /// Paths shorter than this many cells are taken only if no longer one is found.
  int min_path_cells = 3;
  /// Longest path handed to the controller [cells] (replanned when done).
  int max_path_cells = 40;
  /// Controller: waypoint reached within this distance [m]; turn in place while the heading
  /// error exceeds turn_in_place_rad; omega = heading_gain * error.
  double waypoint_tolerance_m = 0.06;
  /// Pure-pursuit look-ahead [m]: the robot steers at the farthest upcoming path cell within it
  /// (0: cell by cell). docs/ebslam_core.md#exploration
  double lookahead_m = 0.2;
  double turn_in_place_rad = 0.8;
  double heading_gain = 2.5;
  double max_speed_mps = 0.3;
  /// Largest commanded turn rate [rad/s]: below the robot's 1.5, because EB-SLAM-2D lost the
  /// robot turning at 1.5 rad/s in place (office seed 5, 72 s); chosen on office and l_shape seed
  /// 1 (200 s: 1.0 covers as much as 1.5, 0.6-0.8 less). docs/results/exploration.md
  double max_turn_rate_rps = 1.0;
  /// After a bump: drive away from the contact for this long at this speed [s, m/s].
  double backout_time_s = 0.5;
  double backout_speed_mps = 0.1;
  /// Bumps in a row (each before the robot has left its cell) after which the robot is stuck.
  int max_bumps_in_a_row = 6;
  /// While EB-SLAM is lost: reverse straight at this speed [m/s] (forwards after a contact
  /// behind), no turning: in the simulated rooms turning in place while lost let the error
  /// grow to metres, driving straight let EB-SLAM re-localise; give up after
  /// relocalise_timeout_s [s] and explore on.
  double relocalise_speed_mps = 0.1;
  double relocalise_timeout_s = 20.0;
  /// No pose for this long [s]: stop and report it.
  double pose_timeout_s = 0.5;
  /// A pose farther than max_speed * dt + pose_jump_m [m] (or a turn beyond max_turn_rate * dt
  /// + pose_jump_rad) from the last one is a jump: the plan is dropped and made anew.
  double pose_jump_m = 0.25;
  double pose_jump_rad = 0.6;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// The exploration maps and the planner (no robot state; see Explorer).
class ExplorationPlanner {
 public:
  /// The grid is centred on `centre` (map frame). Throws std::invalid_argument for an invalid
  /// config.
  ExplorationPlanner(const ExplorationConfig& config, const Eigen::Vector2d& centre);

  const HexGrid& grid() const { return grid_; }
  const ExplorationConfig& config() const { return config_; }

  /// Obstacle exploration map: if `position` lies in another cell than at the last call, every
  /// cell whose centre is within robot_radius_m is incremented. Returns true then.
  bool addCoverage(const Eigen::Vector2d& position);
  /// Blocks the cells in the cone around the contact (pose.theta + direction_robot_rad),
  /// excluding the robot's own cell; remembers the contact point for display.
  void addBump(const Pose2& pose, double direction_robot_rad);
  /// Localisation exploration map: Z of each cell = mean of `normalisation` over the map cells
  /// whose centre lies in the hex cell (EB-SLAM's normalisation map, eq. 7.7).
  void updateLocalisationMap(const GridMap2f& normalisation);
  /// Normalises Z and E over the cells reachable from `robot_cell` (eq. 7.8) and computes the
  /// gain (eq. 7.9, 7.10); cells outside Omega get gain 0.
  void computeGain(int robot_cell);
  /// As computeGain, with Omega grown through blocked cells too (blocked cells get gain 0).
  void computeGain(int robot_cell, bool through_blocked);
  /// Best-first search from the robot's cell (computeGain first) by gain per path cost (one per
  /// cell plus near_blocked_cost next to blocked cells). Returns the cells of the path without
  /// the start cell; empty if the robot is outside the grid or no neighbour is open.
  std::vector<int> plan(const Eigen::Vector2d& position);
  /// A committed plan out of a loop: at least commit_min_cells cells (or the longest found),
  /// ending on a cell with loop_cells[cell] == 0; crosses blocked cells at escape_blocked_cost
  /// if nothing else leaves the loop. Empty if the robot is outside the grid.
  std::vector<int> planOutOf(const Eigen::Vector2d& position,
                             const std::vector<std::uint8_t>& loop_cells);

  const std::vector<float>& localisationMap() const { return z_; }
  const std::vector<float>& obstacleMap() const { return e_; }
  const std::vector<float>& gainMap() const { return gain_; }
  const std::vector<std::uint8_t>& blocked() const { return blocked_; }
  const std::vector<Eigen::Vector2d>& bumpPoints() const { return bump_points_; }
  /// Cells expanded by the last plan() and whether it stopped at its time budget.
  int lastExpandedNodes() const { return last_expanded_; }
  bool lastPlanHitTimeBudget() const { return last_hit_time_; }

 private:
  struct SearchGoal {
    int min_cells = 1;                                   // shorter paths only if nothing else
    const std::vector<std::uint8_t>* exclude = nullptr;  // cells a path may not end on
    bool cross_blocked = false;                          // blocked cells at escape_blocked_cost
  };
  std::vector<int> search(int start_cell, const SearchGoal& goal);
  void updateNearBlocked();

  ExplorationConfig config_;
  HexGrid grid_;
  std::vector<std::uint8_t> near_blocked_;  // cells next to a blocked cell (not blocked)
  bool near_blocked_stale_ = true;
  // Search scratch, kept to avoid allocations per plan.
  std::vector<std::uint8_t> closed_scratch_;
  std::vector<float> z_, e_, gain_;
  std::vector<std::uint8_t> blocked_;
  std::vector<Eigen::Vector2d> bump_points_;
  int last_cell_ = -1;
  // Map cell -> hex cell lookup for updateLocalisationMap, built for one map geometry.
  std::vector<std::int32_t> z_cell_of_;
  std::vector<float> z_cell_area_;
  int z_width_ = 0, z_height_ = 0;
  double z_res_ = 0.0, z_ox_ = 0.0, z_oy_ = 0.0;
  std::vector<int> reachable_;  // scratch
  std::vector<std::uint8_t> in_omega_;
  int last_expanded_ = 0;
  bool last_hit_time_ = false;
};

enum class ExplorationState {
  kExploring,   ///< following a planned path
  kBackingOut,  ///< moving away from a contact
  kNoPose,      ///< no pose for pose_timeout_s: stopped
  kStuck,       ///< bumped on every side, too many bumps in a row, or no path: stopped
  /// EB-SLAM lost track (setLocalisationLost): driving slowly straight back the way it came, over
  /// ceiling just mapped, without turning; the maps are not updated from the untrusted pose.
  kRelocalising,
};
const char* toString(ExplorationState state);

/// The exploring robot's brain: maps, planner, controller and the handling of bad input.
class Explorer {
 public:
  /// `start` (map frame) centres the grid. Throws std::invalid_argument for an invalid config.
  Explorer(const ExplorationConfig& config, const Eigen::Vector2d& start);

  /// One control step at time now_s [s]: the latest pose (nullopt if none arrived since the last
  /// step), the bump ring's reading and, if available, EB-SLAM's normalisation map. Returns the
  /// velocity command. Non-finite poses count as no pose.
  VelocityCommand update(double now_s, const std::optional<Pose2>& pose, const BumpReading& bump,
                         const GridMap2f* normalisation);

  /// The localisation's verdict (e.g. TrackingMonitor, ebslam2d_tracking.h) at time now_s [s]:
  /// while lost, update() turns in place (kRelocalising) and leaves the maps alone; when tracking
  /// returns it replans.
  void setLocalisationLost(bool lost, double now_s);

  ExplorationState state() const { return state_; }
  /// Why the robot is in its state (empty while exploring normally); for logs.
  const std::string& message() const { return message_; }
  /// The planned cells still to drive, and their centres.
  const std::vector<int>& path() const { return path_; }
  std::vector<Eigen::Vector2d> pathPoints() const;
  const ExplorationPlanner& planner() const { return planner_; }
  std::size_t replans() const { return replans_; }
  std::size_t bumps() const { return bumps_; }
  std::size_t poseJumps() const { return pose_jumps_; }
  /// Loops detected (see ExplorationConfig::oscillation_window) and whether the current plan is
  /// a committed one out of a loop.
  std::size_t loopsDetected() const { return loops_; }
  bool committed() const { return committed_; }

 private:
  /// Records a cell change of the robot; true when the recent cells form a loop.
  bool recordCell(int cell);
  void replan(double now_s, const Eigen::Vector2d& position, const GridMap2f* normalisation);
  VelocityCommand follow(const Pose2& pose);

  ExplorationConfig config_;
  ExplorationPlanner planner_;
  ExplorationState state_ = ExplorationState::kExploring;
  std::string message_;
  std::optional<Pose2> pose_;
  double pose_time_s_ = -1.0;
  double start_time_s_ = -1.0;
  bool need_plan_ = true;
  std::vector<int> path_;
  std::size_t next_waypoint_ = 0;
  double backout_until_s_ = 0.0;
  double backout_speed_ = 0.0;
  double retry_plan_at_s_ = 0.0;
  int bumps_in_a_row_ = 0;
  int bump_cell_ = -1;
  std::size_t replans_ = 0;
  std::size_t bumps_ = 0;
  std::size_t pose_jumps_ = 0;
  std::vector<int> recent_cells_;         // the last oscillation_window cell changes
  std::vector<std::uint8_t> loop_cells_;  // per grid cell: part of the detected loop
  bool committed_ = false;
  std::size_t loops_ = 0;
  bool lost_ = false;
  double lost_since_s_ = -1.0;
  double relocalise_direction_ = -1.0;  // -1 reversing, +1 forwards
  std::size_t relocalisations_ = 0;

 public:
  /// Times the explorer stopped to re-localise.
  std::size_t relocalisations() const { return relocalisations_; }
};

/// The random bump-and-turn baseline: drives straight; after a bump backs out and turns to a
/// random heading away from the contact. Needs no pose. Seeded.
class RandomBumpAndTurn {
 public:
  RandomBumpAndTurn(const ExplorationConfig& config, std::uint64_t seed);
  VelocityCommand update(double now_s, const BumpReading& bump);

 private:
  ExplorationConfig config_;
  std::mt19937_64 rng_;
  double backout_until_s_ = -1.0;
  double turn_until_s_ = -1.0;
  double turn_rate_ = 0.0;
  double backout_speed_ = 0.0;
};

}  // namespace ebslam
