// Accuracy and speed of the pose filters' rate cap (EventRateLimiter, the nodes' ~max_event_rate)
// on the simulated floor robot of ebslam_experiment_events2d with a denser stream (a lower
// contrast threshold, --contrast): for every freiburg2_pioneer_* trajectory, seed and cap, the
// events are thinned with the cap (seeded with the filter's seed), then EB-PF and EB-SLAM-2D run
// on what is kept. Writes --out/rate_runs.csv (one line per trajectory, method, cap, seed: events
// in and kept, peak rate, position RMSE (EB-PF direct, EB-SLAM-2D aligned), diverged, events/s
// of processing, real-time factor of filter + thinning) and prints a summary per method and cap
// over the tuning seed (--tune-seed, which chooses the default cap) and the other seeds (held
// out). docs/your_event_camera.md#event-rates reports it.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "ceiling_simulation.h"
#include "ebslam/events/event_rate_limiter.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/events/trajectory_evaluation.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/ebpf.h"
#include "ebslam/slam/ebslam2d.h"
#include "filter_tool_common.h"

namespace fs = std::filesystem;
using namespace ebslam;

namespace {

std::vector<double> parseNumbers(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stod(item));
  return out;
}

// EB-PF's position RMSE in the map frame without alignment (as ebslam_experiment_events2d).
double directRmse(const Trajectory& estimated, const Trajectory& truth) {
  double sum = 0.0;
  int n = 0;
  for (const StampedPose& e : estimated) {
    if (e.t_s < truth.front().t_s || e.t_s > truth.back().t_s) continue;
    sum += (e.position.head<2>() - interpolatePose(truth, e.t_s).position.head<2>()).squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : NAN;
}

// Largest event rate over 10 ms windows [events/s].
double peakRate(const EventVector& events) {
  std::size_t best = 0;
  std::size_t begin = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    while (events[i].t_us - events[begin].t_us >= 10000) ++begin;
    best = std::max(best, i - begin + 1);
  }
  return static_cast<double>(best) / 0.01;
}

struct Result {
  double rmse_m = NAN;
  bool diverged = false;
  double events_per_s = 0.0, realtime_factor = 0.0;
  std::size_t kept = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Accuracy and speed of EB-PF and EB-SLAM-2D under an event rate cap"};
  std::string data_dir = "../shared/data", out_dir = "rate_runs",
              caps_text =
                  "0,1000000,500000,250000,"
                  "125000,60000";
  std::string seeds_text = "1,2,3", only;
  double duration_s = 30.0, contrast = 0.05, failure_m = 0.3, latency_s = 0.02;
  int tune_seed = 1;
  app.add_option("--data", data_dir, "shared data folder (tum-groundtruth inside)")
      ->capture_default_str();
  app.add_option("--out", out_dir, "output folder (simulations cached inside)")
      ->capture_default_str();
  app.add_option("--duration", duration_s, "simulate the first seconds (0 = all)")
      ->capture_default_str();
  app.add_option("--contrast", contrast, "contrast threshold of the simulation (default 0.15)")
      ->capture_default_str();
  app.add_option("--caps", caps_text, "rate caps [events/s]; 0 = no cap")->capture_default_str();
  app.add_option("--seeds", seeds_text, "filter (and thinning) seeds")->capture_default_str();
  app.add_option("--tune-seed", tune_seed, "the seed that chooses the default cap")
      ->capture_default_str();
  app.add_option("--failure", failure_m, "position RMSE counted as diverged [m]")
      ->capture_default_str();
  app.add_option("--ebpf-latency", latency_s, "EB-PF latency compensation [s]")
      ->capture_default_str();
  app.add_option("--only", only, "only trajectories whose name contains this");
  CLI11_PARSE(app, argc, argv);

