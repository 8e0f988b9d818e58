#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "ebslam/simulation/exploration_run.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/slam/exploration.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

ExplorationConfig smallGrid() {
  ExplorationConfig config;
  config.grid_extent_m = 4.0;
  return config;
}

TEST(HexGrid, NeighboursAreSixAtEqualDistanceAndSymmetric) {
  const HexGrid grid(0.15, {1.0, -2.0}, 3.0);
  int interior = 0;
  for (int c = 0; c < grid.size(); ++c) {
    ASSERT_EQ(grid.cellAt(grid.centre(c)).value_or(-1), c);
    for (int nb : grid.neighbours(c)) {
      if (nb < 0) continue;
      EXPECT_NEAR((grid.centre(nb) - grid.centre(c)).norm(), 0.15, 1e-9);
      const auto& back = grid.neighbours(nb);
      EXPECT_NE(std::find(back.begin(), back.end(), c), back.end());
    }
    if (std::count(grid.neighbours(c).begin(), grid.neighbours(c).end(), -1) == 0) ++interior;
  }
  EXPECT_GT(interior, grid.size() / 2);
  // A point belongs to the nearest centre; far outside there is no cell.
  const Eigen::Vector2d p(1.03, -1.97);
  const int cell = grid.cellAt(p).value();
  for (int c = 0; c < grid.size(); ++c) {
    EXPECT_LE((grid.centre(cell) - p).norm(), (grid.centre(c) - p).norm() + 1e-12);
  }
  EXPECT_FALSE(grid.cellAt({10.0, 0.0}).has_value());
  EXPECT_THROW(HexGrid(0.0, {0.0, 0.0}, 1.0), std::invalid_argument);
}

TEST(ExplorationPlanner, GainFollowsEq78To710OverTheReachableCells) {
  ExplorationConfig config = smallGrid();
  ExplorationPlanner planner(config, {0.0, 0.0});
  // Some coverage and a normalisation map that grows with x.
  for (double x = -1.0; x <= 0.5; x += 0.05) planner.addCoverage({x, 0.1 * x});
  for (double x = -0.5; x <= 0.0; x += 0.05) planner.addCoverage({x, 0.3});
  GridMap2f normalisation(200, 200, 0.03, -3.0, -3.0);
  for (int r = 0; r < 200; ++r) {
    for (int c = 0; c < 200; ++c) normalisation.at(c, r) = static_cast<float>(c);
  }
  planner.updateLocalisationMap(normalisation);
  planner.addBump({0.5, 0.0, 0.0}, 0.0);
  const int robot = planner.grid().cellAt({0.0, 0.0}).value();
  planner.computeGain(robot);

  // Reference: Omega by flood fill, then eq. 7.8-7.10 literally.
  const auto& z = planner.localisationMap();
  const auto& e = planner.obstacleMap();
  const auto& blocked = planner.blocked();
  std::vector<int> omega{robot};
  std::set<int> seen{robot};
  for (std::size_t i = 0; i < omega.size(); ++i) {
    for (int nb : planner.grid().neighbours(omega[i])) {
      if (nb >= 0 && !blocked[nb] && seen.insert(nb).second) omega.push_back(nb);
    }
  }
  const auto normalise = [&omega](const std::vector<float>& m, int v) {
    double sum = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int u : omega) {
      sum += m[u];
      lo = std::min<double>(lo, m[u]);
      hi = std::max<double>(hi, m[u]);
    }
    return (m[v] - sum / omega.size()) / (hi - lo);
  };
  const auto logistic = [](double x) { return 1.0 / (1.0 + std::exp(-10.0 * x)); };
  for (int v : omega) {
    const double expected = logistic(-normalise(z, v)) + logistic(-normalise(e, v));
    ASSERT_NEAR(planner.gainMap()[v], expected, 1e-5) << v;
  }
  // Z is the mean of the normalisation map over the hex cell: about the column of its centre.
  const Eigen::Vector2d centre = planner.grid().centre(robot);
  EXPECT_NEAR(z[robot], (centre.x() + 3.0) / 0.03 - 0.5, 1.5);
  // Covered cells gain less than untouched ones.
  const int covered = planner.grid().cellAt({-0.5, -0.05}).value();
  const int untouched = planner.grid().cellAt({-0.5, -1.0}).value();
  EXPECT_GT(e[covered], 0.0f);
  EXPECT_EQ(e[untouched], 0.0f);
  EXPECT_LT(planner.gainMap()[covered], planner.gainMap()[untouched]);
  // Blocked cells are outside Omega: no gain.
  for (int c = 0; c < planner.grid().size(); ++c) {
    if (blocked[c]) {
      EXPECT_EQ(planner.gainMap()[c], 0.0f);
    }
  }
}

