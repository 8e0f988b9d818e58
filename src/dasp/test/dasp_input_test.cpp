// Bad input must raise std::invalid_argument with a reason, never crash.
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>

#include "dasp/dalic.h"
#include "dasp/dasp.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp_synthetic.h"

namespace dasp {
namespace {

// A default config with one member changed.
template <typename Config, typename Member, typename Value>
Config with(Member Config::*member, Value value) {
  Config config;
  config.*member = static_cast<Member>(value);
  return config;
}

// A default DASP config with one experimental knob changed.
template <typename Member, typename Value>
DaspConfig withExperimental(Member DaspExperimental::*member, Value value) {
  DaspConfig config;
  config.experimental.*member = static_cast<Member>(value);
  return config;
}

RgbdFrame goodFrame() { return test::twoPlanes(64, 48, 1.0f, 2.0f, nullptr); }

// Expects std::invalid_argument whose message contains `reason`.
template <typename F>
void expectInvalid(F&& f, const std::string& reason) {
  try {
    f();
    FAIL() << "no exception, expected one mentioning '" << reason << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

TEST(DaspInput, GoodFrameRuns) {
  const Superpixels result = computeDasp(goodFrame(), with(&DaspConfig::superpixel_count, 20));
  EXPECT_FALSE(result.superpixels.empty());
}

TEST(DaspInput, MismatchedSizes) {
  RgbdFrame frame = goodFrame();
  frame.depth = cv::Mat(40, 64, CV_16UC1, cv::Scalar(1000));
  expectInvalid([&] { computeDasp(frame); }, "sizes differ");
  expectInvalid([&] { computeAspRgbd(frame); }, "sizes differ");
}

TEST(DaspInput, WrongEncodings) {
  RgbdFrame frame = goodFrame();
  frame.color = cv::Mat(48, 64, CV_8UC1, cv::Scalar(5));
  expectInvalid([&] { computeDasp(frame); }, "CV_8UC3");
  frame = goodFrame();
  frame.depth = cv::Mat(48, 64, CV_8UC1, cv::Scalar(5));
  expectInvalid([&] { computeDasp(frame); }, "CV_16UC1");
  frame.depth = cv::Mat(48, 64, CV_32SC1, cv::Scalar(5));
  expectInvalid([&] { computeDasp(frame); }, "CV_16UC1");
  frame.depth = cv::Mat();
  expectInvalid([&] { computeDasp(frame); }, "empty");
  expectInvalid([&] { computeAspRgb(cv::Mat(10, 10, CV_32FC3)); }, "CV_8UC3");
}

TEST(DaspInput, NoValidDepth) {
  RgbdFrame frame = goodFrame();
  frame.depth.setTo(0);
  expectInvalid([&] { computeDasp(frame); }, "no valid pixel");
  frame.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  expectInvalid([&] { computeDasp(frame); }, "no valid pixel");
  frame.depth.setTo(-1.0f);
  expectInvalid([&] { computeDasp(frame); }, "no valid pixel");
}

TEST(DaspInput, SuperpixelCountOutOfRange) {
  const RgbdFrame frame = goodFrame();
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::superpixel_count, 0)); },
                "superpixel_count");
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::superpixel_count, 64 * 48 + 1)); },
                "superpixel_count");
  RgbdFrame sparse = goodFrame();
  sparse.depth.setTo(0);
  sparse.depth(cv::Rect(0, 0, 10, 10)).setTo(1000);  // 100 valid pixels
  expectInvalid([&] { computeDasp(sparse, with(&DaspConfig::superpixel_count, 200)); },
                "valid depth");
  expectInvalid([&] { computeAspRgb(frame.color, with(&AspConfig::superpixel_count, 0)); },
                "superpixel_count");
  expectInvalid(
      [&] { computeAspRgb(frame.color, with(&AspConfig::superpixel_count, 64 * 48 + 1)); },
      "superpixel_count");
}

TEST(DaspInput, NonsensicalIntrinsics) {
  RgbdFrame frame = goodFrame();
  frame.intrinsics.fx = 0.0f;
  expectInvalid([&] { computeDasp(frame); }, "focal");
  frame.intrinsics.fx = -100.0f;
  expectInvalid([&] { computeDasp(frame); }, "focal");
  frame.intrinsics.fx = std::numeric_limits<float>::quiet_NaN();
  expectInvalid([&] { computeDasp(frame); }, "focal");
  frame = goodFrame();
  frame.intrinsics.cy = std::numeric_limits<float>::infinity();
  expectInvalid([&] { computeDasp(frame); }, "principal point");
  frame.intrinsics.cy = 1e6f;
  expectInvalid([&] { computeDasp(frame); }, "principal point");
  frame = goodFrame();
  frame.intrinsics.fy = frame.intrinsics.fx * 50.0f;
  expectInvalid([&] { computeDasp(frame); }, "factor 10");
}

TEST(DaspInput, NonsensicalParameters) {
  const RgbdFrame frame = goodFrame();
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::iterations, 0)); }, "iterations");
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::weight_color, -1.0f)); }, "weights");
  expectInvalid(
      [&] { computeDasp(frame, withExperimental(&DaspExperimental::weight_depth, -0.5f)); },
      "weights");
  expectInvalid(
      [&] {
        computeDasp(frame, withExperimental(&DaspExperimental::weight_depth,
                                            std::numeric_limits<float>::quiet_NaN()));
      },
      "weights");
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::window_multiple, 0.0f)); }, "window");
  expectInvalid([&] { computeDasp(frame, with(&DaspConfig::threads, -2)); }, "threads");
  DaspConfig radius;
  radius.size_mode = SizeMode::kRadius;
  radius.radius_m = 0.0f;
  expectInvalid([&] { computeDasp(frame, radius); }, "radius_m");
}

TEST(DalicInput, MetricWeightsMustBeFiniteAndNonNegative) {
  const PixelFeatures features = computeFeatures(goodFrame());
  const cv::Mat density(features.height, features.width, CV_32FC1, cv::Scalar(0.01f));
  EXPECT_NO_THROW(Dalic(features, density, DalicParams{}));
  expectInvalid([&] { Dalic(features, density, with(&DalicParams::weight_color, -1.0f)); },
                "weights");
  expectInvalid([&] { Dalic(features, density, with(&DalicParams::weight_depth, -0.5f)); },
                "weights");
  expectInvalid(
      [&] {
        Dalic(features, density,
              with(&DalicParams::weight_normal, std::numeric_limits<float>::infinity()));
      },
      "weights");
}

TEST(DaspInput, BadUserDensity) {
  const cv::Mat color = test::flatColor(32, 24);
  AspConfig config;
  config.superpixel_count = 10;
  config.density = cv::Mat(24, 32, CV_32FC1, cv::Scalar(-1.0f));
  expectInvalid([&] { computeAspRgb(color, config); }, ">= 0");
  config.density = cv::Mat(24, 32, CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  expectInvalid([&] { computeAspRgb(color, config); }, "NaN");
  config.density = cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0f));
  expectInvalid([&] { computeAspRgb(color, config); }, "image size");
  config.density = cv::Mat::zeros(24, 32, CV_32FC1);
  expectInvalid([&] { computeAspRgb(color, config); }, "integrates to 0");
  expectInvalid([&] { sampleSpds(cv::Mat(4, 4, CV_32FC1, cv::Scalar(-1.0f)), true, 0); }, ">= 0");
}

}  // namespace
}  // namespace dasp
