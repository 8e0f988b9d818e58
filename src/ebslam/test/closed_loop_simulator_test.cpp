#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "ebslam/simulation/closed_loop_simulator.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

const std::string kFloorPlanDir = EBSLAM_FLOOR_PLAN_DIR;

// A 4 m x 3 m room with one box; the robot starts at (1, 1) facing +x.
const char* kSimpleRoom = R"(# test room
name simple
start 1.0 1.0 0.0
walls
0 0
4 0
4 3
0 3
0 0
obstacle  # box
2.5 2.0
3.0 2.0
3.0 2.5
2.5 2.5
2.5 2.0
)";

ClosedLoopSimulatorConfig quietConfig() {
  ClosedLoopSimulatorConfig config;
  config.events.events.noise_rate_hz_per_pixel = 0.0;
  return config;
}

TEST(FloorPlan, ParsesWallsObstaclesAndStart) {
  const FloorPlan plan = parseFloorPlan(kSimpleRoom, "test");
  EXPECT_EQ(plan.name, "simple");
  EXPECT_EQ(plan.walls.size(), 4u);  // the closing vertex is dropped
  ASSERT_EQ(plan.obstacles.size(), 1u);
  EXPECT_TRUE(plan.isFloor({1.0, 1.0}));
  EXPECT_FALSE(plan.isFloor({2.75, 2.25}));  // inside the box
  EXPECT_FALSE(plan.isFloor({5.0, 1.0}));    // outside the walls
  EXPECT_NEAR(plan.clearance({1.0, 1.0}), 1.0, 1e-12);
  EXPECT_NEAR(plan.clearance({2.4, 2.25}), 0.1, 1e-12);  // west face of the box
  EXPECT_TRUE(plan.discFits({1.0, 1.0}, 0.15));
  EXPECT_FALSE(plan.discFits({0.1, 1.0}, 0.15));
}

TEST(FloorPlan, EmptyOrUnclosedPlansAreClearErrors) {
  const auto message = [](const std::string& text) {
    try {
      parseFloorPlan(text, "room.txt");
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message("").find("empty floor plan"), std::string::npos);
  EXPECT_NE(message("# only a comment\n\n").find("empty floor plan"), std::string::npos);
  const std::string unclosed = message("start 1 1 0\nwalls\n0 0\n4 0\n4 3\n0 3\n");
  EXPECT_NE(unclosed.find("not closed"), std::string::npos) << unclosed;
  EXPECT_NE(unclosed.find("room.txt:2"), std::string::npos) << unclosed;  // names the line
  EXPECT_NE(message("start 1 1 0\nwalls\n0 0\n4 0\n4 3\n0 3\n0 0\nobstacle\n1 1\n2 1\n2 2\n1 2\n")
                .find("obstacle polygon is not closed"),
            std::string::npos);
  EXPECT_NE(message("walls\n0 0\n4 0\n4 3\n0 3\n0 0\n").find("no start pose"), std::string::npos);
  EXPECT_NE(message("start 1 1 0\nwalls\n0 0\n4 0\nfour 3\n0 0\n").find("room.txt:5"),
            std::string::npos);
  EXPECT_NE(message("start 1 1 0\n3 4\n").find("outside a walls or obstacle"), std::string::npos);
  EXPECT_NE(message("start 1 1 0\nwalls\n0 0\n4 0\n0 0\n").find("at least three"),
            std::string::npos);
  // Self-intersecting walls (a bow tie) and a start inside an obstacle.
  EXPECT_NE(message("start 1 0.5 0\nwalls\n0 0\n4 3\n4 0\n0 2\n0 0\n").find("intersects itself"),
            std::string::npos);
  EXPECT_NE(message(std::string(kSimpleRoom) + "start 2.75 2.25 0\n").find("no room for the robot"),
            std::string::npos);
  EXPECT_THROW(readFloorPlan("/nonexistent/room.txt"), std::runtime_error);
}

TEST(FloorPlan, ShippedLayoutsParseAndLeaveRoomForTheRobot) {
  int count = 0;
  // Also the held-out layouts in held_out/.
  for (const auto& entry : std::filesystem::recursive_directory_iterator(kFloorPlanDir)) {
    if (entry.path().extension() != ".txt") continue;
    const FloorPlan plan = readFloorPlan(entry.path().string(), 0.15);
    EXPECT_FALSE(plan.name.empty()) << entry.path();
    EXPECT_GE(plan.obstacles.size(), 2u) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 7);
}

TEST(EventStream, MovingInPiecesGivesTheEventsOfOneSimulation) {
  // Constant-speed motion slow enough that no render step is subdivided, with trajectory knots
  // on the render steps: the stream moved knot by knot must reproduce simulate() exactly.
  SimulatorConfig config;
  config.events.seed = 7;
  Trajectory path;
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.004 * i;
    path.push_back(se2ToFloorPose(t, 0.2 * t, 0.05 * t, 0.2 * t));
  }
  const Scene scene = makeCeilingScene(makeLinesAndCirclesTexture(),
                                       visibleCeilingRegion(path, config.camera), 0.01);
  const EventSimulator simulator(config);
  const SimulationResult whole = simulator.simulate(scene, path, 0.0, 0.4);
  ASSERT_GT(whole.signal_events, 1000u);

  const auto pose = [](const StampedPose& p) {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = p.orientation.toRotationMatrix();
    m.translation() = p.position;
    return m;
  };
  EventStream stream(config, scene, pose(path.front()), 0.0);
  EventVector pieces;
  for (std::size_t i = 1; i < path.size(); ++i) {
    stream.moveTo(pose(path[i]), path[i].t_s, pieces);
  }
  EXPECT_EQ(stream.renderSteps(), whole.render_steps);
  ASSERT_EQ(pieces.size(), whole.events.size());
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    ASSERT_EQ(pieces[i].t_us, whole.events[i].t_us) << i;
    ASSERT_EQ(pieces[i].x, whole.events[i].x) << i;
    ASSERT_EQ(pieces[i].y, whole.events[i].y) << i;
    ASSERT_EQ(pieces[i].polarity, whole.events[i].polarity) << i;
  }
  EXPECT_THROW(stream.moveTo(pose(path.back()), 0.1, pieces), std::invalid_argument);  // past
}

