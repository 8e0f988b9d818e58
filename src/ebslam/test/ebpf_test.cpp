#include "ebslam/slam/ebpf.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "synthetic_ceiling.h"

namespace ebslam {
namespace {

double angleDiff(double a, double b) { return std::remainder(a - b, 2.0 * M_PI); }

TEST(CeilingCamera, BackProjectionInvertsProjection) {
  CameraModel model;
  model.kappa1 = -1.5e-3;
  model.kappa2 = 4e-6;
  const CeilingCamera camera(model, 2.59);
  EXPECT_NEAR(camera.wTrig(), 0.03, 1e-9);
  for (int y = 0; y < 128; y += 9) {
    for (int x = 0; x < 128; x += 7) {
      const std::size_t k = static_cast<std::size_t>(y) * 128 + x;
      const Eigen::Vector2d p(camera.offsetX()[k], camera.offsetY()[k]);
      const Eigen::Vector2d pixel = camera.project(p);
      EXPECT_NEAR(pixel.x(), x, 1e-4);
      EXPECT_NEAR(pixel.y(), y, 1e-4);
    }
  }
  EXPECT_THROW(CeilingCamera(model, 0.0), std::invalid_argument);
}

TEST(Ebpf, EdgeLikelihoodIsGaussianOfEdgeDistance) {
  cv::Mat edges(50, 60, CV_8UC1, cv::Scalar(0));
  edges.col(20).setTo(255);
  const GridMap2f map = makeEdgeLikelihoodMap(edges, 0.01, {1.0, 2.0}, 0.015);
  // Pixel (25, 10) is 5 px = 5 cm from the edge column; its centre is at (1.25, 2.10).
  EXPECT_NEAR(map.lookup(1.25, 2.10), std::exp(-0.5 * std::pow(0.05 / 0.015, 2)), 1e-5);
  EXPECT_NEAR(map.lookup(1.20, 2.10), 1.0, 1e-6);
  EXPECT_EQ(map.lookup(-5.0, 2.0), 0.0f);
  EXPECT_THROW(makeEdgeLikelihoodMap(cv::Mat(5, 5, CV_8UC1, cv::Scalar(0)), 0.01, {0, 0}, 0.01),
               std::invalid_argument);
  EXPECT_THROW(makeEdgeLikelihoodMap(cv::Mat(), 0.01, {0, 0}, 0.01), std::invalid_argument);
}

class EbpfOnSyntheticCeiling : public ::testing::Test {
 protected:
  // Generated once for the suite (about 1 s).
  static void SetUpTestSuite() {
    ceiling_ = testing::makeSyntheticCeiling(4.0, 0.01, 11);
    events_ = testing::generateSyntheticEvents(
        ceiling_, camera_, [](double t) { return testing::loopPath(t); }, 0.0, 2.0, 0.15,
        &ground_truth_);
  }
  GridMap2f likelihood() const {
    return makeEdgeLikelihoodMap(ceiling_.edges, ceiling_.metres_per_pixel,
                                 ceiling_.origin_centre_m, 0.5 * camera_.wTrig());
  }
  static inline const CeilingCamera camera_{CameraModel{}, 2.59};
  static inline testing::SyntheticCeiling ceiling_;
  static inline EventVector events_;
  static inline std::vector<std::pair<double, Pose2>> ground_truth_;
};

// EB-PF tracks a 0.6 m path from a known start on a simple synthetic map (thesis 6.5.3:
// 0.6 cm RMSE in simulation); the estimate is compared at every render step.
TEST_F(EbpfOnSyntheticCeiling, ConvergesFromKnownStart) {
  ASSERT_GT(events_.size(), 100000u);
  EbpfConfig config;
  config.filter.g0 = 100.0;  // about 1/20 of the events per pixel of motion here
  EventParticleFilter filter(config, camera_, likelihood(), testing::loopPath(0.0));
  std::size_t next = 0;
  double sq_pos = 0.0;
  double sq_rot = 0.0;
  int n = 0;
  for (const auto& [t, pose] : ground_truth_) {
    const auto t_us = static_cast<std::int64_t>(std::llround(t * 1e6));
    std::size_t end = next;
    while (end < events_.size() && events_[end].t_us <= t_us) ++end;
    filter.process(events_.data() + next, end - next);
    next = end;
    const Pose2 e = filter.estimate();
    sq_pos += std::pow(e.x - pose.x, 2) + std::pow(e.y - pose.y, 2);
    sq_rot += std::pow(angleDiff(e.theta, pose.theta), 2);
    ++n;
  }
  const double rmse_pos = std::sqrt(sq_pos / n);
  const double rmse_rot = std::sqrt(sq_rot / n);
  EXPECT_LT(rmse_pos, 0.01) << "position RMSE [m]";
  EXPECT_LT(rmse_rot, 0.02) << "rotation RMSE [rad]";
  EXPECT_EQ(filter.processedEvents(), events_.size());
}

// A wrong start pose 5 cm / 3 degrees off (more than one pixel) is pulled in by the map.
TEST_F(EbpfOnSyntheticCeiling, RecoversFromOffsetStart) {
  EbpfConfig config;
  config.filter.g0 = 100.0;
  config.filter.num_particles = 100;
  config.filter.initial_spread_m = 0.03;
  config.filter.initial_spread_rad = 0.03;
  Pose2 start = testing::loopPath(0.0);
  start.x += 0.04;
  start.y -= 0.03;
  start.theta += 0.05;
  EventParticleFilter filter(config, camera_, likelihood(), start);
  filter.process(events_);
  const Pose2 truth = ground_truth_.back().second;
  const Pose2 e = filter.estimate();
  EXPECT_LT(std::hypot(e.x - truth.x, e.y - truth.y), 0.015);
  EXPECT_LT(std::abs(angleDiff(e.theta, truth.theta)), 0.02);
}

// Global localisation: hypotheses over the whole 4 m x 4 m ceiling, no start pose; the search
// converges (state back to tracking, N back to the tracking count) on the true pose.
TEST_F(EbpfOnSyntheticCeiling, GlobalLocalisationFindsThePoseWithoutAStart) {
  EbpfConfig config;
  config.filter.g0 = 100.0;
  config.localisation.max_particles = 20000;
  // 2 s of events: a larger share of them is scored than the real-time default.
  config.localisation.search_updates_per_event = 5000.0;
  EventParticleFilter filter(config, camera_, likelihood(), Pose2{1.5, -1.5, 2.0});
  filter.globalLocalisation();
  EXPECT_EQ(filter.state(), TrackingState::kGlobalSearch);
  EXPECT_EQ(filter.particles().size(), 20000);
  EXPECT_GT(filter.knownCells(), 3000u);  // most of the 4 m x 4 m in 5 cm cells
  // Spread over the map: the particles' position spread is about that of a uniform 4 m square.
  const Eigen::Matrix3d spread = filter.particles().covariance();
  EXPECT_GT(spread(0, 0), 0.8);
  EXPECT_GT(spread(1, 1), 0.8);
  filter.process(events_);
  EXPECT_EQ(filter.state(), TrackingState::kTracking);
  EXPECT_EQ(filter.convergences(), 1u);
  EXPECT_EQ(filter.particles().size(), config.filter.num_particles);
  const Pose2 truth = ground_truth_.back().second;
  const Pose2 e = filter.estimate();
  EXPECT_LT(std::hypot(e.x - truth.x, e.y - truth.y), 0.03);
  EXPECT_LT(std::abs(angleDiff(e.theta, truth.theta)), 0.05);
  EXPECT_EQ(filter.processedEvents(), events_.size());
}

// Kidnapping: tracked along the loop, then the events come from a path 1.3 m away; the
// detector fires and the search finds the new pose.
TEST_F(EbpfOnSyntheticCeiling, KidnapIsDetectedAndRecovered) {
  const auto moved = [](double t) {
    Pose2 p = testing::loopPath(t - 2.0);
    return Pose2{p.x - 1.1, p.y - 0.7, p.theta + 1.0};
  };
  std::vector<std::pair<double, Pose2>> truth2;
  const EventVector after =
      testing::generateSyntheticEvents(ceiling_, camera_, moved, 2.0, 4.0, 0.15, &truth2);
  EbpfConfig config;
  config.filter.g0 = 100.0;
  config.localisation.max_particles = 20000;
  config.localisation.recovery_alpha_slow = 2e-5;
  config.localisation.recovery_alpha_fast = 2e-3;
  config.localisation.search_updates_per_event = 5000.0;
  EventParticleFilter filter(config, camera_, likelihood(), testing::loopPath(0.0));
  filter.process(events_);
  EXPECT_EQ(filter.recoveries(), 0u) << "no false alarm while tracking";
  filter.process(after);
  EXPECT_EQ(filter.recoveries(), 1u);
  EXPECT_EQ(filter.state(), TrackingState::kTracking);
  const Pose2 truth = truth2.back().second;
  const Pose2 e = filter.estimate();
  EXPECT_LT(std::hypot(e.x - truth.x, e.y - truth.y), 0.03);
  EXPECT_LT(std::abs(angleDiff(e.theta, truth.theta)), 0.05);
}

// The kidnap detector processes the events in chunks of whole batches: while it does not fire,
// the filter is the same as without it (same particles, same estimate).
TEST_F(EbpfOnSyntheticCeiling, DetectorLeavesTrackingUnchanged) {
  EbpfConfig plain;
  plain.filter.g0 = 100.0;
  EbpfConfig detecting = plain;
  detecting.localisation.recovery_alpha_slow = 2e-5;
  detecting.localisation.recovery_alpha_fast = 2e-3;
  EventParticleFilter a(plain, camera_, likelihood(), testing::loopPath(0.0));
  EventParticleFilter b(detecting, camera_, likelihood(), testing::loopPath(0.0));
  for (std::size_t i = 0; i < events_.size(); i += 1000) {
    const std::size_t n = std::min<std::size_t>(1000, events_.size() - i);
    a.process(events_.data() + i, n);
    b.process(events_.data() + i, n);
  }
  ASSERT_EQ(b.recoveries(), 0u);
  for (int i = 0; i < a.particles().size(); ++i) {
    EXPECT_EQ(a.particles().particle(i).x, b.particles().particle(i).x);
    EXPECT_EQ(a.particles().particle(i).theta, b.particles().particle(i).theta);
  }
  EXPECT_EQ(a.estimate().x, b.estimate().x);
}

TEST(Ebpf, ReseedDrawsAroundTheGivenPose) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  cv::Mat edges(100, 100, CV_8UC1, cv::Scalar(0));
  edges.row(50).setTo(255);
  EbpfConfig config;
  config.filter.num_particles = 2000;
  EventParticleFilter filter(config, camera,
                             makeEdgeLikelihoodMap(edges, 0.05, {-2.5, -2.5}, 0.015), Pose2{});
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov(0, 0) = 0.04;  // 0.2 m
  cov(1, 1) = 0.01;  // 0.1 m
  cov(2, 2) = 0.0;   // heading exact (rviz may send zeros)
  filter.reseed({1.0, -0.5, 3.0}, cov);
  EXPECT_EQ(filter.particles().size(), 2000);
  const Pose2 mean = filter.particles().weightedMean();
  EXPECT_NEAR(mean.x, 1.0, 0.02);
  EXPECT_NEAR(mean.y, -0.5, 0.01);
  EXPECT_NEAR(mean.theta, 3.0, 1e-6);
  const Eigen::Matrix3d spread = filter.particles().covariance();
  EXPECT_NEAR(spread(0, 0), 0.04, 0.006);
  EXPECT_NEAR(spread(1, 1), 0.01, 0.0015);
  // Bad covariances are rejected and change nothing.
  Eigen::Matrix3d bad = cov;
  bad(0, 0) = -1.0;
  EXPECT_THROW(filter.reseed({0, 0, 0}, bad), std::invalid_argument);
  bad = cov;
  bad(0, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(filter.reseed({0, 0, 0}, bad), std::invalid_argument);
  EXPECT_THROW(filter.reseed({std::numeric_limits<double>::infinity(), 0, 0}, cov),
               std::invalid_argument);
  EXPECT_NEAR(filter.particles().weightedMean().x, 1.0, 0.02);
}

TEST(Ebpf, OdometryMovesEveryParticleInItsOwnFrame) {
  ParticleSet2D set;
  set.reset(200, {1.0, 2.0, 0.5}, 0.1, 0.3, 1.0, 7);
  std::vector<Pose2> before;
  for (int i = 0; i < set.size(); ++i) before.push_back(set.particle(i));
  const Pose2 delta{0.3, 0.1, 0.2};
  set.applyOdometry(delta, 0.0, 0.0, 0.0, 0.0);  // noise-free: an exact SE(2) composition
  for (int i = 0; i < set.size(); ++i) {
    const Pose2 expected = compose(before[static_cast<std::size_t>(i)], delta);
    EXPECT_NEAR(set.particle(i).x, expected.x, 1e-5);
    EXPECT_NEAR(set.particle(i).y, expected.y, 1e-5);
    EXPECT_NEAR(angleDiff(set.particle(i).theta, expected.theta), 0.0, 1e-5);
  }
  // With noise the spread grows with the motion (alpha3: 10 % of the distance).
  ParticleSet2D noisy;
  noisy.reset(4000, {0.0, 0.0, 0.0}, 0.0, 0.0, 1.0, 7);
  noisy.applyOdometry({1.0, 0.0, 0.0}, 0.0, 0.0, 0.01, 0.0);
  const Eigen::Matrix3d c = noisy.covariance();
  EXPECT_NEAR(std::sqrt(c(0, 0)), 0.1, 0.01);
  EXPECT_NEAR(noisy.weightedMean().x, 1.0, 0.01);
  // Backwards: a reverse drive, not a half turn.
  ParticleSet2D back;
  back.reset(10, {0.0, 0.0, 0.0}, 0.0, 0.0, 1.0, 7);
  back.applyOdometry({-0.5, 0.0, 0.0}, 0.0, 0.0, 0.0, 0.0);
  EXPECT_NEAR(back.particle(0).x, -0.5, 1e-6);
  EXPECT_NEAR(back.particle(0).theta, 0.0, 1e-6);
}

TEST(Ebpf, KldParticleCountFollowsTheChiSquareBound) {
  // n = chi2_{k-1, 1-delta} / (2 eps) (Fox 2003): chi2_{99, 0.99} = 134.64 -> 1346.
  EXPECT_NEAR(kldParticleCount(100, 0.05, 0.99), 1346, 3);
  EXPECT_EQ(kldParticleCount(1, 0.05, 0.99), 1);
  EXPECT_LT(kldParticleCount(10, 0.05, 0.99), kldParticleCount(1000, 0.05, 0.99));
  EbpfConfig bad;
  bad.localisation.kld_err = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = EbpfConfig{};
  bad.localisation.max_particles = bad.localisation.min_particles - 1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = EbpfConfig{};
  bad.localisation.recovery_alpha_slow = 0.1;  // fast missing
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = EbpfConfig{};
  bad.localisation.search_sigmas_m = {0.1, 0.05};
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(Ebpf, BadInputIsRejectedWithoutSideEffects) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  cv::Mat edges(100, 100, CV_8UC1, cv::Scalar(0));
  edges.row(50).setTo(255);
  EventParticleFilter filter(EbpfConfig{}, camera,
                             makeEdgeLikelihoodMap(edges, 0.05, {-2.5, -2.5}, 0.015), Pose2{});
  filter.process(EventVector{});  // empty stream: no-op
  EXPECT_EQ(filter.processedEvents(), 0u);
  EXPECT_THROW(filter.process(EventVector{{10, 3, 4, true}, {11, 128, 4, true}}),
               std::invalid_argument);
  EXPECT_THROW(filter.process(EventVector{{10, 3, 4, true}, {9, 5, 4, true}}),
               std::invalid_argument);
  EXPECT_EQ(filter.processedEvents(), 0u);
  filter.process(EventVector{{10, 3, 4, true}, {10, 5, 4, false}});
  EXPECT_EQ(filter.processedEvents(), 2u);
  // Time may not run backwards across calls either.
  EXPECT_THROW(filter.process(EventVector{{5, 3, 4, true}}), std::invalid_argument);
  EbpfConfig bad;
  bad.filter.num_particles = 0;
  EXPECT_THROW(
      EventParticleFilter(bad, camera, makeEdgeLikelihoodMap(edges, 0.05, {0, 0}, 0.015), Pose2{}),
      std::invalid_argument);
  bad = EbpfConfig{};
  bad.filter.beta = 1.5;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(Ebpf, SetFilterConfigChangesKnobsAndKeepsThePose) {
  const CeilingCamera camera(CameraModel{}, 2.59);
  cv::Mat edges(100, 100, CV_8UC1, cv::Scalar(0));
  edges.row(50).setTo(255);
  const Pose2 start{0.2, -0.1, 0.3};
  EventParticleFilter filter(EbpfConfig{}, camera,
                             makeEdgeLikelihoodMap(edges, 0.05, {-2.5, -2.5}, 0.015), start);
  EventFilterConfig bad = filter.config().filter;
  bad.resample_every = 0;
  EXPECT_THROW(filter.setFilterConfig(bad), std::invalid_argument);
  EXPECT_EQ(filter.config().filter.resample_every, EbpfConfig{}.filter.resample_every);
  EventFilterConfig changed = filter.config().filter;
  changed.num_particles = 7;
  changed.batch_size = 16;
  filter.setFilterConfig(changed);
  EXPECT_EQ(filter.particles().size(), 7);
  EXPECT_NEAR(filter.estimate().x, start.x, 1e-6);
  EXPECT_NEAR(filter.estimate().theta, start.theta, 1e-6);
  EventVector events;
  for (int i = 0; i < 40; ++i) events.push_back({i, static_cast<std::uint16_t>(i), 5, true});
  filter.process(events);
  EXPECT_EQ(filter.processedEvents(), 40u);
}

TEST(VelocityEstimator, RecoversAConstantVelocityAcrossTheHeadingWrap) {
  VelocityEstimator v(0.1);
  EXPECT_DOUBLE_EQ(v.velocity().x, 0.0);
  for (int k = 0; k <= 40; ++k) {
    const double t = 0.005 * k;
    // 0.3 m/s along x, -0.2 m/s along y, 2 rad/s through +-pi.
    v.add(t, Pose2{1.0 + 0.3 * t, -0.2 * t, std::remainder(3.0 + 2.0 * t, 2.0 * M_PI)});
  }
  EXPECT_NEAR(v.velocity().x, 0.3, 1e-9);
  EXPECT_NEAR(v.velocity().y, -0.2, 1e-9);
  EXPECT_NEAR(v.velocity().theta, 2.0, 1e-9);
  // A gap longer than the window restarts the estimate.
  v.add(1.0, Pose2{});
  EXPECT_DOUBLE_EQ(v.velocity().x, 0.0);
  EbpfConfig bad;
  bad.filter.latency_compensation_s = -0.01;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam
