#include <cmath>
#include <optional>
#include <stdexcept>

#include <gtest/gtest.h>

#include "ebslam/simulation/closed_loop_simulator.h"
#include "ebslam/simulation/exploration_run.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/slam/coverage.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(CoverageConfig, RejectsInvalidParameters) {
  CoverageConfig config;
  EXPECT_NO_THROW(config.validate());
  config.lane_spacing_m = 0.0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config = CoverageConfig{};
  config.uncertain_speed_factor = 1.5;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config = CoverageConfig{};
  config.escape_turn_rate_rps = 0.0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config = CoverageConfig{};
  config.cell_m = std::nan("");
  EXPECT_THROW(CoverageMap(config, {0.0, 0.0}), std::invalid_argument);
}

TEST(CoverageMap, LanesRunThroughTheStartOneSpacingApart) {
  CoverageConfig config;
  CoverageMap map(config, {1.0, 2.0});
  const std::optional<int> start = map.cellAt({1.0, 2.0});
  ASSERT_TRUE(start);
  EXPECT_LT((map.centre(*start) - Eigen::Vector2d(1.0, 2.0)).norm(), 1e-9);
  EXPECT_TRUE(map.isLaneRow(map.row(*start)));
  EXPECT_EQ(map.laneStride(), 5);  // 0.25 m / 0.05 m
  EXPECT_TRUE(map.isLaneRow(map.row(*start) + 5));
  EXPECT_FALSE(map.isLaneRow(map.row(*start) + 2));
  // Turned lanes: the lane frame is the map frame rotated by the lane direction.
  config.lane_direction_rad = kPi / 2.0;
  CoverageMap turned(config, {0.0, 0.0});
  EXPECT_LT((turned.toLane({0.0, 1.0}) - Eigen::Vector2d(1.0, 0.0)).norm(), 1e-9);
  EXPECT_LT((turned.fromLane(turned.toLane({0.3, -0.7})) - Eigen::Vector2d(0.3, -0.7)).norm(),
            1e-9);
}

TEST(CoverageMap, ContactBlocksAheadOnlyAndAVisitClearsIt) {
  CoverageMap map(CoverageConfig{}, {0.0, 0.0});
  // Robot at the origin facing +x, contact straight ahead: the wall at x = 0.15.
  map.addContact(Pose2{0.0, 0.0, 0.0}, 0.0);
  ASSERT_EQ(map.contacts().size(), 1u);
  EXPECT_NEAR(map.contacts()[0].x(), 0.15, 1e-9);
  const auto blocked = [&](double x, double y) { return !map.traversable(*map.cellAt({x, y})); };
  EXPECT_FALSE(blocked(0.0, 0.0));    // where the robot stands
  EXPECT_TRUE(blocked(0.1, 0.0));     // ahead
  EXPECT_TRUE(blocked(0.1, 0.15));    // along the wall's tangent
  EXPECT_FALSE(blocked(0.1, 0.35));   // beyond the assumed wall's length
  EXPECT_FALSE(blocked(-0.1, 0.0));   // behind
  EXPECT_FALSE(blocked(-0.1, 0.15));  // behind, beside
  // The robot's centre later passes (0.1, 0.15): the hypothesis is wrong there.
  map.addVisit({0.1, 0.15});
  EXPECT_FALSE(blocked(0.1, 0.15));
  EXPECT_TRUE(blocked(0.1, 0.0));
}

