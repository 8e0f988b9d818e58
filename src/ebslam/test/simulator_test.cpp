#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/camera_model.h"
#include "ebslam/slam/ebpf.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Vertical stripes (constant along rows): `period_texels` wide, half bright, half dark.
cv::Mat stripeTexture(int period_texels, int periods, float bright, float dark) {
  cv::Mat texture(period_texels, period_texels * periods, CV_32FC1);
  for (int col = 0; col < texture.cols; ++col) {
    const float value = (col % period_texels) < period_texels / 2 ? bright : dark;
    texture.col(col).setTo(value);
  }
  return texture;
}

// Straight constant-speed floor-robot path from (x0, y0) to (x1, y1) with fixed heading.
Trajectory straightPath(double x0, double y0, double x1, double y1, double theta,
                        double duration_s) {
  Trajectory trajectory;
  const int steps = 20;
  for (int i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) / steps;
    trajectory.push_back(
        se2ToFloorPose(s * duration_s, x0 + s * (x1 - x0), y0 + s * (y1 - y0), theta));
  }
  return trajectory;
}

Scene ceilingWith(const cv::Mat& texture, double metres_per_texel) {
  FloorRegion region;
  region.min = Eigen::Vector2d(-6.0, -6.0);
  region.max = Eigen::Vector2d(6.0, 6.0);
  return makeCeilingScene(texture, region, metres_per_texel);
}

SimulatorConfig noiselessConfig() {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 0.0;
  return config;
}

TEST(CameraModel, ProjectAndBackprojectRoundTripWithDistortion) {
  CameraModel camera;
  camera.kappa1 = -4e-4;
  camera.kappa2 = 1e-6;
  ASSERT_NO_THROW(camera.validate());
  for (double u : {0.0, 10.3, 63.5, 100.0, 127.0}) {
    for (double v : {0.0, 40.7, 127.0}) {
      const auto ray = camera.backprojectRay(Eigen::Vector2d(u, v));
      ASSERT_TRUE(ray.has_value());
      const auto pixel = camera.project(2.59 * *ray);
      ASSERT_TRUE(pixel.has_value());
      EXPECT_NEAR(pixel->x(), u, 1e-9);
      EXPECT_NEAR(pixel->y(), v, 1e-9);
    }
  }
  // Eq. 6.3: a point at undistorted radius r appears at r (1 + k1 r + k2 r^2).
  const Eigen::Vector2d distorted = camera.distort(camera.principal_point + Eigen::Vector2d(50, 0));
  EXPECT_NEAR(distorted.x() - camera.principal_point.x(), 50.0 * (1.0 - 4e-4 * 50 + 1e-6 * 2500),
              1e-12);
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0.0, 0.0, -1.0)).has_value());
}

// Eq. 8.3 direction (as CeilingCamera): L applied to the event's own radius undistorts it.
TEST(CameraModel, Eq83DistortionModelUndistortsWithThePolynomial) {
  CameraModel camera;
  camera.kappa1 = 5e-4;
  camera.kappa2 = -1e-6;
  camera.distortion_model = DistortionModel::kUndistortEq83;
  ASSERT_NO_THROW(camera.validate());
  const Eigen::Vector2d event(120.0, 20.0);
  const Eigen::Vector2d d = event - camera.principal_point;
  const double l = 1.0 + 5e-4 * d.norm() - 1e-6 * d.squaredNorm();
  const auto ray = camera.backprojectRay(event);
  ASSERT_TRUE(ray.has_value());
  EXPECT_NEAR(ray->x(), l * d.x() / camera.focal_px, 1e-12);
  EXPECT_NEAR(ray->y(), l * d.y() / camera.focal_px, 1e-12);
  const auto pixel = camera.project(*ray);
  ASSERT_TRUE(pixel.has_value());
  EXPECT_NEAR((*pixel - event).norm(), 0.0, 1e-9);
}

