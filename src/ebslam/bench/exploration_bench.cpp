// Exploration planner step (thesis 7.4) on one core: map update (Z from EB-SLAM's 800 x 800
// normalisation map, E, gain eq. 7.8-7.10) plus the best-first replanning, in the state of a
// half-explored room; beside it, in the same process, EB-SLAM-2D processing the events of one
// 50 ms control period and the closed-loop simulator stepping 50 ms, so the planner's share of
// a control cycle is a ratio of the same machine's work.

#include <cmath>

#include <benchmark/benchmark.h>

#include "ebslam/simulation/closed_loop_simulator.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/ebslam2d.h"
#include "ebslam/slam/exploration.h"

namespace {

constexpr const char* kRoom =
    "start 1 1 0\nwalls\n0 0\n5 0\n5 4\n0 4\n0 0\nobstacle\n2.4 1.5\n3.2 1.5\n3.2 2.2\n2.4 2.2\n"
    "2.4 1.5\n";

// Runs the closed loop with the explorer for `seconds` and keeps the state.
struct Loop {
  ebslam::FloorPlan plan = ebslam::parseFloorPlan(kRoom, "bench room", 0.15);
  ebslam::ClosedLoopSimulator simulator{plan};
  ebslam::EventSlam2d slam{ebslam::Ebslam2dConfig{},
                           ebslam::CeilingCamera(simulator.config().events.camera),
                           ebslam::Pose2{1.0, 1.0, 0.0}};
  ebslam::Explorer explorer{ebslam::ExplorationConfig{}, {1.0, 1.0}};
  ebslam::BumpReading bump;
  ebslam::EventVector events;

  void run(double seconds) {
    for (double t = 0.0; t < seconds; t += 0.05) {
      const ebslam::VelocityCommand command =
          explorer.update(simulator.time(), slam.estimate(), bump, &slam.normalisation());
      events.clear();
      bump = simulator.step(command, 0.05, events);
      slam.process(events);
    }
  }
};

Loop& sharedLoop() {
  static Loop loop = [] {
    Loop l;
    l.run(60.0);
    return l;
  }();
  return loop;
}

// Map update + replanning, as Explorer does on every replan.
void BM_PlannerStep(benchmark::State& state) {
  Loop& loop = sharedLoop();
  ebslam::ExplorationPlanner planner = loop.explorer.planner();  // copy of the explored state
  const ebslam::Pose2 pose = loop.slam.estimate();
  int expanded = 0;
  for (auto _ : state) {
    planner.updateLocalisationMap(loop.slam.normalisation());
    const std::vector<int> path = planner.plan({pose.x, pose.y});
    benchmark::DoNotOptimize(path.data());
    expanded += planner.lastExpandedNodes();
  }
  state.counters["expanded_nodes"] = static_cast<double>(expanded) / state.iterations();
  state.counters["grid_cells"] = planner.grid().size();
}
BENCHMARK(BM_PlannerStep)->Unit(benchmark::kMillisecond);

// EB-SLAM-2D on the events of one 50 ms control period of the same loop.
void BM_SlamControlPeriod(benchmark::State& state) {
  Loop& loop = sharedLoop();
  // 2 s of driving straight at 0.3 m/s from where the loop is: about 40 periods of events.
  ebslam::ClosedLoopSimulator simulator(loop.plan);
  ebslam::EventVector events;
  for (int i = 0; i < 40; ++i) simulator.step({0.3, 0.2}, 0.05, events);
  std::size_t processed = 0;
  for (auto _ : state) {
    state.PauseTiming();
    ebslam::EventSlam2d slam(ebslam::Ebslam2dConfig{},
                             ebslam::CeilingCamera(simulator.config().events.camera),
                             ebslam::Pose2{1.0, 1.0, 0.0});
    state.ResumeTiming();
    slam.process(events);
    processed += events.size();
  }
  // Time per control period = time per iteration / 40.
  state.counters["periods_per_iteration"] = 40;
  state.counters["events_per_period"] = static_cast<double>(events.size()) / 40.0;
  state.counters["events_per_s"] =
      benchmark::Counter(static_cast<double>(processed), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SlamControlPeriod)->Unit(benchmark::kMillisecond);

// The closed-loop simulator (eDVS rendering + robot) for one 50 ms control period.
void BM_SimulatorControlPeriod(benchmark::State& state) {
  Loop& loop = sharedLoop();
  ebslam::ClosedLoopSimulator simulator(loop.plan);
  ebslam::EventVector events;
  double turn = 0.4;
  for (auto _ : state) {
    events.clear();
    const ebslam::BumpReading bump = simulator.step({0.3, turn}, 0.05, events);
    if (bump.contact()) turn = -turn;
    benchmark::DoNotOptimize(events.data());
  }
  state.counters["realtime_factor"] =
      benchmark::Counter(0.05 * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulatorControlPeriod)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
