#include "ebslam/calibration/dedvs_calibration.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "ebslam/simulation/dedvs_io.h"

namespace ebslam {
namespace {

// The simulated run of the calibration tests: shorter than the tool's default run so that each
// test stays within a few seconds.
LedCalibrationRunConfig testRunConfig(double outlier_fraction) {
  LedCalibrationRunConfig config;
  config.poses = 90;
  config.outlier_event_fraction = outlier_fraction;
  config.seed = 1;
  config.simulator.seed = 1;
  config.simulator.events.seed = 1;
  return config;
}

void expectRecovered(const LedCalibrationRun& run) {
  const std::vector<LedCorrespondence> correspondences =
      collectLedCorrespondences(run.events, run.depth_observations);
  ASSERT_GE(correspondences.size(), 20u);
  const DedvsCalibrationResult result = calibrateDedvs(correspondences, run.truth);
  EXPECT_EQ(result.status, CalibrationStatus::kOk);
  const ExtrinsicError error =
      extrinsicError(result.sensors.depth_from_edvs, run.truth.depth_from_edvs);
  EXPECT_LT(error.translation_mm, 1.0);
  // The target is 0.1 deg; with the 90 plate poses a test can afford, rotation and the
  // eDVS principal point are not separated that well (docs/results/dedvs.md, "Calibration").
  EXPECT_LT(error.rotation_deg, 0.2);
  EXPECT_LE(result.rmse_px, 0.5);
  EXPECT_NEAR(result.sensors.edvs.focal_px, run.truth.edvs.focal_px, 1.0);
  EXPECT_LT((result.sensors.edvs.principal_point - run.truth.edvs.principal_point).norm(), 1.0);
  // The depth camera is kept.
  EXPECT_EQ(result.sensors.depth.fx, run.truth.depth.fx);
  EXPECT_EQ(result.sensors.depth_clock_offset_s, run.truth.depth_clock_offset_s);
}

TEST(DedvsCalibration, RecoversSimulatedCalibration) {
  const LedCalibrationRun run = simulateLedCalibrationRun(testRunConfig(0.0));
  EXPECT_EQ(run.outlier_events, 0u);
  expectRecovered(run);
}

TEST(DedvsCalibration, RecoversWithTwentyPercentOutlierEvents) {
  const LedCalibrationRun run = simulateLedCalibrationRun(testRunConfig(0.2));
  EXPECT_NEAR(static_cast<double>(run.outlier_events) / run.events.size(), 0.2, 0.001);
  for (std::size_t i = 1; i < run.events.size(); ++i) {
    ASSERT_LE(run.events[i - 1].t_us, run.events[i].t_us);
  }
  expectRecovered(run);
}

// Synthetic correspondences from the true sensors: exact data give the truth back, and gross
// outliers among them are ignored.
std::vector<LedCorrespondence> syntheticCorrespondences(const DedvsSensors& sensors, int count,
                                                        std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<LedCorrespondence> result;
  while (static_cast<int>(result.size()) < count) {
    LedCorrespondence c;
    c.depth_pixel = Eigen::Vector2d(60.0 + 200.0 * unit(rng), 30.0 + 180.0 * unit(rng));
    c.depth_m = 0.5 + 1.5 * unit(rng);
    const std::optional<Eigen::Vector2d> v = depthToEdvsPixel(sensors, c.depth_pixel, c.depth_m);
    if (!v || !sensors.edvs.isInside(*v)) continue;
    c.edvs_pixel = *v;
    result.push_back(c);
  }
  return result;
}

// Correspondences with the LED where `where` puts it in the eDVS image (by rejection) and
// Gaussian noise of sigma_px on the eDVS pixel.
template <class Where>
std::vector<LedCorrespondence> noisyCorrespondences(const DedvsSensors& sensors, int count,
                                                    double sigma_px, std::uint64_t seed,
                                                    Where where) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma_px);
  std::vector<LedCorrespondence> result;
  while (static_cast<int>(result.size()) < count) {
    LedCorrespondence c;
    c.depth_pixel = Eigen::Vector2d(unit(rng) * 319.0, unit(rng) * 239.0);
    c.depth_m = 0.55 + 1.25 * unit(rng);
    const std::optional<Eigen::Vector2d> v = depthToEdvsPixel(sensors, c.depth_pixel, c.depth_m);
    if (!v || !sensors.edvs.isInside(*v) || !where(*v)) continue;
    c.edvs_pixel = *v + Eigen::Vector2d(noise(rng), noise(rng));
    result.push_back(c);
  }
  return result;
}