TEST(ClosedLoopSimulator, DrivesIntoAWallStopsAndReportsTheBumpInFront) {
  // Facing the south wall (y = 0), 0.45 m away from touching it.
  ClosedLoopSimulator sim(
      parseFloorPlan(std::string(kSimpleRoom) + "start 1.0 0.6 -1.5707963\n", "test"),
      quietConfig());
  EventVector events;
  BumpReading bump;
  int bumps = 0;
  for (int i = 0; i < 60; ++i) {
    bump = sim.step({0.3, 0.0}, 0.05, events);
    if (bump.contact()) {
      ++bumps;
      break;
    }
  }
  ASSERT_EQ(bumps, 1);
  EXPECT_NEAR(sim.pose().y, 0.15, 0.003);     // touching: centre one radius from the wall
  EXPECT_NEAR(bump.direction_rad, 0.0, 0.2);  // straight ahead (the wall is almost square)
  EXPECT_TRUE(bump.segments & 1u);            // segment 0 = forward
  EXPECT_GT(events.size(), 1000u);            // the eDVS saw the motion
  // Pushing on does not move it into the wall; backing off is free and reports no contact.
  sim.step({0.3, 0.0}, 0.5, events);
  EXPECT_GE(sim.pose().y, 0.15 - 1e-9);
  bump = sim.step({-0.2, 0.0}, 0.5, events);
  EXPECT_FALSE(bump.contact());
  EXPECT_GT(sim.pose().y, 0.2);
  // Turning in place at a wall is always possible (disc robot).
  const double theta = sim.pose().theta;
  sim.step({0.0, 1.0}, 0.5, events);
  EXPECT_GT(std::abs(sim.pose().theta - theta), 0.2);
}

TEST(ClosedLoopSimulator, RespectsSpeedAndTurnLimits) {
  ClosedLoopSimulatorConfig config = quietConfig();
  config.simulate_events = false;
  ClosedLoopSimulator sim(parseFloorPlan(kSimpleRoom, "test"), config);
  EventVector events;
  sim.step({5.0, 10.0}, 2.0, events);
  EXPECT_NEAR(sim.velocity().v_mps, config.robot.max_speed_mps, 1e-12);
  EXPECT_NEAR(sim.velocity().omega_rps, config.robot.max_turn_rate_rps, 1e-12);
  EXPECT_TRUE(events.empty());
  const Pose2 before = sim.pose();
  sim.step({5.0, 0.0}, 0.1, events);
  EXPECT_LE(std::hypot(sim.pose().x - before.x, sim.pose().y - before.y),
            config.robot.max_speed_mps * 0.1 + 1e-9);
  EXPECT_THROW(sim.step({NAN, 0.0}, 0.1, events), std::invalid_argument);
  EXPECT_THROW(sim.step({0.0, 0.0}, 0.0, events), std::invalid_argument);
}

TEST(ClosedLoopSimulator, TrappedRobotFeelsContactOnEverySide) {
  // A cell just larger than the robot: forward and backward both bump.
  const FloorPlan plan =
      parseFloorPlan("start 0.2 0.2 0\nwalls\n0 0\n0.4 0\n0.4 0.4\n0 0.4\n0 0\n", "box", 0.15);
  ClosedLoopSimulatorConfig config = quietConfig();
  config.simulate_events = false;
  ClosedLoopSimulator sim(plan, config);
  EventVector events;
  const BumpReading front = sim.step({0.3, 0.0}, 0.5, events);
  const BumpReading back = sim.step({-0.3, 0.0}, 0.5, events);
  ASSERT_TRUE(front.contact());
  ASSERT_TRUE(back.contact());
  EXPECT_NEAR(std::cos(front.direction_rad), 1.0, 0.05);
  EXPECT_NEAR(std::cos(back.direction_rad), -1.0, 0.05);
  EXPECT_TRUE(back.segments & (1u << 4));  // segment 4 of 8 = rear
}

TEST(ClosedLoopSimulator, IsDeterministicForASeed) {
  const FloorPlan plan = parseFloorPlan(kSimpleRoom, "test");
  const auto run = [&plan](std::uint64_t seed) {
    ClosedLoopSimulatorConfig config;
    config.seed = seed;
    ClosedLoopSimulator sim(plan, config);
    EventVector events;
    for (int i = 0; i < 10; ++i) sim.step({0.2, 0.3}, 0.05, events);
    return events;
  };
  const EventVector a = run(3);
  const EventVector b = run(3);
  const EventVector c = run(4);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i].t_us, b[i].t_us);
  EXPECT_NE(a.size(), c.size());  // another ceiling and sensor pattern
}

}  // namespace
}  // namespace ebslam