TEST(CameraModel, ThesisFocalLengthAndTriggerDistance) {
  const CameraModel camera;
  EXPECT_NEAR(camera.triggerDistance(2.59), 0.03, 1e-12);                        // W_trig of 6.5.3
  EXPECT_NEAR(CameraModel::focalFromOpeningAngle(kPi / 2.0, 128), 128.0, 1e-9);  // eq. 6.2
  EXPECT_THROW(CameraModel::focalFromOpeningAngle(0.0), std::invalid_argument);
  CameraModel bad;
  bad.focal_px = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = CameraModel();
  bad.kappa1 = -0.02;  // folds over inside the sensor
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The geometry ebpf/ebslam rely on: a ceiling point seen at pixel e from robot pose
// (x, y, theta) lies at (x, y) + R_z(theta) (D / f) (e - c) (eq. 6.32-6.35).
TEST(EventSimulator, RenderedImageFollowsTheCeilingProjectionOfEq635) {
  cv::Mat texture(400, 400, CV_32FC1, cv::Scalar(0.1));
  texture(cv::Rect(250, 120, 4, 4)).setTo(1.0);  // bright 2 cm dot, 1 cm texels
  FloorRegion region;
  region.min = Eigen::Vector2d(-2.0, -2.0);
  region.max = Eigen::Vector2d(2.0, 2.0);
  const Scene scene = makeCeilingScene(texture, region, 0.01);
  const Eigen::Vector2d dot_world = region.min + Eigen::Vector2d(2.52, 1.22);
  SimulatorConfig config = noiselessConfig();
  const EventSimulator simulator(config);
  const double x = 0.1, y = -0.3, theta = 0.7;
  const StampedPose pose = se2ToFloorPose(0.0, x, y, theta);
  Eigen::Isometry3d camera_pose = Eigen::Isometry3d::Identity();
  camera_pose.linear() = pose.orientation.toRotationMatrix();
  camera_pose.translation() = pose.position;
  const cv::Mat image = simulator.renderIntensity(scene, camera_pose);
  cv::Point brightest;
  cv::minMaxLoc(image, nullptr, nullptr, nullptr, &brightest);
  const double scale = kThesisCeilingHeightM / config.camera.focal_px;
  const Eigen::Vector2d offset(scale * (brightest.x - config.camera.principal_point.x()),
                               scale * (brightest.y - config.camera.principal_point.y()));
  const Eigen::Vector2d world = Eigen::Vector2d(x, y) + Eigen::Rotation2Dd(theta) * offset;
  EXPECT_LT((world - dot_world).norm(), 0.03) << "one pixel is W_trig = 3 cm";
}

// Supersampling integrates the pixel area by rays instead of by the texture pre-filter: both
// renderings of the same view agree up to aliasing residue.
TEST(EventSimulator, SupersamplingAgreesWithPrefilteredRendering) {
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.005);
  SimulatorConfig config = noiselessConfig();
  const StampedPose pose = se2ToFloorPose(0.0, 0.3, -0.2, 0.4);
  Eigen::Isometry3d camera_pose = Eigen::Isometry3d::Identity();
  camera_pose.linear() = pose.orientation.toRotationMatrix();
  camera_pose.translation() = pose.position;
  const cv::Mat single = EventSimulator(config).renderIntensity(scene, camera_pose);
  config.supersampling = 3;
  const cv::Mat super = EventSimulator(config).renderIntensity(scene, camera_pose);
  cv::Mat difference;
  cv::absdiff(single, super, difference);
  EXPECT_LT(cv::mean(difference)[0], 0.006);
  double max_difference = 0.0;
  cv::minMaxLoc(difference, nullptr, &max_difference);
  EXPECT_LT(max_difference, 0.08);
  EXPECT_GT(cv::mean(super)[0], 0.5);  // the bright ceiling, not the background
}