// The reported rotation standard deviation is the rotation's scatter over noise draws, and poses
// in the corners separate the rotation from the principal point better than central ones.
TEST(DedvsCalibration, UncertaintyMatchesTheScatterAndFollowsThePoses) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  auto anywhere = [](const Eigen::Vector2d&) { return true; };
  const Eigen::Matrix3d true_rotation = truth.depth_from_edvs.linear();
  double sum_squares = 0.0, sum_reported = 0.0;
  constexpr int kDraws = 24;
  for (int draw = 0; draw < kDraws; ++draw) {
    const DedvsCalibrationResult result =
        calibrateDedvs(noisyCorrespondences(truth, 120, 0.1, 100 + draw, anywhere), truth);
    ASSERT_EQ(result.status, CalibrationStatus::kOk);
    ASSERT_TRUE(result.uncertainty.has_value());
    // Rotation error about the eDVS x axis (one of the two weak directions) [deg].
    const Eigen::AngleAxisd difference(true_rotation.transpose() *
                                       result.sensors.depth_from_edvs.linear());
    const double error_x = (difference.angle() * difference.axis()).x() * 180.0 / M_PI;
    sum_squares += error_x * error_x;
    sum_reported += result.uncertainty->rotation_axes_std_deg.x();
    EXPECT_GE(result.uncertainty->rotation_std_deg,
              result.uncertainty->rotation_axes_std_deg.maxCoeff() - 1e-12);
  }
  const double scatter = std::sqrt(sum_squares / kDraws);
  const double reported = sum_reported / kDraws;
  EXPECT_GT(reported, 0.5 * scatter);
  EXPECT_LT(reported, 2.0 * scatter);

  // The same number of poses in the central half of the image only: a weaker rotation, and
  // the advice names the corners; with half of them in the corners no advice is needed.
  auto central = [](const Eigen::Vector2d& v) {
    return std::abs(v.x() - 63.5) < 32.0 && std::abs(v.y() - 63.5) < 32.0;
  };
  auto corner = [](const Eigen::Vector2d& v) {
    return std::abs(v.x() - 63.5) > 44.0 && std::abs(v.y() - 63.5) > 44.0;
  };
  const DedvsCalibrationResult weak =
      calibrateDedvs(noisyCorrespondences(truth, 250, 0.1, 7, central), truth);
  std::vector<LedCorrespondence> spread = noisyCorrespondences(truth, 125, 0.1, 8, anywhere);
  const std::vector<LedCorrespondence> corners = noisyCorrespondences(truth, 125, 0.1, 9, corner);
  spread.insert(spread.end(), corners.begin(), corners.end());
  const DedvsCalibrationResult strong = calibrateDedvs(spread, truth);
  ASSERT_TRUE(weak.uncertainty && strong.uncertainty);
  EXPECT_GT(weak.uncertainty->rotation_std_deg, 2.0 * strong.uncertainty->rotation_std_deg);
  EXPECT_GT(weak.uncertainty->rotation_principal_point_correlation,
            strong.uncertainty->rotation_principal_point_correlation);

  const LedPoseCoverage weak_coverage = ledPoseCoverage(
      noisyCorrespondences(truth, 250, 0.1, 7, central), truth.edvs.width, truth.edvs.height);
  EXPECT_EQ(weak_coverage.poses, 250u);
  EXPECT_EQ(weak_coverage.corners[0] + weak_coverage.corners[1] + weak_coverage.corners[2] +
                weak_coverage.corners[3],
            0u);
  const std::string advice = advisePoseDiversity(weak, weak_coverage, 0.05);
  EXPECT_NE(advice.find("corners"), std::string::npos) << advice;
  const LedPoseCoverage strong_coverage =
      ledPoseCoverage(spread, truth.edvs.width, truth.edvs.height);
  EXPECT_GE(strong_coverage.corners[0] + strong_coverage.corners[1] + strong_coverage.corners[2] +
                strong_coverage.corners[3],
            125u);
  for (std::size_t count : strong_coverage.corners) EXPECT_GT(count, 15u);
  EXPECT_LT(strong.uncertainty->rotation_std_deg, 0.05);
  EXPECT_GT(weak.uncertainty->rotation_std_deg, 0.05);
  EXPECT_EQ(advisePoseDiversity(strong, strong_coverage, 0.05), "");
  EXPECT_THROW(ledPoseCoverage(spread, 128, 128, 0.0), std::invalid_argument);
  EXPECT_THROW(advisePoseDiversity(strong, strong_coverage, 0.0), std::invalid_argument);
}

TEST(DedvsCalibration, ExactCorrespondencesGiveTheTruth) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  const DedvsCalibrationResult result =
      calibrateDedvs(syntheticCorrespondences(truth, 200, 1), truth);
  EXPECT_EQ(result.status, CalibrationStatus::kOk);
  const ExtrinsicError error =
      extrinsicError(result.sensors.depth_from_edvs, truth.depth_from_edvs);
  EXPECT_LT(error.translation_mm, 1e-3);
  EXPECT_LT(error.rotation_deg, 1e-4);
  EXPECT_LT(result.rmse_px, 1e-4);
  EXPECT_NEAR(result.sensors.edvs.kappa1, truth.edvs.kappa1, 1e-7);
}

TEST(DedvsCalibration, OutlierCorrespondencesAreIgnored) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  std::vector<LedCorrespondence> data = syntheticCorrespondences(truth, 200, 2);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> pixel(0.0, 127.0);
  for (std::size_t i = 0; i < data.size(); i += 5) {  // 20 % anywhere on the sensor
    data[i].edvs_pixel = Eigen::Vector2d(pixel(rng), pixel(rng));
  }
  const DedvsCalibrationResult result = calibrateDedvs(data, truth);
  EXPECT_EQ(result.status, CalibrationStatus::kOk);
  const ExtrinsicError error =
      extrinsicError(result.sensors.depth_from_edvs, truth.depth_from_edvs);
  EXPECT_LT(error.translation_mm, 0.1);
  EXPECT_LT(error.rotation_deg, 0.01);
  EXPECT_LT(result.rmse_px, 0.05);
  EXPECT_GE(result.inliers, 160u);
}

TEST(DedvsCalibration, UnrelatedCorrespondencesReportAFailure) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  std::vector<LedCorrespondence> data = syntheticCorrespondences(truth, 60, 3);
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> pixel(0.0, 127.0);
  for (LedCorrespondence& c : data) c.edvs_pixel = Eigen::Vector2d(pixel(rng), pixel(rng));
  const DedvsCalibrationResult result = calibrateDedvs(data, truth);
  EXPECT_NE(result.status, CalibrationStatus::kOk);
}

TEST(DedvsCalibration, MisuseThrows) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  const std::vector<LedCorrespondence> data = syntheticCorrespondences(truth, 30, 4);
  EXPECT_THROW(calibrateDedvs({data.begin(), data.begin() + 19}, truth), std::invalid_argument);
  std::vector<LedCorrespondence> bad = data;
  bad[3].depth_m = 0.0;
  EXPECT_THROW(calibrateDedvs(bad, truth), std::invalid_argument);
  bad = data;
  bad[4].edvs_pixel.x() = std::nan("");
  EXPECT_THROW(calibrateDedvs(bad, truth), std::invalid_argument);
  DedvsCalibrationConfig config;
  config.min_correspondences = 3;
  EXPECT_THROW(calibrateDedvs(data, truth, config), std::invalid_argument);
  config = {};
  config.loss_scale_px = 0.0;
  EXPECT_THROW(calibrateDedvs(data, truth, config), std::invalid_argument);
  DedvsSensors no_depth = truth;
  no_depth.depth.fx = 0.0;
  EXPECT_THROW(calibrateDedvs(data, no_depth), std::invalid_argument);

  LedExtractionConfig extraction;
  extraction.window_periods = 1;
  EXPECT_THROW(extractLed({}, 0.0, extraction), std::invalid_argument);
  EXPECT_THROW(extractLed({}, std::nan(""), {}), std::invalid_argument);
  LedCalibrationRunConfig run;
  run.squares = 8;
  EXPECT_THROW(simulateLedCalibrationRun(run), std::invalid_argument);
  run = {};
  run.outlier_event_fraction = 0.95;
  EXPECT_THROW(simulateLedCalibrationRun(run), std::invalid_argument);
}

