// Floor-robot experiment of thesis 6.5.3 / 7.3 in simulation: for every freiburg2_pioneer_*
// motion-capture trajectory, an eDVS looking up at a ceiling 2.59 m above is driven along the
// planar robot path (event simulator), then EB-PF (known ceiling edge map) and EB-SLAM-2D
// (N = 5, 10, 25, 75) run on the events with several seeds. Writes into --out:
//   runs.csv               one line per (trajectory, method, N, B, K, G0, seed): RMSE, failure,
//                          events/s; EB-PF also without latency compensation and its best time
//                          offset; methods ebpf_g0 / ebslam2d_g0 are the G0 sweeps
//   <traj>/events.ebe, ground_truth.tum, ceiling_edges.png, ceiling.png  (cached simulation)
//   <traj>/ebpf_s<seed>.tum, slam_N<n>_s<seed>.tum (+ _map.png for the first seed)
// With --noise-rates, the same trajectories are simulated again at each background-activity rate
// (<traj>/noise<rate>/, with the simulator's noise label per event) and EB-PF (first K) and
// EB-SLAM-2D (N = 10) run with --noise-seeds seeds on the raw events ("off") and on the events the
// background-activity filter passes ("filter"):
//   noise_runs.csv         the columns of runs.csv plus noise_rate, variant
//   denoise.csv            signal kept / noise removed of the filter against the labels per
//                          trajectory, rate and support window
// docs/results/events2d.md is generated from it by scripts/results/events2d_report.py; the whole
// pipeline is scripts/results/events2d_experiment.sh.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ceiling_simulation.h"
#include "ebslam/events/event_denoiser.h"
#include "ebslam/events/event_io.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/events/trajectory_evaluation.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/ebpf.h"
#include "ebslam/slam/ebslam2d.h"
#include "filter_tool_common.h"

namespace fs = std::filesystem;
using namespace ebslam;

namespace {

using tools::Simulated;

Simulated simulateRun(const fs::path& mocap, const fs::path& dir, double duration_s,
                      std::uint64_t seed, double noise_rate_hz, const CameraModel& camera) {
  return tools::simulateFloorRun(makeFloorRobotTrajectory(readTumTrajectory(mocap.string())), dir,
                                 duration_s, seed, noise_rate_hz, camera);
}

// Position / rotation RMSE of an EB-PF run in the map (= world) frame, no alignment; the
// estimate at time t is compared with the ground truth at t + offset_s, using every `stride`-th
// estimate.
std::pair<double, double> directRmse(const Trajectory& estimated, const Trajectory& truth,
                                     double offset_s = 0.0, std::size_t stride = 1) {
  double sp = 0.0, sr = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < estimated.size(); i += stride) {
    const StampedPose& e = estimated[i];
    const double t = e.t_s + offset_s;
    if (t < truth.front().t_s || t > truth.back().t_s) continue;
    const StampedPose g = interpolatePose(truth, t);
    sp += (e.position.head<2>() - g.position.head<2>()).squaredNorm();
    const double dth =
        std::remainder(tools::toPose2(e).theta - tools::toPose2(g).theta, 2.0 * M_PI);
    sr += dth * dth;
    ++n;
  }
  if (n == 0) return {NAN, NAN};
  return {std::sqrt(sp / n), std::sqrt(sr / n) * 180.0 / M_PI};
}

// The thesis smooths the EB-PF path with a mean filter for display (6.5.3); centred moving mean
// of the positions over 2 * half + 1 estimates.
Trajectory meanFiltered(const Trajectory& t, int half) {
  Trajectory out = t;
  const int n = static_cast<int>(t.size());
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int j = std::max(0, i - half); j <= std::min(n - 1, i + half); ++j, ++count) {
      sum += t[j].position;
    }
    out[i].position = sum / count;
  }
  return out;
}

