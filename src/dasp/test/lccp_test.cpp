// The LCCP peer (tools/peers, built with DASP_BUILD_TOOLS only).
#if __has_include("peers/lccp.h")
#include <gtest/gtest.h>

#include <stdexcept>

#include <opencv2/core.hpp>

#include "dasp_synthetic.h"
#include "peers/lccp.h"

namespace dasp {
namespace {

TEST(LccpPeer, SeparatesTwoBoxesAtDifferentDepths) {
  // Two fronto-parallel boxes with a 40 cm depth step between them: LCCP must cut the step.
  RgbdFrame frame = test::twoBoxes();
  int supervoxels = 0;
  const cv::Mat labels = peers::computeLccp(frame, peers::LccpConfig{}, &supervoxels);
  ASSERT_EQ(labels.type(), CV_32SC1);
  EXPECT_GT(supervoxels, 2);
  EXPECT_EQ(labels.at<int>(0, 0), -1);  // no depth, no label
  const int left = labels.at<int>(60, 50);
  const int right = labels.at<int>(60, 110);
  EXPECT_GE(left, 0);
  EXPECT_GE(right, 0);
  EXPECT_NE(left, right);
  frame.depth = cv::Mat();
  EXPECT_THROW(peers::computeLccp(frame, peers::LccpConfig{}), std::invalid_argument);
}

}  // namespace
}  // namespace dasp
#endif
