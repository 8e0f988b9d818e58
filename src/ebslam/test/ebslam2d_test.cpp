#include "ebslam/slam/ebslam2d.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ebslam/events/trajectory_evaluation.h"
#include "synthetic_ceiling.h"

namespace ebslam {
namespace {

StampedPose toStamped(double t, const Pose2& p) {
  StampedPose s;
  s.t_s = t;
  s.position = {p.x, p.y, 0.0};
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(p.theta, Eigen::Vector3d::UnitZ()));
  return s;
}

// EB-SLAM-2D on a short synthetic run (a 0.8 m arc with turning, empty initial map): the path
// matches the ground truth after rigid alignment and the map's strong cells lie on the
// ceiling's true edges.
TEST(Ebslam2d, BuildsMapConsistentWithGroundTruth) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  const testing::SyntheticCeiling ceiling = testing::makeSyntheticCeiling(5.0, 0.01, 5);
  const auto path = [](double t) { return testing::loopPath(t, 0.6, 0.3); };
  std::vector<std::pair<double, Pose2>> ground_truth;
  const EventVector events =
      testing::generateSyntheticEvents(ceiling, camera, path, 0.0, 3.0, 0.15, &ground_truth);
  ASSERT_GT(events.size(), 50000u);

  Ebslam2dConfig config;
  config.filter.g0 = 100.0;
  EventSlam2d slam(config, camera, path(0.0));
  Trajectory estimated;
  Trajectory truth;
  std::size_t next = 0;
  for (const auto& [t, pose] : ground_truth) {
    const auto t_us = static_cast<std::int64_t>(std::llround(t * 1e6));
    std::size_t end = next;
    while (end < events.size() && events[end].t_us <= t_us) ++end;
    slam.process(events.data() + next, end - next);
    next = end;
    estimated.push_back(toStamped(t, slam.estimate()));
    truth.push_back(toStamped(t, pose));
  }
  TrajectoryEvaluationConfig eval;
  eval.estimate_time_offset = false;
  const TrajectoryEvaluation result = evaluateTrajectory(estimated, truth, eval);
  EXPECT_LT(result.position_rmse_m, 0.03);
  EXPECT_LT(result.rotation_rmse_deg, 2.0);
  EXPECT_GT(slam.normalisationUpdates(), 10u);