// Eq. 6.6: moving a distance x parallel to a plane at distance D with G0 effective feature points
// in view gives E_x = x f G0 / D events. Texture: vertical stripes of period P alternating
// between two log intensities dL apart. The field of view (W D / f metres wide) holds
// 2 (W D / f) / P edges, each covering H pixels, so G0 = H (2 W D / (f P)) k with k the events
// per pixel crossing of an edge. For the change detector with threshold C, k is not dL / C: the
// reference level ends within C below the bright level after an ON run and within C above the
// dark level after an OFF run, so with a uniformly random level phase a crossing fires
// k = (dL - C) / C events on average (the first crossing from the initial state fires more, so
// events are counted only after every pixel has crossed two edges).
TEST(EventSimulator, EventCountPerMetreMatchesEq66OnStripes) {
  SimulatorConfig config = noiselessConfig();
  config.events.threshold_mismatch_sigma = 0.0;
  const double c = config.events.contrast_threshold_on;
  const double eps = config.events.log_epsilon;
  const double metres_per_texel = 0.005;
  const int period_texels = 60;  // P = 0.3 m = 10 pixels at D = 2.59 m
  const double period = period_texels * metres_per_texel;
  const CameraModel& camera = config.camera;
  const double d = kThesisCeilingHeightM;
  const double speed = 0.5;       // m/s
  const double warm_up = period;  // two edge crossings per pixel
  const double measured_distance = 2.0 * period;
  const double duration = (warm_up + measured_distance) / speed;
  for (const double contrast_in_thresholds : {2.5, 4.0}) {
    const double log_contrast = contrast_in_thresholds * c;
    const float bright = 0.8f;
    const float dark = static_cast<float>((bright + eps) / std::exp(log_contrast) - eps);
    const Scene scene =
        ceilingWith(stripeTexture(period_texels, 10, bright, dark), metres_per_texel);
    const Trajectory path = straightPath(0.0, 0.0, speed * duration, 0.0, 0.0, duration);
    const SimulationResult result = EventSimulator(config).simulate(scene, path, 0.0, duration);
    const auto warm_up_end_us = static_cast<std::int64_t>(warm_up / speed * 1e6);
    const auto counted = std::count_if(result.events.begin(), result.events.end(),
                                       [&](const Event& e) { return e.t_us > warm_up_end_us; });

    const double edges_in_view = 2.0 * (camera.width * d / camera.focal_px) / period;
    const double events_per_crossing = (log_contrast - c) / c;
    const double g0 = camera.height * edges_in_view * events_per_crossing;
    const double expected = measured_distance * camera.focal_px * g0 / d;  // eq. 6.6
    EXPECT_NEAR(static_cast<double>(counted) / expected, 1.0, 0.03)
        << "contrast " << contrast_in_thresholds << " C: events " << counted << " expected "
        << expected;
    EXPECT_EQ(result.noise_events, 0u);

    if (contrast_in_thresholds == 2.5) {
      // Moving along the stripes changes nothing.
      const Trajectory along = straightPath(0.0, 0.0, 0.0, 0.6, 0.0, 1.2);
      EXPECT_LT(EventSimulator(config).simulate(scene, along, 0.0, 1.2).events.size(),
                expected * 0.002);
    }
  }
}

// Eq. 6.6 vs eq. 6.8: on a statistically isotropic texture every pixel fires in proportion to
// its image speed, so rotating by theta (pixel i moves theta r_i pixels) and translating by x
// (every pixel moves x f / D pixels) give E_theta / theta : E_x / x = 0.38247 S : f / D, the
// thesis' empirical constant for the mean distance of the square sensor's pixels from c.
TEST(EventSimulator, RotationToTranslationEventRatioMatchesEq66AndEq68) {
  SimulatorConfig config = noiselessConfig();
  cv::Mat noise(800, 800, CV_32FC1);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(), 4.0, 4.0, cv::BORDER_REFLECT);
  cv::normalize(noise, noise, 0.15, 0.85, cv::NORM_MINMAX);
  const Scene scene = ceilingWith(noise, 0.01);
  const EventSimulator simulator(config);
  const double x = 0.3;
  const double theta = 0.25;
  const auto translation = static_cast<double>(
      simulator.simulate(scene, straightPath(0.0, 0.0, x, 0.0, 0.0, 1.0), 0.0, 1.0).events.size());
  const Trajectory turn = {se2ToFloorPose(0.0, 0.0, 0.0, 0.0),
                           se2ToFloorPose(1.0, 0.0, 0.0, theta)};
  const auto rotation =
      static_cast<double>(simulator.simulate(scene, turn, 0.0, 1.0).events.size());
  ASSERT_GT(translation, 10000.0);
  const double d = kThesisCeilingHeightM;
  const double expected_ratio = 0.38247 * config.camera.width / (config.camera.focal_px / d);
  EXPECT_NEAR((rotation / theta) / (translation / x) / expected_ratio, 1.0, 0.05)
      << "rotation " << rotation << " translation " << translation;
}

