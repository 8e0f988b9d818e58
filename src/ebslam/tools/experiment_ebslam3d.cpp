// One EB-SLAM-3D run (thesis 8.3-8.4) on depth events along a ground-truth camera path, scored
// like table 8.1: position RMSE after alignment with a time offset (eq. 8.16-8.19), rotation
// error (eq. 8.20), real-time factor (event time span / CPU time of the filter) and peak memory.
// Event sources (--source):
//  - dedvs (default): the D-eDVS simulator (dedvs_simulator.h) renders a furnished room
//    (dedvs_scene.h) along the path, generates the eDVS events and the depth frames, and the
//    D-eDVS depth fusion (dedvs_fusion.h) gives each event its 3D point, each event fused with
//    the depth frame nearest in time; events without a depth go to the filter as viewing rays
//    (scored along the ray with --ray-scoring; --no-ray-scoring drops them before the filter). The
//    path is the depth camera's (TUM convention); the filter tracks the eDVS, scored against the
//    eDVS's truth.
//  - synthetic: synthetic_depth_events.h (a textured box room, geometric event model).
// The path is a TUM ground truth (--groundtruth) or a synthesised hand-held motion (--motion,
// handheld_motions.h; floor_sweep runs in a room without the table, which would stand above it).
// --imu: the rig carries an IMU (imu_simulator.h, readings from the ground truth with noise and
// bias, seeded by --scene-seed); the filter runs twice on the same events, without and with the
// gyro rotation prior (Ebslam3dImuConfig), and prints one JSON line each ("imu": false / true).
// --events-cache keeps the fused D-eDVS events of a (path, duration, scene seed) in a file, so
// that runs differing only in the filter skip the simulation. --diagnostics writes one CSV row per
// recorded estimate: tracking state, ESS, the fit, events used, the pose error before alignment.
// --cover-at T --cover-for D drops every event in [T, T + D) s (the sensor covered: a forced
// loss) and reports how long after T + D the tracking state was back to tracking on a right pose.
// The JSON reports the tracking state's false alarms (lost while the error after alignment is
// below 3 cm) and misses (tracking while it is above 5 cm) as shares of the run time, the
// relocalisations (LOST -> RELOCALISED and their durations) and the filter's memory over time.
// e.g. ebslam_experiment_ebslam3d --groundtruth rgbd_dataset_freiburg1_xyz-groundtruth.txt --seed 2
// Prints one JSON object (stdout). Exit status: 0 success, 1 usage / input error.

#include <sys/resource.h>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <deque>
#include <exception>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/events/trajectory_evaluation.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/simulation/handheld_motions.h"
#include "ebslam/simulation/imu_simulator.h"
#include "ebslam/simulation/synthetic_depth_events.h"
#include "ebslam/slam/dedvs_fusion.h"
#include "ebslam/slam/ebslam3d.h"

namespace {

std::size_t peakRssBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024u;  // Linux: kilobytes
}

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

using PointSink = std::function<void(const ebslam::PointEvent&)>;

// D-eDVS source: simulates the rig along `truth` (shifted to start at 0 s) over
// [0, duration] and streams the fused events to `sink`. Returns the eDVS ground truth.
ebslam::Trajectory dedvsEvents(const ebslam::Trajectory& truth, double duration_s,
                               std::uint64_t seed, bool with_table, const PointSink& sink,
                               std::size_t* simulated, std::size_t* without_depth,
                               const ebslam::CameraModel& event_camera) {
  using namespace ebslam;
  RoomSceneConfig room;
  room.seed = seed;
  room.with_table = with_table;
  const Scene scene = makeRoomScene(truth, room);
  DedvsSimulatorConfig config;
  config.edvs = event_camera;
  config.seed = seed;
  config.events.seed = seed;
  DepthEventFusion fusion(sensorsOf(config));
  // An event is fused once the frame after it has arrived (frames come after every event up to
  // their exposure), so it takes the frame nearest in time.
  std::deque<Event> pending;
  auto fuseUpTo = [&](double t_end_s) {
    while (!pending.empty() && 1e-6 * static_cast<double>(pending.front().t_us) <= t_end_s) {
      const FusedEvent f = fusion.fuse(pending.front());
      pending.pop_front();
      if (!std::isfinite(f.depth_m)) {
        ++*without_depth;
        if (f.ray.allFinite()) sink(rayEvent(f.event.t_us, f.ray));
        continue;
      }
      PointEvent p;
      p.t_us = f.event.t_us;
      p.point = f.point;
      sink(p);
    }
  };
  const DedvsRun run = DedvsSimulator(config).simulate(
      scene, truth, 0.0, duration_s,
      [&](const std::vector<TrueDepthEvent>& batch) {
        *simulated += batch.size();
        for (const TrueDepthEvent& e : batch) pending.push_back(e.event);
      },
      [&](const DepthFrame& frame) {
        fusion.addDepthFrame(frame.depth_mm, frame.stamp_s);
        fuseUpTo(frame.t_s);
      });
  fuseUpTo(std::numeric_limits<double>::infinity());
  return run.edvs_ground_truth;
}

// Events cache: a header (magic, counts), the eDVS truth, the fused events; native byte order
// (a cache is local to a machine).
// Version 2: events without a depth are stored as rays (PointEvent::has_depth).
constexpr std::uint64_t kCacheMagic = 0x33444d414c534246ULL;  // "EBSLAM3D" + version 2

bool readCache(const std::string& path, ebslam::PointEventVector& events, ebslam::Trajectory& truth,
               std::size_t& simulated, std::size_t& without_depth) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::uint64_t header[5] = {};
  in.read(reinterpret_cast<char*>(header), sizeof(header));
  if (!in || header[0] != kCacheMagic) {
    throw std::runtime_error("not an events cache of this version: " + path);
  }
  simulated = header[1];
  without_depth = header[2];
  truth.resize(header[3]);
  for (ebslam::StampedPose& p : truth) {
    double v[8];
    in.read(reinterpret_cast<char*>(v), sizeof(v));
    p.t_s = v[0];
    p.position = Eigen::Vector3d(v[1], v[2], v[3]);
    p.orientation = Eigen::Quaterniond(v[4], v[5], v[6], v[7]);
  }
  events.resize(header[4]);
  in.read(reinterpret_cast<char*>(events.data()),
          static_cast<std::streamsize>(events.size() * sizeof(ebslam::PointEvent)));
  if (!in) throw std::runtime_error("truncated events cache: " + path);
  return true;
}

void writeCache(const std::string& path, const ebslam::PointEventVector& events,
                const ebslam::Trajectory& truth, std::size_t simulated, std::size_t without_depth) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    const std::uint64_t header[5] = {kCacheMagic, simulated, without_depth, truth.size(),
                                     events.size()};
    out.write(reinterpret_cast<const char*>(header), sizeof(header));
    for (const ebslam::StampedPose& p : truth) {
      const double v[8] = {p.t_s,
                           p.position.x(),
                           p.position.y(),
                           p.position.z(),
                           p.orientation.w(),
                           p.orientation.x(),
                           p.orientation.y(),
                           p.orientation.z()};
      out.write(reinterpret_cast<const char*>(v), sizeof(v));
    }
    out.write(reinterpret_cast<const char*>(events.data()),
              static_cast<std::streamsize>(events.size() * sizeof(ebslam::PointEvent)));
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot write " + path);
}

// Per recorded estimate: the filter's health and the error before alignment (the map frame is
// the start pose, so truth relative to its start is comparable directly; the error after the
// evaluation's alignment is in the JSON).
struct DiagnosticRow {
  double t_s;
  ebslam::TrackingHealth health;
  std::size_t chunk_events, used_total;
  double angular_speed, linear_speed;  // [rad/s], [m/s]
  std::size_t memory_bytes;            // map, particles and keyframes
};

// Feeds the events to the filter in chunks of record_step_us of event time and records one
// estimate per chunk; times the filter (thread CPU). With gyro readings, those up to one reading
// past a chunk's end go in before the chunk (as a ROS node holding events until the IMU covers
// them).
class ChunkedRun {
 public:
  ChunkedRun(const ebslam::Ebslam3dConfig& config, std::int64_t record_step_us,
             const std::vector<ebslam::ImuReading>* imu = nullptr)
      : slam_(config), record_step_us_(record_step_us), imu_(imu) {}

  void add(const ebslam::PointEvent& e) {
    if (streamed_ == 0) first_us_ = e.t_us;
    if (!chunk_.empty() && e.t_us >= chunk_.front().t_us + record_step_us_) flush();
    chunk_.push_back(e);
    last_us_ = e.t_us;
    ++streamed_;
  }

  void flush() {
    if (chunk_.empty()) return;
    const double c0 = threadCpuSeconds();
    if (imu_) {
      const std::int64_t until = chunk_.back().t_us;
      while (next_imu_ < imu_->size()) {
        const ebslam::ImuReading& r = (*imu_)[next_imu_];
        const auto t_us = static_cast<std::int64_t>(std::llround(r.t_s * 1e6));
        slam_.addGyro(t_us, r.gyro);
        last_bias_ = r.gyro_bias;
        ++next_imu_;
        if (t_us >= until) break;
      }
    }
    slam_.process(chunk_);
    cpu_s_ += threadCpuSeconds() - c0;
    ebslam::StampedPose p;
    p.t_s = 1e-6 * static_cast<double>(chunk_.back().t_us);
    p.position = slam_.estimate().position;
    p.orientation = slam_.estimate().orientation;
    if (estimate_.empty() || p.t_s > estimate_.back().t_s) {
      estimate_.push_back(p);
      rows_.push_back({p.t_s, slam_.health(), chunk_.size(),
                       static_cast<std::size_t>(slam_.processedEvents()), slam_.angularSpeed(),
                       slam_.linearSpeed(), slam_.memoryBytes()});
    }
    chunk_.clear();
  }
  const std::vector<DiagnosticRow>& rows() const { return rows_; }

  const ebslam::EventSlam3d& slam() const { return slam_; }
  bool withImu() const { return imu_ != nullptr; }
  /// True gyro bias of the last reading given [rad/s].
  const Eigen::Vector3d& lastTrueBias() const { return last_bias_; }
  const ebslam::Trajectory& estimate() const { return estimate_; }
  std::size_t streamed() const { return streamed_; }
  double cpuSeconds() const { return cpu_s_; }
  double spanSeconds() const { return 1e-6 * static_cast<double>(last_us_ - first_us_); }