TEST(ExplorationPlanner, BumpBlocksTheConeInTheContactDirectionOnly) {
  ExplorationConfig config = smallGrid();
  ExplorationPlanner planner(config, {0.0, 0.0});
  const Pose2 pose{0.0, 0.0, kPi / 2};  // facing +y
  planner.addBump(pose, 0.0);           // contact straight ahead: +y
  const HexGrid& grid = planner.grid();
  int blocked = 0;
  for (int c = 0; c < grid.size(); ++c) {
    if (!planner.blocked()[c]) continue;
    ++blocked;
    const Eigen::Vector2d offset = grid.centre(c);
    EXPECT_GT(offset.y(), 0.0);
    EXPECT_LE(std::abs(std::atan2(offset.x(), offset.y())), config.bump_cone_half_angle_rad + 1e-9);
    EXPECT_LE(offset.norm(), config.robot_radius_m + config.bump_cone_depth_m + 1e-9);
  }
  EXPECT_GE(blocked, 2);
  EXPECT_FALSE(planner.blocked()[grid.cellAt({0.0, 0.0}).value()]);    // own cell
  EXPECT_FALSE(planner.blocked()[grid.cellAt({0.0, -0.15}).value()]);  // behind
  EXPECT_TRUE(planner.blocked()[grid.cellAt({0.0, 0.15}).value()]);    // ahead
  ASSERT_EQ(planner.bumpPoints().size(), 1u);
  EXPECT_NEAR(planner.bumpPoints()[0].y(), config.robot_radius_m, 1e-12);
}

TEST(ExplorationPlanner, PlansThroughOpenCellsTowardsTheUnexplored) {
  ExplorationConfig config = smallGrid();
  ExplorationPlanner planner(config, {0.0, 0.0});
  // The left half is explored many times; a wall of blocked cells north of the robot.
  for (int pass = 0; pass < 5; ++pass) {
    for (double x = -1.8; x <= 0.0; x += 0.05) {
      for (double y = -1.8; y <= 1.8; y += 0.1) planner.addCoverage({x, y});
    }
  }
  for (double x = -0.6; x <= 0.6; x += 0.05) planner.addBump({x, 0.2, kPi / 2}, 0.0);
  const std::vector<int> path = planner.plan({0.0, 0.0});
  ASSERT_GE(static_cast<int>(path.size()), config.min_path_cells);
  int previous = planner.grid().cellAt({0.0, 0.0}).value();
  for (int cell : path) {
    const auto& n = planner.grid().neighbours(previous);
    EXPECT_NE(std::find(n.begin(), n.end(), cell), n.end()) << "path cells must be adjacent";
    EXPECT_FALSE(planner.blocked()[cell]);
    previous = cell;
  }
  // Straight into the unexplored right half, and only through unexplored cells.
  EXPECT_GT(planner.grid().centre(path.front()).x(), 0.1);
  for (int cell : path) EXPECT_EQ(planner.obstacleMap()[cell], 0.0f);
  EXPECT_GT(planner.lastExpandedNodes(), 0);
  EXPECT_LE(planner.lastExpandedNodes(), config.planner_max_nodes);
  // Outside the grid there is no plan.
  EXPECT_TRUE(planner.plan({50.0, 0.0}).empty());
}