// Eq. 6.11: the number of events depends on the distance moved, not on the speed.
TEST(EventSimulator, EventCountIsProportionalToDistanceNotSpeed) {
  const SimulatorConfig config = noiselessConfig();
  LinesAndCirclesConfig texture_config;
  texture_config.width_px = 600;
  texture_config.height_px = 600;
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(texture_config), 0.01);
  const EventSimulator simulator(config);
  const double slow = static_cast<double>(
      simulator.simulate(scene, straightPath(0, 0, 0.5, 0.3, 0.2, 2.0), 0.0, 2.0).events.size());
  const double fast = static_cast<double>(
      simulator.simulate(scene, straightPath(0, 0, 0.5, 0.3, 0.2, 0.25), 0.0, 0.25).events.size());
  const double twice = static_cast<double>(
      simulator.simulate(scene, straightPath(0, 0, 1.0, 0.6, 0.2, 1.0), 0.0, 1.0).events.size());
  ASSERT_GT(slow, 1000.0);
  EXPECT_NEAR(fast / slow, 1.0, 0.05);
  EXPECT_NEAR(twice / slow, 2.0, 0.2);
}

TEST(EventSimulator, EventsAreInsideTheSensorTimeOrderedAndDeterministic) {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 2.0;
  config.events.seed = 7;
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  Trajectory path;
  for (int i = 0; i <= 40; ++i) {  // a curve with turning
    const double t = 0.05 * i;
    path.push_back(se2ToFloorPose(t, 0.3 * t, 0.2 * std::sin(2.0 * t), 0.8 * t));
  }
  const EventSimulator simulator(config);
  const SimulationResult first = simulator.simulate(scene, path, 0.2, 1.0);
  const SimulationResult second = simulator.simulate(scene, path, 0.2, 1.0);
  ASSERT_GT(first.events.size(), 1000u);
  EXPECT_EQ(first.events, second.events);
  EXPECT_EQ(first.signal_events + first.noise_events, first.events.size());
  const SensorSize sensor{128, 128};
  for (std::size_t i = 0; i < first.events.size(); ++i) {
    const Event& e = first.events[i];
    ASSERT_TRUE(sensor.contains(e)) << i;
    ASSERT_GE(e.t_us, 200000);
    ASSERT_LE(e.t_us, 1000000);
    if (i > 0) {
      ASSERT_LE(first.events[i - 1].t_us, e.t_us) << i;
    }
  }
  EXPECT_GT(std::count_if(first.events.begin(), first.events.end(),
                          [](const Event& e) { return e.polarity; }),
            0);
  // Ground truth: from t_begin to t_end at 200 Hz, the interpolated path.
  ASSERT_FALSE(first.ground_truth.empty());
  EXPECT_DOUBLE_EQ(first.ground_truth.front().t_s, 0.2);
  EXPECT_DOUBLE_EQ(first.ground_truth.back().t_s, 1.0);
  EXPECT_NEAR(static_cast<double>(first.ground_truth.size()), 0.8 * 200 + 1, 1.0);

  config.events.seed = 8;
  const SimulationResult other = EventSimulator(config).simulate(scene, path, 0.2, 1.0);
  EXPECT_NE(first.events, other.events);
}

TEST(EventSimulator, StaticCameraGivesOnlyNoiseEvents) {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 1.0;
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  const Trajectory still = {se2ToFloorPose(0.0, 0.2, 0.1, 0.3), se2ToFloorPose(2.0, 0.2, 0.1, 0.3)};
  const SimulationResult result = EventSimulator(config).simulate(scene, still, 0.0, 2.0);
  EXPECT_EQ(result.signal_events, 0u);
  const double expected = 1.0 * 128 * 128 * 2.0;  // Poisson mean, sd = sqrt(mean) = 181
  EXPECT_NEAR(static_cast<double>(result.events.size()), expected, 5.0 * std::sqrt(expected));

  config.events.noise_rate_hz_per_pixel = 0.0;
  EXPECT_TRUE(EventSimulator(config).simulate(scene, still, 0.0, 2.0).events.empty());
}

