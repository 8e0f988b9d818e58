// EB-PF as a robot's localiser (beyond the thesis' known start), in simulation: an eDVS looking
// up at a ceiling 2.59 m above (random lines and circles, thesis 6.5.3) driven along the planar
// freiburg2_pioneer_* motion-capture paths and along a synthetic path with 90 deg/s turns.
// Per trajectory and seed it measures
//   tracking   the whole run from the true start (the thesis' setting), with and without the
//              kidnap detector: RMSE, detector false alarms, the particles' covariance per pose
//   global     trials from a uniformly random time without a start pose (global localisation):
//              time until converged (state tracking, error < 10 cm and 5 deg), the longest span
//              of a false convergence (state tracking, error above those)
//   kidnap     tracking for 3 s, then the robot is carried >= 2 m away (the event stream jumps
//              to another part of the run): time until recovered
//   odometry   tracking with simulated wheel odometry (2 % of distance scale error, 1 deg per
//              metre heading drift, signs per seed) as motion prior, N and N/2 particles, against
//              the same without odometry
//   turn       the synthetic path (90 deg/s turns) with and without odometry
// and the NEES of the published covariance: the covariance scale and floors are chosen on the
// tuning trajectory's tracking runs (--tune) and the fraction of poses inside the two-sided 95 %
// chi-square band (3 degrees of freedom) is reported on the others.
// Writes --out/runs.csv (one line per run) and --out/covariance.csv; the simulations are cached
// in --out/<trajectory>/ as by ebslam_experiment_events2d. docs/results/localisation.md reports
// it.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ceiling_simulation.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/ebpf.h"
#include "filter_tool_common.h"

namespace fs = std::filesystem;
using namespace ebslam;

namespace {

constexpr double kDeg = M_PI / 180.0;
// Two-sided 95 % band of the chi-square distribution with 3 degrees of freedom.
constexpr double kChi2Low = 0.2158;
constexpr double kChi2High = 9.3484;

struct Options {
  std::string data_dir = "../shared/data";
  std::string out_dir = "localisation_runs";
  std::string trajectories = "freiburg2_pioneer_360,freiburg2_pioneer_slam,turn90";
  std::string tune = "freiburg2_pioneer_360";
  std::string modes = "tracking,global,kidnap,odometry,turn";
  int seeds = 5;
  int trials = 2;  // global / kidnap trials per seed
  int particles = 50;
  int resample = 25;
  double latency_s = 0.02;
  double window_us = 10000;  // as the ROS node receives messages (100 Hz)
  double converged_m = 0.10;
  double converged_deg = 5.0;
  double global_budget_s = 10.0;
  double kidnap_budget_s = 15.0;
  double kidnap_min_m = 2.0;
  double odom_scale_error = 0.02;
  double odom_drift_deg_per_m = 1.0;
  EbpfLocalisationConfig loc;
  // Kidnap detector of the kidnap runs (off in the others unless --recovery-always).
  double recovery_alpha_slow = 2e-5;
  double recovery_alpha_fast = 2e-3;
  double fitlog_from_s = 0.0;  // fitlog: start a global search this far into the run
};

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// A synthetic floor path of 14 s with a 360 deg turn at 90 deg/s while creeping forward and a
// 180 deg turn back at -90 deg/s (turn rates ramp over 0.25 s), 200 Hz.
Trajectory makeTurnPath() {
  Trajectory t;
  double x = 0.0, y = 0.0, th = 0.0;
  const double dt = 0.005;
  const auto omega_at = [](double s) {
    const auto ramp = [](double s0, double s1, double s) {
      return std::clamp(std::min(s - s0, s1 - s) / 0.25, 0.0, 1.0);
    };
    return 90.0 * kDeg * (ramp(3.0, 7.0, s) - ramp(9.0, 11.0, s));
  };
  for (double s = 0.0; s <= 14.0 + 1e-9; s += dt) {
    t.push_back(se2ToFloorPose(s, x, y, th));
    const double omega = omega_at(s);
    const double v = std::abs(omega) > 0.0 ? 0.1 : 0.3;
    x += v * std::cos(th) * dt;
    y += v * std::sin(th) * dt;
    th += omega * dt;
  }
  return t;
}

struct Window {
  std::size_t begin = 0, end = 0;
};

std::vector<Window> makeWindows(const EventVector& events, double window_us) {
  std::vector<Window> w;
  const auto step = static_cast<std::int64_t>(window_us);
  std::size_t i = 0;
  while (i < events.size()) {
    const std::int64_t t = events[i].t_us;
    const std::int64_t end_us = (t / step + 1) * step;
    std::size_t j = i + 1;
    while (j < events.size() && events[j].t_us < end_us) ++j;
    w.push_back({i, j});
    i = j;
  }
  return w;
}

// First window whose events start at or after t_s.
std::size_t windowAt(const EventVector& events, const std::vector<Window>& w, double t_s) {
  const auto t_us = static_cast<std::int64_t>(t_s * 1e6);
  std::size_t k = 0;
  while (k < w.size() && events[w[k].begin].t_us < t_us) ++k;
  return k;
}

Pose2 truthAt(const Trajectory& truth, double t_s) {
  return tools::toPose2(interpolatePose(truth, t_s));
}

// Motion from a to b in a's frame.
Pose2 relative(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, std::remainder(b.theta - a.theta, 2.0 * M_PI)};
}