// Events of an LED blinking at 500 Hz at a fixed sensor position, a moving edge and noise.
TEST(DedvsCalibration, ExtractLedByItsFrequency) {
  std::vector<Event> events;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> coordinate(0, 127);
  std::uniform_int_distribution<std::int64_t> time(0, 100000);
  for (int k = 0; k < 20000; ++k) {  // noise: 2 events per pixel in 0.1 s
    Event e;
    e.t_us = time(rng);
    e.x = static_cast<std::uint16_t>(coordinate(rng));
    e.y = static_cast<std::uint16_t>(coordinate(rng));
    e.polarity = (k & 1) != 0;
    events.push_back(e);
  }
  for (int column = 0; column < 128; ++column) {  // an edge sweeping right, 3 events per pixel
    for (int row = 0; row < 128; ++row) {
      for (int n = 0; n < 3; ++n) {
        events.push_back(Event{column * 700 + n * 100, static_cast<std::uint16_t>(column),
                               static_cast<std::uint16_t>(row), true});
      }
    }
  }
  // LED: two pixels with equal response, one weaker below (centroid (40.43, 70.15)).
  for (std::int64_t t = 300; t < 100000; t += 2000) {
    for (const auto& [x, y, n] : {std::tuple{40, 70, 3}, {41, 70, 3}, {40, 71, 1}}) {
      for (int k = 0; k < n; ++k) {
        events.push_back(
            Event{t + 110 * k, static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), true});
        events.push_back(Event{t + 1000 + 110 * k, static_cast<std::uint16_t>(x),
                               static_cast<std::uint16_t>(y), false});
      }
    }
  }
  std::sort(events.begin(), events.end(),
            [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
  LedExtractionConfig config;
  config.led_frequency_hz = 500.0;
  config.min_spot_pixels = 3;
  const std::optional<LedObservation> led = extractLed(events, 0.05, config);
  ASSERT_TRUE(led.has_value());
  EXPECT_NEAR(led->pixel.x(), 40.43, 0.03);
  EXPECT_NEAR(led->pixel.y(), 70.15, 0.03);
  EXPECT_EQ(led->pixels, 3);
  // Another frequency does not pass.
  LedExtractionConfig other = config;
  other.led_frequency_hz = 320.0;
  EXPECT_FALSE(extractLed(events, 0.05, other).has_value());
  // Outside the LED's time range: nothing.
  EXPECT_FALSE(extractLed(events, 0.3, config).has_value());
  // Too few pixels for a spot.
  LedExtractionConfig strict = config;
  strict.min_spot_pixels = 4;
  EXPECT_FALSE(extractLed(events, 0.05, strict).has_value());
}

TEST(DedvsCalibration, FusionReadsTheWrittenCalibration) {
  const DedvsSensors truth = sensorsOf(DedvsSimulatorConfig{});
  const DedvsCalibrationResult result =
      calibrateDedvs(syntheticCorrespondences(truth, 100, 8), truth);
  const std::string path =
      (std::filesystem::temp_directory_path() / "ebslam_dedvs_calibration_test.yaml").string();
  writeDedvsSensors(path, result.sensors);
  const DedvsSensors read = readDedvsSensors(path);
  std::filesystem::remove(path);
  EXPECT_NEAR(read.edvs.focal_px, result.sensors.edvs.focal_px, 1e-9);
  EXPECT_NEAR(read.edvs.kappa2, result.sensors.edvs.kappa2, 1e-15);
  EXPECT_TRUE(read.depth_from_edvs.isApprox(result.sensors.depth_from_edvs, 1e-12));
  EXPECT_EQ(read.edvs.distortion_model, DistortionModel::kDivideEq81);
}

}  // namespace
}  // namespace ebslam
