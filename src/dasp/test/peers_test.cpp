// Peer methods (OpenCV SLIC/SEEDS, PCL VCCS) and the evaluation metric set of the tools, on
// synthetic frames. Compiled only when the tools (and with them dasp_peers) are built.
#if __has_include("peers/peers.h")
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dasp/metrics.h"
#include "peers/methods.h"
#include "peers/peers.h"

namespace dasp {
namespace peers {
namespace {

// Two fronto-parallel planes of the same grey at 1.0 m (left) and 1.5 m (right), a 20 px band
// without depth at the bottom.
RgbdFrame twoPlanes(int width = 160, int height = 120) {
  RgbdFrame frame;
  frame.color = cv::Mat(height, width, CV_8UC3, cv::Scalar(128, 128, 128));
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(1000));
  frame.depth.colRange(width / 2, width).setTo(1500);
  frame.depth.rowRange(height - 20, height).setTo(0);
  frame.intrinsics = Intrinsics{131.25f, 131.25f, (width - 1) / 2.0f, (height - 1) / 2.0f};
  return frame;
}

// Colour image with a few flat colour regions.
cv::Mat colorBlocks(int width, int height) {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(40, 90, 200));
  image(cv::Rect(0, 0, width / 2, height / 2)).setTo(cv::Scalar(200, 30, 30));
  image(cv::Rect(width / 2, height / 2, width / 2, height / 2)).setTo(cv::Scalar(20, 220, 60));
  return image;
}

TEST(Peers, SlicLabelsEveryPixelNearK) {
  const cv::Mat image = colorBlocks(200, 150);
  SlicConfig config;
  config.superpixel_count = 300;
  const cv::Mat labels = computeOpenCvSlic(image, config);
  ASSERT_EQ(labels.type(), CV_32SC1);
  EXPECT_EQ(cv::countNonZero(labels < 0), 0);
  const double count = static_cast<double>(metrics::countSegments(labels, cv::Mat()));
  EXPECT_NEAR(count, 300.0, 60.0);
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_EQ(max_label + 1.0, count);  // compact numbering
}

TEST(Peers, SeedsRespectsColourEdges) {
  const cv::Mat image = colorBlocks(200, 150);
  SeedsConfig config;
  config.superpixel_count = 200;
  const cv::Mat labels = computeOpenCvSeeds(image, config);
  EXPECT_EQ(cv::countNonZero(labels < 0), 0);
  EXPECT_GT(metrics::countSegments(labels, cv::Mat()), 20u);
  // The blocks are the ground truth: SEEDS follows such hard colour edges.
  cv::Mat gt(image.size(), CV_32SC1, cv::Scalar(0));
  gt(cv::Rect(0, 0, 100, 75)).setTo(1);
  gt(cv::Rect(100, 75, 100, 75)).setTo(2);
  EXPECT_GT(metrics::achievableSegmentationAccuracy(labels, gt, cv::Mat()), 0.97);
}

TEST(Peers, VccsSeparatesDepthPlanesAndSkipsInvalidDepth) {
  const RgbdFrame frame = twoPlanes();
  VccsConfig config;
  config.superpixel_count = 100;
  const cv::Mat labels = computeVccs(frame, config);
  // No label where depth is missing.
  EXPECT_EQ(cv::countNonZero((labels >= 0) & (frame.depth == 0)), 0);
  EXPECT_GT(metrics::countSegments(labels, cv::Mat()), 10u);
  cv::Mat gt(frame.depth.size(), CV_32SC1, cv::Scalar(1));
  gt.colRange(80, 160).setTo(2);
  const cv::Mat mask = frame.depth > 0;
  EXPECT_GT(metrics::achievableSegmentationAccuracy(labels, gt, mask), 0.99);
}

TEST(Peers, BadInputThrows) {
  EXPECT_THROW(computeOpenCvSlic(cv::Mat(10, 10, CV_8UC1), SlicConfig{}), std::invalid_argument);
  SlicConfig zero;
  zero.superpixel_count = 0;
  EXPECT_THROW(computeOpenCvSlic(colorBlocks(20, 20), zero), std::invalid_argument);
  RgbdFrame frame = twoPlanes();
  frame.depth.setTo(0);
  EXPECT_THROW(computeVccs(frame, VccsConfig{}), std::invalid_argument);
  EXPECT_THROW(parseMethod("FELZENSZWALB"), std::invalid_argument);
  EXPECT_EQ(parseMethod("dasp"), Method::kDasp);
}

TEST(Peers, EvaluateLabelsOnGroundTruthItself) {
  const RgbdFrame frame = twoPlanes();
  cv::Mat gt(frame.depth.size(), CV_32SC1, cv::Scalar(1));
  gt.colRange(80, 160).setTo(2);
  const PixelFeatures features = computeFeatures(frame);
  const FrameReference ref = makeFrameReference(frame, gt, features);
  EXPECT_EQ(cv::countNonZero(ref.mask), 160 * 100);
  cv::Mat labels = gt - 1;
  labels.setTo(-1, frame.depth == 0);
  const auto m = evaluateLabels(labels, ref, 2);
  for (const std::string& name : metricNames()) EXPECT_EQ(m.count(name), 1u) << name;
  EXPECT_DOUBLE_EQ(m.at("boundary_recall"), 1.0);
  EXPECT_DOUBLE_EQ(m.at("ue_np"), 0.0);
  EXPECT_DOUBLE_EQ(m.at("asa"), 1.0);
  EXPECT_DOUBLE_EQ(m.at("superpixels"), 2.0);
  EXPECT_DOUBLE_EQ(m.at("count_ratio"), 1.0);
  EXPECT_NEAR(m.at("ce_depth_mm"), 0.0, 1e-3);  // each plane has one depth
  EXPECT_DOUBLE_EQ(m.at("disconnected_fraction"), 0.0);
}

}  // namespace
}  // namespace peers
}  // namespace dasp
#endif
