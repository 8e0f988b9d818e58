#pragma once

// One closed-loop exploration episode (thesis 7.4) in simulation, for tests and the evaluation
// tool: ClosedLoopSimulator -> events -> EventSlam2d -> pose -> Explorer -> velocity command, or
// the random bump-and-turn baseline (which needs no pose), plus the coverage bookkeeping.
//
// Frames: EB-SLAM's map frame is placed at the robot's start pose in the room's frame (the
// explorer knows nothing else of the room), so the SLAM frame and the room's frame coincide at
// t = 0 and every map can be drawn over the floor plan.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/closed_loop_simulator.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/slam/coverage.h"
#include "ebslam/slam/ebslam2d.h"
#include "ebslam/slam/ebslam2d_tracking.h"
#include "ebslam/slam/exploration.h"

namespace ebslam {

/// Coverage of a room by a disc-shaped robot on a raster: the reachable free area is every floor
/// point the robot's body can touch, i.e. the union of the robot discs at all centre positions
/// connected to the start; the covered area is the union of the discs along the true path.
class CoverageRaster {
 public:
  /// Throws std::invalid_argument for a non-positive radius or resolution.
  CoverageRaster(const FloorPlan& plan, double robot_radius_m, double resolution_m = 0.02);
  /// Marks the robot disc at `position` [m, room frame] as covered.
  void cover(const Eigen::Vector2d& position);
  /// Covered part of the reachable free area, in [0, 1].
  double coveredFraction() const;
  double reachableArea() const;                            ///< [m^2]
  const cv::Mat& reachable() const { return reachable_; }  ///< CV_8UC1, 255 = reachable
  const cv::Mat& covered() const { return covered_; }      ///< CV_8UC1, 255 = covered
  double resolution() const { return resolution_; }
  Eigen::Vector2d origin() const { return origin_; }  ///< room (x, y) of pixel (0, 0)'s corner

 private:
  double radius_ = 0.0;
  double resolution_ = 0.0;
  Eigen::Vector2d origin_;
  cv::Mat reachable_;
  cv::Mat covered_;
  double reachable_pixels_ = 0.0;
};

struct ExplorationRunConfig {
  ClosedLoopSimulatorConfig simulator;
  Ebslam2dConfig slam;
  ExplorationConfig exploration;
  double duration_s = 600.0;       ///< simulated time [s]
  double control_period_s = 0.05;  ///< controller rate 20 Hz [s]
  bool random_baseline = false;    ///< drive the bump-and-turn baseline instead (no SLAM)
  /// Drive the coverage planner (coverage.h) instead of the gain planner.
  bool coverage_planner = false;
  CoverageConfig coverage;
  /// Coverage planner: slow down (CoverageConfig::uncertain_speed_factor) while the tracking
  /// monitor reports EB-SLAM lost.
  bool slow_when_lost = false;
  /// Coverage planner: end the run once it is done and back at the start.
  bool stop_when_done = true;
  std::uint64_t seed = 1;  ///< simulator, ceiling, filter and baseline seed
  double coverage_resolution_m = 0.02;
  double record_period_s = 1.0;  ///< period of the coverage / error time series [s]
  /// Stop early once this covered fraction is reached (1 = never).
  double stop_at_coverage = 1.0;
  /// EB-SLAM-2D's tracking monitor; with relocalise_when_lost the explorer stops exploring while
  /// it reports a collapse (Explorer::setLocalisationLost), else the verdict is only recorded.
  /// Off by default: in office seed 5 both turning in place and reversing straight while lost
  /// let the error grow to 1.5-4 m, where exploring on recovered within 10 s
  /// (docs/results/exploration.md).
  TrackingMonitorConfig tracking;
  bool relocalise_when_lost = false;
};

struct ExplorationSample {
  double t_s = 0.0;
  double covered = 0.0;           ///< covered fraction of the reachable free area
  double position_error_m = 0.0;  ///< |SLAM - true| in the room frame (no alignment), 0 baseline
  std::size_t bumps = 0;          ///< bump events so far
  double contrast = 0.0;          ///< tracking monitor's averaged map contrast (0 baseline)
  bool lost = false;              ///< tracking monitor's verdict
};

struct ExplorationRunResult {
  std::vector<ExplorationSample> samples;
  double time_to_90_s = -1.0;  ///< first time with >= 90 % covered; -1 if never
  double reachable_area_m2 = 0.0;
  std::size_t bump_events = 0;        ///< contacts that began (rising edges of the ring)
  Trajectory ground_truth;            ///< true robot (camera) poses
  Trajectory estimate;                ///< EB-SLAM poses (empty for the baseline)
  std::vector<std::string> messages;  ///< the explorer's state changes and reasons
  std::size_t events = 0;
  double wall_time_s = 0.0;
  double planner_seconds = 0.0;  ///< CPU time in Explorer::update
  std::size_t planner_calls = 0;
  std::size_t collapses = 0;        ///< tracking -> lost verdicts of the monitor
  std::size_t relocalisations = 0;  ///< times the explorer stopped to re-localise
  /// Coverage planner: time it reported done (-1: never), its own covered share then, and the
  /// true covered fraction then.
  double done_time_s = -1.0;
  double done_share = 0.0;
  double covered_at_done = 0.0;
  double slow_seconds = 0.0;  ///< simulated time driven slowly while lost
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> lanes;  ///< coverage lanes driven
  /// Final maps for pictures (empty for the baseline).
  std::vector<Eigen::Vector2d> hex_centres;
  std::vector<float> z, e, gain;
  std::vector<std::uint8_t> blocked;
  std::vector<Eigen::Vector2d> bump_points;  ///< contact points in the SLAM frame
  std::vector<Eigen::Vector2d> last_path;
  cv::Mat covered;  ///< coverage raster (CoverageRaster::covered)
  cv::Mat reachable;
  double raster_resolution_m = 0.0;
  Eigen::Vector2d raster_origin{0.0, 0.0};
  cv::Mat slam_map;  ///< EB-SLAM's map M as an image (mapToImage)
};

/// Runs one episode. `progress` (optional) is called at every record period.
/// Throws std::invalid_argument for invalid configs or plans.
ExplorationRunResult runExploration(
    const FloorPlan& plan, const ExplorationRunConfig& config,
    const std::function<void(const ExplorationSample&)>& progress = {});

}  // namespace ebslam