struct Sample {
  double t_s = 0.0;  // since the start of the segment (event time)
  double err_m = 0.0, err_rad = 0.0;
  Eigen::Vector3d err = Eigen::Vector3d::Zero();  // x, y, theta of estimate - truth
  Eigen::Matrix3d particle_cov = Eigen::Matrix3d::Zero();
  TrackingState state = TrackingState::kTracking;
  double motion_s = 0.0;  // time the robot moved since the segment start (> 2 cm/s or 2 deg/s)
};

struct OdometrySim {
  double scale = 1.0;            // measured distance / true distance
  double drift_rad_per_m = 0.0;  // heading drift per metre driven
};

struct Segment {
  std::size_t w0 = 0, w1 = 0;  // windows [w0, w1)
  double shift_s = 0.0;        // presented event time = original + shift
};

struct RunStats {
  std::vector<Sample> samples;
  double cpu_s = 0.0;
  std::size_t events = 0;
  double span_s = 0.0;  // event time covered
};

// Runs the filter over segments of windows (a kidnap is a second segment elsewhere in the run),
// with simulated odometry when `odometry` is set.
void runSegments(EventParticleFilter& filter, const tools::Simulated& run,
                 const std::vector<Window>& windows, const std::vector<Segment>& segments,
                 const OdometrySim* odometry, double t_origin_s, RunStats& stats) {
  EventVector scratch;
  double motion_s = 0.0;
  for (const Segment& seg : segments) {
    const auto shift_us = static_cast<std::int64_t>(std::llround(seg.shift_s * 1e6));
    double prev_t = -1.0;
    for (std::size_t k = seg.w0; k < seg.w1; ++k) {
      const Window& w = windows[k];
      scratch.assign(run.events.begin() + static_cast<std::ptrdiff_t>(w.begin),
                     run.events.begin() + static_cast<std::ptrdiff_t>(w.end));
      for (Event& e : scratch) e.t_us += shift_us;
      const double t_end = 1e-6 * static_cast<double>(run.events[w.end - 1].t_us);
      const auto start = std::chrono::steady_clock::now();
      if (odometry != nullptr && prev_t >= 0.0) {
        Pose2 d = relative(truthAt(run.ground_truth, prev_t), truthAt(run.ground_truth, t_end));
        const double dist = std::hypot(d.x, d.y);
        d.x *= odometry->scale;
        d.y *= odometry->scale;
        d.theta += odometry->drift_rad_per_m * dist;
        filter.applyOdometry(d);
      }
      filter.process(scratch);
      const Pose2 est = filter.estimate();
      const Eigen::Matrix3d cov = filter.particles().covariance();
      stats.cpu_s +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      stats.events += scratch.size();
      const Pose2 truth = truthAt(run.ground_truth, t_end);
      if (prev_t >= 0.0 && t_end > prev_t) {
        const Pose2 before = truthAt(run.ground_truth, prev_t);
        const double dt = t_end - prev_t;
        if (std::hypot(truth.x - before.x, truth.y - before.y) > 0.02 * dt ||
            std::abs(std::remainder(truth.theta - before.theta, 2 * M_PI)) > 2.0 * kDeg * dt) {
          motion_s += dt;
        }
      }
      prev_t = t_end;
      Sample s;
      s.t_s = t_end + seg.shift_s - t_origin_s;
      s.err = {est.x - truth.x, est.y - truth.y, std::remainder(est.theta - truth.theta, 2 * M_PI)};
      s.err_m = s.err.head<2>().norm();
      s.err_rad = std::abs(s.err.z());
      s.particle_cov = cov;
      s.state = filter.state();
      s.motion_s = motion_s;
      stats.samples.push_back(s);
    }
    if (seg.w1 > seg.w0) {
      stats.span_s += 1e-6 * static_cast<double>(run.events[windows[seg.w1 - 1].end - 1].t_us -
                                                 run.events[windows[seg.w0].begin].t_us);
    }
  }
}

