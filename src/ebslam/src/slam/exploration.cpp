#include "ebslam/slam/exploration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>

#include "ebslam/events/pose.h"
#include "path_following.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Odd-row offset neighbours, counter-clockwise from +x: (dc, dr) for even and odd rows.
constexpr int kEvenRow[6][2] = {{1, 0}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}};
constexpr int kOddRow[6][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 0}, {0, -1}, {1, -1}};

// Logistic function L_a(x) of eq. 7.10.
double logistic(double alpha, double x) { return 1.0 / (1.0 + std::exp(-alpha * x)); }

}  // namespace

HexGrid::HexGrid(double spacing_m, const Eigen::Vector2d& centre, double extent_m) {
  require(std::isfinite(spacing_m) && spacing_m > 0.0, "HexGrid: spacing must be positive");
  require(std::isfinite(extent_m) && extent_m > 0.0, "HexGrid: extent must be positive");
  require(centre.allFinite(), "HexGrid: centre must be finite");
  spacing_ = spacing_m;
  row_height_ = spacing_m * std::sqrt(3.0) / 2.0;
  cols_ = static_cast<int>(std::ceil(extent_m / spacing_)) + 1;
  rows_ = static_cast<int>(std::ceil(extent_m / row_height_)) + 1;
  rows_ += rows_ % 2;  // even row count: the pattern is symmetric about the centre
  require(static_cast<double>(cols_) * rows_ <= 4e6, "HexGrid: more than 4e6 cells");
  origin_ = centre - Eigen::Vector2d(0.5 * (cols_ - 1) * spacing_, 0.5 * (rows_ - 1) * row_height_);
  neighbours_.resize(static_cast<std::size_t>(size()));
  for (int r = 0; r < rows_; ++r) {
    for (int c = 0; c < cols_; ++c) {
      std::array<int, 6>& n = neighbours_[static_cast<std::size_t>(r * cols_ + c)];
      for (int k = 0; k < 6; ++k) {
        const int* d = (r % 2 == 0) ? kEvenRow[k] : kOddRow[k];
        const int nc = c + d[0];
        const int nr = r + d[1];
        n[k] = (nc >= 0 && nc < cols_ && nr >= 0 && nr < rows_) ? nr * cols_ + nc : -1;
      }
    }
  }
}

Eigen::Vector2d HexGrid::centre(int cell) const {
  const int r = cell / cols_;
  const int c = cell % cols_;
  return origin_ + Eigen::Vector2d((c + 0.5 * (r % 2)) * spacing_, r * row_height_);
}

std::optional<int> HexGrid::cellAt(const Eigen::Vector2d& p) const {
  if (!p.allFinite() || cols_ == 0) return std::nullopt;
  const double fr = (p.y() - origin_.y()) / row_height_;
  const int r0 = static_cast<int>(std::floor(fr));
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int r = r0; r <= r0 + 1; ++r) {
    if (r < 0 || r >= rows_) continue;
    const double fc = (p.x() - origin_.x()) / spacing_ - 0.5 * (r % 2);
    const int c = static_cast<int>(std::lround(fc));
    if (c < 0 || c >= cols_) continue;
    const int cell = r * cols_ + c;
    const double d2 = (centre(cell) - p).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = cell;
    }
  }
  // Outside the outermost centres by more than half a cell: not in the grid.
  if (best < 0 || best_d2 > spacing_ * spacing_) return std::nullopt;
  return best;
}

