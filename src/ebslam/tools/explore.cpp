// Autonomous exploration with EB-SLAM (thesis 7.4) in the closed-loop simulator: runs the
// gain planner (and optionally the random bump-and-turn baseline) on floor plans and seeds, e.g.
//   ebslam_explore src/ebslam/floor_plans/*.txt --seeds 1 2 3 4 5 --baseline --output out/
// Writes per run <layout>_<method>_s<seed>_{series.csv,gt.tum,est.tum,hex.csv,bumps.csv,
// covered.png} and one line per run to summary.csv (scripts/results/exploration_report.py plots
// them). Exit status: 0 success, 1 usage / input error.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ebslam/events/trajectory_evaluation.h"
#include "ebslam/simulation/exploration_run.h"

namespace fs = std::filesystem;

namespace {

using namespace ebslam;

// Position errors of a run: after alignment, raw (the samples' error) and largest [m].
struct RunErrors {
  double rmse_aligned = 0.0, rmse_raw = 0.0, max_error = 0.0;
};

RunErrors runErrors(const ExplorationRunResult& r) {
  RunErrors errors;
  TrajectoryEvaluationConfig eval;
  eval.estimate_time_offset = false;  // simulated events share the ground-truth clock
  eval.max_association_gap_s = 0.1;
  errors.rmse_aligned = evaluateTrajectory(r.estimate, r.ground_truth, eval).position_rmse_m;
  double sum2 = 0.0;
  for (const ExplorationSample& s : r.samples) {
    sum2 += s.position_error_m * s.position_error_m;
    errors.max_error = std::max(errors.max_error, s.position_error_m);
  }
  errors.rmse_raw = std::sqrt(sum2 / static_cast<double>(r.samples.size()));
  return errors;
}

// <stem>_{series.csv,gt.tum,covered.png}, and for SLAM runs _{est.tum,hex.csv,bumps.csv,
// path.csv,log.txt,slam_map.png}.
void writeRunFiles(const std::string& stem, const ExplorationRunResult& r) {
  std::ofstream series(stem + "_series.csv");
  series << "t_s,covered,position_error_m,bumps,contrast,lost\n";
  for (const ExplorationSample& s : r.samples) {
    series << s.t_s << ',' << s.covered << ',' << s.position_error_m << ',' << s.bumps << ','
           << s.contrast << ',' << s.lost << '\n';
  }
  writeTumTrajectory(stem + "_gt.tum", r.ground_truth);
  if (!r.estimate.empty()) {
    writeTumTrajectory(stem + "_est.tum", r.estimate);
    std::ofstream hex(stem + "_hex.csv");
    hex << "x,y,z,e,gain,blocked\n";
    for (std::size_t c = 0; c < r.hex_centres.size(); ++c) {
      hex << r.hex_centres[c].x() << ',' << r.hex_centres[c].y() << ',' << r.z[c] << ',' << r.e[c]
          << ',' << r.gain[c] << ',' << static_cast<int>(r.blocked[c]) << '\n';
    }
    std::ofstream bumps(stem + "_bumps.csv");
    bumps << "x,y\n";
    for (const Eigen::Vector2d& b : r.bump_points) bumps << b.x() << ',' << b.y() << '\n';
    std::ofstream path(stem + "_path.csv");
    path << "x,y\n";
    for (const Eigen::Vector2d& p : r.last_path) path << p.x() << ',' << p.y() << '\n';
    std::ofstream log(stem + "_log.txt");
    for (const std::string& m : r.messages) log << m << '\n';
    cv::imwrite(stem + "_slam_map.png", r.slam_map);
  }
  cv::imwrite(stem + "_covered.png", r.covered);
}

// One line of summary.csv and of the console.
void reportRun(std::ofstream& summary, const std::string& layout, const std::string& method,
               int seed, const ExplorationRunResult& r, double divergence_m) {
  const RunErrors errors = r.estimate.empty() ? RunErrors{} : runErrors(r);
  const double duration = r.samples.empty() ? 0.0 : r.samples.back().t_s;
  const bool diverged = !r.estimate.empty() && !(errors.rmse_aligned <= divergence_m);
  const double per_call_ms = r.planner_calls > 0 ? 1e3 * r.planner_seconds / r.planner_calls : 0.0;
  summary << layout << ',' << method << ',' << seed << ',' << duration << ',' << r.time_to_90_s
          << ',' << (r.samples.empty() ? 0.0 : r.samples.back().covered) << ','
          << r.reachable_area_m2 << ',' << errors.rmse_aligned << ',' << errors.rmse_raw << ','
          << errors.max_error << ',' << diverged << ',' << r.bump_events << ','
          << (duration > 0.0 ? r.bump_events * 60.0 / duration : 0.0) << ',' << r.events << ','
          << r.wall_time_s << ',' << per_call_ms << ',' << r.collapses << ',' << r.relocalisations
          << ',' << r.done_time_s << ',' << r.done_share << ',' << r.covered_at_done << ','
          << r.slow_seconds << '\n';
  summary.flush();
  std::printf(
      "%-10s %-6s seed %d: 90%% at %6.1f s, covered %.3f of %.1f m^2, RMSE %.2f cm "
      "(raw %.2f, max %.2f), %zu bumps, %zu collapses, %.0f s wall, planner %.3f ms/call, "
      "done at %.0f s (share %.3f, true %.3f)\n",
      layout.c_str(), method.c_str(), seed, r.time_to_90_s,
      r.samples.empty() ? 0.0 : r.samples.back().covered, r.reachable_area_m2,
      errors.rmse_aligned * 100, errors.rmse_raw * 100, errors.max_error * 100, r.bump_events,
      r.collapses, r.wall_time_s, per_call_ms, r.done_time_s, r.done_share, r.covered_at_done);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Autonomous exploration with EB-SLAM-2D in the closed-loop simulator"};
  std::vector<std::string> plans;
  std::vector<int> seeds{1};
  std::string output = "exploration_out";
  bool with_baseline = false;
  bool baseline_only = false;
  double baseline_duration_s = 0.0;
  double divergence_m = 0.3;
  ExplorationRunConfig config;
  std::string planner = "gain";
  app.add_option("floor_plans", plans, "floor-plan files")->required()->check(CLI::ExistingFile);
  app.add_option("--seeds", seeds, "seeds (simulator, ceiling, filter, baseline)");
  app.add_option("--output", output, "output directory")->capture_default_str();
  app.add_option("--duration", config.duration_s, "simulated time per run [s]")
      ->capture_default_str();
  app.add_option("--particles", config.slam.filter.num_particles, "EB-SLAM particles")
      ->capture_default_str();
  app.add_option("--stop-at", config.stop_at_coverage, "stop a run at this covered fraction")
      ->capture_default_str();
  app.add_option("--hex-spacing", config.exploration.hex_spacing_m, "hex cell spacing [m]")
      ->capture_default_str();
  app.add_option("--cone-depth", config.exploration.bump_cone_depth_m, "bump cone depth [m]")
      ->capture_default_str();
  app.add_option("--cone-half-angle", config.exploration.bump_cone_half_angle_rad,
                 "bump cone half angle [rad]")
      ->capture_default_str();
  app.add_option("--render-rate", config.simulator.events.render_rate_hz,
                 "event simulator's minimum render rate [Hz]")
      ->capture_default_str();
  app.add_option("--max-step-px", config.simulator.events.max_step_motion_px,
                 "event simulator's largest image motion per render step [px]")
      ->capture_default_str();
  app.add_option("--render-per-substep", config.simulator.render_per_substep,
                 "render the eDVS once per 5 ms kinematics sub-step, as runs made before "
                 "(1/0); default: at --render-rate along the step's path")
      ->capture_default_str();
  app.add_option("--lookahead", config.exploration.lookahead_m, "pure-pursuit look-ahead [m]")
      ->capture_default_str();
  app.add_option("--near-blocked-cost", config.exploration.near_blocked_cost,
                 "extra path cost of a cell next to a blocked cell [cells]")
      ->capture_default_str();
  app.add_option("--max-turn-rate", config.exploration.max_turn_rate_rps,
                 "explorer's largest commanded turn rate [rad/s]")
      ->capture_default_str();
  app.add_option("--relocalise", config.relocalise_when_lost,
                 "turn in place while the tracking monitor reports EB-SLAM lost (1/0)")
      ->capture_default_str();
  app.add_option("--lost-contrast", config.tracking.lost_contrast,
                 "tracking monitor: averaged map contrast below which EB-SLAM is lost")
      ->capture_default_str();
  app.add_option("--backout-time", config.exploration.backout_time_s, "back-out time [s]")
      ->capture_default_str();
  app.add_option("--divergence", divergence_m, "position RMSE counted as divergence [m]")
      ->capture_default_str();
  app.add_option("--planner", planner, "exploring planner: coverage (lanes) or gain (thesis 7.4)")
      ->check(CLI::IsMember({"coverage", "gain"}))
      ->capture_default_str();
  app.add_option("--lane-spacing", config.coverage.lane_spacing_m,
                 "coverage: distance between lanes [m]")
      ->capture_default_str();
  app.add_option("--wall-half-length", config.coverage.wall_half_length_m,
                 "coverage: half length of the wall assumed along a contact's tangent [m]")
      ->capture_default_str();
  app.add_option("--wall-depth", config.coverage.wall_depth_m,
                 "coverage: depth of the wall assumed beyond a contact [m]")
      ->capture_default_str();
  app.add_option("--slow-when-lost", config.slow_when_lost,
                 "coverage: drive slower while the tracking monitor reports EB-SLAM lost (1/0)")
      ->capture_default_str();
  app.add_flag("--baseline", with_baseline, "also run the random bump-and-turn baseline");
  app.add_option("--baseline-duration", baseline_duration_s,
                 "simulated time of the baseline runs [s] (default: --duration); the baseline "
                 "simulates no events, so it can run long enough to reach 90 %");
  app.add_flag("--baseline-only", baseline_only, "run only the baseline");
  CLI11_PARSE(app, argc, argv);
  config.coverage_planner = planner == "coverage";
  config.coverage.max_turn_rate_rps = config.exploration.max_turn_rate_rps;

  try {
    fs::create_directories(output);
    const fs::path summary_path = fs::path(output) / "summary.csv";
    const bool new_summary = !fs::exists(summary_path);
    std::ofstream summary(summary_path, std::ios::app);
    if (new_summary) {
      summary << "layout,method,seed,duration_s,time_to_90_s,final_covered,reachable_area_m2,"
                 "rmse_aligned_m,rmse_raw_m,max_error_m,diverged,bumps,bumps_per_min,events,"
                 "wall_s,planner_ms_per_call,collapses,relocalisations,done_s,done_share,"
                 "covered_at_done,slow_s\n";
    }
    std::vector<bool> methods;  // false: the gain planner, true: the random baseline
    if (!baseline_only) methods.push_back(false);
    if (with_baseline || baseline_only) methods.push_back(true);
    for (const std::string& plan_path : plans) {
      const FloorPlan plan = readFloorPlan(plan_path, config.simulator.robot.radius_m);
      const std::string layout =
          plan.name.empty() ? fs::path(plan_path).stem().string() : plan.name;
      for (int seed : seeds) {
        for (bool baseline : methods) {
          ExplorationRunConfig run = config;
          run.seed = static_cast<std::uint64_t>(seed);
          run.random_baseline = baseline;
          if (baseline && baseline_duration_s > 0.0) run.duration_s = baseline_duration_s;
          const std::string method = baseline ? "random" : planner;
          const std::string stem =
              (fs::path(output) / (layout + "_" + method + "_s" + std::to_string(seed))).string();
          const ExplorationRunResult r = runExploration(plan, run);
          writeRunFiles(stem, r);
          reportRun(summary, layout, method, seed, r, divergence_m);
        }
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "ebslam_explore: %s\n", error.what());
    return 1;
  }
  return 0;
}