struct Outcome {
  double converged_s = NAN;         // first time the filter is tracking within the limits
  double converged_motion_s = NAN;  // the same in time of motion
  double false_tracking_s = 0;      // longest span tracking outside the limits
};

Outcome assess(const std::vector<Sample>& samples, double from_s, const Options& o) {
  Outcome out;
  double false_start = NAN;
  double motion_from = 0.0;
  for (const Sample& s : samples) {
    if (s.t_s >= from_s) break;
    motion_from = s.motion_s;
  }
  for (const Sample& s : samples) {
    if (s.t_s < from_s) continue;
    const bool good = s.err_m < o.converged_m && s.err_rad < o.converged_deg * kDeg;
    const bool tracking = s.state == TrackingState::kTracking;
    if (tracking && good && std::isnan(out.converged_s)) {
      out.converged_s = s.t_s - from_s;
      out.converged_motion_s = s.motion_s - motion_from;
    }
    if (tracking && !good) {
      if (std::isnan(false_start)) false_start = s.t_s;
      out.false_tracking_s = std::max(out.false_tracking_s, s.t_s - false_start);
    } else {
      false_start = NAN;
    }
  }
  return out;
}

std::pair<double, double> rmse(const std::vector<Sample>& samples) {
  double p = 0, r = 0;
  for (const Sample& s : samples) p += s.err_m * s.err_m, r += s.err_rad * s.err_rad;
  const double n = std::max<std::size_t>(1, samples.size());
  return {std::sqrt(p / n), std::sqrt(r / n) / kDeg};
}

struct CovarianceModel {
  double scale = 1.0, floor_m = 0.0, floor_rad = 0.0;
};

double neesInBand(const std::vector<const Sample*>& samples, const CovarianceModel& m) {
  if (samples.empty()) return NAN;
  std::size_t in = 0;
  for (const Sample* s : samples) {
    Eigen::Matrix3d p = m.scale * s->particle_cov;
    p(0, 0) += m.floor_m * m.floor_m;
    p(1, 1) += m.floor_m * m.floor_m;
    p(2, 2) += m.floor_rad * m.floor_rad;
    const double nees = s->err.dot(p.ldlt().solve(s->err));
    if (nees >= kChi2Low && nees <= kChi2High) ++in;
  }
  return static_cast<double>(in) / static_cast<double>(samples.size());
}

class Experiment {
 public:
  Experiment(const Options& o, std::ofstream& csv) : o_(o), csv_(csv) {}

  void trajectory(const std::string& name) {
    const fs::path dir = fs::path(o_.out_dir) / name;
    Trajectory floor;
    if (name == "turn90") {
      floor = makeTurnPath();
    } else {
      const fs::path mocap =
          fs::path(o_.data_dir) / "tum-groundtruth" / ("rgbd_dataset_" + name + "-groundtruth.txt");
      floor = makeFloorRobotTrajectory(readTumTrajectory(mocap.string()));
    }
    std::printf("%s: simulating (or reading %s)\n", name.c_str(), dir.c_str());
    std::fflush(stdout);
    run_ = tools::simulateFloorRun(floor, dir, 0.0, 1,
                                   SimulatorConfig{}.events.noise_rate_hz_per_pixel);
    name_ = name;
    camera_.emplace(CameraModel{}, kThesisCeilingHeightM);
    likelihood_ = tools::coarseLikelihood(run_.map, *camera_);
    windows_ = makeWindows(run_.events, o_.window_us);
    const double t0 = 1e-6 * static_cast<double>(run_.events.front().t_us);
    const double t1 = 1e-6 * static_cast<double>(run_.events.back().t_us);
    std::printf("%s: %zu events over %.1f s (%.0f events/s)\n", name.c_str(), run_.events.size(),
                t1 - t0, run_.events.size() / (t1 - t0));
    const std::vector<std::string> modes = split(o_.modes);
    const auto has = [&](const char* m) {
      return std::find(modes.begin(), modes.end(), m) != modes.end();
    };
    const bool turn = name == "turn90";
    for (int seed = 1; seed <= o_.seeds; ++seed) {
      if (turn) {
        if (has("turn")) turnRuns(seed);
        continue;
      }
      if (has("tracking")) trackingRuns(seed);
      if (has("global")) {
        for (int trial = 0; trial < o_.trials; ++trial) globalRun(seed, trial, t0, t1);
      }
      if (has("kidnap")) {
        for (int trial = 0; trial < o_.trials; ++trial) kidnapRun(seed, trial, t0, t1);
      }
      if (has("odometry")) odometryRuns(seed);
      if (has("fitlog")) fitLog(seed);
    }
  }