// Labels: signal events where the camera moves, noise events match the noise count, and the
// labelled sink sees the same events as the plain one.
TEST(EventSimulator, NoiseLabelsMarkTheNoiseEvents) {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 1.0;
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  const Trajectory path = straightPath(0.0, 0.0, 0.5, 0.0, 0.0, 1.0);
  const EventSimulator simulator(config);
  const SimulationResult result = simulator.simulate(scene, path, 0.0, 1.0);
  ASSERT_EQ(result.noise_labels.size(), result.events.size());
  const auto noise = static_cast<std::size_t>(
      std::count(result.noise_labels.begin(), result.noise_labels.end(), std::uint8_t{1}));
  EXPECT_EQ(noise, result.noise_events);
  EXPECT_GT(result.signal_events, 10000u);
  EXPECT_GT(result.noise_events, 10000u);
  EventVector streamed;
  simulator.simulate(scene, path, 0.0, 1.0, [&](const EventVector& e) {
    streamed.insert(streamed.end(), e.begin(), e.end());
  });
  EXPECT_EQ(streamed, result.events);

  // Without noise every event is signal; the signal events are the same as with noise.
  config.events.noise_rate_hz_per_pixel = 0.0;
  const SimulationResult clean = EventSimulator(config).simulate(scene, path, 0.0, 1.0);
  EventVector signal;
  for (std::size_t i = 0; i < result.events.size(); ++i) {
    if (!result.noise_labels[i]) signal.push_back(result.events[i]);
  }
  EXPECT_EQ(signal.size(), clean.events.size());
  EXPECT_EQ(std::count(clean.noise_labels.begin(), clean.noise_labels.end(), std::uint8_t{1}), 0);
}

// Per-pixel rates: a log-normal spread keeps the mean rate but concentrates the noise on fewer
// pixels; hot pixels fire at their own rate; the fixed pattern does not change with the knobs.
TEST(EventSimulator, NoiseRateSpreadAndHotPixels) {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 2.0;
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  const Trajectory still = {se2ToFloorPose(0.0, 0.2, 0.1, 0.3), se2ToFloorPose(4.0, 0.2, 0.1, 0.3)};
  const auto perPixel = [&](const SimulatorConfig& c) {
    const SimulationResult r = EventSimulator(c).simulate(scene, still, 0.0, 4.0);
    std::vector<int> counts(128 * 128, 0);
    for (const Event& e : r.events) ++counts[e.y * 128 + e.x];
    return counts;
  };
  const auto variance = [](const std::vector<int>& counts, double& mean) {
    mean = 0.0;
    for (int c : counts) mean += c;
    mean /= counts.size();
    double var = 0.0;
    for (int c : counts) var += (c - mean) * (c - mean);
    return var / counts.size();
  };
  double mean_uniform = 0.0, mean_spread = 0.0;
  const double var_uniform = variance(perPixel(config), mean_uniform);
  EXPECT_NEAR(mean_uniform, 8.0, 0.2);
  EXPECT_NEAR(var_uniform, 8.0, 0.6);  // Poisson: variance = mean
  config.events.noise_rate_log_sigma = 1.0;
  const double var_spread = variance(perPixel(config), mean_spread);
  EXPECT_NEAR(mean_spread, 8.0, 0.5);  // mean kept
  // Mixed Poisson: var = mean + mean^2 (e^{sigma^2} - 1) = 8 + 64 * 1.718 = 118.
  EXPECT_GT(var_spread, 60.0);

  config.events.noise_rate_log_sigma = 0.0;
  config.events.hot_pixel_fraction = 0.01;
  config.events.hot_pixel_rate_hz = 100.0;
  const std::vector<int> counts = perPixel(config);
  const auto hot = std::count_if(counts.begin(), counts.end(), [](int c) { return c > 200; });
  EXPECT_NEAR(static_cast<double>(hot), 0.01 * 128 * 128, 40.0);

  config.events.hot_pixel_fraction = 1.5;
  EXPECT_THROW(EventSimulator{config}, std::invalid_argument);
  config.events.hot_pixel_fraction = 0.0;
  config.events.noise_rate_log_sigma = -1.0;
  EXPECT_THROW(EventSimulator{config}, std::invalid_argument);
  config.events.noise_rate_log_sigma = 0.0;
  config.events.hot_pixel_rate_hz = std::nan("");
  EXPECT_THROW(EventSimulator{config}, std::invalid_argument);
}

