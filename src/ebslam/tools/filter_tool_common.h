#pragma once

// Options and output shared by the run_ebpf and run_ebslam2d tools (not a tool itself).

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ebslam/events/event_io.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/slam/camera_model.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/event_filter.h"

namespace ebslam::tools {

/// When the tools record the estimate (runFilter()), and where the filter starts.
struct RunOptions {
  std::size_t every = 100;
  std::int64_t message_us = 0;
  std::vector<double> start{0.0, 0.0, 0.0};  // x y theta [m, m, rad]
  std::string start_from;                    // TUM trajectory whose first pose is the start
  /// The notes are appended to the help of --start and --start-from.
  void add(CLI::App& app, const std::string& start_note = "",
           const std::string& start_from_note = "") {
    app.add_option("--start", start, "initial pose x y theta [m, m, rad]" + start_note)
        ->expected(3);
    app.add_option("--start-from", start_from,
                   "take the initial pose from this TUM trajectory" + start_from_note)
        ->check(CLI::ExistingFile);
    app.add_option("--every", every, "record the estimate every this many events")
        ->capture_default_str();
    app.add_option("--message-us", message_us,
                   "instead: process and record per window of this much event time [us], as the "
                   "ROS nodes receive messages (10000 = 100 Hz)")
        ->check(CLI::NonNegativeNumber);
  }
  /// Throws std::invalid_argument for --every 0, std::runtime_error for an empty --start-from.
  Pose2 startPose() const;
};

struct CameraOptions {
  CameraModel camera;
  double ceiling_m = 2.59;
  void add(CLI::App& app) {
    app.add_option("--focal", camera.focal_px, "focal length [pixels]")->capture_default_str();
    app.add_option("--cx", camera.principal_point.x(), "optical centre column [pixels]")
        ->capture_default_str();
    app.add_option("--cy", camera.principal_point.y(), "optical centre row [pixels]")
        ->capture_default_str();
    app.add_option("--kappa1", camera.kappa1, "radial distortion, eq. 6.3 [1/pixel]")
        ->capture_default_str();
    app.add_option("--kappa2", camera.kappa2, "radial distortion, eq. 6.3 [1/pixel^2]")
        ->capture_default_str();
    app.add_option("--ceiling", ceiling_m, "distance sensor - ceiling D [m]")
        ->capture_default_str();
  }
};

inline void addFilterOptions(CLI::App& app, EventFilterConfig& f) {
  app.add_option("-N,--particles", f.num_particles, "number of particles N")->capture_default_str();
  app.add_option("-B,--batch", f.batch_size, "batch size B")->capture_default_str();
  app.add_option("-K,--resample", f.resample_every, "events between resamplings K")
      ->capture_default_str();
  app.add_option("--beta", f.beta, "influence of the last G0 events (eq. 6.27)")
      ->capture_default_str();
  app.add_option("--g0", f.g0, "effective feature count G0 (eq. 6.9, 6.10, 6.27)")
      ->capture_default_str();
  app.add_option("--diffusion-scale", f.experimental.diffusion_scale,
                 "factor on the diffusion (eq. 6.38)")
      ->capture_default_str();
  app.add_option("--initial-spread", f.initial_spread_m, "initial position spread [m]")
      ->capture_default_str();
  app.add_option("--initial-spread-rad", f.initial_spread_rad, "initial heading spread [rad]")
      ->capture_default_str();
  app.add_flag("--best-particle", "report the best particle instead of the weighted mean")
      ->each([&f](const std::string&) { f.estimate = PoseEstimateMode::kBestParticle; });
  app.add_flag("--reset-scores", f.experimental.reset_scores_on_resample,
               "reset all scores to their mean on resampling (default: children inherit)");
  app.add_flag("--adapt-g0", f.experimental.adapt_g0,
               "estimate G0 online from events per pixel of motion");
  app.add_option("--adapt-g0-divisor", f.experimental.adapt_g0_divisor,
                 "adaptive G0 = events/pixel / this")
      ->capture_default_str();
  app.add_option("--latency", f.latency_compensation_s,
                 "report the pose extrapolated by this event latency [s]")
      ->capture_default_str();
  app.add_option("--velocity-window", f.experimental.velocity_window_s,
                 "velocity estimate baseline [s]")
      ->capture_default_str();
  app.add_option("--seed", f.seed, "random seed")->capture_default_str();
}

/// Camera pose (camera -> world, z up) of an SE(2) pose, as in simulator_scenes.h.
inline StampedPose toStampedPose(double t_s, const Pose2& p) {
  StampedPose s;
  s.t_s = t_s;
  s.position = Eigen::Vector3d(p.x, p.y, 0.0);
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(p.theta, Eigen::Vector3d::UnitZ()));
  return s;
}

/// SE(2) pose of a camera pose with z up (yaw of the rotation).
inline Pose2 toPose2(const StampedPose& s) {
  const Eigen::Matrix3d r = s.orientation.toRotationMatrix();
  return {s.position.x(), s.position.y(), std::atan2(r(1, 0), r(0, 0))};
}

inline Pose2 RunOptions::startPose() const {
  if (every == 0) throw std::invalid_argument("--every must be positive");
  if (start_from.empty()) return Pose2{start[0], start[1], start[2]};
  const Trajectory gt = readTumTrajectory(start_from);
  if (gt.empty()) throw std::runtime_error("empty trajectory " + start_from);
  return toPose2(gt.front());
}

/// Reads events; a damaged file is processed up to the damage with a warning, an empty stream or
/// events that break the filter's preconditions are reported as errors by the caller.
inline EventReadResult readEventsOrThrow(const std::string& path) {
  EventReadResult r = readEventFile(path);
  if (r.error)
    std::fprintf(stderr, "warning: %s (using the %zu events before it)\n", r.error->c_str(),
                 r.events.size());
  if (r.events.empty()) throw std::runtime_error("no events in " + path);
  if (r.non_monotonic > 0) {
    throw std::runtime_error(path + ": " + std::to_string(r.non_monotonic) +
                             " events have timestamps earlier than their predecessor (first at "
                             "index " +
                             std::to_string(*r.first_non_monotonic_index) +
                             "); sort them first (ebslam_event_convert --sort)");
  }
  return r;
}

/// Runs `filter` over the events in chunks of `every` events, recording the estimate after each
/// chunk; with message_us > 0 in chunks of event time instead, [k message_us, (k + 1) message_us)
/// (what the ROS nodes receive from a source publishing every message_us, e.g. the event
/// simulator node with ~publish_rate 1e6 / message_us). Returns the processing time [s] (file I/O
/// excluded).
template <typename Filter>
double runFilter(Filter& filter, const EventVector& events, std::size_t every,
                 Trajectory& trajectory, std::int64_t message_us = 0) {
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < events.size();) {
    std::size_t n = std::min(every, events.size() - i);
    if (message_us > 0) {
      // floor division: event times may be negative
      const std::int64_t t = events[i].t_us;
      const std::int64_t window = t / message_us - (t % message_us < 0 ? 1 : 0);
      const std::int64_t end_us = (window + 1) * message_us;
      n = 1;
      while (i + n < events.size() && events[i + n].t_us < end_us) ++n;
    }
    filter.process(events.data() + i, n);
    const double t = static_cast<double>(events[i + n - 1].t_us) * 1e-6;
    i += n;
    if (!trajectory.empty() && t <= trajectory.back().t_s) continue;  // TUM needs rising times
    trajectory.push_back(toStampedPose(t, filter.estimate()));
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace ebslam::tools
