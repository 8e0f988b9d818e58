#include "ebslam/calibration/dedvs_rgbd_led.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ebslam {
namespace {

constexpr double kFrameRate = 30.0;
constexpr double kLedHz = 250.0;

// A synthetic still scene: a static textured background (grey levels 60-180), a tilted plane
// of depth 1/z = 1/z0 + a du + b dv, and blinking spots (Gaussian, sigma 2 px, +120 grey levels
// while on) sampled at the frame times (instantaneous exposure), colour noise sigma 2.
struct Spot {
  Eigen::Vector2d pixel;
  double frequency_hz;
};

struct SyntheticScene {
  int width = 160;
  int height = 120;
  double z0 = 1.2;
  double a = 2e-4, b = -1e-4;
  Eigen::Vector2d plane_origin{80.0, 60.0};
  std::vector<Spot> spots;
  double depth_outlier_fraction = 0.0;  // depth pixels replaced by random depths
  std::uint64_t seed = 1;

  double trueDepth(const Eigen::Vector2d& pixel) const {
    const Eigen::Vector2d d = pixel - plane_origin;
    return 1.0 / (1.0 / z0 + a * d.x() + b * d.y());
  }

  std::vector<RgbdLedFrame> frames(int count, double t0_s = 1000.0) const {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    cv::Mat background(height, width, CV_32FC1);
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) background.at<float>(r, c) = 60.0f + 120.0f * uniform(rng);
    }
    std::vector<RgbdLedFrame> result;
    for (int k = 0; k < count; ++k) {
      RgbdLedFrame frame;
      frame.t_s = t0_s + k / kFrameRate;
      frame.grey = background.clone();
      frame.depth_m = cv::Mat(height, width, CV_32FC1);
      for (const Spot& spot : spots) {
        const double phase = std::fmod(frame.t_s * spot.frequency_hz, 1.0);
        if (phase >= 0.5) continue;
        for (int r = 0; r < height; ++r) {
          for (int c = 0; c < width; ++c) {
            const double d2 = (Eigen::Vector2d(c, r) - spot.pixel).squaredNorm();
            frame.grey.at<float>(r, c) += static_cast<float>(120.0 * std::exp(-0.5 * d2 / 4.0));
          }
        }
      }
      for (int r = 0; r < height; ++r) {
        for (int c = 0; c < width; ++c) {
          float& g = frame.grey.at<float>(r, c);
          g = std::min(255.0f, g + static_cast<float>(2.0 * gauss(rng)));
          const double z = trueDepth(Eigen::Vector2d(c, r));
          frame.depth_m.at<float>(r, c) = uniform(rng) < depth_outlier_fraction
                                              ? static_cast<float>(0.5 + 3.0 * uniform(rng))
                                              : static_cast<float>(z + 0.002 * gauss(rng));
        }
      }
      result.push_back(frame);
    }
    return result;
  }
};

TEST(RgbdLedFinder, FindsTheBlinkingPixelAndItsDepth) {
  SyntheticScene scene;
  scene.spots = {{Eigen::Vector2d(70.3, 45.7), kLedHz}};
  const RgbdLedObservation o = findRgbdLed(scene.frames(9));
  ASSERT_EQ(o.status, RgbdLedStatus::kFound) << toString(o.status);
  EXPECT_LT((o.pixel - scene.spots[0].pixel).norm(), 0.1);
  EXPECT_NEAR(o.depth_m, scene.trueDepth(scene.spots[0].pixel), 0.002);
  EXPECT_EQ(o.frames, 9);
  EXPECT_GT(o.amplitude, 10.0 * o.noise);
}

TEST(RgbdLedFinder, RejectsDepthOutliers) {
  SyntheticScene scene;
  scene.spots = {{Eigen::Vector2d(100.6, 80.2), kLedHz}};
  scene.depth_outlier_fraction = 0.25;
  const RgbdLedObservation o = findRgbdLed(scene.frames(8));
  ASSERT_EQ(o.status, RgbdLedStatus::kFound) << toString(o.status);
  EXPECT_NEAR(o.depth_m, scene.trueDepth(scene.spots[0].pixel), 0.003);
  // Without the rejection the mean of 1/z is pulled far off.
  RgbdLedConfig loose;
  loose.depth_outlier_sigmas = 1e6;
  const RgbdLedObservation biased = findRgbdLed(scene.frames(8), loose);
  ASSERT_EQ(biased.status, RgbdLedStatus::kFound);
  EXPECT_GT(std::abs(biased.depth_m - scene.trueDepth(scene.spots[0].pixel)), 0.02);
}