// A pocket of blocked cells around the robot (x in [-0.6, 0.6], y in [-0.45, 0.45]) whose only
// way out is a gap in the east wall, explored inside. Cone of 0.3 rad, 0.15 m deep.
ExplorationPlanner pocketPlanner(double gap_half_width_m, double near_blocked_cost = 2.0) {
  ExplorationConfig config = smallGrid();
  config.near_blocked_cost = near_blocked_cost;
  config.bump_cone_half_angle_rad = 0.3;
  config.bump_cone_depth_m = 0.15;
  ExplorationPlanner planner(config, {0.0, 0.0});
  for (int pass = 0; pass < 5; ++pass) {
    for (double x = -0.6; x <= 0.6; x += 0.05) {
      for (double y = -0.45; y <= 0.45; y += 0.05) planner.addCoverage({x, y});
    }
  }
  for (double x = -0.75; x <= 0.75; x += 0.05) {
    planner.addBump({x, 0.45, kPi / 2}, 0.0);
    planner.addBump({x, -0.45, -kPi / 2}, 0.0);
  }
  for (double y = -0.6; y <= 0.6; y += 0.05) {
    planner.addBump({-0.6, y, kPi}, 0.0);
    if (std::abs(y) >= gap_half_width_m) planner.addBump({0.6, y, 0.0}, 0.0);
  }
  return planner;
}

// Cells reachable from `from` through cells for which `open` holds.
template <typename Open>
std::vector<std::uint8_t> flood(const HexGrid& grid, int from, Open open) {
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(grid.size()), 0);
  std::vector<int> queue{from};
  seen[from] = 1;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    for (int nb : grid.neighbours(queue[head])) {
      if (nb < 0 || seen[nb] || !open(nb)) continue;
      seen[nb] = 1;
      queue.push_back(nb);
    }
  }
  return seen;
}

TEST(ExplorationPlanner, LeavesAnExploredPocketThroughAGapTheBodyFits) {
  ExplorationPlanner planner = pocketPlanner(0.2);
  const HexGrid& grid = planner.grid();
  const int robot = grid.cellAt({0.0, 0.0}).value();
  const int outside = grid.cellAt({1.5, 0.0}).value();
  const auto& blocked = planner.blocked();
  const auto next_to_blocked = [&](int c) {
    for (int nb : grid.neighbours(c)) {
      if (nb >= 0 && blocked[nb]) return true;
    }
    return false;
  };
  // The room for the test: the way out exists, but only over cells next to blocked ones (so a
  // planner that avoids those whenever it can stays inside), and inside there is room for that.
  ASSERT_TRUE(flood(grid, robot, [&](int c) { return !blocked[c]; })[outside]);
  const auto clear = flood(grid, robot, [&](int c) { return !blocked[c] && !next_to_blocked(c); });
  ASSERT_FALSE(clear[outside]);
  ASSERT_GE(std::count(clear.begin(), clear.end(), 1), 6);
  const std::vector<int> path = planner.plan({0.0, 0.0});
  ASSERT_FALSE(path.empty());
  int previous = robot;
  for (int cell : path) {
    const auto& n = grid.neighbours(previous);
    EXPECT_NE(std::find(n.begin(), n.end(), cell), n.end()) << "path cells must be adjacent";
    EXPECT_FALSE(blocked[cell]);
    previous = cell;
  }
  EXPECT_GT(grid.centre(path.back()).x(), 0.7) << "the plan must leave the pocket";
  // Avoiding cells next to blocked ones at any price (the old rule) keeps the robot inside.
  ExplorationPlanner avoiding = pocketPlanner(0.2, 1e6);
  const std::vector<int> trapped = avoiding.plan({0.0, 0.0});
  ASSERT_FALSE(trapped.empty());
  EXPECT_LT(avoiding.grid().centre(trapped.back()).x(), 0.7);
  // Without a gap there is no way out and the plan stays inside.
  ExplorationPlanner closed = pocketPlanner(0.0);
  const std::vector<int> inside = closed.plan({0.0, 0.0});
  for (int cell : inside) EXPECT_LT(closed.grid().centre(cell).x(), 0.7);
}