 private:
  ebslam::EventSlam3d slam_;
  const std::int64_t record_step_us_;
  ebslam::PointEventVector chunk_;
  ebslam::Trajectory estimate_;
  std::vector<DiagnosticRow> rows_;
  std::size_t streamed_ = 0;
  std::int64_t first_us_ = 0, last_us_ = 0;
  double cpu_s_ = 0.0;
  const std::vector<ebslam::ImuReading>* imu_;
  std::size_t next_imu_ = 0;
  Eigen::Vector3d last_bias_ = Eigen::Vector3d::Zero();
};

// The final map's voxels above 1 as 'x y z value' lines.
void writeMapXyz(const std::string& path, const ebslam::EventSlam3d& slam) {
  std::ofstream out(path);
  slam.map().forEachVoxel(1.0f, [&](const ebslam::VoxelIndex& v, float value) {
    const Eigen::Vector3f c = slam.map().voxelCentre(v);
    out << c.x() << ' ' << c.y() << ' ' << c.z() << ' ' << value << '\n';
  });
  if (!out) throw std::runtime_error("cannot write " + path);
}

void writeDiagnostics(const std::string& path, const ChunkedRun& run,
                      const ebslam::Trajectory& truth) {
  std::ofstream out(path);
  out << "t_s,state,ess_share,fit_fast,fit_slow,fit_ratio,mapped_share,depthless_share,"
         "angular_speed,linear_speed,memory_bytes,chunk_events,used_events,position_error_m,"
         "rotation_error_deg\n";
  const ebslam::StampedPose start = ebslam::interpolatePose(truth, truth.front().t_s);
  const Eigen::Quaterniond inv_start = start.orientation.conjugate();
  const ebslam::Trajectory& estimate = run.estimate();
  for (std::size_t i = 0; i < run.rows().size(); ++i) {
    const DiagnosticRow& r = run.rows()[i];
    const ebslam::StampedPose t = ebslam::interpolatePose(truth, r.t_s);
    const Eigen::Vector3d rel_position = inv_start * (t.position - start.position);
    const Eigen::Quaterniond rel_orientation = inv_start * t.orientation;
    const double position_error = (estimate[i].position - rel_position).norm();
    const double rotation_error =
        estimate[i].orientation.angularDistance(rel_orientation) * 180.0 / M_PI;
    out << r.t_s << ',' << ebslam::toString(r.health.state) << ',' << r.health.ess_share << ','
        << r.health.fit_fast << ',' << r.health.fit_slow << ',' << r.health.fit_ratio << ','
        << r.health.mapped_share << ',' << r.health.depthless_share << ',' << r.angular_speed << ','
        << r.linear_speed << ',' << r.memory_bytes << ',' << r.chunk_events << ',' << r.used_total
        << ',' << position_error << ',' << rotation_error << '\n';
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

// What a run used and measured, for the JSON line.
struct RunSummary {
  std::string groundtruth, source, preset;
  std::uint64_t scene_seed = 0;
  std::size_t simulated = 0, without_depth = 0;
  double cover_at_s = -1.0, cover_for_s = 0.0;  // forced loss (cover_at_s < 0: none)
  double cover_origin_s = 0.0;                  // event time of the path's start [s]
  std::size_t covered = 0;                      // events dropped by the cover
  ebslam::ImuSimulatorConfig imu;
};

// The tracking state against the error after alignment, over the run's time (each recorded
// estimate stands for the time to the next one), the relocalisations, the forced loss and the
// memory's growth.
struct StateSummary {
  double run_s = 0.0;
  double false_alarm_share = 0.0;  // lost while the error is below 3 cm
  double miss_share = 0.0;         // tracking while the error is above 5 cm
  double lost_share = 0.0;
  std::vector<double> relocalisation_s;  // LOST -> TRACKING durations [s]
  double cover_recovery_s = -1.0;  // tracking on a right pose again after the cover (-1: never)
  bool cover_noticed = false;      // the state left tracking after the cover
  double memory_first_minute_mib = 0.0, memory_end_mib = 0.0, memory_growth_mib_per_min = 0.0;
};

StateSummary summariseStates(const std::vector<DiagnosticRow>& rows,
                             const ebslam::TrajectoryEvaluation& eval, const RunSummary& summary) {
  using ebslam::TrackingState;
  StateSummary out;
  if (rows.size() < 2) return out;
  // Error per row (rows and estimates are 1:1; the evaluation lists the associated ones).
  std::vector<double> error(rows.size(), std::numeric_limits<double>::quiet_NaN());
  std::size_t e = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    while (e < eval.errors.size() && eval.errors[e].t_s < rows[i].t_s - 1e-9) ++e;
    if (e < eval.errors.size() && std::abs(eval.errors[e].t_s - rows[i].t_s) < 1e-9) {
      error[i] = eval.errors[e].position_error_m;
    }
  }
  double total = 0.0, false_alarm = 0.0, miss = 0.0, lost = 0.0;
  double lost_start = -1.0;
  const double cover_end = summary.cover_at_s >= 0.0
                               ? summary.cover_origin_s + summary.cover_at_s + summary.cover_for_s
                               : std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    const double dt = std::min(rows[i + 1].t_s - rows[i].t_s, 0.1);  // gaps (a cover) not counted
    const TrackingState state = rows[i].health.state;
    if (std::isfinite(error[i])) {
      total += dt;
      if (state == TrackingState::kLost) {
        lost += dt;
        if (error[i] < 0.03) false_alarm += dt;
      }
      if (state == TrackingState::kTracking && error[i] > 0.05) miss += dt;
    }
    if (state == TrackingState::kLost && lost_start < 0.0) lost_start = rows[i].t_s;
    if (state == TrackingState::kTracking && lost_start >= 0.0) {
      out.relocalisation_s.push_back(rows[i].t_s - lost_start);
      lost_start = -1.0;
    }
    if (rows[i].t_s >= cover_end && state != TrackingState::kTracking) out.cover_noticed = true;
  }
  out.run_s = total;
  if (total > 0.0) {
    out.false_alarm_share = false_alarm / total;
    out.miss_share = miss / total;
    out.lost_share = lost / total;
  }
  // Recovered: from the first row after the cover on which the state is tracking and stays so
  // for 1 s with every error below 5 cm.
  for (std::size_t i = 0; i < rows.size() && std::isfinite(cover_end); ++i) {
    if (rows[i].t_s < cover_end) continue;
    bool good = true;
    std::size_t j = i;
    for (; j < rows.size() && rows[j].t_s < rows[i].t_s + 1.0 && good; ++j) {
      good = rows[j].health.state == TrackingState::kTracking && std::isfinite(error[j]) &&
             error[j] < 0.05;
    }
    if (good && j < rows.size()) {
      out.cover_recovery_s = rows[i].t_s - cover_end;
      break;
    }
  }
  // Memory: at the end of the first minute (or of the first half of a shorter run), at the end,
  // and its growth over the second half of the run.
  const double t0 = rows.front().t_s, t1 = rows.back().t_s;
  const double first = std::min(t0 + 60.0, 0.5 * (t0 + t1)), half = 0.5 * (t0 + t1);
  double m_first = 0.0, m_half = 0.0;
  for (const DiagnosticRow& r : rows) {
    if (r.t_s <= first) m_first = static_cast<double>(r.memory_bytes);
    if (r.t_s <= half) m_half = static_cast<double>(r.memory_bytes);
  }
  const double mib = 1.0 / 1048576.0;
  out.memory_first_minute_mib = m_first * mib;
  out.memory_end_mib = static_cast<double>(rows.back().memory_bytes) * mib;
  if (t1 > half) {
    out.memory_growth_mib_per_min =
        (static_cast<double>(rows.back().memory_bytes) - m_half) * mib / ((t1 - half) / 60.0);
  }
  return out;
}

