#include "ebslam/slam/coverage.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "ebslam/events/pose.h"
#include "path_following.h"

namespace ebslam {
namespace {

constexpr float kFar = 1e9f;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

void CoverageConfig::validate() const {
  require(positive(cell_m) && cell_m <= 0.5, "CoverageConfig: cell_m must be in (0, 0.5]");
  require(positive(grid_extent_m) && grid_extent_m / cell_m <= 4000.0,
          "CoverageConfig: grid_extent_m must be positive and at most 4000 cells");
  require(positive(robot_radius_m), "CoverageConfig: robot_radius_m must be positive");
  require(positive(lane_spacing_m) && lane_spacing_m >= cell_m,
          "CoverageConfig: lane_spacing_m must be at least cell_m");
  require(std::isfinite(lane_direction_rad), "CoverageConfig: lane_direction_rad must be finite");
  require(std::isfinite(contact_block_radius_m) && contact_block_radius_m >= 0.0,
          "CoverageConfig: contact_block_radius_m must be >= 0");
  require(std::isfinite(wall_half_length_m) && wall_half_length_m >= 0.0 &&
              std::isfinite(wall_depth_m) && wall_depth_m >= 0.0,
          "CoverageConfig: wall_half_length_m and wall_depth_m must be >= 0");
  require(std::isfinite(clearance_cost) && clearance_cost >= 0.0 && clearance_cells >= 0 &&
              clearance_cells <= 10,
          "CoverageConfig: clearance_cost must be >= 0 and clearance_cells in [0, 10]");
  require(positive(max_speed_mps) && positive(max_turn_rate_rps) && positive(heading_gain),
          "CoverageConfig: max_speed_mps, max_turn_rate_rps and heading_gain must be positive");
  require(positive(turn_in_place_rad), "CoverageConfig: turn_in_place_rad must be positive");
  require(positive(lookahead_m) && positive(waypoint_tolerance_m),
          "CoverageConfig: lookahead_m and waypoint_tolerance_m must be positive");
  require(positive(uncertain_speed_factor) && uncertain_speed_factor <= 1.0,
          "CoverageConfig: uncertain_speed_factor must be in (0, 1]");
  require(std::isfinite(backout_time_s) && backout_time_s >= 0.0 && positive(backout_speed_mps),
          "CoverageConfig: backout_time_s must be >= 0 and backout_speed_mps positive");
  require(max_bumps_per_goal >= 1, "CoverageConfig: max_bumps_per_goal must be >= 1");
  require(repeat_bumps >= 2 && positive(repeat_bump_radius_m) && positive(repeat_bump_window_s),
          "CoverageConfig: repeat_bumps must be >= 2, repeat_bump_radius_m and "
          "repeat_bump_window_s positive");
  require(
      positive(escape_turn_rate_rps) && std::isfinite(escape_forward_m) && escape_forward_m >= 0.0,
      "CoverageConfig: escape_turn_rate_rps must be positive and escape_forward_m >= 0");
  require(std::isfinite(side_bump_skip_m) && side_bump_skip_m >= 0.0,
          "CoverageConfig: side_bump_skip_m must be >= 0");
  require(positive(progress_m) && positive(progress_timeout_s),
          "CoverageConfig: progress_m and progress_timeout_s must be positive");
  require(positive(pose_timeout_s), "CoverageConfig: pose_timeout_s must be positive");
  require(positive(start_tolerance_m), "CoverageConfig: start_tolerance_m must be positive");
}

// ---------------------------------------------------------------------------------------------
// CoverageMap

CoverageMap::CoverageMap(const CoverageConfig& config, const Eigen::Vector2d& start)
    : config_(config) {
  config_.validate();
  require(start.allFinite(), "CoverageMap: start must be finite");
  cos_ = std::cos(config_.lane_direction_rad);
  sin_ = std::sin(config_.lane_direction_rad);
  // An odd number of cells puts the start at a cell centre.
  const int half = static_cast<int>(std::floor(0.5 * config_.grid_extent_m / config_.cell_m));
  cols_ = rows_ = 2 * half + 1;
  start_row_ = half;
  lane_stride_ =
      std::max(1, static_cast<int>(std::lround(config_.lane_spacing_m / config_.cell_m)));
  origin_uw_ = toLane(start) - config_.cell_m * Eigen::Vector2d(half + 0.5, half + 0.5);
  const auto n = static_cast<std::size_t>(size());
  visit_distance_.assign(n, kFar);
  hard_.assign(n, 0);
  soft_.assign(n, 0);
  abandoned_.assign(n, 0);
  near_blocked_.assign(n, 0);
}

Eigen::Vector2d CoverageMap::toLane(const Eigen::Vector2d& p) const {
  return {cos_ * p.x() + sin_ * p.y(), -sin_ * p.x() + cos_ * p.y()};
}

Eigen::Vector2d CoverageMap::fromLane(const Eigen::Vector2d& uw) const {
  return {cos_ * uw.x() - sin_ * uw.y(), sin_ * uw.x() + cos_ * uw.y()};
}

Eigen::Vector2d CoverageMap::centre(int cell) const {
  return fromLane(origin_uw_ + config_.cell_m * Eigen::Vector2d(col(cell) + 0.5, row(cell) + 0.5));
}

std::optional<int> CoverageMap::cellAt(const Eigen::Vector2d& p) const {
  if (!p.allFinite()) return std::nullopt;
  const Eigen::Vector2d g = (toLane(p) - origin_uw_) / config_.cell_m;
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < cols_ && g.y() < rows_)) return std::nullopt;
  return index(static_cast<int>(g.x()), static_cast<int>(g.y()));
}