void ExplorationConfig::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("ExplorationConfig: " + what);
  };
  if (!positive(hex_spacing_m)) fail("hex_spacing_m must be positive");
  if (!positive(grid_extent_m)) fail("grid_extent_m must be positive");
  if (!positive(robot_radius_m)) fail("robot_radius_m must be positive");
  if (!(std::isfinite(bump_cone_depth_m) && bump_cone_depth_m >= 0.0)) {
    fail("bump_cone_depth_m must be >= 0");
  }
  if (!(bump_cone_half_angle_rad >= 0.0 && bump_cone_half_angle_rad <= kPi)) {
    fail("bump_cone_half_angle_rad must be in [0, pi]");
  }
  if (!(std::isfinite(weight_z) && weight_z >= 0.0)) fail("weight_z must be >= 0");
  if (!(std::isfinite(weight_e) && weight_e >= 0.0)) fail("weight_e must be >= 0");
  if (!positive(alpha)) fail("alpha must be positive");
  if (planner_max_nodes < 1) fail("planner_max_nodes must be >= 1");
  if (!(std::isfinite(near_blocked_cost) && near_blocked_cost >= 0.0)) {
    fail("near_blocked_cost must be >= 0");
  }
  if (!(std::isfinite(escape_blocked_cost) && escape_blocked_cost >= 0.0)) {
    fail("escape_blocked_cost must be >= 0");
  }
  if (oscillation_window < 0) fail("oscillation_window must be >= 0");
  if (oscillation_max_cells < 1) fail("oscillation_max_cells must be >= 1");
  if (commit_min_cells < 1) fail("commit_min_cells must be >= 1");
  if (!positive(planner_time_budget_s)) fail("planner_time_budget_s must be positive");
  if (min_path_cells < 1) fail("min_path_cells must be >= 1");
  if (max_path_cells < min_path_cells) fail("max_path_cells must be >= min_path_cells");
  if (!positive(waypoint_tolerance_m)) fail("waypoint_tolerance_m must be positive");
  if (!positive(turn_in_place_rad)) fail("turn_in_place_rad must be positive");
  if (!(std::isfinite(lookahead_m) && lookahead_m >= 0.0)) fail("lookahead_m must be >= 0");
  if (!positive(heading_gain)) fail("heading_gain must be positive");
  if (!positive(max_speed_mps)) fail("max_speed_mps must be positive");
  if (!(std::isfinite(relocalise_speed_mps) && relocalise_speed_mps >= 0.0)) {
    fail("relocalise_speed_mps must be >= 0");
  }
  if (!(std::isfinite(relocalise_timeout_s) && relocalise_timeout_s >= 0.0)) {
    fail("relocalise_timeout_s must be >= 0");
  }
  if (!positive(max_turn_rate_rps)) fail("max_turn_rate_rps must be positive");
  if (!positive(backout_time_s)) fail("backout_time_s must be positive");
  if (!positive(backout_speed_mps)) fail("backout_speed_mps must be positive");
  if (max_bumps_in_a_row < 1) fail("max_bumps_in_a_row must be >= 1");
  if (!positive(pose_timeout_s)) fail("pose_timeout_s must be positive");
  if (!positive(pose_jump_m)) fail("pose_jump_m must be positive");
  if (!positive(pose_jump_rad)) fail("pose_jump_rad must be positive");
}

ExplorationPlanner::ExplorationPlanner(const ExplorationConfig& config,
                                       const Eigen::Vector2d& centre)
    : config_(config) {
  config_.validate();
  grid_ = HexGrid(config_.hex_spacing_m, centre, config_.grid_extent_m);
  const auto n = static_cast<std::size_t>(grid_.size());
  z_.assign(n, 0.0f);
  e_.assign(n, 0.0f);
  gain_.assign(n, 0.0f);
  blocked_.assign(n, 0);
  near_blocked_.assign(n, 0);
  in_omega_.assign(n, 0);
  closed_scratch_.assign(n, 0);
}

bool ExplorationPlanner::addCoverage(const Eigen::Vector2d& position) {
  const std::optional<int> cell = grid_.cellAt(position);
  if (!cell || *cell == last_cell_) return false;
  last_cell_ = *cell;
  // Cells within the robot radius lie at most ceil(radius / spacing) + 1 rings away.
  const double r2 = config_.robot_radius_m * config_.robot_radius_m;
  const int rings = static_cast<int>(std::ceil(config_.robot_radius_m / grid_.spacing())) + 1;
  std::vector<int> frontier{*cell};
  std::vector<int> seen{*cell};
  for (int ring = 0; ring <= rings && !frontier.empty(); ++ring) {
    std::vector<int> next;
    for (int c : frontier) {
      if ((grid_.centre(c) - position).squaredNorm() <= r2 || c == *cell) e_[c] += 1.0f;
      for (int nb : grid_.neighbours(c)) {
        if (nb < 0 || std::find(seen.begin(), seen.end(), nb) != seen.end()) continue;
        seen.push_back(nb);
        next.push_back(nb);
      }
    }
    frontier.swap(next);
  }
  return true;
}

void ExplorationPlanner::addBump(const Pose2& pose, double direction_robot_rad) {
  const Eigen::Vector2d position(pose.x, pose.y);
  const double direction = pose.theta + direction_robot_rad;
  const Eigen::Vector2d unit(std::cos(direction), std::sin(direction));
  bump_points_.push_back(position + config_.robot_radius_m * unit);
  const std::optional<int> own = grid_.cellAt(position);
  const double reach = config_.robot_radius_m + config_.bump_cone_depth_m;
  const double cos_half = std::cos(config_.bump_cone_half_angle_rad);
  // Visit the cells within `reach` (bounding box in grid rows/columns around the position).
  const double min_distance = 0.5 * grid_.spacing();
  for (double dy = -reach; dy <= reach + 1e-9; dy += 0.5 * grid_.spacing()) {
    for (double dx = -reach; dx <= reach + 1e-9; dx += 0.5 * grid_.spacing()) {
      const std::optional<int> cell = grid_.cellAt(position + Eigen::Vector2d(dx, dy));
      if (!cell || (own && *cell == *own)) continue;
      const Eigen::Vector2d offset = grid_.centre(*cell) - position;
      const double distance = offset.norm();
      if (distance < min_distance || distance > reach) continue;
      if (offset.dot(unit) >= cos_half * distance) blocked_[*cell] = 1;
    }
  }
  near_blocked_stale_ = true;
}

void ExplorationPlanner::updateNearBlocked() {
  if (!near_blocked_stale_) return;
  near_blocked_stale_ = false;
  std::fill(near_blocked_.begin(), near_blocked_.end(), 0);
  for (int c = 0; c < grid_.size(); ++c) {
    if (!blocked_[c]) continue;
    for (int nb : grid_.neighbours(c)) {
      if (nb >= 0 && !blocked_[nb]) near_blocked_[nb] = 1;
    }
  }
}

void ExplorationPlanner::updateLocalisationMap(const GridMap2f& normalisation) {
  if (normalisation.width <= 0 || normalisation.height <= 0) return;
  const bool same_geometry = normalisation.width == z_width_ && normalisation.height == z_height_ &&
                             normalisation.resolution_m == z_res_ &&
                             normalisation.origin_x_m == z_ox_ && normalisation.origin_y_m == z_oy_;
  if (!same_geometry) {
    z_width_ = normalisation.width;
    z_height_ = normalisation.height;
    z_res_ = normalisation.resolution_m;
    z_ox_ = normalisation.origin_x_m;
    z_oy_ = normalisation.origin_y_m;
    z_cell_of_.assign(normalisation.cellCount(), -1);
    z_cell_area_.assign(static_cast<std::size_t>(grid_.size()), 0.0f);
    for (int r = 0; r < z_height_; ++r) {
      for (int c = 0; c < z_width_; ++c) {
        const Eigen::Vector2d p(z_ox_ + (c + 0.5) * z_res_, z_oy_ + (r + 0.5) * z_res_);
        if (const std::optional<int> cell = grid_.cellAt(p)) {
          z_cell_of_[static_cast<std::size_t>(r) * z_width_ + c] = *cell;
          z_cell_area_[*cell] += 1.0f;
        }
      }
    }
  }
  std::fill(z_.begin(), z_.end(), 0.0f);
  const std::size_t count = normalisation.cellCount();
  for (std::size_t i = 0; i < count; ++i) {
    const std::int32_t cell = z_cell_of_[i];
    if (cell >= 0) z_[cell] += normalisation.data[i];
  }
  for (std::size_t k = 0; k < z_.size(); ++k) {
    if (z_cell_area_[k] > 0.0f) z_[k] /= z_cell_area_[k];
  }
}

void ExplorationPlanner::computeGain(int robot_cell) { computeGain(robot_cell, false); }

