// Simulates the D-eDVS (thesis 8.2) carried along a hand-held TUM trajectory through a
// furnished room and writes the run as files (layout in ebslam/simulation/dedvs_io.h): events with
// true depth, depth and colour frames, ground-truth trajectories, sensors.yaml.
//
// Example:
//   ebslam_dedvs_simulate --trajectory rgbd_dataset_freiburg1_desk-groundtruth.txt
//     --duration 10 --output out/desk
// Times in the output are seconds (events: microseconds) since the trajectory's first pose.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"

int main(int argc, char** argv) {
  CLI::App app{"Simulate the D-eDVS (eDVS + depth camera) along a TUM trajectory in a room"};
  std::string trajectory_path, output;
  double t_begin = 0.0, duration = 5.0, contrast = 0.35, speed = 1.0;
  std::uint64_t seed = 1;
  int depth_width = 320;
  app.add_option("--trajectory", trajectory_path, "TUM trajectory of the rig (depth optical frame)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--output", output, "output directory")->required();
  app.add_option("--t-begin", t_begin, "start, seconds after the trajectory start")
      ->capture_default_str();
  app.add_option("--duration", duration, "simulated time [s]; <= 0: to the end")
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the room, the event model and the depth noise")
      ->capture_default_str();
  app.add_option("--texture-contrast", contrast, "dead-leaves texture contrast in [0, 2]")
      ->capture_default_str();
  app.add_option("--speed", speed, "time scale of the trajectory (2 = twice as fast)")
      ->capture_default_str();
  app.add_option("--depth-width", depth_width, "depth image width: 320 or 640")
      ->capture_default_str()
      ->check(CLI::IsMember({320, 640}));
  CLI11_PARSE(app, argc, argv);
  try {
    ebslam::Trajectory trajectory = ebslam::readTumTrajectory(trajectory_path);
    if (trajectory.size() < 2) throw std::runtime_error("trajectory has fewer than two poses");
    const double t0 = trajectory.front().t_s;
    for (ebslam::StampedPose& pose : trajectory) pose.t_s = (pose.t_s - t0) / speed;
    const double t_end = duration > 0.0 ? std::min(trajectory.back().t_s, t_begin + duration)
                                        : trajectory.back().t_s;
    ebslam::RoomSceneConfig room;
    room.seed = seed;
    room.texture_contrast = contrast;
    const ebslam::Scene scene = ebslam::makeRoomScene(trajectory, room);
    ebslam::DedvsSimulatorConfig config;
    config.seed = seed;
    config.events.seed = seed;
    config.depth.camera = config.depth.camera.scaled(depth_width / 320.0);
    const ebslam::DedvsSimulator simulator(config);
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    const ebslam::DedvsRun run = simulator.simulate(scene, trajectory, t_begin, t_end);
    const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ebslam::writeDedvsRun(output, run, ebslam::sensorsOf(config));
    const double simulated = t_end - t_begin;
    std::printf(
        "simulated %.2f s: %zu events (%zu signal, %zu noise), %.0f events/s, %zu renders, "
        "%zu depth frames, %zu planes\n",
        simulated, run.events.size(), run.signal_events, run.noise_events,
        run.events.size() / simulated, run.render_steps, run.depth_frames.size(),
        scene.planes.size());
    std::printf("cpu %.2f s (wall %.2f s): %.2f x real time on one core\n", cpu_s, wall_s,
                simulated / cpu_s);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "dedvs_simulate: %s\n", error.what());
    return 1;
  }
  return 0;
}