bool CoverageMap::open(int cell) const {
  return isLaneRow(row(cell)) && traversable(cell) &&
         visit_distance_[cell] > 0.5 * config_.lane_spacing_m;
}

void CoverageMap::addVisit(const Eigen::Vector2d& p) {
  const std::optional<int> at = cellAt(p);
  if (!at) return;
  const double reach = std::max(config_.robot_radius_m, 0.5 * config_.lane_spacing_m);
  const int k = static_cast<int>(std::ceil(reach / config_.cell_m)) + 1;
  const int c0 = col(*at), r0 = row(*at);
  for (int r = std::max(0, r0 - k); r <= std::min(rows_ - 1, r0 + k); ++r) {
    for (int c = std::max(0, c0 - k); c <= std::min(cols_ - 1, c0 + k); ++c) {
      const int cell = index(c, r);
      const auto d = static_cast<float>((centre(cell) - p).norm());
      if (d < visit_distance_[cell]) visit_distance_[cell] = d;
      // The robot's centre was here: no obstacle hypothesis holds at this cell.
      if (d <= config_.cell_m && (soft_[cell] != 0 || hard_[cell] != 0)) {
        soft_[cell] = 0;
        hard_[cell] = 0;
        clearance_stale_ = true;
      }
    }
  }
}

void CoverageMap::addContact(const Pose2& pose, double direction_robot_rad) {
  const Eigen::Vector2d c(pose.x, pose.y);
  if (!c.allFinite() || !std::isfinite(pose.theta) || !std::isfinite(direction_robot_rad)) return;
  const double a = pose.theta + direction_robot_rad;
  const Eigen::Vector2d n(std::cos(a), std::sin(a));
  const Eigen::Vector2d t(-n.y(), n.x());
  const Eigen::Vector2d q = c + config_.robot_radius_m * n;
  contacts_.push_back(q);
  const std::optional<int> at = cellAt(c);
  if (!at) return;
  const double reach = config_.robot_radius_m + config_.contact_block_radius_m +
                       config_.wall_depth_m + config_.wall_half_length_m;
  const int k = static_cast<int>(std::ceil(reach / config_.cell_m)) + 1;
  const int c0 = col(*at), r0 = row(*at);
  for (int r = std::max(0, r0 - k); r <= std::min(rows_ - 1, r0 + k); ++r) {
    for (int cc = std::max(0, c0 - k); cc <= std::min(cols_ - 1, c0 + k); ++cc) {
      const int cell = index(cc, r);
      const Eigen::Vector2d p = centre(cell);
      const Eigen::Vector2d d = p - c;
      if (d.norm() <= config_.cell_m) continue;  // where the robot stands
      if ((p - q).norm() < config_.contact_block_radius_m) hard_[cell] = 1;
      const double ahead = d.dot(n);
      if (ahead > 0.5 * config_.cell_m && ahead <= config_.wall_depth_m &&
          std::abs(d.dot(t)) <= config_.wall_half_length_m) {
        soft_[cell] = 1;
      }
    }
  }
  clearance_stale_ = true;
}