  // Map consistency: over the well-observed cells, the map M correlates with the true edge
  // map (Gaussian of the distance to the nearest Canny edge, sigma = W_trig) in the world frame
  // (the run starts at the true pose, so map and world frames coincide up to drift), and much
  // less once the map is shifted by 10 cells.
  cv::Mat not_edges = (ceiling.edges == 0);
  cv::Mat distance_px;
  cv::distanceTransform(not_edges, distance_px, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  const GridMap2f& m = slam.map();
  const double sigma = camera.wTrig();
  const auto edgeness = [&](int col, int row) {
    const double wx = m.origin_x_m + (col + 0.5) * m.resolution_m;
    const double wy = m.origin_y_m + (row + 0.5) * m.resolution_m;
    const int c = static_cast<int>(
        std::lround((wx - ceiling.origin_centre_m.x()) / ceiling.metres_per_pixel));
    const int r = static_cast<int>(
        std::lround((wy - ceiling.origin_centre_m.y()) / ceiling.metres_per_pixel));
    if (r < 0 || c < 0 || r >= distance_px.rows || c >= distance_px.cols) return -1.0;
    const double d = distance_px.at<float>(r, c) * ceiling.metres_per_pixel;
    return std::exp(-0.5 * d * d / (sigma * sigma));
  };
  const auto correlation = [&](int shift) {
    std::vector<double> a, b;
    for (int r = 0; r < m.height; ++r) {
      for (int c = 0; c + shift < m.width; ++c) {
        if (slam.normalisation().at(c + shift, r) < 5.0f) continue;
        const double e = edgeness(c, r);
        if (e < 0.0) continue;
        a.push_back(m.at(c + shift, r));
        b.push_back(e);
      }
    }
    const double n = static_cast<double>(a.size());
    double ma = 0, mb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
    double sab = 0, saa = 0, sbb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      sab += (a[i] - ma) * (b[i] - mb);
      saa += (a[i] - ma) * (a[i] - ma);
      sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
  };
  const double aligned = correlation(0);
  const double shifted = correlation(10);
  EXPECT_GT(aligned, 0.3);
  EXPECT_GT(aligned, 3.0 * std::abs(shifted));
}

// Without lens distortion the normalisation map Z is accumulated by a row-linear fast path; a
// negligible distortion takes the general per-cell projection. Both must give the same Z.
TEST(Ebslam2d, PinholeNormalisationMatchesGeneralProjection) {
  const testing::SyntheticCeiling ceiling = testing::makeSyntheticCeiling(4.0, 0.01, 3);
  const auto path = [](double t) { return testing::loopPath(t, 0.6, 0.3); };
  const CeilingCamera pinhole(CameraModel{}, 2.59);
  CameraModel almost_pinhole;
  almost_pinhole.kappa1 = 1e-15;
  const CeilingCamera general(almost_pinhole, 2.59);
  const EventVector events = testing::generateSyntheticEvents(ceiling, pinhole, path, 0.0, 0.4);
  ASSERT_GT(events.size(), 5000u);
  Ebslam2dConfig config;
  config.filter.g0 = 100.0;
  EventSlam2d a(config, pinhole, path(0.0));
  EventSlam2d b(config, general, path(0.0));
  a.process(events);
  b.process(events);
  ASSERT_GT(a.normalisationUpdates(), 3u);
  ASSERT_EQ(a.normalisationUpdates(), b.normalisationUpdates());
  double total = 0.0, max_diff = 0.0;
  std::size_t touched = 0;
  for (std::size_t k = 0; k < a.normalisation().cellCount(); ++k) {
    total += a.normalisation().data[k];
    touched += a.normalisation().data[k] > 0.0f;
    max_diff = std::max(max_diff, static_cast<double>(std::abs(a.normalisation().data[k] -
                                                               b.normalisation().data[k])));
  }
  EXPECT_GT(touched, 10000u);
  EXPECT_LT(max_diff, 1e-3 * total / static_cast<double>(touched));
}

// Background activity of `rate_hz` per pixel over [t0, t1) [s], merged into `events` by time.
void addNoise(EventVector& events, double rate_hz, double t0, double t1, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::exponential_distribution<double> gap(rate_hz * 128 * 128);
  std::uniform_int_distribution<int> pixel(0, 127);
  for (double t = t0 + gap(rng); t < t1; t += gap(rng)) {
    events.push_back(Event{static_cast<std::int64_t>(t * 1e6),
                           static_cast<std::uint16_t>(pixel(rng)),
                           static_cast<std::uint16_t>(pixel(rng)), (rng() & 1u) != 0});
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
}

// Robust start: the robot stands still for 1 s under 1 Hz of background activity per pixel (no
// signal at all), then drives. The thesis' per-event diffusion lets the pose random-walk on the
// noise; the noise-aware diffusion holds it (signal fraction near 0) and follows the motion that
// follows (signal fraction near 1).
TEST(Ebslam2d, NoiseAwareDiffusionHoldsStillUnderBackgroundActivity) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  const testing::SyntheticCeiling ceiling = testing::makeSyntheticCeiling(5.0, 0.01, 5);
  const auto path = [](double t) { return testing::loopPath(std::max(0.0, t - 1.0), 0.6, 0.3); };
  std::vector<std::pair<double, Pose2>> ground_truth;
  EventVector events =
      testing::generateSyntheticEvents(ceiling, camera, path, 1.0, 2.0, 0.15, &ground_truth);
  addNoise(events, 1.0, 0.0, 2.0, 3);
  const auto still_end = static_cast<std::size_t>(
      std::find_if(events.begin(), events.end(), [](const Event& e) { return e.t_us >= 1000000; }) -
      events.begin());
  ASSERT_GT(still_end, 12000u);  // 16384 expected

  const auto drift = [&](bool noise_aware, double& signal_fraction_still, double& final_error) {
    Ebslam2dConfig config;
    config.filter.g0 = 100.0;
    config.noise_aware_diffusion = noise_aware;
    EventSlam2d slam(config, camera, path(0.0));
    slam.process(events.data(), still_end);
    const Pose2 held = slam.estimate();
    signal_fraction_still = slam.signalFraction();
    if (noise_aware) {
      EXPECT_NEAR(slam.backgroundRateHz(), 128.0 * 128.0, 0.15 * 128 * 128);
    }
    slam.process(events.data() + still_end, events.size() - still_end);
    const Pose2 end = slam.estimate();
    const Pose2 truth = ground_truth.back().second;
    final_error = std::hypot(end.x - truth.x, end.y - truth.y);
    return std::hypot(held.x - path(0.0).x, held.y - path(0.0).y);
  };
  double fraction_plain = 0.0, fraction_aware = 0.0, error_plain = 0.0, error_aware = 0.0;
  const double drift_plain = drift(false, fraction_plain, error_plain);
  const double drift_aware = drift(true, fraction_aware, error_aware);
  EXPECT_EQ(fraction_plain, 1.0);
  EXPECT_LT(fraction_aware, 0.25);
  EXPECT_LT(drift_aware, 0.005) << drift_plain;
  EXPECT_GT(drift_plain, 2.0 * drift_aware);
  // After 1 s of driving (0.3 m, unaligned): as close to the truth as the thesis' model.
  EXPECT_LT(error_aware, 0.08) << "the plain model: " << error_plain;

  Ebslam2dConfig bad;
  bad.experimental.rate_window_s = 0.0;
  EXPECT_THROW(EventSlam2d(bad, camera), std::invalid_argument);
  bad = Ebslam2dConfig{};
  bad.experimental.noise_floor_band = 0.5;
  EXPECT_THROW(EventSlam2d(bad, camera), std::invalid_argument);
}

TEST(Ebslam2d, BadInputIsRejected) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  EventSlam2d slam(Ebslam2dConfig{}, camera);
  slam.process(EventVector{});
  EXPECT_EQ(slam.processedEvents(), 0u);
  EXPECT_THROW(slam.process(EventVector{{1, 200, 3, true}}), std::invalid_argument);
  EXPECT_THROW(slam.process(EventVector{{5, 1, 3, true}, {4, 1, 3, true}}), std::invalid_argument);
  EXPECT_EQ(slam.processedEvents(), 0u);
  Ebslam2dConfig bad;
  bad.cell_size_wtrig = 0.0;
  EXPECT_THROW(EventSlam2d(bad, camera), std::invalid_argument);
  bad = Ebslam2dConfig{};
  bad.map_size_m = 1e6;
  EXPECT_THROW(EventSlam2d(bad, camera), std::invalid_argument);
  // An all-zero map image does not crash the visualisation.
  EXPECT_EQ(mapToImage(slam.map()).at<std::uint8_t>(0, 0), 255);
}

// Runtime knobs change without losing the map; an invalid change throws and changes nothing.
TEST(Ebslam2d, SetFilterConfigKeepsTheMap) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  const testing::SyntheticCeiling ceiling = testing::makeSyntheticCeiling(5.0, 0.01, 5);
  const auto path = [](double t) { return testing::loopPath(t, 0.6, 0.3); };
  const EventVector events =
      testing::generateSyntheticEvents(ceiling, camera, path, 0.0, 0.5, 0.15);
  ASSERT_GT(events.size(), 1000u);
  EventSlam2d slam(Ebslam2dConfig{}, camera, path(0.0));
  const std::size_t half = events.size() / 2;
  slam.process(events.data(), half);
  const Pose2 before = slam.estimate();
  double mass = 0.0;
  for (float v : slam.occurrence().data) mass += v;
  ASSERT_GT(mass, 0.0);

  EventFilterConfig bad = slam.config().filter;
  bad.batch_size = 0;
  EXPECT_THROW(slam.setFilterConfig(bad), std::invalid_argument);
  EXPECT_EQ(slam.config().filter.batch_size, Ebslam2dConfig{}.filter.batch_size);

  EventFilterConfig changed = slam.config().filter;
  changed.num_particles = 25;
  changed.batch_size = 8;
  changed.resample_every = 50;
  slam.setFilterConfig(changed);
  EXPECT_EQ(slam.particles().size(), 25);
  EXPECT_EQ(slam.config().filter.batch_size, 8);
  double mass_after = 0.0;
  for (float v : slam.occurrence().data) mass_after += v;
  EXPECT_DOUBLE_EQ(mass_after, mass);
  EXPECT_NEAR(slam.estimate().x, before.x, 1e-3);
  EXPECT_NEAR(slam.estimate().y, before.y, 1e-3);
  slam.process(events.data() + half, events.size() - half);
  EXPECT_EQ(slam.processedEvents(), events.size());
}

}  // namespace
}  // namespace ebslam