  try {
    const std::vector<double> caps = parseNumbers(caps_text);
    const std::vector<double> seeds = parseNumbers(seeds_text);
    std::vector<fs::path> mocap;
    for (const auto& entry : fs::directory_iterator(fs::path(data_dir) / "tum-groundtruth")) {
      const std::string name = entry.path().filename().string();
      if (name.find("freiburg2_pioneer_") != std::string::npos &&
          name.find(only) != std::string::npos) {
        mocap.push_back(entry.path());
      }
    }
    std::sort(mocap.begin(), mocap.end());
    if (mocap.empty()) throw std::runtime_error("no freiburg2_pioneer_* files in " + data_dir);
    fs::create_directories(out_dir);
    std::ofstream csv(fs::path(out_dir) / "rate_runs.csv");
    csv << "trajectory,method,cap,seed,events,kept,mean_rate,peak_rate,duration_s,rmse_m,diverged,"
           "events_per_s,realtime_factor\n";
    const CeilingCamera camera(CameraModel{}, kThesisCeilingHeightM);
    // (method, cap) -> (tuning seed results, held-out results)
    std::map<std::pair<std::string, double>, std::pair<std::vector<Result>, std::vector<Result>>>
        summary;
    for (const fs::path& file : mocap) {
      std::string name = file.stem().string();
      name = name.substr(name.find("pioneer_"));
      name = name.substr(0, name.find("-groundtruth"));
      std::ostringstream folder;
      folder << name << "_c" << contrast;
      const tools::Simulated run = tools::simulateFloorRun(
          makeFloorRobotTrajectory(readTumTrajectory(file.string())),
          fs::path(out_dir) / folder.str(), duration_s, 1,
          EventModelConfig{}.noise_rate_hz_per_pixel, CameraModel{}, contrast);
      const double run_s = run.ground_truth.back().t_s - run.ground_truth.front().t_s;
      const double mean_rate = static_cast<double>(run.events.size()) / run_s;
      const double peak = peakRate(run.events);
      std::printf("%s: %zu events over %.1f s, mean %.0f events/s, peak %.0f events/s (10 ms)\n",
                  name.c_str(), run.events.size(), run_s, mean_rate, peak);
      const Pose2 start = tools::toPose2(run.ground_truth.front());
      const GridMap2f likelihood = tools::coarseLikelihood(run.map, camera);
      TrajectoryEvaluationConfig eval;
      eval.estimate_time_offset = false;
      for (double seed_value : seeds) {
        const auto seed = static_cast<std::uint64_t>(seed_value);
        for (double cap : caps) {
          EventRateLimiterConfig limit;
          limit.max_rate_eps = cap;
          limit.seed = seed;
          for (const std::string& method : std::vector<std::string>{"ebpf", "ebslam2d"}) {
            Result r;
            Trajectory estimate;
            const auto t0 = std::chrono::steady_clock::now();
            EventRateLimiter limiter(limit);
            EventVector kept = run.events;
            limiter.thinInPlace(kept);
            r.kept = kept.size();
            double seconds = 0.0;
            if (method == "ebpf") {
              EbpfConfig config;
              config.filter.latency_compensation_s = latency_s;
              config.filter.seed = seed;
              EventParticleFilter filter(config, camera, likelihood, start);
              tools::runFilter(filter, kept, 100, estimate);
              seconds =
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
              r.rmse_m = directRmse(estimate, run.ground_truth);
            } else {
              Ebslam2dConfig config;
              config.filter.seed = seed;
              EventSlam2d slam(config, camera, start);
              tools::runFilter(slam, kept, 100, estimate);
              seconds =
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
              r.rmse_m = evaluateTrajectory(estimate, run.ground_truth, eval).position_rmse_m;
            }
            r.diverged = !(r.rmse_m <= failure_m);
            r.events_per_s = static_cast<double>(run.events.size()) / seconds;
            r.realtime_factor = run_s / seconds;
            csv << name << ',' << method << ',' << cap << ',' << seed << ',' << run.events.size()
                << ',' << r.kept << ',' << mean_rate << ',' << peak << ',' << run_s << ','
                << r.rmse_m << ',' << r.diverged << ',' << r.events_per_s << ','
                << r.realtime_factor << '\n';
            csv.flush();
            std::printf(
                "  %-8s cap %8.0f seed %llu: kept %5.1f %%, RMSE %.2f cm%s, %.2fx real time\n",
                method.c_str(), cap, static_cast<unsigned long long>(seed),
                100.0 * static_cast<double>(r.kept) / static_cast<double>(run.events.size()),
                100 * r.rmse_m, r.diverged ? " (diverged)" : "", r.realtime_factor);
            std::fflush(stdout);
            auto& entry = summary[{method, cap}];
            (static_cast<int>(seed) == tune_seed ? entry.first : entry.second).push_back(r);
          }
        }
      }
    }
    const auto mean = [](const std::vector<Result>& v, double Result::*field) {
      double s = 0.0;
      int n = 0;
      for (const Result& r : v) {
        if (!r.diverged) s += r.*field, ++n;
      }
      return n > 0 ? s / n : NAN;
    };
    const auto diverged = [](const std::vector<Result>& v) {
      return std::count_if(v.begin(), v.end(), [](const Result& r) { return r.diverged; });
    };
    std::printf(
        "\nmethod    cap [ev/s]  seed %d: RMSE [cm] div  | other seeds: RMSE [cm] div  | "
        "real time (all)\n",
        tune_seed);
    for (const auto& [key, results] : summary) {
      std::vector<Result> all = results.first;
      all.insert(all.end(), results.second.begin(), results.second.end());
      std::printf("%-8s %10.0f  %14.2f %4ld  | %18.2f %4ld  | %.2fx\n", key.first.c_str(),
                  key.second, 100 * mean(results.first, &Result::rmse_m), diverged(results.first),
                  100 * mean(results.second, &Result::rmse_m), diverged(results.second),
                  mean(all, &Result::realtime_factor));
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
  return 0;
}