void CoverageMap::abandon(const Eigen::Vector2d& p, double radius_m) {
  const std::optional<int> at = cellAt(p);
  if (!at) return;
  const int k = static_cast<int>(std::ceil(radius_m / config_.cell_m)) + 1;
  const int c0 = col(*at), r0 = row(*at);
  for (int r = std::max(0, r0 - k); r <= std::min(rows_ - 1, r0 + k); ++r) {
    for (int c = std::max(0, c0 - k); c <= std::min(cols_ - 1, c0 + k); ++c) {
      const int cell = index(c, r);
      if ((centre(cell) - p).norm() <= radius_m) abandoned_[cell] = 1;
    }
  }
  clearance_stale_ = true;
}

void CoverageMap::updateClearance() {
  if (!clearance_stale_) return;
  clearance_stale_ = false;
  std::fill(near_blocked_.begin(), near_blocked_.end(), 0);
  const int k = config_.clearance_cells;
  if (k == 0) return;
  for (int cell = 0; cell < size(); ++cell) {
    if (hard_[cell] == 0 && soft_[cell] == 0) continue;
    const int c0 = col(cell), r0 = row(cell);
    for (int r = std::max(0, r0 - k); r <= std::min(rows_ - 1, r0 + k); ++r) {
      for (int c = std::max(0, c0 - k); c <= std::min(cols_ - 1, c0 + k); ++c) {
        near_blocked_[index(c, r)] = 1;
      }
    }
  }
}

