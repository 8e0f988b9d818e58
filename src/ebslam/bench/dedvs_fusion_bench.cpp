// Time per event of the D-eDVS depth fusion (DepthEventFusion::fuse, nearest surface along the
// pixel's precomputed ray) beside the time per event of reading the project's binary event
// file (event_io, same events) in the same process. Input: 0.3 s of a simulated run in front of
// a wall with a box (about 10^5 events).

#include <filesystem>
#include <string>

#include <benchmark/benchmark.h>

#include "ebslam/events/event_io.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/dedvs_fusion.h"

namespace {

struct Fixture {
  ebslam::DedvsSimulatorConfig config;
  ebslam::DedvsRun run;
  ebslam::EventVector events;
  std::string path;
  Fixture() {
    ebslam::DeadLeavesConfig leaves;
    leaves.size_px = 256;
    ebslam::TexturedPlane wall;
    wall.pose.translation() = Eigen::Vector3d(-4.0, -4.0, 2.0);
    wall.size_m = Eigen::Vector2d(8.0, 8.0);
    wall.texture = ebslam::makeDeadLeavesTexture(leaves);
    wall.metres_per_texel = 0.005;
    ebslam::Scene scene;
    scene.planes.push_back(wall);
    ebslam::addBox(scene, Eigen::Vector3d(-0.3, -0.3, 1.0), Eigen::Vector3d(0.1, 0.3, 1.2),
                   wall.texture, 0.005);
    ebslam::Trajectory trajectory;
    for (int i = 0; i <= 10; ++i) {
      ebslam::StampedPose pose;
      pose.t_s = 0.03 * i;
      pose.orientation =
          Eigen::Quaterniond(Eigen::AngleAxisd(0.8 * pose.t_s, Eigen::Vector3d::UnitY()));
      trajectory.push_back(pose);
    }
    run = ebslam::DedvsSimulator(config).simulate(scene, trajectory, 0.0, 0.3);
    for (const ebslam::TrueDepthEvent& e : run.events) events.push_back(e.event);
    path = (std::filesystem::temp_directory_path() / "dedvs_fusion_bench.ebe").string();
    ebslam::writeEventFile(path, events, ebslam::SensorSize{128, 128});
  }
};

Fixture& fixture() {
  static Fixture instance;
  return instance;
}

void BM_DedvsFuseEvent(benchmark::State& state) {
  Fixture& f = fixture();
  ebslam::DepthEventFusion fusion(ebslam::sensorsOf(f.config));
  fusion.addDepthFrame(f.run.depth_frames[4].depth_mm, f.run.depth_frames[4].stamp_s);
  const std::int64_t t_us = static_cast<std::int64_t>(f.run.depth_frames[4].t_s * 1e6);
  double sum = 0.0;
  for (auto _ : state) {
    for (ebslam::Event e : f.events) {
      e.t_us = t_us;  // all against the one frame: the per-event work alone
      sum += fusion.fuse(e).depth_m;
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(f.events.size()));
  state.counters["table_bytes"] = static_cast<double>(fusion.tableBytes());
  state.counters["samples_per_ray"] = fusion.meanSamplesPerRay();
}

void BM_ReadEventFile(benchmark::State& state) {
  Fixture& f = fixture();
  std::size_t count = 0;
  for (auto _ : state) {
    const ebslam::EventReadResult result = ebslam::readEventFile(f.path);
    count += result.events.size();
  }
  benchmark::DoNotOptimize(count);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(f.events.size()));
}

BENCHMARK(BM_DedvsFuseEvent)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadEventFile)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
