// Runs the Event-based Particle Filter (thesis 6.4-6.5) offline on an event file against a known
// ceiling edge map, at full speed, e.g.
//   ebslam_run_ebpf run.ebe --edges ceiling_edges.png --map-resolution 0.01 --map-origin -3 -3
//       --start-from ground_truth.tum --trajectory ebpf.tum --particles-png particles.png
// Writes the pose estimate every --every events as a TUM trajectory (camera pose, z up, as the
// simulator's ground truth) and prints the processing rate in events per second.
// Exit status: 0 success, 1 usage / input error.

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ebslam/slam/ebpf.h"
#include "ebslam/slam/ebslam2d.h"
#include "filter_tool_common.h"

int main(int argc, char** argv) {
  using namespace ebslam;
  CLI::App app{"Event-based Particle Filter: localisation under a ceiling with a known edge map"};
  std::string events_path, edges_path, trajectory_path, likelihood_png;
  double map_resolution = 0.01;
  std::vector<double> map_origin{0.0, 0.0};
  tools::RunOptions run;
  tools::CameraOptions camera_options;
  EbpfConfig config;
  app.add_option("events", events_path, "event file (binary, text or rpg)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--edges", edges_path, "ceiling edge map (8-bit image, non-zero = edge)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--map-resolution", map_resolution, "edge map pixel size [m]")
      ->capture_default_str();
  app.add_option("--map-origin", map_origin, "world x y [m] of edge map pixel (0,0)'s centre")
      ->expected(2)
      ->capture_default_str();
  app.add_option("--gamma", config.gamma, "sensor model sigma in W_trig (eq. 6.37)")
      ->capture_default_str();
  app.add_option("-o,--trajectory", trajectory_path, "output TUM trajectory");
  app.add_option("--likelihood-png", likelihood_png, "write the cached sensor model as PNG");
  run.add(app);
  camera_options.add(app);
  tools::addFilterOptions(app, config.filter);
  CLI11_PARSE(app, argc, argv);

  try {
    const Pose2 start_pose = run.startPose();
    const CeilingCamera camera(camera_options.camera, camera_options.ceiling_m);
    const cv::Mat edges = cv::imread(edges_path, cv::IMREAD_GRAYSCALE);
    if (edges.empty()) throw std::runtime_error("cannot read edge map " + edges_path);
    GridMap2f likelihood = makeEdgeLikelihoodMap(
        edges, map_resolution, {map_origin[0], map_origin[1]}, config.gamma * camera.wTrig());
    if (!likelihood_png.empty()) {
      cv::imwrite(likelihood_png, mapToImage(likelihood, 1.0));
    }
    const EventReadResult input = tools::readEventsOrThrow(events_path);
    EventParticleFilter filter(config, camera, std::move(likelihood), start_pose);
    Trajectory trajectory;
    const double seconds =
        tools::runFilter(filter, input.events, run.every, trajectory, run.message_us);
    std::printf("EB-PF: %zu events, N=%d B=%d K=%d, %.3f s, %.0f events/s\n", input.events.size(),
                config.filter.num_particles, config.filter.batch_size, config.filter.resample_every,
                seconds, input.events.size() / seconds);
    if (!trajectory_path.empty()) writeTumTrajectory(trajectory_path, trajectory);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