TEST(ExplorationPlanner, PrefersKeepingClearOfBlockedCellsWhenThatIsCheap) {
  // A row of blocked cells north of y = 0.2; the unexplored east is reached along the row or a
  // cell further south, which costs nothing extra: the plan keeps clear of the row.
  ExplorationConfig config = smallGrid();
  ExplorationPlanner planner(config, {0.0, 0.0});
  for (int pass = 0; pass < 5; ++pass) {
    for (double x = -2.1; x <= 0.0; x += 0.05) {
      for (double y = -2.1; y <= 2.1; y += 0.1) planner.addCoverage({x, y});
    }
  }
  for (double x = -1.8; x <= 1.8; x += 0.05) planner.addBump({x, 0.0, kPi / 2}, 0.0);
  const std::vector<int> path = planner.plan({0.0, -0.3});
  ASSERT_GE(path.size(), 3u);
  int near = 0;
  for (int cell : path) {
    for (int nb : planner.grid().neighbours(cell)) {
      if (nb >= 0 && planner.blocked()[nb]) {
        ++near;
        break;
      }
    }
  }
  EXPECT_EQ(near, 0);
  EXPECT_GT(planner.grid().centre(path.back()).x(), 0.2);
}

TEST(Explorer, DetectsALoopOfRevisitedCellsAndCommitsToAPlanOutOfIt) {
  ExplorationConfig config = smallGrid();
  Explorer explorer(config, {0.0, 0.0});
  const BumpReading none;
  // Three cells visited in turn: a loop once oscillation_window cell changes have been seen.
  const std::vector<Eigen::Vector2d> cycle{{0.0, 0.0}, {0.15, 0.0}, {0.075, 0.13}};
  double t = 0.0;
  for (int k = 0; k <= config.oscillation_window + 1; ++k) {
    const Eigen::Vector2d& p = cycle[static_cast<std::size_t>(k) % cycle.size()];
    explorer.update(t, Pose2{p.x(), p.y(), 0.0}, none, nullptr);
    t += 0.6;  // slow enough to be no pose jump
    if (k + 1 < config.oscillation_window) {
      EXPECT_EQ(explorer.loopsDetected(), 0u) << k;
    }
  }
  EXPECT_EQ(explorer.loopsDetected(), 1u);
  EXPECT_TRUE(explorer.committed());
  EXPECT_NE(explorer.message().find("loop"), std::string::npos) << explorer.message();
  // The committed plan is long and ends away from the loop's cells and their neighbours.
  const std::vector<Eigen::Vector2d> points = explorer.pathPoints();
  ASSERT_GE(static_cast<int>(points.size()), config.commit_min_cells - 1);
  double nearest = 1e9;
  for (const Eigen::Vector2d& c : cycle) nearest = std::min(nearest, (points.back() - c).norm());
  EXPECT_GT(nearest, 1.5 * config.hex_spacing_m);
  // Normal driving (a new cell at every change) is no loop.
  Explorer straight(config, {0.0, 0.0});
  for (int k = 0; k < 3 * config.oscillation_window; ++k) {
    straight.update(0.6 * k, Pose2{-1.5 + 0.05 * k, 0.0, 0.0}, none, nullptr);
  }
  EXPECT_EQ(straight.loopsDetected(), 0u);
}