TEST(RgbdLedFinder, IgnoresALightOfAnotherFrequency) {
  SyntheticScene scene;
  // Another light blinking at 145 Hz next to the 250 Hz LED: at 30 frames/s it blinks at 5 Hz
  // in the frames, the LED at 10 Hz; over 12 frames only the LED is coherent at 250 Hz.
  scene.spots = {{Eigen::Vector2d(40.2, 30.4), kLedHz}, {Eigen::Vector2d(120.0, 90.0), 145.0}};
  const RgbdLedObservation o = findRgbdLed(scene.frames(12));
  ASSERT_EQ(o.status, RgbdLedStatus::kFound) << toString(o.status);
  EXPECT_LT((o.pixel - scene.spots[0].pixel).norm(), 0.15);
}

TEST(RgbdLedFinder, TwoLedsAtTheFrequencyAreAmbiguous) {
  SyntheticScene scene;
  scene.spots = {{Eigen::Vector2d(40.0, 30.0), kLedHz}, {Eigen::Vector2d(120.0, 90.0), kLedHz}};
  EXPECT_EQ(findRgbdLed(scene.frames(9)).status, RgbdLedStatus::kAmbiguous);
}

TEST(RgbdLedFinder, NoLedIsReported) {
  SyntheticScene scene;
  const RgbdLedObservation o = findRgbdLed(scene.frames(9));
  EXPECT_EQ(o.status, RgbdLedStatus::kNoBlinkingPixel);
  // A wrong LED frequency finds nothing either.
  scene.spots = {{Eigen::Vector2d(70.0, 50.0), kLedHz}};
  RgbdLedConfig wrong;
  wrong.led_frequency_hz = 173.0;
  EXPECT_EQ(findRgbdLed(scene.frames(9), wrong).status, RgbdLedStatus::kNoBlinkingPixel);
  // The user is told what to check.
  LedPairing pairing;
  pairing.segments = 40;
  pairing.rgbd_status[static_cast<std::size_t>(RgbdLedStatus::kNoBlinkingPixel)] = 40;
  const std::string message = diagnoseLedPairing(pairing, 20, RgbdLedConfig{}, kFrameRate);
  EXPECT_NE(message.find("not found in the colour frames"), std::string::npos) << message;
  EXPECT_NE(message.find("--led-frequency"), std::string::npos) << message;
}

TEST(RgbdLedFinder, FrequencyAliasedByTheFrameRateIsReported) {
  SyntheticScene scene;
  scene.spots = {{Eigen::Vector2d(70.0, 50.0), 240.0}};
  RgbdLedConfig config;
  config.led_frequency_hz = 240.0;  // 8 x 30 Hz: every frame sees the same phase
  const RgbdLedObservation o = findRgbdLed(scene.frames(9), config);
  EXPECT_EQ(o.status, RgbdLedStatus::kFrequencyAliased);
  LedPairing pairing;
  pairing.segments = 30;
  pairing.rgbd_status[static_cast<std::size_t>(RgbdLedStatus::kFrequencyAliased)] = 30;
  const std::string message = diagnoseLedPairing(pairing, 20, config, kFrameRate);
  EXPECT_NE(message.find("multiple of the colour frame rate"), std::string::npos) << message;
}

