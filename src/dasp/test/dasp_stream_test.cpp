// DaspSegmenter (buffers kept across frames) and connectivity on the surface.
#include <gtest/gtest.h>

#include <utility>

#include <opencv2/core.hpp>

#include "dasp/connectivity.h"
#include "dasp/dasp.h"
#include "dasp_synthetic.h"

namespace dasp {
namespace {

bool sameSuperpixels(const Superpixels& a, const Superpixels& b) {
  if (a.superpixels.size() != b.superpixels.size()) return false;
  if (cv::countNonZero(a.labels != b.labels) != 0) return false;
  for (std::size_t i = 0; i < a.superpixels.size(); ++i) {
    if (a.superpixels[i].position != b.superpixels[i].position) return false;
    if (a.superpixels[i].pixel_count != b.superpixels[i].pixel_count) return false;
  }
  return true;
}

TEST(DaspSegmenter, StreamGivesTheOneShotResultForEveryFrame) {
  DaspConfig config;
  config.superpixel_count = 60;
  DaspSegmenter segmenter(config);
  const RgbdFrame planes = test::twoPlanes(160, 120, 1.0f, 1.6f, nullptr);
  const RgbdFrame slanted = test::slantedPlane(160, 120, 1.2f, 0.6f);
  const RgbdFrame smaller = test::twoPlanes(80, 60, 0.8f, 1.1f, nullptr);
  // Alternating frames (and a size change) must not leak state from one frame into the next.
  for (const RgbdFrame* frame : {&planes, &slanted, &planes, &smaller, &planes}) {
    const Superpixels streamed = segmenter.compute(*frame);
    const Superpixels one_shot = computeDasp(*frame, config);
    EXPECT_TRUE(sameSuperpixels(streamed, one_shot));
  }
}

TEST(ComputeDasp, ReusedBuffersGiveTheResultOfFreshOnes) {
  // computeDasp keeps one set of buffers per thread: calls with other parameters and image
  // sizes in between must not change a result.
  DaspConfig a;
  a.superpixel_count = 60;
  DaspConfig b;
  b.superpixel_count = 25;
  b.weight_normal = 0.0f;
  b.iterations = 3;
  const RgbdFrame planes = test::twoPlanes(160, 120, 1.0f, 1.6f, nullptr);
  const RgbdFrame smaller = test::slantedPlane(80, 60, 1.2f, 0.6f);
  const std::pair<const RgbdFrame*, const DaspConfig*> calls[] = {
      {&planes, &a}, {&smaller, &b}, {&planes, &b}, {&smaller, &a}, {&planes, &a}};
  for (const auto& [frame, config] : calls) {
    const Superpixels reused = computeDasp(*frame, *config);
    const Superpixels fresh = DaspSegmenter(*config).compute(*frame);
    EXPECT_TRUE(sameSuperpixels(reused, fresh))
        << config->superpixel_count << " " << frame->color.cols;
  }
}

TEST(DaspSegmenter, BadFrameThrowsAndTheNextFrameStillWorks) {
  DaspSegmenter segmenter;
  RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.6f, nullptr);
  RgbdFrame no_depth = frame;
  no_depth.depth = cv::Mat(frame.depth.size(), frame.depth.type(), cv::Scalar(0));  // not shared
  EXPECT_THROW(segmenter.compute(no_depth), std::invalid_argument);
  DaspConfig config;
  EXPECT_TRUE(sameSuperpixels(segmenter.compute(frame), computeDasp(frame, config)));
}

TEST(Connectivity, DepthJumpSplitsALabelOnTheSurface) {
  // One label over two planes (left at 1 m, right at 2 m), a second label to the right at 2 m.
  // Without depth the first label is one piece; with depth its far part is a separate surface
  // piece and joins the far label it touches.
  cv::Mat labels(6, 12, CV_32SC1, cv::Scalar(0));
  labels(cv::Rect(8, 0, 4, 6)).setTo(1);
  cv::Mat depth(6, 12, CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(0, 0, 5, 6)).setTo(1.0f);
  cv::Mat image_only = labels.clone();
  EXPECT_EQ(enforceConnectivity(image_only, cv::Mat(), cv::Mat(), 1.0), 2);
  EXPECT_EQ(image_only.at<int>(0, 6), image_only.at<int>(0, 0));
  cv::Mat on_surface = labels.clone();
  EXPECT_EQ(enforceConnectivity(on_surface, cv::Mat(), cv::Mat(), 1.0, depth, 0.05f), 2);
  EXPECT_EQ(on_surface.at<int>(0, 6), on_surface.at<int>(0, 10));  // far part joined label 1
  EXPECT_NE(on_surface.at<int>(0, 6), on_surface.at<int>(0, 0));
}

TEST(Connectivity, PieceWalledInByDepthJumpsStillGetsALabel) {
  // A small far piece surrounded by a near label: it has no neighbour on its own surface, so
  // it joins across the jump instead of staying unlabelled.
  cv::Mat labels(8, 8, CV_32SC1, cv::Scalar(0));
  labels(cv::Rect(3, 3, 2, 2)).setTo(1);
  cv::Mat depth(8, 8, CV_32FC1, cv::Scalar(1.0f));
  depth(cv::Rect(3, 3, 2, 2)).setTo(2.0f);
  EXPECT_EQ(enforceConnectivity(labels, cv::Mat(), cv::Mat(), 5.0, depth, 0.05f), 1);
  EXPECT_EQ(labels.at<int>(3, 3), labels.at<int>(0, 0));
  EXPECT_THROW(enforceConnectivity(labels, cv::Mat(), cv::Mat(), 1.0, depth, 0.0f),
               std::invalid_argument);
}

}  // namespace
}  // namespace dasp