// Time offset [s] that minimises the direct position RMSE (the lag of the estimate behind the
// ground truth is -offset): 5 ms grid over [-80, 40] ms, then 1 ms around the best.
double bestTimeOffset(const Trajectory& estimated, const Trajectory& truth) {
  const auto cost = [&](double off) { return directRmse(estimated, truth, off, 4).first; };
  double best = 0.0, best_cost = cost(0.0);
  for (int ms = -80; ms <= 40; ms += 5) {
    const double c = cost(1e-3 * ms);
    if (c < best_cost) best_cost = c, best = 1e-3 * ms;
  }
  const double centre = best;
  for (int ms = -4; ms <= 4; ++ms) {
    const double c = cost(centre + 1e-3 * ms);
    if (c < best_cost) best_cost = c, best = centre + 1e-3 * ms;
  }
  return best;
}

// Comma-separated numbers, e.g. "25,100" (throws std::invalid_argument on a bad item).
template <typename T>
std::vector<T> parseList(const std::string& text) {
  std::vector<T> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if constexpr (std::is_same_v<T, std::string>) {
      out.push_back(item);
    } else if constexpr (std::is_integral_v<T>) {
      out.push_back(static_cast<T>(std::stoi(item)));
    } else {
      out.push_back(static_cast<T>(std::stod(item)));
    }
  }
  return out;
}

// The command line.
struct Options {
  std::string data_dir = "../shared/data";
  std::string out_dir = "events2d_runs";
  std::string particles_text = "5,10,25,75";
  std::string ebpf_resample_text = "25,100";
  double duration_s = 0.0;
  int seeds = 3;
  double failure_m = 0.3;
  double g0_ebpf = EbpfConfig{}.filter.g0;
  double g0_slam = Ebslam2dConfig{}.filter.g0;
  double latency_s = 0.02;
  std::string g0_sweep_ebpf = "30,60,100,250";
  std::string g0_sweep_slam = "30,60,100";
  int batch = 3;
  std::string noise_rates_text;
  int noise_seeds = 10;
  std::string denoise_windows_text = "10000,20000,50000,100000,200000";
  BackgroundActivityFilterConfig denoise;
  bool noise_only = false;
  std::string noise_variants_text = "off,filter,robust,filter+robust";
  std::string trajectory_filter;
  std::string camera = "edvs128";
  bool scale_g0 = false;
  CameraModel camera_model;  // from `camera`
  double g0_factor = 1.0;    // applied to every G0 when scale_g0
};

void addOptions(CLI::App& app, Options& o) {
  app.add_option("--data", o.data_dir, "shared data folder (tum-groundtruth inside)")
      ->capture_default_str();
  app.add_option("--out", o.out_dir, "output folder")->capture_default_str();
  app.add_option("--duration", o.duration_s, "simulate only the first seconds (0 = all)")
      ->capture_default_str();
  app.add_option("--seeds", o.seeds, "filter seeds per trajectory")->capture_default_str();
  app.add_option("--slam-particles", o.particles_text, "EB-SLAM-2D particle counts")
      ->capture_default_str();
  app.add_option("--ebpf-resample", o.ebpf_resample_text,
                 "EB-PF resampling intervals K (the thesis' default is 100)")
      ->capture_default_str();
  app.add_option("--failure", o.failure_m, "aligned position RMSE counted as diverged [m]")
      ->capture_default_str();
  app.add_option("--g0-ebpf", o.g0_ebpf, "G0 of EB-PF")->capture_default_str();
  app.add_option("--g0-slam", o.g0_slam, "G0 of EB-SLAM-2D")->capture_default_str();
  app.add_option("--ebpf-latency", o.latency_s,
                 "EB-PF latency compensation [s] (EventFilterConfig::latency_compensation_s)")
      ->capture_default_str();
  app.add_option("--g0-sweep-ebpf", o.g0_sweep_ebpf,
                 "G0 values compared for EB-PF (first K of --ebpf-resample; empty: none)")
      ->capture_default_str();
  app.add_option("--g0-sweep-slam", o.g0_sweep_slam,
                 "G0 values compared for EB-SLAM-2D at N = 10 (empty: none)")
      ->capture_default_str();
  app.add_option("-B,--batch", o.batch, "batch size B")->capture_default_str();
  app.add_option("--noise-rates", o.noise_rates_text,
                 "background-activity rates [Hz per pixel] of the noise runs (empty: none)")
      ->capture_default_str();
  app.add_option("--noise-seeds", o.noise_seeds, "filter seeds per noise run")
      ->capture_default_str();
  app.add_option("--denoise-window-us", o.denoise.window_us,
                 "support window of the background-activity filter [us]")
      ->capture_default_str();
  app.add_flag("--denoise-refractory", o.denoise.refractory_filter,
               "also the per-pixel refractory filter");
  app.add_option("--noise-variants", o.noise_variants_text,
                 "variants of the noise runs: off, filter, robust, filter+robust")
      ->capture_default_str();
  app.add_option("--only", o.trajectory_filter, "only trajectories whose name contains this");
  app.add_flag("--noise-only", o.noise_only,
               "only the noise runs (the default-noise runs and G0 sweeps are left out)");
  app.add_option("--camera", o.camera,
                 "upward event camera: edvs128, davis240, davis346, vga, hd720 (the thesis' lens "
                 "scaled to the sensor: same horizontal field of view)")
      ->capture_default_str();
  app.add_option("--scale-g0", o.scale_g0,
                 "scale every G0 (events per pixel of motion, eq. 6.8) by the focal length "
                 "relative to the thesis' eDVS (an edge spans that many more pixels); off by "
                 "default: on a DAVIS346 it shrinks EB-PF's diffusion until the filter lags "
                 "behind a turn (40-45 cm on pioneer_360, 0.37 cm without)")
      ->capture_default_str();
  app.add_option("--denoise-windows", o.denoise_windows_text,
                 "support windows [us] scored against the noise labels")
      ->capture_default_str();
}