void ExplorationPlanner::computeGain(int robot_cell, bool through_blocked) {
  std::fill(gain_.begin(), gain_.end(), 0.0f);
  std::fill(in_omega_.begin(), in_omega_.end(), 0);
  reachable_.clear();
  if (robot_cell < 0 || robot_cell >= grid_.size()) return;
  // Omega: cells connected to the robot's cell through unblocked cells (breadth-first).
  reachable_.push_back(robot_cell);
  in_omega_[robot_cell] = 1;
  for (std::size_t head = 0; head < reachable_.size(); ++head) {
    for (int nb : grid_.neighbours(reachable_[head])) {
      if (nb < 0 || in_omega_[nb] || (blocked_[nb] && !through_blocked)) continue;
      in_omega_[nb] = 1;
      reachable_.push_back(nb);
    }
  }
  // Eq. 7.8 over Omega for Z and E.
  const auto statistics = [this](const std::vector<float>& map, double& mean, double& range) {
    double sum = 0.0;
    float lo = std::numeric_limits<float>::infinity();
    float hi = -lo;
    for (int c : reachable_) {
      sum += map[c];
      lo = std::min(lo, map[c]);
      hi = std::max(hi, map[c]);
    }
    mean = sum / static_cast<double>(reachable_.size());
    range = static_cast<double>(hi) - lo;
  };
  double z_mean = 0.0, z_range = 0.0, e_mean = 0.0, e_range = 0.0;
  statistics(z_, z_mean, z_range);
  statistics(e_, e_mean, e_range);
  // A constant map (range 0) carries no preference: M_0 = 0 everywhere.
  const double z_scale = z_range > 0.0 ? 1.0 / z_range : 0.0;
  const double e_scale = e_range > 0.0 ? 1.0 / e_range : 0.0;
  for (int c : reachable_) {
    if (blocked_[c]) continue;  // Omega crossed blocked cells (escape): they promise nothing
    const double z0 = (z_[c] - z_mean) * z_scale;
    const double e0 = (e_[c] - e_mean) * e_scale;
    gain_[c] = static_cast<float>(config_.weight_z * logistic(config_.alpha, -z0) +
                                  config_.weight_e * logistic(config_.alpha, -e0));
  }
}

std::vector<int> ExplorationPlanner::plan(const Eigen::Vector2d& position) {
  last_expanded_ = 0;
  last_hit_time_ = false;
  const std::optional<int> start = grid_.cellAt(position);
  if (!start) return {};
  updateNearBlocked();
  computeGain(*start);
  SearchGoal goal;
  goal.min_cells = config_.min_path_cells;
  return search(*start, goal);
}

std::vector<int> ExplorationPlanner::planOutOf(const Eigen::Vector2d& position,
                                               const std::vector<std::uint8_t>& loop_cells) {
  last_expanded_ = 0;
  last_hit_time_ = false;
  const std::optional<int> start = grid_.cellAt(position);
  if (!start || loop_cells.size() != blocked_.size()) return {};
  updateNearBlocked();
  computeGain(*start);
  SearchGoal goal;
  goal.min_cells = config_.commit_min_cells;
  goal.exclude = &loop_cells;
  std::vector<int> path = search(*start, goal);
  if (!path.empty() && !loop_cells[path.back()]) return path;
  computeGain(*start, true);
  goal.cross_blocked = true;
  std::vector<int> escape = search(*start, goal);
  return escape.empty() ? path : escape;
}

std::vector<int> ExplorationPlanner::search(int start_cell, const SearchGoal& goal) {
  const auto t0 = std::chrono::steady_clock::now();
  struct Node {
    int cell;
    int parent;   // index into nodes, -1 for the start
    int length;   // cells after the start
    float cost;   // path cost [cells]: 1 per cell plus the near-blocked and escape extras
    double gain;  // summed gain of the cells after the start
  };
  std::vector<Node> nodes;
  nodes.reserve(static_cast<std::size_t>(config_.planner_max_nodes) * 3);
  nodes.push_back({start_cell, -1, 0, 0.0f, 0.0});
  // (gain per cost, -node index): among equal priorities the older node first, so the order
  // does not depend on how the heap breaks ties.
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry> open;
  std::vector<std::uint8_t>& closed = closed_scratch_;
  std::fill(closed.begin(), closed.end(), 0);
  closed[start_cell] = 1;
  open.push({0.0, 0});
  int best = -1;
  double best_score = -1.0;
  int best_short = -1;  // best among paths that miss the goal (too short or ending excluded)
  double best_short_score = -1.0;
  const float near_cost = static_cast<float>(config_.near_blocked_cost);
  const float escape_cost = static_cast<float>(config_.escape_blocked_cost);
  while (!open.empty() && last_expanded_ < config_.planner_max_nodes) {
    const int index = -open.top().second;
    open.pop();
    const Node node = nodes[static_cast<std::size_t>(index)];
    if (index != 0) {
      if (closed[node.cell]) continue;  // reached before on a path of higher gain per cost
      closed[node.cell] = 1;
    }
    ++last_expanded_;
    if (node.length > 0) {
      // Ties (equal gain per cost) go to the longer path: more progress per plan.
      const double score = node.gain / node.cost + 1e-9 * node.length;
      const bool ends_ok = goal.exclude == nullptr || !(*goal.exclude)[node.cell];
      if (node.length >= goal.min_cells && ends_ok) {
        if (score > best_score) {
          best_score = score;
          best = index;
        }
      } else {
        // Missing the goal: ending outside the excluded cells first, then by gain per cost; or
        // the longest path (the farthest step out of a loop).
        const double fallback = ends_ok ? 1e6 + score : node.length;
        if (fallback > best_short_score) {
          best_short_score = fallback;
          best_short = index;
        }
      }
    }
    if ((last_expanded_ & 63) == 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
            config_.planner_time_budget_s) {
      last_hit_time_ = true;
      break;
    }
    if (node.length >= config_.max_path_cells) continue;
    for (int nb : grid_.neighbours(node.cell)) {
      if (nb < 0 || closed[nb]) continue;
      float step = 1.0f;
      if (blocked_[nb]) {
        if (!goal.cross_blocked) continue;
        step += escape_cost;
      } else if (near_blocked_[nb]) {
        step += near_cost;
      }
      const double gain = node.gain + gain_[nb];
      const float cost = node.cost + step;
      nodes.push_back({nb, index, node.length + 1, cost, gain});
      open.push({gain / cost, -(static_cast<int>(nodes.size()) - 1)});
    }
  }
  const int chosen = best >= 0 ? best : best_short;
  std::vector<int> path;
  for (int i = chosen; i > 0; i = nodes[static_cast<std::size_t>(i)].parent) {
    path.push_back(nodes[static_cast<std::size_t>(i)].cell);
  }
  std::reverse(path.begin(), path.end());
  return path;
}

const char* toString(ExplorationState state) {
  switch (state) {
    case ExplorationState::kExploring:
      return "exploring";
    case ExplorationState::kBackingOut:
      return "backing out";
    case ExplorationState::kNoPose:
      return "no pose";
    case ExplorationState::kStuck:
      return "stuck";
    case ExplorationState::kRelocalising:
      return "relocalising";
  }
  return "unknown";
}

Explorer::Explorer(const ExplorationConfig& config, const Eigen::Vector2d& start)
    : config_(config), planner_(config, start) {}

std::vector<Eigen::Vector2d> Explorer::pathPoints() const {
  std::vector<Eigen::Vector2d> points;
  for (std::size_t i = next_waypoint_; i < path_.size(); ++i) {
    points.push_back(planner_.grid().centre(path_[i]));
  }
  return points;
}

void Explorer::setLocalisationLost(bool lost, double now_s) {
  if (lost == lost_) return;
  lost_ = lost;
  if (lost) {
    lost_since_s_ = now_s;
    ++relocalisations_;
    state_ = ExplorationState::kRelocalising;
    message_ = "localisation lost; driving straight back to re-localise";
    relocalise_direction_ = -1.0;
    path_.clear();
    next_waypoint_ = 0;
  } else {
    lost_since_s_ = -1.0;
    if (state_ == ExplorationState::kRelocalising) state_ = ExplorationState::kExploring;
    message_ = "localisation back; replanning";
    recent_cells_.clear();
  }
  need_plan_ = true;
}

bool Explorer::recordCell(int cell) {
  const auto window = static_cast<std::size_t>(config_.oscillation_window);
  if (window == 0) return false;
  recent_cells_.push_back(cell);
  if (recent_cells_.size() > window) recent_cells_.erase(recent_cells_.begin());
  if (recent_cells_.size() < window) return false;
  std::vector<int> distinct = recent_cells_;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  if (static_cast<int>(distinct.size()) > config_.oscillation_max_cells) return false;
  // A loop: these cells and their neighbours (the robot's body reaches them) are not a goal.
  loop_cells_.assign(static_cast<std::size_t>(planner_.grid().size()), 0);
  for (int c : distinct) {
    loop_cells_[c] = 1;
    for (int nb : planner_.grid().neighbours(c)) {
      if (nb >= 0) loop_cells_[nb] = 1;
    }
  }
  recent_cells_.clear();
  return true;
}

void Explorer::replan(double now_s, const Eigen::Vector2d& position,
                      const GridMap2f* normalisation) {
  if (normalisation != nullptr) planner_.updateLocalisationMap(*normalisation);
  const std::optional<int> cell = planner_.grid().cellAt(position);
  if (committed_ && cell && !loop_cells_[*cell] && next_waypoint_ >= path_.size() &&
      !path_.empty()) {
    committed_ = false;  // the committed plan was driven to its end, out of the loop
  }
  path_ = committed_ ? planner_.planOutOf(position, loop_cells_) : planner_.plan(position);
  next_waypoint_ = 0;
  need_plan_ = false;
  ++replans_;
  if (path_.empty()) {
    state_ = ExplorationState::kStuck;
    message_ = planner_.grid().cellAt(position)
                   ? "no path: every neighbouring cell is blocked; retrying in 2 s"
                   : "no path: the robot is outside the exploration grid";
    retry_plan_at_s_ = now_s + 2.0;
  } else if (state_ == ExplorationState::kStuck) {
    state_ = ExplorationState::kExploring;
    message_.clear();
  }
}

VelocityCommand Explorer::follow(const Pose2& pose) {
  const Eigen::Vector2d position(pose.x, pose.y);
  const auto distance = [&](std::size_t j) {
    return (planner_.grid().centre(path_[j]) - position).norm();
  };
  next_waypoint_ = path_following::nearestAhead(next_waypoint_, path_.size(), 4, distance);
  while (next_waypoint_ < path_.size() && distance(next_waypoint_) < config_.waypoint_tolerance_m) {
    ++next_waypoint_;
  }
  if (next_waypoint_ >= path_.size()) {
    need_plan_ = true;
    return {};
  }
  // Pure pursuit over the cells: steer at the farthest upcoming cell within the look-ahead
  // distance, so that the 60-degree zig-zags of a hex path become one smooth line.
  const std::size_t target =
      path_following::lookaheadTarget(next_waypoint_, path_.size(), config_.lookahead_m, distance);
  return path_following::steerTowards(pose, planner_.grid().centre(path_[target]),
                                      config_.heading_gain, config_.max_turn_rate_rps,
                                      config_.turn_in_place_rad, config_.max_speed_mps);
}