TEST(CoverageMap, NearestOpenLaneSampleAndDoneInASealedBox) {
  CoverageConfig config;
  config.grid_extent_m = 3.0;
  CoverageMap map(config, {0.0, 0.0});
  // Before anything is known the nearest open sample is next to the robot on its lane.
  map.addVisit({0.0, 0.0});
  std::vector<int> path = map.pathToNearestOpen({0.0, 0.0});
  ASSERT_FALSE(path.empty());
  EXPECT_TRUE(map.open(path.back()));
  EXPECT_LT((map.centre(path.back()) - Eigen::Vector2d(0.0, 0.0)).norm(), 0.2);
  // Seal a 1 m x 1 m box of robot centres with contacts every 0.1 m, then sweep its lanes.
  for (double s = -0.5; s <= 0.5 + 1e-9; s += 0.1) {
    map.addContact(Pose2{s, 0.5, kPi / 2.0}, 0.0);
    map.addContact(Pose2{s, -0.5, -kPi / 2.0}, 0.0);
    map.addContact(Pose2{0.5, s, 0.0}, 0.0);
    map.addContact(Pose2{-0.5, s, kPi}, 0.0);
  }
  const CoverageMap::Census before = map.census({0.0, 0.0});
  EXPECT_GT(before.open_reachable, 20);
  EXPECT_LT(before.open_reachable, 150);  // sealed: the 3 m grid beyond is not reachable
  for (double y = -0.5; y <= 0.5 + 1e-9; y += 0.25) {
    for (double x = -0.5; x <= 0.5 + 1e-9; x += 0.02) map.addVisit({x, y});
  }
  EXPECT_TRUE(map.pathToNearestOpen({0.0, 0.0}).empty());
  EXPECT_TRUE(map.pathToNearestOpen({0.0, 0.0}, true).empty());  // contacts seal it
  const CoverageMap::Census after = map.census({0.0, 0.0});
  EXPECT_EQ(after.open_reachable, 0);
  EXPECT_GT(after.visited, 20);
  EXPECT_GT(map.sweptArea(), 1.2);  // 1 m x 1 m of centres plus the body's reach
}

// office seed 2 (EB-SLAM in the loop) said "done" at 20 s with 7 % covered: given-up goals and wall
// hypotheses had closed a pocket around the robot. Before "done" only contacts may stop it.
TEST(CoverageMap, GivenUpCellsAroundTheRobotYieldBeforeDone) {
  CoverageConfig config;
  config.grid_extent_m = 3.0;
  CoverageMap map(config, {0.0, 0.0});
  map.addVisit({0.0, 0.0});
  for (int k = 0; k < 8; ++k) {
    const double a = k * kPi / 4.0;
    map.abandon({0.25 * std::cos(a), 0.25 * std::sin(a)}, 0.12);
  }
  EXPECT_TRUE(map.pathToNearestOpen({0.0, 0.0}).empty());
  EXPECT_EQ(map.census({0.0, 0.0}).open_reachable, 0);
  const std::vector<int> escape = map.pathToNearestOpen({0.0, 0.0}, true);
  ASSERT_FALSE(escape.empty());
  EXPECT_TRUE(map.open(escape.back()));
  EXPECT_GT((map.centre(escape.back()) - Eigen::Vector2d(0.0, 0.0)).norm(), 0.3);
}

TEST(CoverageExplorer, StopsWithoutAPoseAndBacksOutOfABump) {
  CoverageExplorer explorer(CoverageConfig{}, Pose2{0.0, 0.0, 0.0});
  VelocityCommand command = explorer.update(0.0, std::nullopt, {});
  EXPECT_EQ(command.v_mps, 0.0);
  command = explorer.update(1.0, std::nullopt, {});
  EXPECT_EQ(explorer.state(), CoverageState::kNoPose);
  command = explorer.update(1.05, Pose2{0.0, 0.0, 0.0}, {});
  EXPECT_NE(explorer.state(), CoverageState::kNoPose);
  BumpReading bump;
  bump.segments = 1;  // front
  command = explorer.update(1.1, Pose2{0.0, 0.0, 0.0}, bump);
  EXPECT_EQ(explorer.state(), CoverageState::kBackingOut);
  EXPECT_LT(command.v_mps, 0.0);
  EXPECT_EQ(explorer.map().contacts().size(), 1u);
}