TEST(Explorer, ReversesStraightWithoutMappingWhileTheLocalisationIsLost) {
  ExplorationConfig config = smallGrid();
  Explorer explorer(config, {0.0, 0.0});
  const BumpReading none;
  explorer.update(0.0, Pose2{}, none, nullptr);
  explorer.setLocalisationLost(true, 0.05);
  const std::vector<float> e_before = explorer.planner().obstacleMap();
  VelocityCommand command = explorer.update(0.1, Pose2{0.5, 0.5, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kRelocalising);
  EXPECT_EQ(command.v_mps, -config.relocalise_speed_mps);
  EXPECT_EQ(command.omega_rps, 0.0);
  EXPECT_EQ(explorer.planner().obstacleMap(), e_before) << "no coverage from a lost pose";
  BumpReading rear;
  rear.segments = 1u << 4;
  rear.direction_rad = kPi;
  command = explorer.update(0.15, Pose2{0.5, 0.5, 0.0}, rear, nullptr);
  EXPECT_EQ(command.v_mps, config.relocalise_speed_mps) << "forwards after a contact behind";
  EXPECT_EQ(explorer.bumps(), 0u) << "no blocked cells from a lost pose";
  EXPECT_EQ(explorer.relocalisations(), 1u);
  // Tracking is back: a new plan from the trusted pose.
  const std::size_t replans = explorer.replans();
  explorer.setLocalisationLost(false, 0.2);
  command = explorer.update(0.25, Pose2{0.5, 0.5, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kExploring);
  EXPECT_GT(explorer.replans(), replans);
  // Lost for longer than relocalise_timeout_s: explores on regardless.
  explorer.setLocalisationLost(true, 1.0);
  explorer.update(1.0 + 0.5 * config.relocalise_timeout_s, Pose2{0.5, 0.5, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kRelocalising);
  explorer.update(1.1 + config.relocalise_timeout_s, Pose2{0.5, 0.5, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kExploring);
  EXPECT_NE(explorer.message().find("not re-localised"), std::string::npos);
}

TEST(Explorer, StopsAndSaysSoWithoutAPose) {
  Explorer explorer(smallGrid(), {0.0, 0.0});
  const BumpReading none;
  VelocityCommand command = explorer.update(0.0, Pose2{}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kExploring);
  EXPECT_GT(std::abs(command.v_mps) + std::abs(command.omega_rps), 0.0);
  // Poses stop arriving: the robot keeps going only until the timeout.
  command = explorer.update(0.3, std::nullopt, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kExploring);
  command = explorer.update(1.0, std::nullopt, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kNoPose);
  EXPECT_EQ(command.v_mps, 0.0);
  EXPECT_EQ(command.omega_rps, 0.0);
  EXPECT_NE(explorer.message().find("no pose for 1.00 s"), std::string::npos) << explorer.message();
  // A NaN pose is no pose either; a valid one resumes.
  explorer.update(1.1, Pose2{NAN, 0.0, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kNoPose);
  command = explorer.update(1.2, Pose2{}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kExploring);
}

TEST(Explorer, ReplansWhenThePoseJumps) {
  Explorer explorer(smallGrid(), {0.0, 0.0});
  const BumpReading none;
  explorer.update(0.0, Pose2{}, none, nullptr);
  explorer.update(0.05, Pose2{0.01, 0.0, 0.0}, none, nullptr);
  const std::size_t replans = explorer.replans();
  explorer.update(0.1, Pose2{1.0, 0.5, 0.0}, none, nullptr);  // 1.1 m in 50 ms
  EXPECT_EQ(explorer.poseJumps(), 1u);
  EXPECT_GT(explorer.replans(), replans);
  EXPECT_NE(explorer.message().find("pose jumped"), std::string::npos);
  // The new plan starts next to the new pose.
  ASSERT_FALSE(explorer.pathPoints().empty());
  EXPECT_LT((explorer.pathPoints().front() - Eigen::Vector2d(1.0, 0.5)).norm(), 0.4);
}

TEST(Explorer, BacksOutOfABumpAndReportsATrap) {
  Explorer explorer(smallGrid(), {0.0, 0.0});
  BumpReading front;
  front.segments = 1u;  // segment 0: straight ahead
  front.direction_rad = 0.0;
  VelocityCommand command = explorer.update(0.0, Pose2{}, front, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kBackingOut);
  EXPECT_LT(command.v_mps, 0.0);
  EXPECT_EQ(explorer.bumps(), 1u);
  BumpReading rear;
  rear.segments = 1u << 4;
  rear.direction_rad = kPi;
  command = explorer.update(0.1, Pose2{}, rear, nullptr);
  EXPECT_GT(command.v_mps, 0.0);  // contact behind: out forwards
  // Contacts in front and behind at once: trapped.
  BumpReading both;
  both.segments = 1u | (1u << 4);
  both.direction_rad = kPi / 2;
  command = explorer.update(0.2, Pose2{}, both, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kStuck);
  EXPECT_EQ(command.v_mps, 0.0);
  EXPECT_NE(explorer.message().find("every side"), std::string::npos);
}

TEST(Explorer, ReportsStuckWhenEveryNeighbourIsBlocked) {
  Explorer explorer(smallGrid(), {0.0, 0.0});
  const BumpReading none;
  BumpReading bump;
  bump.segments = 1u;
  // Bumps all around (one direction at a time, from the same spot).
  for (int k = 0; k < 12; ++k) {
    bump.direction_rad = 0.0;
    explorer.update(0.1 * k, Pose2{0.0, 0.0, k * kPi / 6}, bump, nullptr);
  }
  const VelocityCommand command = explorer.update(5.0, Pose2{0.0, 0.0, 0.0}, none, nullptr);
  EXPECT_EQ(explorer.state(), ExplorationState::kStuck);
  EXPECT_EQ(command.v_mps, 0.0);
  EXPECT_FALSE(explorer.message().empty());
}

TEST(ExplorationRun, ShortClosedLoopEpisodeCoversAndLocalises) {
  const FloorPlan plan = parseFloorPlan(
      "start 1 1 0\nwalls\n0 0\n3 0\n3 2.5\n0 2.5\n0 0\nobstacle\n2 1.5\n2.4 1.5\n2.4 2\n2 2\n2 "
      "1.5\n",
      "test room", 0.15);
  ExplorationRunConfig config;
  config.duration_s = 5.0;
  const ExplorationRunResult run = runExploration(plan, config);
  ASSERT_GE(run.samples.size(), 5u);
  EXPECT_GT(run.samples.back().covered, run.samples.front().covered + 0.03);
  EXPECT_GT(run.events, 10000u);
  for (const ExplorationSample& s : run.samples) EXPECT_LT(s.position_error_m, 0.15) << s.t_s;
  EXPECT_EQ(run.estimate.size(), 100u);  // one pose per 50 ms control step
  // The baseline drives without SLAM on the same room.
  config.random_baseline = true;
  const ExplorationRunResult baseline = runExploration(plan, config);
  EXPECT_TRUE(baseline.estimate.empty());
  EXPECT_GT(baseline.samples.back().covered, 0.02);
}

TEST(CoverageRaster, ReachableAreaExcludesWhatTheRobotCannotTouch) {
  // 2 m x 1 m room, a wall across x = 1.0 .. 1.1 leaving no gap: only the left part counts.
  const FloorPlan plan = parseFloorPlan(
      "start 0.4 0.5 0\nwalls\n0 0\n2 0\n2 1\n0 1\n0 0\nobstacle\n1 0\n1.1 0\n1.1 1\n1 1\n1 0\n",
      "test", 0.15);
  CoverageRaster coverage(plan, 0.15, 0.01);
  EXPECT_NEAR(coverage.reachableArea(), 1.0, 0.05);  // the left 1 m x 1 m (corners rounded)
  EXPECT_EQ(coverage.coveredFraction(), 0.0);
  coverage.cover({0.5, 0.5});
  EXPECT_NEAR(coverage.coveredFraction(), kPi * 0.15 * 0.15 / coverage.reachableArea(), 0.01);
}

}  // namespace
}  // namespace ebslam