VelocityCommand Explorer::update(double now_s, const std::optional<Pose2>& pose,
                                 const BumpReading& bump, const GridMap2f* normalisation) {
  if (start_time_s_ < 0.0) start_time_s_ = now_s;
  const bool valid =
      pose && std::isfinite(pose->x) && std::isfinite(pose->y) && std::isfinite(pose->theta);
  if (valid) {
    if (pose_ && pose_time_s_ >= 0.0) {
      const double dt = std::max(0.0, now_s - pose_time_s_);
      const double moved = std::hypot(pose->x - pose_->x, pose->y - pose_->y);
      const double turned = std::abs(wrapAngle(pose->theta - pose_->theta));
      if (moved > config_.max_speed_mps * dt + config_.pose_jump_m ||
          turned > config_.max_turn_rate_rps * dt + config_.pose_jump_rad) {
        ++pose_jumps_;
        std::ostringstream text;
        text.precision(2);
        text << "pose jumped by " << moved << " m / " << turned << " rad in " << dt
             << " s; replanning";
        message_ = text.str();
        need_plan_ = true;
      }
    }
    pose_ = *pose;
    pose_time_s_ = now_s;
  }
  const double since_pose = pose_time_s_ < 0.0 ? now_s - start_time_s_ : now_s - pose_time_s_;
  if (!pose_ || since_pose > config_.pose_timeout_s) {
    if (pose_ || since_pose > config_.pose_timeout_s) {
      std::ostringstream text;
      text.precision(2);
      text << std::fixed << "no pose for " << since_pose << " s; stopped";
      message_ = text.str();
      state_ = ExplorationState::kNoPose;
    }
    need_plan_ = true;
    return {};
  }
  if (state_ == ExplorationState::kNoPose) {
    state_ = ExplorationState::kExploring;
    message_ = "pose is back; replanning";
    need_plan_ = true;
  }
  if (lost_ && lost_since_s_ >= 0.0 && now_s - lost_since_s_ > config_.relocalise_timeout_s) {
    lost_since_s_ = -1.0;  // gave up: explore on the pose as it is
    state_ = ExplorationState::kExploring;
    message_ = "not re-localised; exploring on";
    need_plan_ = true;
  }
  if (lost_ && lost_since_s_ >= 0.0) {
    state_ = ExplorationState::kRelocalising;
    if (bump.contact()) {
      // Away from the contact, without marking a map cell from a pose not to be trusted.
      relocalise_direction_ = std::cos(bump.direction_rad) >= 0.0 ? -1.0 : 1.0;
    }
    return {relocalise_direction_ * config_.relocalise_speed_mps, 0.0};
  }
  const Eigen::Vector2d position(pose_->x, pose_->y);
  if (planner_.addCoverage(position)) {
    const std::optional<int> cell = planner_.grid().cellAt(position);
    if (cell && *cell != bump_cell_) bumps_in_a_row_ = 0;
    if (cell && recordCell(*cell)) {
      ++loops_;
      committed_ = true;
      need_plan_ = true;
      message_ = "going round in a loop; committing to a plan out of it";
    }
  }

  if (bump.contact()) {
    ++bumps_;
    planner_.addBump(*pose_, bump.direction_rad);
    const std::optional<int> cell = planner_.grid().cellAt(position);
    ++bumps_in_a_row_;
    bump_cell_ = cell ? *cell : -1;
    // Pressed segments in the front and in the rear half: no straight way out.
    bool front = false, rear = false;
    const int n = std::max(1, bump.segment_count);
    for (int k = 0; k < n; ++k) {
      if (!(bump.segments >> k & 1u)) continue;
      const double c = std::cos(2.0 * kPi * k / n);
      if (c > 0.3) front = true;
      if (c < -0.3) rear = true;
    }
    if ((front && rear) || bumps_in_a_row_ > config_.max_bumps_in_a_row) {
      state_ = ExplorationState::kStuck;
      message_ = front && rear ? "bumped on every side: trapped, stopped"
                               : "too many bumps in a row without leaving the cell; stopped";
      path_.clear();
      retry_plan_at_s_ = now_s + 2.0;
      return {};
    }
    state_ = ExplorationState::kBackingOut;
    backout_until_s_ = now_s + config_.backout_time_s;
    backout_speed_ = std::cos(bump.direction_rad) >= 0.0 ? -config_.backout_speed_mps
                                                         : config_.backout_speed_mps;
    need_plan_ = true;
    return {backout_speed_, 0.0};
  }
  if (state_ == ExplorationState::kBackingOut) {
    if (now_s < backout_until_s_) return {backout_speed_, 0.0};
    state_ = ExplorationState::kExploring;
    message_.clear();
  }
  if (state_ == ExplorationState::kStuck) {
    if (now_s < retry_plan_at_s_) return {};
    bumps_in_a_row_ = 0;
    need_plan_ = true;
  }
  if (need_plan_) replan(now_s, position, normalisation);
  if (state_ == ExplorationState::kStuck) return {};
  VelocityCommand command = follow(*pose_);
  if (need_plan_) {
    replan(now_s, position, normalisation);
    if (state_ == ExplorationState::kStuck) return {};
    command = follow(*pose_);
  }
  return command;
}

RandomBumpAndTurn::RandomBumpAndTurn(const ExplorationConfig& config, std::uint64_t seed)
    : config_(config), rng_(seed) {
  config_.validate();
}

VelocityCommand RandomBumpAndTurn::update(double now_s, const BumpReading& bump) {
  if (bump.contact()) {
    backout_speed_ = std::cos(bump.direction_rad) >= 0.0 ? -config_.backout_speed_mps
                                                         : config_.backout_speed_mps;
    backout_until_s_ = now_s + config_.backout_time_s;
    // New heading: uniformly random in the half plane away from the contact.
    std::uniform_real_distribution<double> away(0.5 * kPi, 1.5 * kPi);
    const double turn = wrapAngle(bump.direction_rad + away(rng_));
    turn_rate_ = turn >= 0.0 ? config_.max_turn_rate_rps : -config_.max_turn_rate_rps;
    turn_until_s_ = backout_until_s_ + std::abs(turn) / config_.max_turn_rate_rps;
    return {backout_speed_, 0.0};
  }
  if (now_s < backout_until_s_) return {backout_speed_, 0.0};
  if (now_s < turn_until_s_) return {0.0, turn_rate_};
  return {config_.max_speed_mps, 0.0};
}

}  // namespace ebslam