// In a corner a contact ahead and one behind alternate: backing out alone never ends. After
// repeat_bumps contacts at one place the explorer turns in place until the contact is behind,
// ignoring contacts while it turns, then drives away from it.
TEST(CoverageExplorer, TurnsAwayFromAPlaceWhereBumpsRepeat) {
  const CoverageConfig config;
  CoverageExplorer explorer(config, Pose2{0.0, 0.0, 0.0});
  explorer.setLocalisationUncertain(true);  // slows driving, not the timed escape
  const Pose2 pose{0.0, 0.0, 0.0};
  explorer.update(0.0, pose, {});
  BumpReading left;
  left.segments = 1u << 2;  // segment 2: 90 degrees, the robot's left
  left.direction_rad = 0.5 * kPi;
  VelocityCommand command;
  double t = 0.0;
  for (int i = 0; i < config.repeat_bumps; ++i) {
    t += 0.05;
    command = explorer.update(t, pose, left);
  }
  EXPECT_EQ(explorer.escapes(), 1u);
  EXPECT_EQ(command.v_mps, 0.0);
  EXPECT_DOUBLE_EQ(command.omega_rps, -config.escape_turn_rate_rps);  // right: contact behind
  const double turn_s = 0.5 * kPi / config.escape_turn_rate_rps;
  for (; t + 0.05 < 0.05 * config.repeat_bumps + turn_s; t += 0.05) {
    command = explorer.update(t + 0.05, pose, left);  // still pressed: ignored while turning
    EXPECT_EQ(command.v_mps, 0.0);
    EXPECT_DOUBLE_EQ(command.omega_rps, -config.escape_turn_rate_rps);
  }
  t += 0.1;
  BumpReading behind;  // the same wall, now behind: does not stop the escape
  behind.segments = 1u << 4;
  behind.direction_rad = kPi;
  command = explorer.update(t, pose, behind);
  EXPECT_DOUBLE_EQ(command.v_mps, config.backout_speed_mps);
  EXPECT_EQ(command.omega_rps, 0.0);
  EXPECT_EQ(explorer.escapes(), 1u);
  // The forward leg ends after escape_forward_m; then the explorer plans again.
  t += config.escape_forward_m / config.backout_speed_mps + 0.1;
  command = explorer.update(t, pose, {});
  EXPECT_NE(explorer.state(), CoverageState::kBackingOut);
}

// The planner on its own in a furnished room, with the true pose and no events (ten times
// faster than with EB-SLAM): it must cover the room, say so and come back.
TEST(CoverageExplorer, SweepsAFurnishedRoomReportsDoneAndReturns) {
  const FloorPlan plan = parseFloorPlan(
      "start 0.5 0.5 0\nwalls\n0 0\n3 0\n3 2.5\n0 2.5\n0 0\n"
      "obstacle\n1.6 1.1\n2.2 1.1\n2.2 1.6\n1.6 1.6\n1.6 1.1\n"
      "obstacle\n0.8 1.8\n0.85 1.8\n0.85 1.85\n0.8 1.85\n0.8 1.8\n",
      "test room", 0.15);
  ClosedLoopSimulatorConfig sim_config;
  sim_config.simulate_events = false;
  ClosedLoopSimulator simulator(plan, sim_config);
  CoverageRaster raster(plan, 0.15, 0.02);
  CoverageExplorer explorer(CoverageConfig{}, plan.start);
  BumpReading bump;
  EventVector events;
  double covered_at_done = -1.0;
  for (int i = 0; i < 20 * 600 && explorer.state() != CoverageState::kDone; ++i) {
    const VelocityCommand command = explorer.update(simulator.time(), simulator.pose(), bump);
    if (explorer.done() && covered_at_done < 0.0) covered_at_done = raster.coveredFraction();
    bump = simulator.step(command, 0.05, events);
    raster.cover({simulator.pose().x, simulator.pose().y});
  }
  EXPECT_EQ(explorer.state(), CoverageState::kDone) << explorer.message();
  EXPECT_GE(covered_at_done, 0.9);
  EXPECT_GE(raster.coveredFraction(), 0.93);
  EXPECT_GE(explorer.coveredShare(), 0.9);
  EXPECT_LT(explorer.doneTime(), 400.0);
  EXPECT_LT(std::hypot(simulator.pose().x - 0.5, simulator.pose().y - 0.5), 0.15);
  EXPECT_GT(explorer.lanes().size(), 8u);
}

}  // namespace
}  // namespace ebslam
