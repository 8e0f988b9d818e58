#pragma once

// Systematic coverage for a floor robot with a bump ring, localised by EB-SLAM-2D: boustrophedon
// lanes one robot width apart (less an overlap for the pose error), obstacles and the room's
// boundary learned from bumps only, the nearest unswept reachable lane sample when a lane cannot
// go on (the backtracking of BA*, Viet et al. 2013: boustrophedon motions joined by shortest
// paths on the learned grid, an online equivalent of a boustrophedon cell decomposition), "done"
// when no reachable lane sample is left unswept, then back to the start.
// Frames: EB-SLAM's map frame (x, y [m], theta [rad]); lanes run along lane_direction_rad in it.
// Details: docs/ebslam_core.md#coverage

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ebslam/slam/floor_robot.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam {

struct CoverageConfig {
  double cell_m = 0.05;         ///< grid resolution [m]
  double grid_extent_m = 12.0;  ///< side of the square grid centred on the start [m]
  double robot_radius_m = 0.15;
  /// Distance between lanes [m]: the robot's width (0.30 m) less 5 cm of overlap, so that a
  /// pose error of up to 2.5 cm either side leaves no stripe unswept.
  double lane_spacing_m = 0.25;
  /// Lane direction in the map frame [rad]; 0: along the map's x axis (the room's walls when the
  /// map frame is aligned with the room, as EB-SLAM's is when started along a wall).
  double lane_direction_rad = 0.0;
  /// A contact at q (robot centre c, contact direction n): robot centres closer than this to q
  /// are impossible [m] (the robot's radius less a margin for the pose error).
  double contact_block_radius_m = 0.14;
  /// The contact's obstacle is assumed to continue along its tangent: centres p with
  /// 0 < (p - c).n <= wall_depth_m and |(p - c).t| <= wall_half_length_m are blocked until the
  /// robot's centre passes there [m]. Seals a wall with few bumps.
  double wall_half_length_m = 0.2;
  double wall_depth_m = 0.15;
  /// Transit paths: extra cost [cells] of a cell within clearance_cells of a blocked one.
  double clearance_cost = 3.0;
  int clearance_cells = 2;
  /// Controller: speed, turn-rate cap (EB-SLAM-2D loses the robot turning fast, see
  /// ExplorationConfig::max_turn_rate_rps), heading gain, turn in place above this heading error,
  /// pure-pursuit look-ahead and waypoint tolerance.
  double max_speed_mps = 0.3;
  double max_turn_rate_rps = 1.0;
  double heading_gain = 2.5;
  double turn_in_place_rad = 0.6;
  double lookahead_m = 0.25;
  double waypoint_tolerance_m = 0.06;
  /// While the localisation is uncertain (setLocalisationUncertain): this fraction of the speed
  /// and turn rate.
  double uncertain_speed_factor = 0.5;
  /// After a bump: drive away from the contact for this long at this speed [s, m/s].
  double backout_time_s = 0.5;
  double backout_speed_mps = 0.1;
  /// A contact beside the robot while sweeping gives up this much of the lane ahead [m].
  double side_bump_skip_m = 0.5;
  /// This many bumps within repeat_bump_radius_m [m] of each other within repeat_bump_window_s
  /// [s] give up the lane samples at the contact and the current goal.
  int repeat_bumps = 3;
  double repeat_bump_radius_m = 0.1;
  double repeat_bump_window_s = 20.0;
  /// Escape after repeated bumps (in a corner backing out and driving on can both be blocked,
  /// and each contact would start another back-out): turn in place at escape_turn_rate_rps
  /// [rad/s] until the contact is behind the robot, ignoring contacts while turning (a disc can
  /// always turn), then drive escape_forward_m [m] at backout_speed_mps, stopped only by a
  /// contact ahead.
  double escape_turn_rate_rps = 0.5;
  double escape_forward_m = 0.2;
  /// A goal is given up after this many bumps on the way, or when the path to it has not
  /// shortened by progress_m within progress_timeout_s [s].
  int max_bumps_per_goal = 4;
  double progress_m = 0.1;
  double progress_timeout_s = 15.0;
  /// No pose for this long [s]: stop and report it.
  double pose_timeout_s = 0.5;
  /// Drive back to the start once done.
  bool return_to_start = true;
  double start_tolerance_m = 0.1;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// The learned grid: where the robot's centre has been, where it cannot be (from bumps), and
/// the lane samples. ROS-free, no robot state (see CoverageExplorer).
class CoverageMap {
 public:
  /// The grid is centred on `start` (map frame); the lane through the start is lane 0.
  /// Throws std::invalid_argument for an invalid config.
  CoverageMap(const CoverageConfig& config, const Eigen::Vector2d& start);

  int cols() const { return cols_; }
  int rows() const { return rows_; }
  int size() const { return cols_ * rows_; }
  /// Rows between lanes.
  int laneStride() const { return lane_stride_; }
  Eigen::Vector2d centre(int cell) const;
  std::optional<int> cellAt(const Eigen::Vector2d& p) const;
  int col(int cell) const { return cell % cols_; }
  int row(int cell) const { return cell / cols_; }
  int index(int col, int row) const { return row * cols_ + col; }
  bool inside(int col, int row) const { return col >= 0 && row >= 0 && col < cols_ && row < rows_; }
  /// Lane frame: u along the lanes, w across [m] (rotation of the map frame).
  Eigen::Vector2d toLane(const Eigen::Vector2d& p) const;
  Eigen::Vector2d fromLane(const Eigen::Vector2d& uw) const;

  /// The robot's centre was at `p`: its body swept the floor around it.
  void addVisit(const Eigen::Vector2d& p);
  /// A bump at robot pose `pose` in direction `direction_robot_rad` (robot frame).
  void addContact(const Pose2& pose, double direction_robot_rad);
  /// Gives up the lane samples within radius_m of p (unreachable goals).
  void abandon(const Eigen::Vector2d& p, double radius_m);

  bool isLaneRow(int row) const { return (row - start_row_) % lane_stride_ == 0; }
  /// The robot's centre may be at the cell (no contact, hypothesis or abandonment says no).
  bool traversable(int cell) const {
    return hard_[cell] == 0 && soft_[cell] == 0 && abandoned_[cell] == 0;
  }
  /// Distance from the cell's centre to the nearest visited robot centre [m] (capped).
  float visitDistance(int cell) const { return visit_distance_[cell]; }
  /// A lane sample still to sweep: on a lane row, traversable, no visit within half a lane.
  bool open(int cell) const;

  /// Shortest path (8-connected, clearance cost) from `from` to the nearest open lane sample;
  /// empty if none is reachable. Cells from the start's successor to the goal. contacts_only:
  /// the path may cross wall hypotheses and given-up cells (only contacts block it).
  std::vector<int> pathToNearestOpen(const Eigen::Vector2d& from, bool contacts_only = false);
  /// Shortest path from `from` to `goal`'s cell; empty if unreachable.
  std::vector<int> pathTo(const Eigen::Vector2d& from, const Eigen::Vector2d& goal);
  /// Open lane samples reachable from `from`, visited lane samples and abandoned ones.
  struct Census {
    int open_reachable = 0;
    int visited = 0;
    int abandoned = 0;
  };
  Census census(const Eigen::Vector2d& from);
  /// Swept floor area (cells within the robot's radius of a visit) [m^2].
  double sweptArea() const;

  const std::vector<std::uint8_t>& hardBlocked() const { return hard_; }
  const std::vector<std::uint8_t>& softBlocked() const { return soft_; }
  const std::vector<Eigen::Vector2d>& contacts() const { return contacts_; }

 private:
  std::vector<int> dijkstra(int start, int goal, bool contacts_only);  // goal < 0: nearest open
  void updateClearance();

  CoverageConfig config_;
  double cos_ = 1.0, sin_ = 0.0;
  Eigen::Vector2d origin_uw_;  // lane-frame corner of cell (0, 0)
  int cols_ = 0, rows_ = 0;
  int start_row_ = 0;
  int lane_stride_ = 5;
  std::vector<float> visit_distance_;
  std::vector<std::uint8_t> hard_, soft_, abandoned_;
  std::vector<std::uint8_t> near_blocked_;
  bool clearance_stale_ = true;
  std::vector<Eigen::Vector2d> contacts_;
  // Dijkstra scratch.
  std::vector<float> cost_;
  std::vector<std::int32_t> parent_;
};

enum class CoverageState {
  kSweeping,    ///< driving along a lane
  kTransit,     ///< driving to the next lane or the nearest unswept region
  kBackingOut,  ///< moving away from a contact
  kReturning,   ///< nothing reachable left unswept: driving back to the start
  kDone,        ///< done (at the start, or where the way back ended): stopped
  kNoPose,      ///< no pose for pose_timeout_s: stopped
};
const char* toString(CoverageState state);

/// The covering robot's brain: the learned grid, the lane logic and the path-following
/// controller.
class CoverageExplorer {
 public:
  /// `start` (map frame) centres the grid and is where the robot returns. Throws
  /// std::invalid_argument for an invalid config.
  CoverageExplorer(const CoverageConfig& config, const Pose2& start);

  /// One control step at time now_s [s]: the latest pose (nullopt if none arrived since the
  /// last step; non-finite counts as none) and the bump ring's reading. Returns the command.
  VelocityCommand update(double now_s, const std::optional<Pose2>& pose, const BumpReading& bump);
  /// The localisation's verdict (e.g. TrackingMonitor): while uncertain the robot drives at
  /// uncertain_speed_factor of its speed and turn rate.
  void setLocalisationUncertain(bool uncertain) { uncertain_ = uncertain; }

  CoverageState state() const { return state_; }
  /// True once nothing reachable is left unswept (also while returning).
  bool done() const { return done_; }
  double doneTime() const { return done_time_s_; }
  /// Share of the reachable lane samples swept when done was decided (or now, before).
  double coveredShare() const { return covered_share_; }
  const std::string& message() const { return message_; }
  const CoverageMap& map() const { return map_; }
  /// Remaining planned path (map frame), for display.
  const std::vector<Eigen::Vector2d>& path() const { return path_; }
  /// Lanes driven so far: start and end of each (map frame).
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& lanes() const { return lanes_; }
  std::size_t bumps() const { return bumps_; }
  std::size_t goalsAbandoned() const { return goals_abandoned_; }
  /// Escape manoeuvres after repeated bumps (CoverageConfig::escape_turn_rate_rps).
  std::size_t escapes() const { return escapes_; }

 private:
  void decide(double now_s, const Eigen::Vector2d& position);
  bool startLane(int row, const Eigen::Vector2d& position, int preferred_direction);
  int runEnd(int row, int col, int direction) const;
  void startTransit(double now_s, std::vector<int> cells, CoverageState state);
  VelocityCommand sweep(double now_s, const Pose2& pose);
  VelocityCommand follow(double now_s, const Pose2& pose);
  VelocityCommand steer(const Pose2& pose, const Eigen::Vector2d& target) const;
  void finishLane(const Eigen::Vector2d& position);
  void updateShare(const Eigen::Vector2d& position);

  CoverageConfig config_;
  CoverageMap map_;
  Pose2 start_;
  CoverageState state_ = CoverageState::kTransit;
  CoverageState resume_state_ = CoverageState::kSweeping;
  std::string message_;
  std::optional<Pose2> pose_;
  double pose_time_s_ = -1.0;
  double start_time_s_ = -1.0;
  bool need_decision_ = true;
  bool uncertain_ = false;
  bool done_ = false;
  double done_time_s_ = -1.0;
  double covered_share_ = 0.0;
  // Lane being swept: grid row, direction along u (+1 / -1), end column; side of the next lane.
  int lane_row_ = 0;
  int lane_direction_ = 1;
  int lane_side_ = 1;
  Eigen::Vector2d lane_start_{0.0, 0.0};
  // Transit.
  std::vector<Eigen::Vector2d> path_;
  std::size_t next_waypoint_ = 0;
  int goal_cell_ = -1;
  int goal_bumps_ = 0;
  double best_remaining_m_ = 0.0;
  double progress_since_s_ = 0.0;
  int sweep_after_transit_row_ = -1;
  int sweep_after_transit_direction_ = 0;
  double backout_until_s_ = 0.0;
  double backout_speed_ = 0.0;
  // Escape manoeuvre: turning until escape_turn_until_s_, then forward until
  // escape_forward_until_s_.
  double escape_turn_until_s_ = -1.0;
  double escape_forward_until_s_ = -1.0;
  double escape_omega_ = 0.0;
  std::size_t escapes_ = 0;
  std::optional<Eigen::Vector2d> last_visit_;
  std::vector<std::pair<double, Eigen::Vector2d>> recent_bumps_;  // (time, robot position)
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> lanes_;
  std::size_t bumps_ = 0;
  std::size_t goals_abandoned_ = 0;
};

}  // namespace ebslam