SensorSize sensorSize(const Options& o) {
  return {static_cast<std::uint32_t>(o.camera_model.width),
          static_cast<std::uint32_t>(o.camera_model.height)};
}

// The freiburg2_pioneer_* trajectories of the shared data whose name contains `filter`, sorted.
std::vector<fs::path> pioneerTrajectories(const std::string& data_dir, const std::string& filter) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(fs::path(data_dir) / "tum-groundtruth")) {
    const std::string name = entry.path().filename().string();
    if (name.find("freiburg2_pioneer_") != std::string::npos &&
        name.find(filter) != std::string::npos) {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no freiburg2_pioneer_* files in " + data_dir);
  return files;
}

// Runs EB-PF and EB-SLAM-2D on one simulated trajectory and writes a CSV line per run.
class TrajectoryRuns {
 public:
  TrajectoryRuns(const Options& options, const std::string& name, const fs::path& dir,
                 const Simulated& run, const CeilingCamera& camera)
      : options_(options),
        name_(name),
        dir_(dir),
        run_(run),
        camera_(camera),
        run_duration_(run.ground_truth.back().t_s - run.ground_truth.front().t_s),
        start_(tools::toPose2(run.ground_truth.front())),
        likelihood_(tools::coarseLikelihood(run.map, camera)) {
    eval_.estimate_time_offset = false;  // simulated events share the ground truth's clock
  }

  double duration() const { return run_duration_; }

  void ebpf(const std::string& method, int k, double g0, int seed, bool save,
            const EventVector& events, std::ostream& out, const std::string& suffix) const {
    EbpfConfig config;
    config.filter.resample_every = k;
    config.filter.g0 = g0 * options_.g0_factor;
    config.filter.batch_size = options_.batch;
    config.filter.latency_compensation_s = options_.latency_s;
    config.filter.seed = static_cast<std::uint64_t>(seed);
    EventParticleFilter filter(config, camera_, likelihood_, start_);
    // As tools::runFilter, recording the compensated and the raw estimate.
    Trajectory estimate, raw;
    const auto t_start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < events.size(); i += 100) {
      const std::size_t n = std::min<std::size_t>(100, events.size() - i);
      filter.process(events.data() + i, n);
      const double t = static_cast<double>(events[i + n - 1].t_us) * 1e-6;
      if (!estimate.empty() && t <= estimate.back().t_s) continue;
      estimate.push_back(tools::toStampedPose(t, filter.estimate()));
      raw.push_back(tools::toStampedPose(t, filter.rawEstimate()));
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    if (save) {
      writeTumTrajectory(
          (dir_ / ("ebpf_K" + std::to_string(k) + "_s" + std::to_string(seed) + ".tum")).string(),
          estimate);
    }
    const Trajectory& truth = run_.ground_truth;
    const auto [pos, rot] = directRmse(estimate, truth);
    const double pos_raw = directRmse(raw, truth).first;
    const double offset = bestTimeOffset(raw, truth);
    const bool failed = !(pos <= options_.failure_m);
    const double smoothed = directRmse(meanFiltered(estimate, 10), truth).first;
    out << name_ << ',' << method << ',' << config.filter.num_particles << ',' << options_.batch
        << ',' << k << ',' << g0 << ',' << options_.latency_s << ',' << seed << ',' << events.size()
        << ',' << run_duration_ << ',' << pos << ',' << rot << ',' << failed << ','
        << events.size() / seconds << ',' << smoothed << ',' << pos_raw << ',' << offset << suffix
        << '\n';
    out.flush();
    std::printf(
        "  %-8s N=%3d K=%3d G0=%5.0f seed %d: RMSE %.2f cm %.2f deg (raw %.2f cm, best "
        "offset %+.0f ms), %.0f events/s\n",
        method.c_str(), config.filter.num_particles, k, g0, seed, pos * 100, rot, pos_raw * 100,
        offset * 1e3, events.size() / seconds);
    std::fflush(stdout);
  }

  void slam(const std::string& method, int n, double g0, int seed, bool save,
            const EventVector& events, std::ostream& out, const std::string& suffix,
            bool noise_aware = false) const {
    Ebslam2dConfig config;
    config.noise_aware_diffusion = noise_aware;
    config.filter.g0 = g0 * options_.g0_factor;
    config.filter.batch_size = options_.batch;
    config.filter.num_particles = n;
    config.filter.seed = static_cast<std::uint64_t>(seed);
    EventSlam2d slam(config, camera_, start_);
    Trajectory estimate;
    const double seconds = tools::runFilter(slam, events, 100, estimate);
    const std::string stem = "slam_N" + std::to_string(n) + "_s" + std::to_string(seed);
    if (save) {
      writeTumTrajectory((dir_ / (stem + ".tum")).string(), estimate);
      if (seed == 1) cv::imwrite((dir_ / (stem + "_map.png")).string(), mapToImage(slam.map()));
    }
    const TrajectoryEvaluation e = evaluateTrajectory(estimate, run_.ground_truth, eval_);
    const bool failed = !(e.position_rmse_m <= options_.failure_m);
    out << name_ << ',' << method << ',' << n << ',' << options_.batch << ','
        << config.filter.resample_every << ',' << g0 << ",0," << seed << ',' << events.size() << ','
        << run_duration_ << ',' << e.position_rmse_m << ',' << e.rotation_rmse_deg << ',' << failed
        << ',' << events.size() / seconds << ",,," << suffix << '\n';
    out.flush();
    std::printf("  %-8s N=%3d G0=%5.0f seed %d: RMSE %.2f cm %.2f deg%s, %.0f events/s\n",
                method.c_str(), n, g0, seed, e.position_rmse_m * 100, e.rotation_rmse_deg,
                failed ? " (diverged)" : "", events.size() / seconds);
    std::fflush(stdout);
  }

 private:
  const Options& options_;
  const std::string name_;
  const fs::path dir_;
  const Simulated& run_;
  const CeilingCamera& camera_;
  const double run_duration_;
  const Pose2 start_;
  const GridMap2f likelihood_;
  TrajectoryEvaluationConfig eval_;
};

// The runs at the simulator's default noise: EB-PF per K, EB-SLAM-2D per N, and the G0 sweeps
// (over every trajectory and seed: the defaults are chosen on the whole set).
void defaultNoiseRuns(const Options& o, const TrajectoryRuns& runs, const EventVector& events,
                      std::ostream& csv) {
  const std::vector<int> ebpf_k = parseList<int>(o.ebpf_resample_text);
  for (int k : ebpf_k) {
    for (int seed = 1; seed <= o.seeds; ++seed) {
      runs.ebpf("ebpf", k, o.g0_ebpf, seed, true, events, csv, "");
    }
  }
  for (int n : parseList<int>(o.particles_text)) {
    for (int seed = 1; seed <= o.seeds; ++seed) {
      runs.slam("ebslam2d", n, o.g0_slam, seed, true, events, csv, "");
    }
  }
  for (double g0 : parseList<double>(o.g0_sweep_ebpf)) {
    if (ebpf_k.empty() || g0 == o.g0_ebpf) continue;  // the main runs above
    for (int seed = 1; seed <= o.seeds; ++seed) {
      runs.ebpf("ebpf_g0", ebpf_k[0], g0, seed, false, events, csv, "");
    }
  }
  for (double g0 : parseList<double>(o.g0_sweep_slam)) {
    if (g0 == o.g0_slam) continue;
    for (int seed = 1; seed <= o.seeds; ++seed) {
      runs.slam("ebslam2d_g0", 10, g0, seed, false, events, csv, "");
    }
  }
}

// The background-activity filter scored against the noise labels, per support window, support
// and polarity rule: a line of denoise.csv each.
void scoreDenoiser(const Options& o, const std::string& name, double rate, const Simulated& noisy,
                   std::ostream& denoise_csv) {
  for (int window : parseList<int>(o.denoise_windows_text)) {
    for (const auto& [support, polarity] :
         {std::pair<int, bool>{1, false}, {1, true}, {2, false}, {2, true}, {3, true}, {4, true}}) {
      BackgroundActivityFilterConfig c = o.denoise;
      c.window_us = window;
      c.min_support = support;
      c.polarity_match = polarity;
      const auto t_start = std::chrono::steady_clock::now();
      const DenoisingScore d = scoreDenoising(c, sensorSize(o), noisy.events, noisy.noise_labels);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      denoise_csv << name << ',' << rate << ',' << window << ',' << support << ',' << polarity
                  << ',' << c.refractory_filter << ',' << d.signal << ',' << d.signal_kept << ','
                  << d.noise << ',' << d.noise_removed << ',' << noisy.events.size() / seconds
                  << '\n';
      std::printf(
          "  noise %g Hz, window %d us, support %d%s: signal kept %.1f %%, noise removed "
          "%.1f %%\n",
          rate, window, support, polarity ? " same polarity" : "", 100.0 * d.signalKeptFraction(),
          100.0 * d.noiseRemovedFraction());
    }
  }
  denoise_csv.flush();
}

// Noise runs: the trajectory simulated again at background-activity rate `rate`, the denoiser
// scored, then EB-PF (first K) and EB-SLAM-2D (N = 10) per seed and variant.
void noiseRuns(const Options& o, const fs::path& mocap, const fs::path& dir,
               const std::string& name, double rate, const TrajectoryRuns& runs,
               std::ostream& noise_csv, std::ostream& denoise_csv) {
  char rate_text[32];
  std::snprintf(rate_text, sizeof rate_text, "%g", rate);
  const Simulated noisy = simulateRun(mocap, dir / ("noise" + std::string(rate_text)), o.duration_s,
                                      1, rate, o.camera_model);
  if (noisy.noise_labels.size() != noisy.events.size()) {
    throw std::runtime_error("no noise labels for " + (dir / rate_text).string() +
                             "; delete the folder to simulate it again");
  }
  scoreDenoiser(o, name, rate, noisy, denoise_csv);
  BackgroundActivityFilter filter(o.denoise, sensorSize(o));
  EventVector filtered;
  filter.filter(noisy.events, filtered);
  std::printf("  noise %g Hz: %zu events, %zu after the filter\n", rate, noisy.events.size(),
              filtered.size());
  std::fflush(stdout);
  const std::vector<int> ebpf_k = parseList<int>(o.ebpf_resample_text);
  // Seeds outermost: an interrupted sweep has every variant with the same seeds.
  const std::vector<std::string> variants = parseList<std::string>(o.noise_variants_text);
  for (int seed = 1; seed <= o.noise_seeds; ++seed) {
    for (const std::string& variant : variants) {
      // off: raw events, thesis model; filter: the background-activity filter first;
      // robust: EB-SLAM-2D's noise-aware diffusion (EB-PF runs only without it).
      const bool use_filter = variant == "filter" || variant == "filter+robust";
      const bool robust = variant == "robust" || variant == "filter+robust";
      if (!use_filter && !robust && variant != "off") {
        throw std::invalid_argument("unknown noise variant '" + variant + "'");
      }
      const EventVector& events = use_filter ? filtered : noisy.events;
      const std::string suffix = "," + std::string(rate_text) + "," + variant;
      if (!ebpf_k.empty() && !robust) {
        runs.ebpf("ebpf", ebpf_k[0], o.g0_ebpf, seed, false, events, noise_csv, suffix);
      }
      runs.slam("ebslam2d", 10, o.g0_slam, seed, false, events, noise_csv, suffix, robust);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Simulated floor-robot runs: EB-PF and EB-SLAM-2D accuracy and speed"};
  Options o;
  addOptions(app, o);
  CLI11_PARSE(app, argc, argv);

  try {
    const std::vector<fs::path> mocap_files = pioneerTrajectories(o.data_dir, o.trajectory_filter);
    fs::create_directories(o.out_dir);
    const char* header =
        "trajectory,method,particles,batch,resample,g0,latency_s,seed,events,duration_s,"
        "rmse_pos_m,rmse_rot_deg,failed,events_per_s,rmse_pos_smoothed_m,rmse_pos_raw_m,"
        "best_offset_s";
    std::ofstream csv(fs::path(o.out_dir) / "runs.csv");
    csv << header << '\n';
    const std::vector<double> noise_rates = parseList<double>(o.noise_rates_text);
    std::ofstream noise_csv, denoise_csv;
    if (!noise_rates.empty()) {
      noise_csv.open(fs::path(o.out_dir) / "noise_runs.csv");
      noise_csv << header << ",noise_rate,variant\n";
      denoise_csv.open(fs::path(o.out_dir) / "denoise.csv");
      denoise_csv << "trajectory,noise_rate,window_us,min_support,polarity_match,refractory,signal,"
                     "signal_kept,noise,"
                     "noise_removed,events_per_s\n";
    }
    o.camera_model = CameraModel::preset(o.camera);
    const CeilingCamera camera(o.camera_model, kThesisCeilingHeightM);
    if (o.scale_g0) {
      // G0 counts events per pixel of motion (eq. 6.8): an edge of the same length on the
      // ceiling spans f / f_thesis times the pixels.
      o.g0_factor = o.camera_model.focal_px / CameraModel{}.focal_px;
    }
    std::printf("camera %s: %d x %d, f = %.1f px, W_trig = %.2f cm, G0 factor %.3f\n",
                o.camera.c_str(), o.camera_model.width, o.camera_model.height,
                o.camera_model.focal_px, 100.0 * camera.wTrig(), o.g0_factor);
    for (const fs::path& mocap : mocap_files) {
      std::string name = mocap.filename().string();
      name = name.substr(name.find("freiburg2_"));
      if (const auto end = name.find("-groundtruth"); end != std::string::npos) name.resize(end);
      const fs::path dir = fs::path(o.out_dir) / name;
      const auto sim_start = std::chrono::steady_clock::now();
      const Simulated run = simulateRun(mocap, dir, o.duration_s, 1,
                                        EventModelConfig{}.noise_rate_hz_per_pixel, o.camera_model);
      const double sim_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - sim_start).count();
      const TrajectoryRuns runs(o, name, dir, run, camera);
      std::printf("%s: %zu events over %.1f s (simulation/loading %.1f s)\n", name.c_str(),
                  run.events.size(), runs.duration(), sim_seconds);
      std::fflush(stdout);
      if (!o.noise_only) defaultNoiseRuns(o, runs, run.events, csv);
      for (double rate : noise_rates) {
        noiseRuns(o, mocap, dir, name, rate, runs, noise_csv, denoise_csv);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