// A change of several thresholds within one render step fires several events in one pixel,
// at increasing interpolated times and all of one polarity.
TEST(EventSimulator, SeveralThresholdCrossingsInOneStepGiveSeveralEvents) {
  SimulatorConfig config = noiselessConfig();
  config.events.threshold_mismatch_sigma = 0.0;
  config.events.randomize_initial_reference = false;
  config.events.refractory_period_us = 0.0;
  config.render_rate_hz = 1.0;         // one render step for the whole motion
  config.max_step_motion_px = 1000.0;  // no subdivision
  const double c = config.events.contrast_threshold_on;
  const float bright = 0.8f;
  const float dark = static_cast<float>((bright + config.events.log_epsilon) / std::exp(3.5 * c) -
                                        config.events.log_epsilon);
  const Scene scene = ceilingWith(stripeTexture(600, 4, bright, dark), 0.005);  // P = 3 m
  // Shift by a quarter period: about a quarter of the pixels change from bright to dark.
  const Trajectory path = straightPath(0.0, 0.0, 0.75, 0.0, 0.0, 1.0);
  const SimulationResult result = EventSimulator(config).simulate(scene, path, 0.0, 1.0);
  ASSERT_EQ(result.render_steps, 1u);
  std::map<int, std::vector<Event>> per_pixel;
  for (const Event& e : result.events) per_pixel[e.y * 128 + e.x].push_back(e);
  ASSERT_FALSE(per_pixel.empty());
  std::size_t triple = 0;
  for (const auto& [pixel, events] : per_pixel) {
    EXPECT_LE(events.size(), 3u);
    if (events.size() == 3) {
      ++triple;
      EXPECT_EQ(events[0].polarity, events[1].polarity);
      EXPECT_EQ(events[1].polarity, events[2].polarity);
      EXPECT_LT(events[0].t_us, events[1].t_us);
      EXPECT_LT(events[1].t_us, events[2].t_us);
    }
  }
  EXPECT_GT(triple, 1000u);
}

TEST(EventSimulator, RefractoryPeriodLimitsThePixelRate) {
  SimulatorConfig config = noiselessConfig();
  config.events.refractory_period_us = 50000.0;  // 50 ms
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  const Trajectory path = straightPath(0.0, 0.0, 1.0, 0.0, 0.0, 0.5);
  const SimulationResult result = EventSimulator(config).simulate(scene, path, 0.0, 0.5);
  std::map<int, std::int64_t> last;
  for (const Event& e : result.events) {
    const int pixel = e.y * 128 + e.x;
    const auto found = last.find(pixel);
    if (found != last.end()) {
      EXPECT_GE(e.t_us - found->second, 49999) << "pixel " << pixel;
    }
    last[pixel] = e.t_us;
  }
  config.events.refractory_period_us = 0.0;
  EXPECT_GT(EventSimulator(config).simulate(scene, path, 0.0, 0.5).events.size(),
            result.events.size() * 2);
}