TEST(RgbdLedFinder, TooFewFramesAndBadInput) {
  SyntheticScene scene;
  scene.spots = {{Eigen::Vector2d(70.0, 50.0), kLedHz}};
  EXPECT_EQ(findRgbdLed(scene.frames(3)).status, RgbdLedStatus::kTooFewFrames);
  EXPECT_THROW(findRgbdLed({}), std::invalid_argument);
  std::vector<RgbdLedFrame> frames = scene.frames(6);
  frames[3].t_s = frames[2].t_s;
  EXPECT_THROW(findRgbdLed(frames), std::invalid_argument);
  frames = scene.frames(6);
  frames[2].depth_m = cv::Mat(10, 10, CV_32FC1);
  EXPECT_THROW(findRgbdLed(frames), std::invalid_argument);
  RgbdLedConfig bad;
  bad.min_frames = 2;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(RgbdLedTracker, SplitsStillSegmentsAtMotion) {
  // Two rests of 8 frames with the LED at different pixels, separated by a frame where the
  // whole background shifted (the plate moved).
  SyntheticScene first, second;
  first.spots = {{Eigen::Vector2d(50.4, 40.6), kLedHz}};
  second.spots = {{Eigen::Vector2d(110.2, 70.3), kLedHz}};
  second.seed = 2;  // another background: everything changed
  std::vector<RgbdLedFrame> stream = first.frames(8, 10.0);
  for (RgbdLedFrame& f : second.frames(8, 10.0 + 9.0 / kFrameRate)) stream.push_back(f);
  RgbdLedTracker tracker;
  std::vector<RgbdLedObservation> observations;
  for (RgbdLedFrame& f : stream) {
    if (auto o = tracker.push(f)) observations.push_back(*o);
  }
  RgbdLedFrame older = stream.back();
  older.t_s -= 1.0;
  EXPECT_THROW(tracker.push(older), std::invalid_argument);
  if (auto o = tracker.finish()) observations.push_back(*o);
  ASSERT_EQ(observations.size(), 2u);
  ASSERT_EQ(observations[0].status, RgbdLedStatus::kFound);
  ASSERT_EQ(observations[1].status, RgbdLedStatus::kFound);
  EXPECT_LT((observations[0].pixel - first.spots[0].pixel).norm(), 0.1);
  EXPECT_LT((observations[1].pixel - second.spots[0].pixel).norm(), 0.1);
  EXPECT_EQ(observations[0].frames, 8);
  EXPECT_NEAR(observations[1].t_begin_s, 10.0 + 9.0 / kFrameRate, 1e-9);
}

TEST(LedPairing, TooFewPosesAreExplained) {
  LedPairing pairing;
  pairing.segments = 12;
  pairing.rgbd_status[static_cast<std::size_t>(RgbdLedStatus::kFound)] = 12;
  pairing.correspondences.resize(12);
  const std::string message = diagnoseLedPairing(pairing, 20, RgbdLedConfig{}, kFrameRate);
  EXPECT_NE(message.find("only 12 usable LED poses, at least 20"), std::string::npos) << message;
  EXPECT_NE(message.find("Record more poses"), std::string::npos) << message;
  pairing.correspondences.resize(20);
  EXPECT_TRUE(diagnoseLedPairing(pairing, 20, RgbdLedConfig{}, kFrameRate).empty());
  // Found in the frames, not in the events: the eDVS side and the frequency are named.
  LedPairing no_edvs;
  no_edvs.segments = 30;
  no_edvs.rgbd_status[static_cast<std::size_t>(RgbdLedStatus::kFound)] = 30;
  no_edvs.edvs_missing = 30;
  const std::string edvs = diagnoseLedPairing(no_edvs, 20, RgbdLedConfig{}, kFrameRate);
  EXPECT_NE(edvs.find("eDVS events"), std::string::npos) << edvs;
}

TEST(DepthClockOffset, MeasuredFromThePlatesMotion) {
  // The plate moves for 50 ms every 300 ms: 20 events/ms while it moves, 2/ms background.
  // Frames at 30 Hz stamped 12 ms late; their motion is the moving time within their interval.
  const double offset = 0.012;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto moving = [](double t) { return std::fmod(t, 0.3) >= 0.25; };
  std::vector<Event> events;
  for (std::int64_t us = 0; us < 6000000; ++us) {
    const double rate = moving(us * 1e-6) ? 0.02 : 0.002;  // per us
    if (uniform(rng) < rate) events.push_back({us, 1, 1, true});
  }
  std::vector<double> stamps, motion;
  for (int k = 0; k < 170; ++k) {
    const double t = 0.05 + k / kFrameRate;  // true exposure time
    stamps.push_back(t + offset);
    double moved = 0.0;
    for (double s = t - 1.0 / kFrameRate; s < t; s += 1e-4) moved += moving(s) ? 1e-4 : 0.0;
    motion.push_back(k == 0 ? 0.0 : 1000.0 * moved);
  }
  const std::optional<double> measured = estimateDepthClockOffset(events, stamps, motion);
  ASSERT_TRUE(measured.has_value());
  EXPECT_NEAR(*measured, offset, 0.002);
  // No motion in the frames: nothing to measure.
  std::vector<double> still(motion.size(), 0.0);
  EXPECT_FALSE(estimateDepthClockOffset(events, stamps, still).has_value());
  EXPECT_THROW(estimateDepthClockOffset(events, stamps, {1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam
