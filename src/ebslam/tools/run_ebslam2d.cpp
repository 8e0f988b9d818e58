// Runs EB-SLAM-2D (thesis 7.2-7.3, alg. 8) offline on an event file at full speed, e.g.
//   ebslam_run_ebslam2d run.ebe --trajectory slam.tum --map-png map.png -N 10
// Writes the pose estimate every --every events as a TUM trajectory (camera pose, z up, in the
// map frame, which starts at --start), the final maps as PNG (M; optionally O and Z) and prints
// the processing rate in events per second.
// Exit status: 0 success, 1 usage / input error.

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "ebslam/slam/ebslam2d.h"
#include "filter_tool_common.h"

int main(int argc, char** argv) {
  using namespace ebslam;
  CLI::App app{"EB-SLAM-2D: event-based SLAM under a ceiling"};
  std::string events_path, trajectory_path, map_png, occurrence_png, normalisation_png;
  tools::RunOptions run;
  bool splat_all = false;
  tools::CameraOptions camera_options;
  Ebslam2dConfig config;
  app.add_option("events", events_path, "event file (binary, text or rpg)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--cell", config.cell_size_wtrig, "map cell size [W_trig]")->capture_default_str();
  app.add_option("--map-size", config.map_size_m, "map side length [m]")->capture_default_str();
  app.add_option("--splat-sigma", config.splat_sigma_wtrig, "occurrence splat sigma [W_trig]")
      ->capture_default_str();
  app.add_flag("--splat-all-particles", splat_all,
               "splat every particle weighted by its score (eq. 7.6) instead of p_*");
  app.add_option("--z-step", config.normalisation_step_px,
                 "update Z after this much image motion of p_* [pixels]")
      ->capture_default_str();
  app.add_option("--z-prior", config.normalisation_prior_px, "Z0 in M = O / (Z + Z0) [pixels]")
      ->capture_default_str();
  app.add_flag("--noise-aware", config.noise_aware_diffusion,
               "scale the per-event diffusion by the estimated signal fraction (robust start "
               "under background activity)");
  app.add_option("--rate-window", config.experimental.rate_window_s,
                 "event-rate window of the noise-aware diffusion [s]")
      ->capture_default_str();
  app.add_option("-o,--trajectory", trajectory_path, "output TUM trajectory");
  app.add_option("--map-png", map_png, "final map M as PNG (dark = likely to fire)");
  app.add_option("--occurrence-png", occurrence_png, "final occurrence map O as PNG");
  app.add_option("--normalisation-png", normalisation_png, "final normalisation map Z as PNG");
  run.add(app, " (map frame)", " (puts the map in its frame)");
  camera_options.add(app);
  tools::addFilterOptions(app, config.filter);
  CLI11_PARSE(app, argc, argv);

  try {
    const Pose2 start_pose = run.startPose();
    if (splat_all) config.splat = OccurrenceSplat::kAllParticles;
    const CeilingCamera camera(camera_options.camera, camera_options.ceiling_m);
    const EventReadResult input = tools::readEventsOrThrow(events_path);
    EventSlam2d slam(config, camera, start_pose);
    Trajectory trajectory;
    const double seconds =
        tools::runFilter(slam, input.events, run.every, trajectory, run.message_us);
    std::printf("EB-SLAM-2D: %zu events, N=%d B=%d K=%d, %.3f s, %.0f events/s\n",
                input.events.size(), config.filter.num_particles, config.filter.batch_size,
                config.filter.resample_every, seconds, input.events.size() / seconds);
    if (!trajectory_path.empty()) writeTumTrajectory(trajectory_path, trajectory);
    if (!map_png.empty()) cv::imwrite(map_png, mapToImage(slam.map()));
    if (!occurrence_png.empty()) cv::imwrite(occurrence_png, mapToImage(slam.occurrence()));
    if (!normalisation_png.empty()) {
      cv::imwrite(normalisation_png, mapToImage(slam.normalisation(), 0.99, false));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
