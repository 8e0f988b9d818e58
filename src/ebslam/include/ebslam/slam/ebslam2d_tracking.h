#pragma once

// Tracking state of EB-SLAM-2D while exploring: detects a collapse of the localisation from
// the agreement of each control period's events with the map at the estimated pose.
//
// Signal: the map contrast c = mean of M at the period's events mapped through the estimate,
// divided by the mean of M over the whole sensor footprint at the estimate (a fixed subsample of
// pixels). Events of a tracked sensor fall on the ceiling's edges, which the map holds as its
// high values (eq. 7.5): c well above 1. A lost estimate maps them onto arbitrary places of the
// map: c near 1, in practice a drop to well under half of its level while tracking (the
// reference). The ratio does not depend on the map's scale (M grows with the observations).
// A period with fewer than min_events events (standing still or a featureless view) or over an
// unmapped footprint gives no verdict: the state holds. Frames: EB-SLAM's map frame.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/particle_set2d.h"
#include "ebslam/slam/tracking_state.h"

namespace ebslam {

struct TrackingMonitorConfig {
  /// Fewer events than this in one update give no verdict (a few events make c noisy; a robot
  /// that stands still sees only noise).
  int min_events = 300;
  /// Time constant of the contrast's exponential average [s].
  double time_constant_s = 0.5;
  /// The reference: the contrast averaged over reference_time_constant_s [s] while tracking
  /// (how well this ceiling's edges are mapped; 4-9 in the simulated rooms).
  double reference_time_constant_s = 20.0;
  /// The first warmup_s [s] after the first verdict only learn the reference (the young map
  /// holds little but the events just added: its contrast starts high and settles).
  double warmup_s = 10.0;
  /// Averaged contrast below lost_ratio times the reference, or below lost_contrast, for
  /// lost_after_s [s]: lost; back above recovered_ratio times the reference and above
  /// recovered_contrast for recovered_after_s [s]: tracking again. Chosen on office seed 5's
  /// collapse (contrast 7-9 before, 2.2-3.7 during it; 4.6 at the lowest while tracking).
  double lost_ratio = 0.5;
  double recovered_ratio = 0.7;
  /// A contrast far above the reference is a collapse too: a lost estimate's events soon land on
  /// the map they have just written at the wrong pose (two_rooms seed 5: 5 -> 17 at its collapse;
  /// while tracking it stayed within 1.5 times the reference). Above lost_ratio_high times the
  /// reference counts like below lost_ratio; tracking again needs it below
  /// recovered_ratio_high times the reference.
  double lost_ratio_high = 2.0;
  double recovered_ratio_high = 1.5;
  double lost_contrast = 1.6;
  double lost_after_s = 0.5;
  double recovered_contrast = 2.2;
  double recovered_after_s = 1.0;
  /// A footprint whose mean M is below this fraction of the map's largest value holds no map
  /// yet: no verdict.
  double min_footprint_fraction = 1e-3;
  /// Footprint subsample: every footprint_stride_px-th pixel in x and y.
  int footprint_stride_px = 4;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class TrackingMonitor {
 public:
  /// Throws std::invalid_argument for an invalid config.
  TrackingMonitor(const TrackingMonitorConfig& config, const CeilingCamera& camera);

  /// One control period at time now_s [s]: its events, EB-SLAM's estimate after them and its
  /// map M. Returns the state.
  TrackingState update(double now_s, const Event* events, std::size_t count, const Pose2& estimate,
                       const GridMap2f& map);
  TrackingState update(double now_s, const EventVector& events, const Pose2& estimate,
                       const GridMap2f& map) {
    return update(now_s, events.data(), events.size(), estimate, map);
  }

  TrackingState state() const { return state_; }
  /// Averaged contrast (0 before the first verdict) and that of the last update with a verdict.
  double contrast() const { return average_; }
  double lastContrast() const { return last_; }
  double reference() const { return reference_; }
  /// Updates that gave a verdict, and collapses detected (tracking -> lost).
  std::size_t verdicts() const { return verdicts_; }
  std::size_t collapses() const { return collapses_; }
  /// Resets to tracking, e.g. after the map frame was re-anchored.
  void reset();

 private:
  TrackingMonitorConfig config_;
  CeilingCamera camera_;
  std::vector<std::uint32_t> footprint_;  // pixel indices of the footprint subsample
  float map_max_ = 0.0f;
  std::size_t map_max_scan_ = 0;  // updates since the map's largest value was scanned
  TrackingState state_ = TrackingState::kTracking;
  double average_ = 0.0;
  double reference_ = 0.0;
  double last_ = 0.0;
  double last_time_s_ = -1.0;
  double first_time_s_ = -1.0;
  double below_since_s_ = -1.0;
  double above_since_s_ = -1.0;
  std::size_t verdicts_ = 0;
  std::size_t collapses_ = 0;
};

}  // namespace ebslam