std::vector<int> CoverageMap::dijkstra(int start, int goal, bool contacts_only) {
  updateClearance();
  const auto passable = [&](int cell) {
    return contacts_only ? hard_[cell] == 0 : traversable(cell);
  };
  const auto n = static_cast<std::size_t>(size());
  cost_.assign(n, kFar);
  parent_.assign(n, -1);
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  cost_[start] = 0.0f;
  queue.push({0.0f, start});
  static const int dc[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static const int dr[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  const auto diagonal = static_cast<float>(std::sqrt(2.0));
  int found = -1;
  while (!queue.empty()) {
    const auto [cost, cell] = queue.top();
    queue.pop();
    if (cost > cost_[cell]) continue;
    if (goal >= 0 ? cell == goal : (cell != start && open(cell))) {
      found = cell;
      break;
    }
    const int c0 = col(cell), r0 = row(cell);
    for (int k = 0; k < 8; ++k) {
      const int c = c0 + dc[k], r = r0 + dr[k];
      if (!inside(c, r)) continue;
      const int next = index(c, r);
      if (!passable(next) && next != goal) continue;
      // No corner cutting between two blocked cells.
      if (k >= 4 && (!passable(index(c, r0)) || !passable(index(c0, r)))) continue;
      const float step = (k < 4 ? 1.0f : diagonal) +
                         (near_blocked_[next] ? static_cast<float>(config_.clearance_cost) : 0.0f);
      if (cost + step < cost_[next]) {
        cost_[next] = cost + step;
        parent_[next] = cell;
        queue.push({cost_[next], next});
      }
    }
  }
  std::vector<int> path;
  if (found < 0) return path;
  for (int cell = found; cell != start && cell >= 0; cell = parent_[cell]) path.push_back(cell);
  std::reverse(path.begin(), path.end());
  return path;
}

std::vector<int> CoverageMap::pathToNearestOpen(const Eigen::Vector2d& from, bool contacts_only) {
  const std::optional<int> start = cellAt(from);
  if (!start) return {};
  return dijkstra(*start, -1, contacts_only);
}

std::vector<int> CoverageMap::pathTo(const Eigen::Vector2d& from, const Eigen::Vector2d& goal) {
  const std::optional<int> start = cellAt(from);
  const std::optional<int> target = cellAt(goal);
  if (!start || !target) return {};
  if (*start == *target) return {*target};
  return dijkstra(*start, *target, false);
}

CoverageMap::Census CoverageMap::census(const Eigen::Vector2d& from) {
  Census result;
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(size()), 0);
  const std::optional<int> start = cellAt(from);
  if (start) {
    std::vector<int> stack{*start};
    seen[*start] = 1;
    while (!stack.empty()) {
      const int cell = stack.back();
      stack.pop_back();
      if (open(cell)) ++result.open_reachable;
      const int c0 = col(cell), r0 = row(cell);
      static const int dc[4] = {1, -1, 0, 0};
      static const int dr[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const int c = c0 + dc[k], r = r0 + dr[k];
        if (!inside(c, r)) continue;
        const int next = index(c, r);
        if (seen[next] || !traversable(next)) continue;
        seen[next] = 1;
        stack.push_back(next);
      }
    }
  }
  const float swept = static_cast<float>(0.5 * config_.lane_spacing_m);
  for (int cell = 0; cell < size(); ++cell) {
    if (!isLaneRow(row(cell))) continue;
    if (visit_distance_[cell] <= swept) {
      ++result.visited;
    } else if (abandoned_[cell] != 0 && hard_[cell] == 0 && soft_[cell] == 0) {
      ++result.abandoned;
    }
  }
  return result;
}

double CoverageMap::sweptArea() const {
  const auto r = static_cast<float>(config_.robot_radius_m);
  const auto count = std::count_if(visit_distance_.begin(), visit_distance_.end(),
                                   [r](float d) { return d <= r; });
  return static_cast<double>(count) * config_.cell_m * config_.cell_m;
}

// ---------------------------------------------------------------------------------------------
// CoverageExplorer

const char* toString(CoverageState state) {
  switch (state) {
    case CoverageState::kSweeping:
      return "sweeping";
    case CoverageState::kTransit:
      return "transit";
    case CoverageState::kBackingOut:
      return "backing out";
    case CoverageState::kReturning:
      return "returning";
    case CoverageState::kDone:
      return "done";
    case CoverageState::kNoPose:
      return "no pose";
  }
  return "unknown";
}

CoverageExplorer::CoverageExplorer(const CoverageConfig& config, const Pose2& start)
    : config_(config), map_(config, Eigen::Vector2d(start.x, start.y)), start_(start) {
  config_.validate();
}

int CoverageExplorer::runEnd(int row, int col, int direction) const {
  // Open samples ahead along the row; a stretch of swept samples (e.g. a transit path crossed
  // the lane) shorter than half a metre is driven through.
  const int gap_cells = std::max(2, static_cast<int>(std::lround(0.5 / config_.cell_m)));
  int last_open = col;
  int gap = 0;
  for (int c = col + direction; map_.inside(c, row); c += direction) {
    const int cell = map_.index(c, row);
    if (!map_.traversable(cell)) break;
    if (map_.open(cell)) {
      last_open = c;
      gap = 0;
    } else if (++gap > gap_cells) {
      break;
    }
  }
  return last_open;
}

bool CoverageExplorer::startLane(int row, const Eigen::Vector2d& position,
                                 int preferred_direction) {
  const std::optional<int> at = map_.cellAt(position);
  if (!at) return false;
  const int col = map_.col(*at);
  const int forward = runEnd(row, col, preferred_direction);
  const int backward = runEnd(row, col, -preferred_direction);
  const int forward_length = std::abs(forward - col);
  const int backward_length = std::abs(backward - col);
  if (forward_length == 0 && backward_length == 0) return false;
  lane_row_ = row;
  lane_direction_ = forward_length >= 2 || forward_length >= backward_length ? preferred_direction
                                                                             : -preferred_direction;
  lane_start_ = position;
  state_ = CoverageState::kSweeping;
  path_.clear();
  return true;
}

void CoverageExplorer::finishLane(const Eigen::Vector2d& position) {
  lanes_.emplace_back(lane_start_, position);
}

void CoverageExplorer::startTransit(double now_s, std::vector<int> cells, CoverageState state) {
  const int goal = cells.empty() ? -1 : cells.back();
  if (goal != goal_cell_) goal_bumps_ = 0;
  goal_cell_ = goal;
  path_.clear();
  for (int cell : cells) path_.push_back(map_.centre(cell));
  next_waypoint_ = 0;
  best_remaining_m_ = 1e9;
  progress_since_s_ = now_s;
  state_ = state;
}

void CoverageExplorer::updateShare(const Eigen::Vector2d& position) {
  const CoverageMap::Census census = map_.census(position);
  const int total = census.visited + census.open_reachable + census.abandoned;
  covered_share_ = total > 0 ? static_cast<double>(census.visited) / total : 0.0;
}

void CoverageExplorer::decide(double now_s, const Eigen::Vector2d& position) {
  need_decision_ = false;
  if (done_) {
    const std::vector<int> home = map_.pathTo(position, Eigen::Vector2d(start_.x, start_.y));
    if (!config_.return_to_start || home.empty() || goal_bumps_ >= config_.max_bumps_per_goal ||
        (position - Eigen::Vector2d(start_.x, start_.y)).norm() <= config_.start_tolerance_m) {
      state_ = CoverageState::kDone;
      path_.clear();
      return;
    }
    startTransit(now_s, home, CoverageState::kReturning);
    return;
  }
  const std::optional<int> at = map_.cellAt(position);
  if (at) {
    const int col = map_.col(*at);
    // 1. Go on along the robot's own lane row (the other part of a lane entered midway).
    if (map_.isLaneRow(map_.row(*at)) && startLane(map_.row(*at), position, -lane_direction_)) {
      return;
    }
    // 2. Boustrophedon: the neighbouring lane on the current side, else on the other side, at
    // the robot's column (or within 3 cells of it), reached by a short path.
    for (int side : {lane_side_, -lane_side_}) {
      const int row = lane_row_ + side * map_.laneStride();
      for (int offset : {0, 1, -1, 2, -2, 3, -3}) {
        const int c = col + offset * lane_direction_ * -1;
        if (!map_.inside(c, row) || !map_.open(map_.index(c, row))) continue;
        std::vector<int> cells = map_.pathTo(position, map_.centre(map_.index(c, row)));
        if (cells.empty() || static_cast<int>(cells.size()) > 3 * map_.laneStride()) continue;
        lane_side_ = side;
        sweep_after_transit_row_ = row;
        sweep_after_transit_direction_ = -lane_direction_;
        startTransit(now_s, std::move(cells), CoverageState::kTransit);
        return;
      }
    }
  }
  // 3. The nearest unswept reachable lane sample.
  std::vector<int> cells = map_.pathToNearestOpen(position);
  if (cells.empty()) {
    // Hypothesised walls and given-up goals can close a pocket around the robot (two bumps
    // close together, a pose error): before "done", they yield; only contacts stop the search.
    cells = map_.pathToNearestOpen(position, true);
  }
  if (!cells.empty()) {
    sweep_after_transit_row_ = map_.row(cells.back());
    sweep_after_transit_direction_ = lane_direction_;
    startTransit(now_s, std::move(cells), CoverageState::kTransit);
    return;
  }
  // 4. Nothing reachable is left unswept.
  done_ = true;
  done_time_s_ = now_s;
  updateShare(position);
  std::ostringstream text;
  text.precision(1);
  text << std::fixed << "done: " << 100.0 * covered_share_
       << " % of the reachable lane samples swept";
  message_ = text.str();
  goal_bumps_ = 0;
  need_decision_ = true;
  decide(now_s, position);
}

VelocityCommand CoverageExplorer::steer(const Pose2& pose, const Eigen::Vector2d& target) const {
  return path_following::steerTowards(pose, target, config_.heading_gain, config_.max_turn_rate_rps,
                                      config_.turn_in_place_rad, config_.max_speed_mps);
}

VelocityCommand CoverageExplorer::sweep(double now_s, const Pose2& pose) {
  const Eigen::Vector2d position(pose.x, pose.y);
  const std::optional<int> at = map_.cellAt(position);
  if (!at) {
    need_decision_ = true;
    return {};
  }
  const Eigen::Vector2d uw = map_.toLane(position);
  const int end_col = runEnd(lane_row_, map_.col(*at), lane_direction_);
  const Eigen::Vector2d end_uw = map_.toLane(map_.centre(map_.index(end_col, lane_row_)));
  const double remaining = (end_uw.x() - uw.x()) * lane_direction_;
  if (end_col == map_.col(*at) || remaining < config_.waypoint_tolerance_m) {
    finishLane(position);
    need_decision_ = true;
    (void)now_s;
    return {};
  }
  const double u = uw.x() + lane_direction_ * std::min(config_.lookahead_m, remaining);
  return steer(pose, map_.fromLane(Eigen::Vector2d(u, end_uw.y())));
}

VelocityCommand CoverageExplorer::follow(double now_s, const Pose2& pose) {
  const Eigen::Vector2d position(pose.x, pose.y);
  const auto distance = [&](std::size_t j) { return (path_[j] - position).norm(); };
  next_waypoint_ = path_following::nearestAhead(next_waypoint_, path_.size(), 6, distance);
  while (next_waypoint_ < path_.size() &&
         (next_waypoint_ + 1 < path_.size()
              ? distance(next_waypoint_) < config_.lookahead_m * 0.5
              : distance(next_waypoint_) < config_.waypoint_tolerance_m)) {
    ++next_waypoint_;
  }
  if (next_waypoint_ >= path_.size()) {
    // Arrived.
    path_.clear();
    if (state_ == CoverageState::kReturning) {
      state_ = CoverageState::kDone;
      return {};
    }
    if (!startLane(sweep_after_transit_row_, position, sweep_after_transit_direction_)) {
      need_decision_ = true;
      return {};
    }
    return sweep(now_s, pose);
  }
  // Progress: the remaining path length must shrink.
  double remaining = distance(next_waypoint_);
  for (std::size_t j = next_waypoint_ + 1; j < path_.size(); ++j) {
    remaining += (path_[j] - path_[j - 1]).norm();
  }
  if (remaining < best_remaining_m_ - config_.progress_m) {
    best_remaining_m_ = remaining;
    progress_since_s_ = now_s;
  } else if (now_s - progress_since_s_ > config_.progress_timeout_s) {
    if (state_ == CoverageState::kReturning) {
      state_ = CoverageState::kDone;
      message_ += "; the way back is blocked";
      return {};
    }
    map_.abandon(path_.back(), 0.5 * config_.lane_spacing_m);
    ++goals_abandoned_;
    need_decision_ = true;
    return {};
  }
  return steer(pose, path_[path_following::lookaheadTarget(next_waypoint_, path_.size(),
                                                           config_.lookahead_m, distance)]);
}

VelocityCommand CoverageExplorer::update(double now_s, const std::optional<Pose2>& pose,
                                         const BumpReading& bump) {
  if (start_time_s_ < 0.0) start_time_s_ = now_s;
  const bool valid =
      pose && std::isfinite(pose->x) && std::isfinite(pose->y) && std::isfinite(pose->theta);
  if (valid) {
    pose_ = *pose;
    pose_time_s_ = now_s;
  }
  const double since_pose = pose_time_s_ < 0.0 ? now_s - start_time_s_ : now_s - pose_time_s_;
  if (!pose_ || since_pose > config_.pose_timeout_s) {
    if (pose_ || since_pose > config_.pose_timeout_s) {
      if (state_ != CoverageState::kNoPose) resume_state_ = state_;
      state_ = CoverageState::kNoPose;
      std::ostringstream text;
      text.precision(2);
      text << std::fixed << "no pose for " << since_pose << " s; stopped";
      message_ = text.str();
    }
    return {};
  }
  if (state_ == CoverageState::kNoPose) {
    state_ = done_ ? CoverageState::kReturning : CoverageState::kTransit;
    need_decision_ = true;
    message_ = done_ ? message_ : "pose is back";
  }
  const Eigen::Vector2d position(pose_->x, pose_->y);
  if (!last_visit_ || (position - *last_visit_).norm() >= 0.02) {
    map_.addVisit(position);
    last_visit_ = position;
  }
  if (state_ == CoverageState::kDone) return {};

  const double factor = uncertain_ ? config_.uncertain_speed_factor : 1.0;
  const auto scaled = [factor](VelocityCommand command) {
    command.v_mps *= factor;
    command.omega_rps *= factor;
    return command;
  };
  // The escape is timed for its own rate and speed: not scaled while uncertain (scaling would
  // turn half the angle and drive half the distance).
  if (now_s < escape_turn_until_s_) return {0.0, escape_omega_};
  if (now_s < escape_forward_until_s_) {
    if (!bump.contact() || std::cos(bump.direction_rad) < 0.5) {
      return {config_.backout_speed_mps, 0.0};
    }
    escape_forward_until_s_ = -1.0;  // a contact ahead: handled as any bump
  }
  if (bump.contact()) {
    ++bumps_;
    map_.addContact(*pose_, bump.direction_rad);
    // Bumping again and again at one place (a contact the learned cells do not explain, e.g. an
    // obstacle's corner the robot grazes while turning): give up the lane samples ahead.
    recent_bumps_.erase(std::remove_if(recent_bumps_.begin(), recent_bumps_.end(),
                                       [&](const std::pair<double, Eigen::Vector2d>& b) {
                                         return now_s - b.first > config_.repeat_bump_window_s;
                                       }),
                        recent_bumps_.end());
    const auto repeats =
        std::count_if(recent_bumps_.begin(), recent_bumps_.end(),
                      [&](const std::pair<double, Eigen::Vector2d>& b) {
                        return (b.second - position).norm() < config_.repeat_bump_radius_m;
                      });
    recent_bumps_.emplace_back(now_s, position);
    if (repeats + 1 >= config_.repeat_bumps) {
      const double a = pose_->theta + bump.direction_rad;
      map_.abandon(position + config_.robot_radius_m * Eigen::Vector2d(std::cos(a), std::sin(a)),
                   config_.robot_radius_m);
      if (!path_.empty() && !done_) map_.abandon(path_.back(), 0.5 * config_.lane_spacing_m);
      ++goals_abandoned_;
      recent_bumps_.clear();
      // Turn until the contact is behind (by the shorter way), then drive away from it.
      const double turn = std::remainder(bump.direction_rad + M_PI, 2.0 * M_PI);
      escape_omega_ = turn >= 0.0 ? config_.escape_turn_rate_rps : -config_.escape_turn_rate_rps;
      escape_turn_until_s_ = now_s + std::abs(turn) / config_.escape_turn_rate_rps;
      escape_forward_until_s_ =
          escape_turn_until_s_ + config_.escape_forward_m / config_.backout_speed_mps;
      ++escapes_;
      message_ = "bumps repeat at one place: turning away from the contact";
      if (state_ == CoverageState::kSweeping) finishLane(position);
      state_ = CoverageState::kBackingOut;
      backout_until_s_ = now_s;
      need_decision_ = true;
      return {0.0, escape_omega_};
    }
    if (state_ == CoverageState::kSweeping) {
      finishLane(position);
      // A contact beside the robot: the lane runs too close to an obstacle along it (its cells
      // stay traversable, the robot would bump again): give up the lane ahead.
      if (std::abs(std::sin(bump.direction_rad)) > 0.5) {
        const Eigen::Vector2d ahead = map_.fromLane(Eigen::Vector2d(lane_direction_, 0.0));
        for (double s = 0.0; s <= config_.side_bump_skip_m; s += config_.cell_m) {
          map_.abandon(position + s * ahead, 0.5 * config_.cell_m);
        }
      }
    }
    if ((state_ == CoverageState::kTransit || state_ == CoverageState::kReturning) &&
        ++goal_bumps_ >= config_.max_bumps_per_goal && !path_.empty() && !done_) {
      map_.abandon(path_.back(), 0.5 * config_.lane_spacing_m);
      ++goals_abandoned_;
    }
    state_ = CoverageState::kBackingOut;
    backout_until_s_ = now_s + config_.backout_time_s;
    backout_speed_ = std::cos(bump.direction_rad) >= 0.0 ? -config_.backout_speed_mps
                                                         : config_.backout_speed_mps;
    need_decision_ = true;
    return {backout_speed_, 0.0};
  }
  if (state_ == CoverageState::kBackingOut) {
    if (now_s < backout_until_s_) return {backout_speed_, 0.0};
    state_ = done_ ? CoverageState::kReturning : CoverageState::kTransit;
    need_decision_ = true;
  }
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (need_decision_) decide(now_s, position);
    VelocityCommand command;
    switch (state_) {
      case CoverageState::kSweeping:
        command = sweep(now_s, *pose_);
        break;
      case CoverageState::kTransit:
      case CoverageState::kReturning:
        command = follow(now_s, *pose_);
        break;
      default:
        return {};
    }
    if (!need_decision_) return scaled(command);
  }
  return {};
}

}  // namespace ebslam