void printJson(const RunSummary& r, const ebslam::Ebslam3dConfig& config, const ChunkedRun& run,
               const ebslam::TrajectoryEvaluation& eval) {
  const ebslam::EventSlam3d& slam = run.slam();
  const StateSummary states = summariseStates(run.rows(), eval, r);
  std::string relocalisations = "[";
  for (std::size_t i = 0; i < states.relocalisation_s.size(); ++i) {
    relocalisations += (i ? ", " : "") + std::to_string(states.relocalisation_s[i]);
  }
  relocalisations += "]";
  const double span = run.spanSeconds(), cpu = run.cpuSeconds();
  const std::size_t streamed = run.streamed();
  std::printf(
      "{\"groundtruth\": \"%s\", \"source\": \"%s\", \"preset\": \"%s\", \"seed\": %llu, "
      "\"scene_seed\": %llu, "
      "\"N\": %d, \"K\": %d, \"B\": %d, \"event_share\": %g, \"voxel_m\": %g, "
      "\"sigma_position_m\": %g, \"sigma_rotation_rad\": %g, \"alpha\": %g, "
      "\"duration_s\": %.3f, \"simulated_events\": %zu, \"events_without_depth\": %zu, "
      "\"events\": %zu, \"events_per_s_stream\": %.0f, "
      "\"used_events\": %llu, \"cpu_s\": %.4f, \"events_per_s\": %.0f, \"realtime_factor\": "
      "%.2f, "
      "\"rmse_m\": %.5f, \"max_error_m\": %.5f, \"rotation_rmse_deg\": %.4f, "
      "\"time_offset_s\": %.4f, \"peak_memory_bytes\": %zu, \"peak_rss_bytes\": %zu, "
      "\"map_chunks\": %zu, "
      "\"evicted_chunks\": %llu, \"max_event_rate\": %g, \"sigma_position_per_sqrt_s\": %g, "
      "\"sigma_rotation_per_sqrt_s\": %g, \"lost_count\": %llu, \"time_lost_s\": %.3f, "
      "\"final_state\": \"%s\", \"diffusion_min_scale\": %g, \"diffusion_max_scale\": %g, "
      "\"reference_angular_speed\": %g, \"reference_linear_speed\": %g, "
      "\"ray_scoring\": %s, \"rays_scored\": %llu, \"rays_unscored\": %llu, "
      "\"relocalisation\": %s, \"relocalisations\": %llu, \"relocalisation_s\": %s, "
      "\"last_relocalisation_s\": %.3f, \"false_alarm_share\": %.4f, \"miss_share\": %.4f, "
      "\"lost_share\": %.4f, \"cover_at_s\": %g, \"cover_for_s\": %g, \"covered_events\": %zu, "
      "\"cover_noticed\": %s, \"cover_recovery_s\": %.3f, \"memory_first_minute_mib\": %.3f, "
      "\"memory_end_mib\": %.3f, \"memory_growth_mib_per_min\": %.4f, \"keyframes\": %zu, "
      "\"motion_window_s\": %g, \"ray_min_depthless_share\": %g, \"max_event_gap_s\": %g, "
      "\"event_gaps\": %llu, ",
      r.groundtruth.c_str(), r.source.c_str(), r.preset.c_str(),
      static_cast<unsigned long long>(config.seed), static_cast<unsigned long long>(r.scene_seed),
      config.num_particles, config.resample_every, config.batch_size, config.event_share,
      config.voxel_size_m, config.sigma_position_m, config.sigma_rotation_rad, config.score_alpha,
      span, r.simulated, r.without_depth, streamed, static_cast<double>(streamed) / span,
      static_cast<unsigned long long>(slam.processedEvents()), cpu,
      static_cast<double>(streamed) / cpu, span / cpu, eval.position_rmse_m, eval.position_max_m,
      eval.rotation_rmse_deg, eval.alignment.time_offset_s, slam.peakMemoryBytes(), peakRssBytes(),
      slam.map().chunkCount(), static_cast<unsigned long long>(slam.map().evictedChunks()),
      config.max_event_rate, config.sigma_position_per_sqrt_s, config.sigma_rotation_per_sqrt_s,
      static_cast<unsigned long long>(slam.health().lost_count), slam.health().time_lost_s,
      ebslam::toString(slam.health().state), config.diffusion_min_scale, config.diffusion_max_scale,
      config.reference_angular_speed, config.reference_linear_speed,
      config.rays.enabled ? "true" : "false", static_cast<unsigned long long>(slam.raysScored()),
      static_cast<unsigned long long>(slam.raysUnscored()),
      config.relocalisation.enabled ? "true" : "false",
      static_cast<unsigned long long>(slam.health().relocalisations), relocalisations.c_str(),
      slam.health().last_relocalisation_s, states.false_alarm_share, states.miss_share,
      states.lost_share, r.cover_at_s, r.cover_for_s, r.covered,
      states.cover_noticed ? "true" : "false", states.cover_recovery_s,
      states.memory_first_minute_mib, states.memory_end_mib, states.memory_growth_mib_per_min,
      slam.keyframes().size(), config.motion_window_s, config.rays.min_depthless_share,
      config.health.max_event_gap_s, static_cast<unsigned long long>(slam.health().event_gaps));
  const ebslam::GyroPrior& gyro = slam.gyro();
  std::printf(
      "\"imu\": %s, \"imu_rate_hz\": %g, \"gyro_noise_density\": %g, "
      "\"gyro_bias_random_walk\": %g, \"imu_sigma_rotation_per_sqrt_s\": %g, "
      "\"imu_bias_window_s\": %g, \"gyro_predicted_batches\": %llu, "
      "\"gyro_uncovered_batches\": %llu, \"gyro_bias_error_rad_s\": %.5f, "
      "\"gyro_bias_true_rad_s\": %.5f}\n",
      run.withImu() ? "true" : "false", r.imu.rate_hz, r.imu.gyro_noise_density,
      r.imu.gyro_bias_random_walk, config.imu.sigma_rotation_per_sqrt_s, config.imu.bias_window_s,
      static_cast<unsigned long long>(slam.gyroPredictedBatches()),
      static_cast<unsigned long long>(slam.gyroUncoveredBatches()),
      run.withImu() ? (gyro.bias() - run.lastTrueBias()).norm() : 0.0, run.lastTrueBias().norm());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ebslam;
  CLI::App app{"EB-SLAM-3D on simulated depth events along a ground-truth path"};
  std::string groundtruth, motion, source = "dedvs", preset = "default", trajectory_out, map_out,
                                   truth_out, diagnostics_out, events_cache;
  double duration_s = 0.0, record_every_s = 0.01;
  std::uint64_t scene_seed = 1;
  SyntheticRoomConfig room;
  SyntheticEventConfig sim;
  SyntheticDepthSensor sensor;
  Ebslam3dConfig config;
  auto* gt_opt = app.add_option("--groundtruth", groundtruth, "TUM ground-truth camera path")
                     ->check(CLI::ExistingFile);
  auto* motion_opt =
      app.add_option("--motion", motion,
                     "synthesised hand-held path instead: yaw_turn, floor_sweep, shake, orbit "
                     "(handheld_motions.h; 15 s unless --motion-duration)")
          ->check(CLI::IsMember({"yaw_turn", "floor_sweep", "shake", "orbit"}))
          ->excludes(gt_opt);
  double motion_duration_s = 15.0;
  app.add_option("--motion-duration", motion_duration_s, "length of the --motion path [s]")
      ->capture_default_str();
  app.add_option("--source", source,
                 "depth events: dedvs (D-eDVS simulator + depth fusion) or synthetic "
                 "(synthetic_depth_events.h)")
      ->check(CLI::IsMember({"dedvs", "synthetic"}))
      ->capture_default_str();
  app.add_option("--preset", preset,
                 "default, fast (this project's presets) or thesis (the thesis' 8.4 default set)")
      ->check(CLI::IsMember({"default", "fast", "thesis"}))
      ->capture_default_str();
  std::string camera_name = "edvs128";
  app.add_option("--camera", camera_name,
                 "event camera of the D-eDVS rig: edvs128, davis240, davis346, vga, hd720 (the "
                 "rig's eDVS lens scaled to the sensor: same horizontal field of view)")
      ->capture_default_str();
  app.add_option("--duration", duration_s, "use only the first this many seconds (0 = all)");
  app.add_option("--seed", config.seed, "filter seed (the scene and events use --scene-seed)");
  app.add_option("--scene-seed", scene_seed, "seed of the room, its events and the depth noise");
  auto* n_opt = app.add_option("-N,--particles", config.num_particles, "N");
  auto* k_opt = app.add_option("-K,--resample-every", config.resample_every, "K");
  auto* b_opt = app.add_option("-B,--batch", config.batch_size, "B");
  auto* share_opt = app.add_option("--event-share", config.event_share, "share of events used");
  auto* voxel_opt = app.add_option("--voxel", config.voxel_size_m, "voxel edge [m]");
  auto* sp_opt = app.add_option("--sigma-position", config.sigma_position_m, "[m] per event");
  auto* sr_opt = app.add_option("--sigma-rotation", config.sigma_rotation_rad, "[rad] per event");
  auto* alpha_opt = app.add_option("--alpha", config.score_alpha, "score decay per event");
  auto* rate_opt =
      app.add_option("--max-rate", config.max_event_rate, "events used per s at most (0 = all)");
  auto* spt_opt = app.add_option("--sigma-position-time", config.sigma_position_per_sqrt_s,
                                 "diffusion [m / sqrt(s) of event time]");
  auto* srt_opt = app.add_option("--sigma-rotation-time", config.sigma_rotation_per_sqrt_s,
                                 "diffusion [rad / sqrt(s) of event time]");
  auto* dmin_opt = app.add_option("--diffusion-min-scale", config.diffusion_min_scale,
                                  "lower bound of the speed scale of the per-time diffusion");
  auto* dmax_opt = app.add_option("--diffusion-max-scale", config.diffusion_max_scale,
                                  "upper bound of the speed scale of the per-time diffusion");
  auto* wref_opt = app.add_option("--reference-angular-speed", config.reference_angular_speed,
                                  "angular speed of diffusion scale 1 [rad/s]");
  auto* vref_opt = app.add_option("--reference-linear-speed", config.reference_linear_speed,
                                  "linear speed of diffusion scale 1 [m/s]");
  auto* window_opt = app.add_option("--motion-window", config.motion_window_s,
                                    "window of the speed measure [s of event time]");
  auto* ray_share_opt =
      app.add_option("--ray-min-depthless-share", config.rays.min_depthless_share,
                     "score rays only while this share of the events has no depth (0 = always)");
  auto* lost_fit_opt =
      app.add_option("--lost-fit", config.health.lost_fit, "tracking state: lost below this fit");
  auto* recover_fit_opt = app.add_option("--recover-fit", config.health.recover_fit,
                                         "tracking state: recovering at or above this fit");
  auto* fit_time_opt = app.add_option("--fit-time", config.health.fast_time_s,
                                      "tracking state: smoothing of the fit [s of event time]");
  auto* gap_opt = app.add_option("--max-event-gap", config.health.max_event_gap_s,
                                 "tracking state: lost after a gap in the events [s] (0 = off)");
  auto* reloc_n_opt = app.add_option("--relocalisation-particles", config.relocalisation.particles,
                                     "particles while searching when lost");
  app.add_option("--diagnostics", diagnostics_out,
                 "CSV per recorded estimate: tracking state, ESS, fit, error before alignment");
  app.add_option("--events-cache", events_cache,
                 "file of the fused D-eDVS events: read if it exists, else written");
  double max_map_mb = -1.0;
  app.add_option("--max-map-mb", max_map_mb, "map memory bound [MiB] (0 = unbounded)");
  bool splat_all = false, no_rays = false, no_relocalisation = false;
  double cover_at_s = -1.0, cover_for_s = 2.0;
  bool rays = false;
  app.add_flag("--no-ray-scoring", no_rays, "drop events without a depth before the filter");
  app.add_flag("--ray-scoring", rays, "score events without a depth along their ray");
  app.add_flag("--no-relocalisation", no_relocalisation, "no search when lost (keeps mapping)");
  app.add_option("--cover-at", cover_at_s,
                 "forced loss: drop every event from this time on [s from the start]");
  app.add_option("--cover-for", cover_for_s, "length of the forced loss [s]")
      ->capture_default_str();
  app.add_flag("--splat-all-particles", splat_all, "eq. 8.9 with every particle");
  app.add_option("--edges-per-m2", room.edges_per_square_m, "synthetic room texture density")
      ->capture_default_str();
  app.add_option("--noise-share", sim.noise_share, "synthetic noise events per edge event")
      ->capture_default_str();
  bool use_imu = false, imu_only = false;
  ImuSimulatorConfig imu_sim;
  app.add_flag("--imu", use_imu,
               "simulate the rig's IMU and run the filter without and with the gyro prior "
               "(two JSON lines)");
  app.add_flag("--imu-only", imu_only, "with --imu: only the run with the gyro prior");
  app.add_option("--imu-rate", imu_sim.rate_hz, "IMU readings per second [Hz]")
      ->capture_default_str();
  app.add_option("--gyro-noise", imu_sim.gyro_noise_density,
                 "gyro white noise density [rad/s/sqrt(Hz)] (simulated and assumed)")
      ->capture_default_str();
  app.add_option("--gyro-bias-walk", imu_sim.gyro_bias_random_walk,
                 "gyro bias random walk [rad/s per sqrt(s)] (simulated and assumed)")
      ->capture_default_str();
  app.add_option("--gyro-initial-bias", imu_sim.gyro_initial_bias_std,
                 "std. dev. of the simulated turn-on bias per axis [rad/s]")
      ->capture_default_str();
  app.add_option("--imu-sigma-rotation-time", config.imu.sigma_rotation_per_sqrt_s,
                 "rotation diffusion kept besides the gyro's noise [rad / sqrt(s)]")
      ->capture_default_str();
  app.add_option("--imu-bias-window", config.imu.bias_window_s,
                 "window of the bias measurements [s of event time]")
      ->capture_default_str();
  app.add_option("-o,--trajectory", trajectory_out, "estimated path (TUM)");
  app.add_option("--aligned-truth", truth_out, "CSV of per-pose errors and aligned positions");
  app.add_option("--map-xyz", map_out, "final map voxels above 1 as 'x y z value' lines");
  CLI11_PARSE(app, argc, argv);
  if (gt_opt->count() + motion_opt->count() != 1) {
    std::fprintf(stderr, "error: give --groundtruth or --motion\n");
    return 1;
  }

  try {
    Ebslam3dConfig base = preset == "fast"     ? Ebslam3dConfig::fast()
                          : preset == "thesis" ? Ebslam3dConfig::thesis()
                                               : Ebslam3dConfig::defaults();
    // Explicit options override the preset.
    const Ebslam3dConfig given = config;
    config = base;
    config.seed = given.seed;
    config.imu = given.imu;  // the presets leave the IMU part at its defaults
    if (n_opt->count()) config.num_particles = given.num_particles;
    if (k_opt->count()) config.resample_every = given.resample_every;
    if (b_opt->count()) config.batch_size = given.batch_size;
    if (share_opt->count()) config.event_share = given.event_share;
    if (voxel_opt->count()) config.voxel_size_m = given.voxel_size_m;
    if (sp_opt->count()) config.sigma_position_m = given.sigma_position_m;
    if (sr_opt->count()) config.sigma_rotation_rad = given.sigma_rotation_rad;
    if (alpha_opt->count()) config.score_alpha = given.score_alpha;
    if (rate_opt->count()) config.max_event_rate = given.max_event_rate;
    if (spt_opt->count()) config.sigma_position_per_sqrt_s = given.sigma_position_per_sqrt_s;
    if (srt_opt->count()) config.sigma_rotation_per_sqrt_s = given.sigma_rotation_per_sqrt_s;
    if (dmin_opt->count()) config.diffusion_min_scale = given.diffusion_min_scale;
    if (dmax_opt->count()) config.diffusion_max_scale = given.diffusion_max_scale;
    if (wref_opt->count()) config.reference_angular_speed = given.reference_angular_speed;
    if (vref_opt->count()) config.reference_linear_speed = given.reference_linear_speed;
    if (window_opt->count()) config.motion_window_s = given.motion_window_s;
    if (ray_share_opt->count()) {
      config.rays.min_depthless_share = given.rays.min_depthless_share;
    }
    if (lost_fit_opt->count()) config.health.lost_fit = given.health.lost_fit;
    if (recover_fit_opt->count()) config.health.recover_fit = given.health.recover_fit;
    if (fit_time_opt->count()) config.health.fast_time_s = given.health.fast_time_s;
    if (gap_opt->count()) config.health.max_event_gap_s = given.health.max_event_gap_s;
    if (reloc_n_opt->count()) config.relocalisation.particles = given.relocalisation.particles;
    if (max_map_mb >= 0.0) config.max_map_bytes = static_cast<std::size_t>(max_map_mb * 1048576.0);
    if (splat_all) config.splat = MapSplat3d::kAllParticles;
    if (rays) config.rays.enabled = true;
    if (no_rays) config.rays.enabled = false;
    if (no_relocalisation) config.relocalisation.enabled = false;
    if (cover_at_s >= 0.0 && !(cover_for_s > 0.0))
      throw std::runtime_error("--cover-for must be > 0");
    const CameraModel event_camera =
        CameraModel::preset(camera_name, DedvsSimulatorConfig::defaultEdvsCamera());
    Trajectory truth;
    if (!motion.empty()) {
      // The path's shape is fixed (seed 1); --scene-seed varies the room, events and noise.
      truth = makeHandheldMotion(handheldMotionFromString(motion), motion_duration_s, 1);
      groundtruth = "motion:" + motion;
    } else {
      truth = readTumTrajectory(groundtruth);
    }
    if (truth.size() < 2) throw std::runtime_error("ground truth has fewer than two poses");
    const bool with_table = motion != "floor_sweep";

    RunSummary summary;
    summary.groundtruth = groundtruth;
    summary.source = source;
    summary.preset = preset;
    summary.scene_seed = scene_seed;
    summary.cover_at_s = cover_at_s;
    summary.cover_for_s = cover_for_s;
    const auto record_step_us = static_cast<std::int64_t>(record_every_s * 1e6);
    std::unique_ptr<ChunkedRun> run;
    PointEventVector held;  // with --imu: the events, for the two runs
    // The cover is timed from the path's start (event times are the path's, shifted to 0 for
    // the D-eDVS source).
    double cover_origin_s = 0.0;
    const PointSink sink = [&](const PointEvent& e) {
      const double t = 1e-6 * static_cast<double>(e.t_us) - cover_origin_s;
      if (cover_at_s >= 0.0 && t >= cover_at_s && t < cover_at_s + cover_for_s) {
        ++summary.covered;
        return;
      }
      if (no_rays && !e.has_depth) return;
      if (use_imu) {
        held.push_back(e);
      } else {
        run->add(e);
      }
    };
    Trajectory sensor_truth;
    // The IMU's body (rig) path and span, and its frame -> the tracked sensor's.
    const Trajectory* imu_body = &truth;
    double imu_t0 = 0.0, imu_t1 = 0.0;
    Eigen::Quaterniond sensor_from_imu = imu_sim.body_from_imu;
    imu_sim.seed = scene_seed;
    if (source == "dedvs") {
      const double t0 = truth.front().t_s;
      for (StampedPose& pose : truth) pose.t_s -= t0;
      const double t1 =
          duration_s > 0.0 ? std::min(truth.back().t_s, duration_s) : truth.back().t_s;
      config.focal_px = event_camera.focal_px;
      DedvsSimulatorConfig rig;
      rig.imu = imu_sim;
      sensor_from_imu = edvsFromImu(rig);
      imu_t1 = t1;
      run = std::make_unique<ChunkedRun>(config, record_step_us);
      PointEventVector cached;
      if (!events_cache.empty() &&
          readCache(events_cache, cached, sensor_truth, summary.simulated, summary.without_depth)) {
        for (const PointEvent& e : cached) sink(e);
      } else if (!events_cache.empty()) {
        const PointSink store = [&](const PointEvent& e) { cached.push_back(e); };
        sensor_truth = dedvsEvents(truth, t1, scene_seed, with_table, store, &summary.simulated,
                                   &summary.without_depth, event_camera);
        writeCache(events_cache, cached, sensor_truth, summary.simulated, summary.without_depth);
        for (const PointEvent& e : cached) sink(e);
      } else {
        sensor_truth = dedvsEvents(truth, t1, scene_seed, with_table, sink, &summary.simulated,
                                   &summary.without_depth, event_camera);
      }
    } else {
      config.focal_px = sensor.focal_px;
      const double t0 = truth.front().t_s;
      cover_origin_s = t0;
      summary.cover_origin_s = t0;
      const double t1 =
          duration_s > 0.0 ? std::min(truth.back().t_s, t0 + duration_s) : truth.back().t_s;
      room.seed = scene_seed;
      sim.seed = scene_seed;
      const auto scene = makeSyntheticRoom(truth, room);
      const PointEventVector events = simulateDepthEvents(scene, sensor, truth, t0, t1, sim);
      imu_t0 = t0;
      imu_t1 = t1;
      run = std::make_unique<ChunkedRun>(config, record_step_us);
      summary.simulated = events.size();
      for (const PointEvent& e : events) sink(e);
      sensor_truth = truth;
    }
    // The runs: one, or without and with the gyro prior on the same events.
    std::vector<ImuReading> imu_readings;
    std::vector<std::unique_ptr<ChunkedRun>> runs;
    if (use_imu) {
      summary.imu = imu_sim;
      imu_readings = simulateImu(*imu_body, imu_t0, imu_t1, imu_sim);
      config.imu.gyro.sensor_from_imu = sensor_from_imu;
      config.imu.gyro.noise_density = imu_sim.gyro_noise_density;
      config.imu.gyro.bias_random_walk = imu_sim.gyro_bias_random_walk;
      if (!imu_only) runs.push_back(std::make_unique<ChunkedRun>(config, record_step_us));
      runs.push_back(std::make_unique<ChunkedRun>(config, record_step_us, &imu_readings));
      for (std::unique_ptr<ChunkedRun>& r : runs) {
        for (const PointEvent& e : held) r->add(e);
      }
    } else {
      summary.imu.rate_hz = 0.0;
      runs.push_back(std::move(run));
    }
    TrajectoryEvaluationConfig eval_config;
    eval_config.max_time_offset_s = 0.2;
    eval_config.estimate_body_rotation = false;
    for (std::unique_ptr<ChunkedRun>& r : runs) {
      r->flush();
      if (r->streamed() == 0) throw std::runtime_error("no events");
      if (r->estimate().size() < 3) throw std::runtime_error("too few events for an estimate");
      const TrajectoryEvaluation eval =
          evaluateTrajectory(r->estimate(), sensor_truth, eval_config);
      // Files: of the last run (the one with the gyro prior under --imu).
      if (r == runs.back()) {
        if (!trajectory_out.empty()) writeTumTrajectory(trajectory_out, r->estimate());
        if (!truth_out.empty()) writeTrajectoryErrorsCsv(truth_out, eval);
        if (!map_out.empty()) writeMapXyz(map_out, r->slam());
        if (!diagnostics_out.empty()) writeDiagnostics(diagnostics_out, *r, sensor_truth);
      }
      printJson(summary, config, *r, eval);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
