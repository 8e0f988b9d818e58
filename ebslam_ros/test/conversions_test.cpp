// ebslam_ros/conversions.h: image and camera messages of the simulators and bag writers.
#include "ebslam_ros/conversions.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace ebslam_ros {
namespace {

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp = ros::Time(12, 345);
  h.frame_id = "camera_depth_optical_frame";
  return h;
}

TEST(Conversions, ImageRoundTripsAnRoiRowByRow) {
  cv::Mat depth(7, 9, CV_16UC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) depth.at<std::uint16_t>(r, c) = 1000 + 10 * r + c;
  }
  const cv::Mat roi = depth(cv::Rect(2, 1, 5, 4));  // not continuous
  ASSERT_FALSE(roi.isContinuous());
  const sensor_msgs::Image msg = toImageMsg(roi, "16UC1", header());
  EXPECT_EQ(msg.header.stamp, ros::Time(12, 345));
  EXPECT_EQ(msg.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(msg.width, 5u);
  EXPECT_EQ(msg.height, 4u);
  EXPECT_EQ(msg.step, 10u);
  EXPECT_EQ(msg.encoding, "16UC1");
  EXPECT_EQ(msg.is_bigendian, 0);
  ASSERT_EQ(msg.data.size(), 40u);
  const cv::Mat back(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_16UC1,
                     const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  EXPECT_EQ(cv::countNonZero(back != roi), 0);

  const cv::Mat colour(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  const sensor_msgs::Image bgr = toImageMsg(colour, "bgr8", header());
  EXPECT_EQ(bgr.step, 12u);
  ASSERT_EQ(bgr.data.size(), 36u);
  EXPECT_EQ(bgr.data[0], 10);
  EXPECT_EQ(bgr.data[35], 30);
}

TEST(Conversions, EmptyImageIsRefused) {
  EXPECT_THROW(toImageMsg(cv::Mat(), "mono8", header()), std::invalid_argument);
}

TEST(Conversions, CameraInfoOfARectifiedPinhole) {
  const sensor_msgs::CameraInfo info =
      toCameraInfoMsg(320, 240, 285.5, 286.0, 159.5, 119.25, header());
  EXPECT_EQ(info.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(info.width, 320u);
  EXPECT_EQ(info.height, 240u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  ASSERT_EQ(info.D.size(), 5u);
  for (double d : info.D) EXPECT_EQ(d, 0.0);
  EXPECT_EQ(info.K[0], 285.5);
  EXPECT_EQ(info.K[2], 159.5);
  EXPECT_EQ(info.K[4], 286.0);
  EXPECT_EQ(info.K[5], 119.25);
  EXPECT_EQ(info.K[8], 1.0);
  EXPECT_EQ(info.R[0] + info.R[4] + info.R[8], 3.0);
  EXPECT_EQ(info.P[0], 285.5);
  EXPECT_EQ(info.P[2], 159.5);
  EXPECT_EQ(info.P[3], 0.0);
  EXPECT_EQ(info.P[5], 286.0);
  EXPECT_EQ(info.P[6], 119.25);
  EXPECT_EQ(info.P[10], 1.0);
}

}  // namespace
}  // namespace ebslam_ros
