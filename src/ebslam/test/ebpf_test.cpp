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