  // Covariance model chosen on the tuning trajectory, reported on the others.
  void covarianceReport(std::ofstream& out) const {
    std::vector<const Sample*> tune, held;
    for (const auto& [name, samples] : tracking_samples_) {
      for (const Sample& s : samples) (name == o_.tune ? tune : held).push_back(&s);
    }
    CovarianceModel best;
    double best_in = -1.0;
    // A positive scale keeps the search's covariance (metres: the hypotheses' spread) honest.
    for (double scale : {0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 2.0, 4.0}) {
      for (double floor_mm : {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
        for (double floor_deg : {0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5}) {
          const CovarianceModel m{scale, 1e-3 * floor_mm, floor_deg * kDeg};
          const double in = neesInBand(tune, m);
          if (in > best_in) best_in = in, best = m;
        }
      }
    }
    const double raw_tune = neesInBand(tune, CovarianceModel{});
    const double raw_held = neesInBand(held, CovarianceModel{});
    const double held_in = neesInBand(held, best);
    out << "set,poses,scale,floor_m,floor_deg,in_band_raw,in_band\n";
    out << "tune," << tune.size() << ',' << best.scale << ',' << best.floor_m << ','
        << best.floor_rad / kDeg << ',' << raw_tune << ',' << best_in << '\n';
    out << "held_out," << held.size() << ',' << best.scale << ',' << best.floor_m << ','
        << best.floor_rad / kDeg << ',' << raw_held << ',' << held_in << '\n';
    std::printf(
        "covariance: scale %.1f, floor %.1f mm, %.2f deg (chosen on %s, %zu poses: %.1f %% in "
        "band, unscaled %.1f %%); held out (%zu poses): %.1f %% in band (unscaled %.1f %%)\n",
        best.scale, best.floor_m * 1e3, best.floor_rad / kDeg, o_.tune.c_str(), tune.size(),
        100 * best_in, 100 * raw_tune, held.size(), 100 * held_in, 100 * raw_held);
  }

 private:
  EbpfConfig config(int seed, int particles, bool recovery) const {
    EbpfConfig c;
    c.filter.num_particles = particles;
    c.filter.resample_every = o_.resample;
    c.filter.latency_compensation_s = o_.latency_s;
    c.filter.seed = static_cast<std::uint64_t>(seed);
    c.localisation = o_.loc;
    c.localisation.seed = static_cast<std::uint64_t>(seed) * 7919;
    if (recovery) {
      c.localisation.recovery_alpha_slow = o_.recovery_alpha_slow;
      c.localisation.recovery_alpha_fast = o_.recovery_alpha_fast;
    }
    return c;
  }

  void write(const std::string& mode, int seed, int trial, int n, bool odometry, const RunStats& st,
             const Outcome& oc, const EventParticleFilter& f, double extra = NAN) {
    const auto [pos, rot] = rmse(st.samples);
    csv_ << name_ << ',' << mode << ',' << seed << ',' << trial << ',' << n << ',' << odometry
         << ',' << pos << ',' << rot << ',' << oc.converged_s << ',' << oc.converged_motion_s << ','
         << oc.false_tracking_s << ',' << f.recoveries() << ',' << f.convergences() << ','
         << st.events << ',' << st.span_s << ',' << st.events / std::max(1e-9, st.cpu_s) << ','
         << st.events / std::max(1e-9, st.span_s) << ',' << extra << '\n';
    csv_.flush();
    std::printf(
        "  %-9s seed %d trial %d N=%-3d odo=%d: RMSE %.2f cm %.2f deg, converged %s s, false "
        "tracking %.2f s, recoveries %llu, %.0f events/s (%.1fx real time)%s\n",
        mode.c_str(), seed, trial, n, odometry, pos * 100, rot,
        std::isnan(oc.converged_s) ? "never" : std::to_string(oc.converged_s).substr(0, 5).c_str(),
        oc.false_tracking_s, static_cast<unsigned long long>(f.recoveries()),
        st.events / std::max(1e-9, st.cpu_s),
        (st.events / std::max(1e-9, st.cpu_s)) / (st.events / std::max(1e-9, st.span_s)),
        std::isnan(extra) ? "" : (", extra " + std::to_string(extra)).c_str());
    std::fflush(stdout);
  }

  Pose2 startPose() const { return tools::toPose2(run_.ground_truth.front()); }

  void trackingRuns(int seed) {
    for (bool recovery : {false, true}) {
      EventParticleFilter f(config(seed, o_.particles, recovery), *camera_, likelihood_,
                            startPose());
      RunStats st;
      runSegments(f, run_, windows_, {{0, windows_.size(), 0.0}}, nullptr,
                  1e-6 * static_cast<double>(run_.events.front().t_us), st);
      write(recovery ? "tracking_detector" : "tracking", seed, 0, o_.particles, false, st,
            assess(st.samples, 0.0, o_), f);
      if (!recovery) {
        auto& all = tracking_samples_[name_];
        all.insert(all.end(), st.samples.begin(), st.samples.end());
      }
    }
  }

  void globalRun(int seed, int trial, double t0, double t1) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 1000 +
                        static_cast<std::uint64_t>(trial));
    const double run_s = o_.global_budget_s + 3.0;
    std::uniform_real_distribution<double> start(t0 + 0.5, t1 - run_s);
    const double ts = start(rng);
    const std::size_t w0 = windowAt(run_.events, windows_, ts);
    const std::size_t w1 = windowAt(run_.events, windows_, ts + run_s);
    EventParticleFilter f(config(seed, o_.particles, false), *camera_, likelihood_, Pose2{});
    f.globalLocalisation();
    RunStats st;
    runSegments(f, run_, windows_, {{w0, w1, 0.0}}, nullptr, ts, st);
    write("global", seed, trial, o_.particles, false, st, assess(st.samples, 0.0, o_), f, ts - t0);
  }

  void kidnapRun(int seed, int trial, double t0, double t1) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 1000 + 500 +
                        static_cast<std::uint64_t>(trial));
    const double before_s = 3.0, after_s = o_.kidnap_budget_s + 3.0;
    std::uniform_real_distribution<double> time(t0 + 0.5, t1 - after_s);
    double ta = 0, tb = 0;
    for (int attempt = 0; attempt < 10000; ++attempt) {
      ta = time(rng) + before_s;
      tb = time(rng);
      if (ta + 0.0 > t1 - after_s) continue;
      const Pose2 a = truthAt(run_.ground_truth, ta), b = truthAt(run_.ground_truth, tb);
      if (std::hypot(a.x - b.x, a.y - b.y) >= o_.kidnap_min_m) break;
    }
    const Pose2 a = truthAt(run_.ground_truth, ta), b = truthAt(run_.ground_truth, tb);
    const double jump = std::hypot(a.x - b.x, a.y - b.y);
    const std::size_t wa0 = windowAt(run_.events, windows_, ta - before_s);
    const std::size_t wa1 = windowAt(run_.events, windows_, ta);
    const std::size_t wb0 = windowAt(run_.events, windows_, tb);
    const std::size_t wb1 = windowAt(run_.events, windows_, tb + after_s);
    const double ta_end = 1e-6 * static_cast<double>(run_.events[windows_[wa1 - 1].end - 1].t_us);
    const double tb_start = 1e-6 * static_cast<double>(run_.events[windows_[wb0].begin].t_us);
    const double shift = ta_end - tb_start + 1e-6;
    EventParticleFilter f(config(seed, o_.particles, true), *camera_, likelihood_,
                          truthAt(run_.ground_truth, ta - before_s));
    RunStats st;
    const double origin = ta - before_s;
    runSegments(f, run_, windows_, {{wa0, wa1, 0.0}, {wb0, wb1, shift}}, nullptr, origin, st);
    // Recovered: tracking within the limits after the kidnap (the first samples after it are
    // wrong by construction).
    Outcome oc = assess(st.samples, ta_end - origin + 1e-3, o_);
    // A recovery needs the detector first: before it fires the filter still reports tracking.
    std::vector<Sample> after;
    for (const Sample& s : st.samples) {
      if (s.t_s > ta_end - origin) after.push_back(s);
    }
    double first_search = NAN;
    const double kidnap_motion = after.empty() ? 0.0 : after.front().motion_s;
    for (const Sample& s : after) {
      if (s.state == TrackingState::kGlobalSearch) {
        first_search = s.t_s - (ta_end - origin);
        break;
      }
    }
    // Recovery time: first time after the detection that the filter tracks within the limits.
    oc.converged_s = NAN;
    oc.converged_motion_s = NAN;
    if (!std::isnan(first_search)) {
      for (const Sample& s : after) {
        const double t = s.t_s - (ta_end - origin);
        if (t < first_search) continue;
        if (s.state == TrackingState::kTracking && s.err_m < o_.converged_m &&
            s.err_rad < o_.converged_deg * kDeg) {
          oc.converged_s = t;
          oc.converged_motion_s = s.motion_s - kidnap_motion;
          break;
        }
      }
    }
    write("kidnap", seed, trial, o_.particles, false, st, oc, f, jump);
    std::printf("    kidnap %.2f m at %.1f s, detected after %.2f s\n", jump, ta - t0,
                first_search);
  }

  // The kidnap detector's signals per window of a tracking run (for choosing its parameters).
  void fitLog(int seed) {
    EventParticleFilter f(config(seed, o_.particles, true), *camera_, likelihood_, startPose());
    std::ofstream out(fs::path(o_.out_dir) / (name_ + "_fit_s" + std::to_string(seed) + ".csv"));
    out << "t,events,fit,w_fast,w_slow,state,err_m,n,level,spread_m,spread_deg\n";
    if (o_.trials < 0) f.globalLocalisation();
    const double t0 = 1e-6 * static_cast<double>(run_.events.front().t_us);
    for (const Window& w : windows_) {
      if (1e-6 * static_cast<double>(run_.events[w.begin].t_us) < t0 + o_.fitlog_from_s) continue;
      f.process(run_.events.data() + w.begin, w.end - w.begin);
      const double t = 1e-6 * static_cast<double>(run_.events[w.end - 1].t_us);
      const Pose2 e = f.estimate(), g = truthAt(run_.ground_truth, t);
      const Eigen::Matrix3d c = f.particles().covariance();
      out << t - t0 << ',' << w.end - w.begin << ',' << f.particles().lastBatchMeanValue() << ','
          << f.fitFast() << ',' << f.fitSlow() << ',' << toString(f.state()) << ','
          << std::hypot(e.x - g.x, e.y - g.y) << ',' << f.particles().size() << ','
          << f.searchLevel() << ',' << std::sqrt(c(0, 0) + c(1, 1)) << ','
          << std::sqrt(c(2, 2)) / kDeg << '\n';
    }
  }

  OdometrySim odometrySim(int seed) const {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 31 + 7);
    const double s1 = (rng() & 1) ? 1.0 : -1.0, s2 = (rng() & 1) ? 1.0 : -1.0;
    return {1.0 + s1 * o_.odom_scale_error, s2 * o_.odom_drift_deg_per_m * kDeg};
  }

  void odometryRuns(int seed) {
    const OdometrySim odo = odometrySim(seed);
    for (int n : {o_.particles, o_.particles / 2}) {
      for (bool use : {false, true}) {
        EventParticleFilter f(config(seed, n, false), *camera_, likelihood_, startPose());
        RunStats st;
        runSegments(f, run_, windows_, {{0, windows_.size(), 0.0}}, use ? &odo : nullptr,
                    1e-6 * static_cast<double>(run_.events.front().t_us), st);
        write("odometry", seed, 0, n, use, st, assess(st.samples, 0.0, o_), f);
      }
    }
  }

  void turnRuns(int seed) {
    const OdometrySim odo = odometrySim(seed);
    for (int n : {o_.particles, o_.particles / 2}) {
      for (bool use : {false, true}) {
        EventParticleFilter f(config(seed, n, false), *camera_, likelihood_, startPose());
        RunStats st;
        runSegments(f, run_, windows_, {{0, windows_.size(), 0.0}}, use ? &odo : nullptr,
                    1e-6 * static_cast<double>(run_.events.front().t_us), st);
        double worst = 0.0;
        for (const Sample& s : st.samples) worst = std::max(worst, s.err_m);
        write("turn", seed, 0, n, use, st, assess(st.samples, 0.0, o_), f, worst);
      }
    }
  }

  const Options& o_;
  std::ofstream& csv_;
  std::string name_;
  tools::Simulated run_;
  std::optional<CeilingCamera> camera_;
  GridMap2f likelihood_;
  std::vector<Window> windows_;
  std::map<std::string, std::vector<Sample>> tracking_samples_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"EB-PF localisation experiment: global localisation, kidnapping, odometry, NEES"};
  Options o;
  EbpfLocalisationConfig& l = o.loc;
  app.add_option("--data", o.data_dir, "shared data folder (tum-groundtruth inside)")
      ->capture_default_str();
  app.add_option("--out", o.out_dir, "output folder (simulations cached there)")
      ->capture_default_str();
  app.add_option("--trajectories", o.trajectories,
                 "comma-separated freiburg2_pioneer_* names and/or turn90 (synthetic turns)")
      ->capture_default_str();
  app.add_option("--tune", o.tune, "trajectory on which the covariance model is chosen")
      ->capture_default_str();
  app.add_option("--modes", o.modes, "tracking,global,kidnap,odometry,turn")->capture_default_str();
  app.add_option("--seeds", o.seeds, "seeds 1..n per trajectory")->capture_default_str();
  app.add_option("--trials", o.trials, "global / kidnap trials per seed")->capture_default_str();
  app.add_option("-N,--particles", o.particles, "tracking particle count N")->capture_default_str();
  app.add_option("-K,--resample", o.resample, "events between resamplings K")
      ->capture_default_str();
  app.add_option("--latency", o.latency_s, "latency compensation [s]")->capture_default_str();
  app.add_option("--min-particles", l.min_particles, "KLD: min_particles")->capture_default_str();
  app.add_option("--max-particles", l.max_particles, "KLD: max_particles")->capture_default_str();
  app.add_option("--kld-err", l.kld_err, "KLD: kld_err")->capture_default_str();
  app.add_option("--search-budget", l.search_updates_per_event,
                 "particle updates per event while searching")
      ->capture_default_str();
  app.add_option("--converged-spread", l.converged_spread_m, "converged position spread [m]")
      ->capture_default_str();
  app.add_option("--converged-events", l.converged_events, "converged for this many events")
      ->capture_default_str();
  app.add_option("--converged-min-fit", l.converged_min_fit, "converged: minimum mean map value")
      ->capture_default_str();
  app.add_option("--level-switch", l.level_switch_ratio, "coarse-to-fine switch ratio")
      ->capture_default_str();
  app.add_option("--search-sigmas", l.search_sigmas_m, "coarse sensor-model sigmas [m]")
      ->delimiter(',');
  app.add_option("--recovery-alpha-slow", o.recovery_alpha_slow, "kidnap runs: alpha slow")
      ->capture_default_str();
  app.add_option("--recovery-alpha-fast", o.recovery_alpha_fast, "kidnap runs: alpha fast")
      ->capture_default_str();
  app.add_option("--recovery-ratio", l.recovery_ratio, "w_fast / w_slow below this: kidnapped")
      ->capture_default_str();
  app.add_option("--recovery-events", l.recovery_events, "... for this many events")
      ->capture_default_str();
  app.add_option("--fitlog-from", o.fitlog_from_s, "fitlog: start this far into the run [s]");
  app.add_option("--odom-alpha", l.odom_alpha1, "odom_alpha1 (rotation from rotation)")
      ->capture_default_str();
  app.add_option("--odom-alpha2", l.odom_alpha2)->capture_default_str();
  app.add_option("--odom-alpha3", l.odom_alpha3)->capture_default_str();
  app.add_option("--odom-alpha4", l.odom_alpha4)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    fs::create_directories(o.out_dir);
    std::ofstream csv(fs::path(o.out_dir) / "runs.csv");
    csv << "trajectory,mode,seed,trial,particles,odometry,position_rmse_m,rotation_rmse_deg,"
           "converged_s,converged_motion_s,false_tracking_s,recoveries,convergences,events,span_s,"
           "events_per_s,"
           "event_rate,extra\n";
    Experiment experiment(o, csv);
    for (const std::string& name : split(o.trajectories)) experiment.trajectory(name);
    std::ofstream cov(fs::path(o.out_dir) / "covariance.csv");
    experiment.covarianceReport(cov);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