TEST(EventSimulator, RejectsInvalidInput) {
  const Scene scene = ceilingWith(makeLinesAndCirclesTexture(), 0.01);
  const EventSimulator simulator(noiselessConfig());
  const Trajectory path = straightPath(0.0, 0.0, 1.0, 0.0, 0.0, 1.0);
  EXPECT_THROW(simulator.simulate(scene, {}, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(simulator.simulate(scene, path, -1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(simulator.simulate(scene, path, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(simulator.simulate(scene, path, 0.0, 2.0), std::invalid_argument);
  Trajectory nan_path = path;
  nan_path[3].position.x() = std::nan("");
  EXPECT_THROW(simulator.simulate(scene, nan_path, 0.0, 1.0), std::invalid_argument);
  Trajectory backwards = path;
  std::swap(backwards[2].t_s, backwards[3].t_s);
  EXPECT_THROW(simulator.simulate(scene, backwards, 0.0, 1.0), std::invalid_argument);
  Scene broken = scene;
  broken.planes[0].texture = cv::Mat();
  EXPECT_THROW(simulator.simulate(broken, path, 0.0, 1.0), std::invalid_argument);
  SimulatorConfig config;
  config.events.contrast_threshold_on = 0.0;
  EXPECT_THROW(EventSimulator{config}, std::invalid_argument);
  config = SimulatorConfig();
  config.render_rate_hz = std::nan("");
  EXPECT_THROW(EventSimulator{config}, std::invalid_argument);
  // An empty scene is valid: every ray sees the background, nothing changes.
  EXPECT_TRUE(simulator.simulate(Scene{}, path, 0.0, 1.0).events.empty());
}

TEST(FloorRobotTrajectory, ProjectsForwardLookingMocapPosesIntoThePlane) {
  // A forward-looking camera (optical axis horizontal) on a robot with heading psi, with some
  // mount tilt and height wobble that must be dropped.
  Trajectory mocap;
  for (int i = 0; i <= 300; ++i) {
    const double t = 100.0 + 0.01 * i;
    const double psi = 3.0 * std::sin(0.5 * t);  // crosses +-pi: needs unwrapping
    // Camera -> robot: optical axis (z) forward = robot x, camera x = -robot y, y = -robot z.
    Eigen::Matrix3d camera_in_robot;
    camera_in_robot << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    const Eigen::Matrix3d tilt =
        (Eigen::AngleAxisd(0.05 * std::sin(7.0 * t), Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(0.03 * std::cos(5.0 * t), Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
    StampedPose pose;
    pose.t_s = t;
    pose.position = Eigen::Vector3d(std::cos(t), 2.0 * std::sin(t), 0.55 + 0.01 * std::sin(9 * t));
    pose.orientation =
        Eigen::Quaterniond(Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                           camera_in_robot * tilt);
    mocap.push_back(pose);
  }
  FloorRobotTrajectoryConfig config;
  config.smoothing_half_window_s = 0.0;
  config.resample_interval_s = 0.0;
  const Trajectory floor = makeFloorRobotTrajectory(mocap, config);
  ASSERT_EQ(floor.size(), mocap.size());
  for (std::size_t i = 0; i < floor.size(); i += 17) {
    const Pose2 se2 = floorPoseToSe2(floor[i]);
    const double psi = 3.0 * std::sin(0.5 * mocap[i].t_s);
    EXPECT_NEAR(floor[i].t_s, mocap[i].t_s - 100.0, 1e-9);
    EXPECT_NEAR(se2.x, mocap[i].position.x(), 1e-12);
    EXPECT_NEAR(se2.y, mocap[i].position.y(), 1e-12);
    EXPECT_NEAR(floor[i].position.z(), 0.0, 1e-12);
    EXPECT_NEAR(std::remainder(se2.theta - psi, 2.0 * kPi), 0.0, 1e-9);
    // Camera looks up.
    EXPECT_NEAR((floor[i].orientation * Eigen::Vector3d::UnitZ()).z(), 1.0, 1e-12);
  }
  // Resampled and smoothed: uniform 5 ms steps over the same span.
  const Trajectory resampled = makeFloorRobotTrajectory(mocap);
  EXPECT_NO_THROW(validateTrajectory(resampled));
  EXPECT_NEAR(resampled[1].t_s - resampled[0].t_s, 0.005, 1e-12);
  EXPECT_NEAR(resampled.back().t_s, 3.0, 1e-9);

  EXPECT_THROW(makeFloorRobotTrajectory({mocap[0]}), std::invalid_argument);
  Trajectory up = mocap;
  for (StampedPose& pose : up) pose.orientation = Eigen::Quaterniond::Identity();
  EXPECT_THROW(makeFloorRobotTrajectory(up), std::invalid_argument);
}

// The repository's 12 s excerpt of freiburg2_pioneer_360 always, the whole run when ../shared
// has it.
TEST(FloorRobotTrajectory, PioneerRunsBecomePlanarPaths) {
  const auto check = [](const std::string& file, double min_duration_s, double min_length_m,
                        double max_length_m, double min_region_m) {
    SCOPED_TRACE(file);
    const Trajectory floor = makeFloorRobotTrajectory(readTumTrajectory(file));
    ASSERT_GT(floor.size(), 1000u);
    EXPECT_NEAR(floor.front().t_s, 0.0, 1e-12);
    EXPECT_GT(floor.back().t_s, min_duration_s);
    double path_length = 0.0;
    for (std::size_t i = 1; i < floor.size(); ++i) {
      path_length += (floor[i].position - floor[i - 1].position).norm();
      EXPECT_LT((floor[i].position - floor[i - 1].position).norm(), 0.02)  // < 4 m/s
          << "at " << floor[i].t_s;
    }
    EXPECT_GT(path_length, min_length_m);
    EXPECT_LT(path_length, max_length_m);
    const FloorRegion region = visibleCeilingRegion(floor, CameraModel());
    EXPECT_GT((region.max - region.min).minCoeff(), min_region_m);
  };
  check(std::string(EBSLAM_SAMPLE_SESSION_DIR) + "/pioneer_360_excerpt.txt", 11.9, 1.5, 6.0, 2.5);
  const std::filesystem::path file = std::filesystem::path(EBSLAM_SHARED_DATA_DIR) /
                                     "tum-groundtruth" /
                                     "rgbd_dataset_freiburg2_pioneer_360-groundtruth.txt";
  if (std::filesystem::exists(file)) check(file.string(), 60.0, 3.0, 30.0, 4.0);
}

TEST(CeilingMap, EdgesLieWhereTheTextureChanges) {
  // One dark vertical band 20 texels wide at columns [100, 120) with 1 cm texels.
  cv::Mat texture(300, 300, CV_32FC1, cv::Scalar(0.9));
  texture.colRange(100, 120).setTo(0.1);
  FloorRegion region;
  region.min = Eigen::Vector2d(0.0, 0.0);
  region.max = Eigen::Vector2d(3.0, 3.0);
  const Scene scene = makeCeilingScene(texture, region, 0.01);
  CeilingMapConfig config;
  config.metres_per_pixel = 0.02;
  const CeilingMap map = renderCeilingMap(scene, region, config);
  ASSERT_EQ(map.edges.cols, 150);
  ASSERT_EQ(map.edges.rows, 150);
  // origin_m is the centre of pixel (0, 0), which covers [0, 2) cm.
  EXPECT_DOUBLE_EQ(map.origin_m.x(), 0.01);
  EXPECT_DOUBLE_EQ(map.origin_m.y(), 0.01);
  // Band edges at x = 1.0 m and 1.2 m: map columns 50 and 60 (+-1).
  const int row = 75;
  for (int col = 0; col < map.edges.cols; ++col) {
    const bool near_edge = std::abs(col - 50) <= 1 || std::abs(col - 60) <= 1;
    if (!near_edge) {
      EXPECT_EQ(map.edges.at<std::uint8_t>(row, col), 0) << col;
    }
  }
  EXPECT_GT(cv::countNonZero(map.edges.colRange(49, 52)), 100);
  EXPECT_GT(cv::countNonZero(map.edges.colRange(59, 62)), 100);
  EXPECT_THROW(renderCeilingMap(Scene{}, region, config), std::invalid_argument);
}

TEST(CeilingMap, LikelihoodMapFromItPutsEdgesWhereTheyAreInTheWorld) {
  // The sensor model built from renderCeilingMap's edges and origin must look up an edge pixel
  // at every world point the pixel covers: [region.min + col * res, region.min + (col + 1) res).
  cv::Mat texture(300, 300, CV_32FC1, cv::Scalar(0.9));
  texture.colRange(100, 120).setTo(0.1);
  FloorRegion region;
  region.min = Eigen::Vector2d(-1.0, -0.5);
  region.max = Eigen::Vector2d(2.0, 2.5);
  const Scene scene = makeCeilingScene(texture, region, 0.01);
  CeilingMapConfig config;
  config.metres_per_pixel = 0.02;
  const CeilingMap map = renderCeilingMap(scene, region, config);
  const GridMap2f likelihood =
      makeEdgeLikelihoodMap(map.edges, map.metres_per_pixel, map.origin_m, 0.015);
  const int row = 75;
  int checked = 0;
  for (int col = 1; col + 1 < map.edges.cols; ++col) {
    if (map.edges.at<std::uint8_t>(row, col) == 0 || map.edges.at<std::uint8_t>(row, col - 1) ||
        map.edges.at<std::uint8_t>(row, col + 1)) {
      continue;  // an isolated edge pixel along the row: its neighbours score below 1
    }
    const double y = region.min.y() + (row + 0.5) * config.metres_per_pixel;
    for (const double f : {0.1, 0.5, 0.9}) {
      const double x = region.min.x() + (col + f) * config.metres_per_pixel;
      EXPECT_FLOAT_EQ(likelihood.lookup(x, y), 1.0f) << "col " << col << " fraction " << f;
    }
    EXPECT_LT(likelihood.lookup(region.min.x() + (col + 1.1) * config.metres_per_pixel, y), 1.0f);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

}  // namespace
}  // namespace ebslam
