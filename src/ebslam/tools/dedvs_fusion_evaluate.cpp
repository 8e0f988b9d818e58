// Evaluates the D-eDVS depth fusion (thesis 8.2, fig. 8.5) on simulated runs: for each TUM
// trajectory a room is built, the D-eDVS simulated, and every event fused with the depth
// frames (nearest frame in time, calibration = the simulated truth). Reports per run the
// share of signal events given a depth, the median absolute depth error against the
// simulator's true depth per depth band beside the depth camera's own median absolute noise
// at that depth (0.674 sigma(z)), and the share of fused events on the wrong surface
// (|error| > 10 % of the true depth), overall and at depth edges. Markdown table on stdout,
// optional CSV.
//
// Example:
//   ebslam_dedvs_fusion_evaluate --trajectory fr1_desk.txt fr1_room.txt fr1_xyz.txt --duration 8

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/dedvs_fusion.h"

namespace {

double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

constexpr double kBands[] = {0.5, 1.0, 1.5, 2.0, 3.0, 4.0};  // true depth bands [m]
constexpr int kBandCount = 5;

// Counts and errors of one run's fusion.
struct FusionStats {
  std::size_t signal = 0, fused = 0, wrong = 0, edge = 0, edge_wrong = 0, edge_neither = 0;
  std::vector<double> errors;  // |fused - true depth| [m]
  // per band: errors and true depths [m]
  std::vector<std::vector<double>> band_errors = std::vector<std::vector<double>>(kBandCount);
  std::vector<std::vector<double>> band_truth = std::vector<std::vector<double>>(kBandCount);
};

// Fuses every signal event of `run` with the depth frames as they would have arrived, and
// scores it against the simulator's true depth. Writes the events of [t_begin + 1, +1.05) s to
// fused_out if it is open.
FusionStats fuseRun(const ebslam::DedvsRun& run, const ebslam::DedvsSimulatorConfig& config,
                    double t_begin, std::ofstream& fused_out) {
  ebslam::DepthEventFusion fusion(ebslam::sensorsOf(config));
  std::size_t next_frame = 0;
  const double half_period = 0.5 / config.depth.frame_rate_hz;
  FusionStats s;
  for (const ebslam::TrueDepthEvent& e : run.events) {
    const double t = e.event.t_us * 1e-6;
    // Frames arrive up to half a period after their exposure: the nearest one is known.
    while (next_frame < run.depth_frames.size() &&
           run.depth_frames[next_frame].t_s <= t + half_period) {
      fusion.addDepthFrame(run.depth_frames[next_frame].depth_mm,
                           run.depth_frames[next_frame].stamp_s);
      ++next_frame;
    }
    if (e.is_noise || !std::isfinite(e.depth_m)) continue;
    ++s.signal;
    const ebslam::FusedEvent f = fusion.fuse(e.event);
    if (fused_out && t >= t_begin + 1.0 && t < t_begin + 1.05) {
      fused_out << e.event.t_us << ' ' << e.event.x << ' ' << e.event.y << ' ' << f.depth_m << ' '
                << e.depth_m << ' ' << f.point.x() << ' ' << f.point.y() << ' ' << f.point.z()
                << '\n';
    }
    if (!std::isfinite(f.depth_m)) continue;
    ++s.fused;
    const double error = std::abs(static_cast<double>(f.depth_m) - e.depth_m);
    s.errors.push_back(error);
    const bool is_wrong = error > 0.1 * e.depth_m;
    s.wrong += is_wrong;
    if (e.at_depth_edge) {
      ++s.edge;
      s.edge_wrong += is_wrong;
      // Neither surface the pixel's footprint covers (3 x 3 rays) within 10 %.
      s.edge_neither +=
          std::abs(f.depth_m - e.neighbourhood_min_depth_m) > 0.1f * e.neighbourhood_min_depth_m &&
          std::abs(f.depth_m - e.neighbourhood_max_depth_m) > 0.1f * e.neighbourhood_max_depth_m;
    }
    for (int b = 0; b < kBandCount; ++b) {
      if (e.depth_m >= kBands[b] && e.depth_m < kBands[b + 1]) {
        s.band_errors[b].push_back(error);
        s.band_truth[b].push_back(e.depth_m);
      }
    }
  }
  return s;
}

// The run's row of the first table (stdout), its band rows (for the second table) and CSV rows.
void reportRun(const std::string& name, double simulated_s, const ebslam::DedvsRun& run,
               const ebslam::DedvsSimulatorConfig& config, const FusionStats& s,
               std::vector<std::string>& band_rows, std::ofstream& csv) {
  const double fused_share = s.signal ? static_cast<double>(s.fused) / s.signal : 0.0;
  const double wrong_share = s.fused ? static_cast<double>(s.wrong) / s.fused : 0.0;
  const double edge_share = s.edge ? static_cast<double>(s.edge_wrong) / s.edge : 0.0;
  const double neither_share = s.edge ? static_cast<double>(s.edge_neither) / s.edge : 0.0;
  std::printf("| %s | %.1f s | %zu | %.1f %% | %.1f mm | %.2f %% | %.2f %% / %.2f %% (%zu) |\n",
              name.c_str(), simulated_s, run.events.size(), 100.0 * fused_share,
              1000.0 * median(s.errors), 100.0 * wrong_share, 100.0 * edge_share,
              100.0 * neither_share, s.edge);
  for (int b = 0; b < kBandCount; ++b) {
    const double z = median(s.band_truth[b]);
    const double camera = 0.674 * ebslam::depthNoiseSigma(config.depth, z);
    char row[256];
    std::snprintf(row, sizeof(row), "| %s | %.1f-%.1f m | %zu | %.1f mm | %.1f mm |", name.c_str(),
                  kBands[b], kBands[b + 1], s.band_errors[b].size(),
                  1000.0 * median(s.band_errors[b]), 1000.0 * camera);
    band_rows.push_back(row);
    if (csv) {
      csv << name << ',' << run.events.size() << ',' << s.signal << ',' << fused_share << ','
          << median(s.errors) << ',' << kBands[b] << '-' << kBands[b + 1] << ','
          << s.band_errors[b].size() << ',' << median(s.band_errors[b]) << ',' << camera << ','
          << wrong_share << ',' << s.edge << ',' << edge_share << ',' << neither_share << '\n';
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Evaluate the D-eDVS depth fusion on simulated TUM hand-held runs"};
  std::vector<std::string> trajectories;
  std::string csv_path;
  double t_begin = 2.0, duration = 8.0;
  std::uint64_t seed = 1;
  app.add_option("--trajectory", trajectories, "TUM trajectories")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--t-begin", t_begin, "start, seconds after each trajectory's start")
      ->capture_default_str();
  app.add_option("--duration", duration, "simulated seconds per run")->capture_default_str();
  app.add_option("--seed", seed, "seed")->capture_default_str();
  app.add_option("--csv", csv_path, "also write the figures as CSV");
  std::string fused_path;
  app.add_option("--fused-out", fused_path,
                 "write the first run's fused events of its second 50 ms after --t-begin + 1 s as "
                 "text: t_us x y fused_depth_m true_depth_m X Y Z (eDVS frame)");
  CLI11_PARSE(app, argc, argv);
  try {
    std::ofstream csv;
    if (!csv_path.empty()) {
      csv.open(csv_path);
      csv << "run,events,signal_events,fused_share,median_abs_error_m,band,band_events,"
             "band_median_abs_error_m,band_camera_median_abs_noise_m,wrong_surface_share,"
             "edge_events,edge_wrong_surface_share\n";
    }
    std::printf(
        "| run | simulated | events | signal events with depth | median abs error | wrong "
        "surface, all fused | at depth edges: wrong vs the pixel centre / neither surface in 3x3 "
        "(edge events) |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    std::vector<std::string> band_rows;
    std::ofstream fused_out;
    if (!fused_path.empty()) fused_out.open(fused_path);
    for (const std::string& path : trajectories) {
      ebslam::Trajectory trajectory = ebslam::readTumTrajectory(path);
      const double t0 = trajectory.front().t_s;
      for (ebslam::StampedPose& pose : trajectory) pose.t_s -= t0;
      const double t_end = std::min(trajectory.back().t_s, t_begin + duration);
      ebslam::RoomSceneConfig room;
      room.seed = seed;
      const ebslam::Scene scene = ebslam::makeRoomScene(trajectory, room);
      ebslam::DedvsSimulatorConfig config;
      config.seed = seed;
      config.events.seed = seed;
      const ebslam::DedvsRun run =
          ebslam::DedvsSimulator(config).simulate(scene, trajectory, t_begin, t_end);
      const FusionStats stats = fuseRun(run, config, t_begin, fused_out);
      if (fused_out) fused_out.close();  // first run only
      reportRun(std::filesystem::path(path).stem().string(), t_end - t_begin, run, config, stats,
                band_rows, csv);
    }
    std::printf(
        "\n| run | true depth | events | median abs error | depth camera's median abs noise at "
        "that depth |\n");
    std::printf("|---|---|---|---|---|\n");
    for (const std::string& row : band_rows) std::printf("%s\n", row.c_str());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "dedvs_fusion_evaluate: %s\n", error.what());
    return 1;
  }
  return 0;
}
