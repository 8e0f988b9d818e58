#include "ebslam/simulation/exploration_run.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "ebslam/slam/ceiling_camera.h"

namespace ebslam {
namespace {

double cpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

}  // namespace

CoverageRaster::CoverageRaster(const FloorPlan& plan, double robot_radius_m, double resolution_m)
    : radius_(robot_radius_m), resolution_(resolution_m) {
  if (!(std::isfinite(robot_radius_m) && robot_radius_m > 0.0 && std::isfinite(resolution_m) &&
        resolution_m > 0.0)) {
    throw std::invalid_argument("CoverageRaster: radius and resolution must be positive");
  }
  plan.validate();
  origin_ = plan.boundsMin();
  const Eigen::Vector2d size = plan.boundsMax() - origin_;
  const int cols = static_cast<int>(std::ceil(size.x() / resolution_));
  const int rows = static_cast<int>(std::ceil(size.y() / resolution_));
  // Centres where the robot fits, then the component connected to the start.
  cv::Mat centres(rows, cols, CV_8UC1, cv::Scalar(0));
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector2d p = origin_ + resolution_ * Eigen::Vector2d(c + 0.5, r + 0.5);
      if (plan.discFits(p, radius_)) centres.at<std::uint8_t>(r, c) = 255;
    }
  }
  const Eigen::Vector2d start =
      (Eigen::Vector2d(plan.start.x, plan.start.y) - origin_) / resolution_;
  cv::Point seed(std::clamp(static_cast<int>(start.x()), 0, cols - 1),
                 std::clamp(static_cast<int>(start.y()), 0, rows - 1));
  cv::Mat connected(rows + 2, cols + 2, CV_8UC1, cv::Scalar(0));
  if (centres.at<std::uint8_t>(seed) != 0) {
    cv::floodFill(centres, connected, seed, cv::Scalar(255), nullptr, cv::Scalar(0), cv::Scalar(0),
                  4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  }
  const cv::Mat reachable_centres = connected(cv::Rect(1, 1, cols, rows)).clone();
  const int k = static_cast<int>(std::round(radius_ / resolution_));
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * k + 1, 2 * k + 1));
  cv::dilate(reachable_centres, reachable_, disc);
  reachable_pixels_ = cv::countNonZero(reachable_);
  covered_ = cv::Mat(rows, cols, CV_8UC1, cv::Scalar(0));
}

void CoverageRaster::cover(const Eigen::Vector2d& position) {
  const Eigen::Vector2d p = (position - origin_) / resolution_;
  // cv::circle with a fixed-point shift of 4 bits: sub-pixel centre and radius.
  const int shift = 4;
  const double scale = 1 << shift;
  cv::circle(covered_,
             cv::Point(static_cast<int>(std::lround((p.x() - 0.5) * scale)),
                       static_cast<int>(std::lround((p.y() - 0.5) * scale))),
             static_cast<int>(std::lround(radius_ / resolution_ * scale)), cv::Scalar(255),
             cv::FILLED, cv::LINE_8, shift);
}

double CoverageRaster::coveredFraction() const {
  if (reachable_pixels_ <= 0.0) return 0.0;
  cv::Mat both;
  cv::bitwise_and(covered_, reachable_, both);
  return cv::countNonZero(both) / reachable_pixels_;
}

double CoverageRaster::reachableArea() const {
  return reachable_pixels_ * resolution_ * resolution_;
}

ExplorationRunResult runExploration(const FloorPlan& plan, const ExplorationRunConfig& config,
                                    const std::function<void(const ExplorationSample&)>& progress) {
  if (!(config.duration_s > 0.0 && config.control_period_s > 0.0 && config.record_period_s > 0.0)) {
    throw std::invalid_argument("runExploration: durations and periods must be positive");
  }
  const auto wall_start = std::chrono::steady_clock::now();
  ClosedLoopSimulatorConfig sim_config = config.simulator;
  sim_config.seed = config.seed;
  if (config.random_baseline) sim_config.simulate_events = false;
  ClosedLoopSimulator simulator(plan, sim_config);
  const Pose2 start = plan.start;
  Ebslam2dConfig slam_config = config.slam;
  slam_config.filter.seed = config.seed;
  std::optional<EventSlam2d> slam;
  std::optional<Explorer> explorer;
  std::optional<CoverageExplorer> coverer;
  std::optional<RandomBumpAndTurn> baseline;
  std::optional<TrackingMonitor> monitor;
  if (config.random_baseline) {
    // The baseline needs no localisation: it turns at the robot's full rate.
    ExplorationConfig random_config = config.exploration;
    random_config.max_turn_rate_rps = sim_config.robot.max_turn_rate_rps;
    baseline.emplace(random_config, config.seed);
  } else {
    slam.emplace(
        slam_config,
        CeilingCamera(simulator.config().events.camera, simulator.config().ceiling_height_m),
        start);
    if (config.coverage_planner) {
      coverer.emplace(config.coverage, start);
    } else {
      explorer.emplace(config.exploration, Eigen::Vector2d(start.x, start.y));
    }
    monitor.emplace(config.tracking, CeilingCamera(simulator.config().events.camera,
                                                   simulator.config().ceiling_height_m));
  }
  CoverageRaster coverage(plan, simulator.config().robot.radius_m, config.coverage_resolution_m);

  ExplorationRunResult result;
  result.reachable_area_m2 = coverage.reachableArea();
  coverage.cover(Eigen::Vector2d(simulator.pose().x, simulator.pose().y));
  BumpReading bump;
  bool was_contact = false;
  EventVector events;
  double next_record_s = 0.0;
  std::string last_message;
  ExplorationState last_state = ExplorationState::kExploring;
  const auto steps = static_cast<long>(std::ceil(config.duration_s / config.control_period_s));
  for (long i = 0; i <= steps; ++i) {
    const double t = simulator.time();
    const Pose2 estimate = slam ? slam->estimate() : Pose2{};
    if (t + 1e-9 >= next_record_s) {
      ExplorationSample sample;
      sample.t_s = t;
      sample.covered = coverage.coveredFraction();
      sample.bumps = result.bump_events;
      if (monitor) {
        sample.contrast = monitor->contrast();
        sample.lost = monitor->state() == TrackingState::kLost;
      }
      if (slam) {
        sample.position_error_m =
            std::hypot(estimate.x - simulator.pose().x, estimate.y - simulator.pose().y);
      }
      if (sample.covered >= 0.9 && result.time_to_90_s < 0.0) result.time_to_90_s = t;
      result.samples.push_back(sample);
      if (progress) progress(sample);
      next_record_s += config.record_period_s;
      if (sample.covered >= config.stop_at_coverage) break;
    }
    if (i == steps) break;
    VelocityCommand command;
    if (baseline) {
      command = baseline->update(t, bump);
    } else if (coverer) {
      const double c0 = cpuSeconds();
      command = coverer->update(t, estimate, bump);
      result.planner_seconds += cpuSeconds() - c0;
      ++result.planner_calls;
      if (coverer->done() && result.done_time_s < 0.0) {
        result.done_time_s = t;
        result.done_share = coverer->coveredShare();
        result.covered_at_done = coverage.coveredFraction();
      }
      if (coverer->message() != last_message) {
        last_message = coverer->message();
        std::ostringstream text;
        text.precision(1);
        text << std::fixed << t << " s: " << toString(coverer->state())
             << (last_message.empty() ? "" : ": " + last_message);
        result.messages.push_back(text.str());
      }
      if (config.stop_when_done && coverer->state() == CoverageState::kDone) {
        ExplorationSample sample;
        sample.t_s = t;
        sample.covered = coverage.coveredFraction();
        sample.bumps = result.bump_events;
        sample.contrast = monitor->contrast();
        sample.lost = monitor->state() == TrackingState::kLost;
        sample.position_error_m =
            std::hypot(estimate.x - simulator.pose().x, estimate.y - simulator.pose().y);
        if (sample.covered >= 0.9 && result.time_to_90_s < 0.0) result.time_to_90_s = t;
        result.samples.push_back(sample);
        break;
      }
    } else {
      const double c0 = cpuSeconds();
      command = explorer->update(t, estimate, bump, &slam->normalisation());
      result.planner_seconds += cpuSeconds() - c0;
      ++result.planner_calls;
      if (explorer->state() != last_state || explorer->message() != last_message) {
        last_state = explorer->state();
        last_message = explorer->message();
        std::ostringstream text;
        text.precision(1);
        text << std::fixed << t << " s: " << toString(last_state)
             << (last_message.empty() ? "" : ": " + last_message);
        result.messages.push_back(text.str());
      }
    }
    events.clear();
    bump = simulator.step(command, config.control_period_s, events);
    result.events += events.size();
    if (slam) {
      slam->process(events);
      const Pose2 p = slam->estimate();
      result.estimate.push_back(se2ToFloorPose(simulator.time(), p.x, p.y, p.theta));
      const TrackingState tracking = monitor->update(simulator.time(), events, p, slam->map());
      if (explorer && config.relocalise_when_lost) {
        explorer->setLocalisationLost(tracking == TrackingState::kLost, simulator.time());
      }
      if (coverer && config.slow_when_lost) {
        const bool lost = tracking == TrackingState::kLost;
        coverer->setLocalisationUncertain(lost);
        if (lost) result.slow_seconds += config.control_period_s;
      }
    }
    if (bump.contact() && !was_contact) ++result.bump_events;
    was_contact = bump.contact();
    coverage.cover(Eigen::Vector2d(simulator.pose().x, simulator.pose().y));
  }
  result.ground_truth = simulator.groundTruth();
  if (coverer) {
    const CoverageMap& map = coverer->map();
    for (int c = 0; c < map.size(); ++c) {
      if (map.hardBlocked()[c] == 0 && map.softBlocked()[c] == 0) continue;
      result.hex_centres.push_back(map.centre(c));
      result.z.push_back(0.0f);
      result.e.push_back(map.visitDistance(c));
      result.gain.push_back(0.0f);
      result.blocked.push_back(1);
    }
    result.bump_points = map.contacts();
    result.last_path = coverer->path();
    result.lanes = coverer->lanes();
    result.slam_map = mapToImage(slam->map());
    result.collapses = monitor->collapses();
  }
  if (explorer) {
    const ExplorationPlanner& planner = explorer->planner();
    for (int c = 0; c < planner.grid().size(); ++c) {
      result.hex_centres.push_back(planner.grid().centre(c));
    }
    result.z = planner.localisationMap();
    result.e = planner.obstacleMap();
    result.gain = planner.gainMap();
    result.blocked = planner.blocked();
    result.bump_points = planner.bumpPoints();
    result.last_path = explorer->pathPoints();
    result.slam_map = mapToImage(slam->map());
    result.collapses = monitor->collapses();
    result.relocalisations = explorer->relocalisations();
  }
  result.covered = coverage.covered().clone();
  result.reachable = coverage.reachable().clone();
  result.raster_resolution_m = coverage.resolution();
  result.raster_origin = coverage.origin();
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace ebslam
