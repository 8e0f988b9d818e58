// Round trips of every conversion in conversions.h, and the errors for messages that cannot be
// represented.
#include <cv_bridge/cv_bridge.h>
#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>

#include "dasp_ros/conversions.h"

namespace {

using dasp_ros::toColorImageMsg;
using dasp_ros::toColorMat;

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp = ros::Time(100, 5);
  h.frame_id = "camera_rgb_optical_frame";
  return h;
}

cv::Mat randomImage(int rows, int cols, int type, double low, double high, int seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, low, high);
  return m;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(Conversions, ColorRoundTrip) {
  const cv::Mat color = randomImage(7, 11, CV_8UC3, 0, 256, 1);
  const sensor_msgs::Image msg = toColorImageMsg(color, header());
  EXPECT_EQ(msg.encoding, "bgr8");
  EXPECT_EQ(msg.header.frame_id, "camera_rgb_optical_frame");
  EXPECT_TRUE(same(toColorMat(msg), color));
}

TEST(Conversions, Rgb8IsSwappedToBgr) {
  sensor_msgs::Image msg =
      toColorImageMsg(cv::Mat(2, 2, CV_8UC3, cv::Scalar(10, 20, 30)), header());
  msg.encoding = "rgb8";  // same bytes read as R=10, G=20, B=30
  const cv::Mat bgr = toColorMat(msg);
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 1), cv::Vec3b(30, 20, 10));
}

TEST(Conversions, DepthRoundTripAndMetres) {
  const cv::Mat depth = randomImage(5, 9, CV_16UC1, 0, 5000, 2);
  EXPECT_TRUE(same(dasp_ros::toDepthMat(dasp_ros::toDepthImageMsg(depth, header())), depth));

  cv::Mat metres(1, 4, CV_32FC1);
  metres.at<float>(0) = 1.2345f;
  metres.at<float>(1) = std::nanf("");
  metres.at<float>(2) = -1.0f;
  metres.at<float>(3) = 70.0f;  // beyond 16-bit millimetres
  const sensor_msgs::Image msg = *cv_bridge::CvImage(header(), "32FC1", metres).toImageMsg();
  const cv::Mat mm = dasp_ros::toDepthMat(msg);
  EXPECT_EQ(mm.at<uint16_t>(0), 1235);
  EXPECT_EQ(mm.at<uint16_t>(1), 0);
  EXPECT_EQ(mm.at<uint16_t>(2), 0);
  EXPECT_EQ(mm.at<uint16_t>(3), 0);
}

TEST(Conversions, LabelRoundTrip) {
  const cv::Mat labels = randomImage(6, 4, CV_32SC1, -1, 1000, 3);
  EXPECT_TRUE(same(dasp_ros::toLabelMat(dasp_ros::toLabelImageMsg(labels, header())), labels));
}

// Shared data point into the message (no copy), copied data do not; both equal the image, and a
// non-continuous Mat (a view) is written row by row like cv_bridge writes it.
TEST(Conversions, SharedImagesPointIntoTheMessage) {
  const cv::Mat color = randomImage(6, 5, CV_8UC3, 0, 256, 4);
  const sensor_msgs::Image color_msg = toColorImageMsg(color, header());
  const cv::Mat shared = toColorMat(color_msg, dasp_ros::ImageData::kShare);
  EXPECT_TRUE(same(shared, color));
  EXPECT_EQ(shared.data, color_msg.data.data());
  EXPECT_NE(toColorMat(color_msg).data, color_msg.data.data());
  const cv::Mat depth = randomImage(4, 3, CV_16UC1, 0, 5000, 5);
  const sensor_msgs::Image depth_msg = dasp_ros::toDepthImageMsg(depth, header());
  EXPECT_EQ(dasp_ros::toDepthMat(depth_msg, dasp_ros::ImageData::kShare).data,
            depth_msg.data.data());
  const cv::Mat labels = randomImage(8, 8, CV_32SC1, -1, 1000, 6);
  const cv::Mat view = labels(cv::Rect(1, 2, 5, 4));
  ASSERT_FALSE(view.isContinuous());
  const sensor_msgs::Image labels_msg = dasp_ros::toLabelImageMsg(view, header());
  EXPECT_EQ(labels_msg, *cv_bridge::CvImage(header(), "32SC1", view).toImageMsg());
  EXPECT_TRUE(same(dasp_ros::toLabelMat(labels_msg, dasp_ros::ImageData::kShare), view));
}

TEST(Conversions, CameraInfoRoundTrip) {
  const dasp::Intrinsics in{525.0f, 526.0f, 319.5f, 239.5f};
  const sensor_msgs::CameraInfo info = dasp_ros::toCameraInfo(in, 640, 480, header());
  EXPECT_EQ(info.width, 640u);
  const dasp::Intrinsics out = dasp_ros::toIntrinsics(info);
  EXPECT_EQ(out.fx, in.fx);
  EXPECT_EQ(out.fy, in.fy);
  EXPECT_EQ(out.cx, in.cx);
  EXPECT_EQ(out.cy, in.cy);
}

TEST(Conversions, SuperpixelsRoundTrip) {
  dasp::Superpixels in;
  in.labels = randomImage(4, 5, CV_32SC1, -1, 2, 4);
  for (int i = 0; i < 2; ++i) {
    dasp::Superpixel sp;
    sp.id = i;
    sp.u = 1.5f + i;
    sp.v = 2.25f;
    sp.pixel_count = 10 + i;
    sp.color = {0.1f, 0.2f, 0.3f};
    sp.position = {0.5f, -0.25f, 1.5f + i};
    sp.normal = {0.0f, 0.6f, -0.8f};
    sp.radius_m = 0.02f;
    sp.density = 0.001f;
    sp.thickness = 0.003f;
    sp.eccentricity = 0.4f;
    sp.flatness = 0.9f;
    sp.area_m2 = 0.0011f;
    in.superpixels.push_back(sp);
  }
  const auto msg = dasp_ros::toSuperpixelArrayMsg(in, header());
  EXPECT_EQ(msg.width, 5u);
  EXPECT_EQ(msg.height, 4u);
  const auto out = dasp_ros::toSuperpixels(msg, dasp_ros::toLabelImageMsg(in.labels, header()));
  EXPECT_TRUE(same(out.labels, in.labels));
  ASSERT_EQ(out.superpixels.size(), in.superpixels.size());
  for (std::size_t i = 0; i < in.superpixels.size(); ++i) {
    const auto& a = in.superpixels[i];
    const auto& b = out.superpixels[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.u, b.u);
    EXPECT_EQ(a.pixel_count, b.pixel_count);
    EXPECT_EQ(a.color, b.color);
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.normal, b.normal);
    EXPECT_EQ(a.radius_m, b.radius_m);
    EXPECT_EQ(a.density, b.density);
    EXPECT_EQ(a.thickness, b.thickness);
    EXPECT_EQ(a.eccentricity, b.eccentricity);
    EXPECT_EQ(a.flatness, b.flatness);
    EXPECT_EQ(a.area_m2, b.area_m2);
  }
}

TEST(Conversions, BadMessagesThrowInvalidArgument) {
  sensor_msgs::Image msg = toColorImageMsg(cv::Mat(2, 2, CV_8UC3, cv::Scalar(0)), header());
  msg.encoding = "yuv422";
  EXPECT_THROW(toColorMat(msg), std::invalid_argument);
  msg.encoding = "bgr8";
  msg.data.resize(5);  // truncated data
  EXPECT_THROW(toColorMat(msg), std::invalid_argument);
  sensor_msgs::Image empty;
  empty.encoding = "16UC1";
  EXPECT_THROW(dasp_ros::toDepthMat(empty), std::invalid_argument);

  const sensor_msgs::Image color = toColorImageMsg(cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), header());
  const sensor_msgs::Image depth =
      dasp_ros::toDepthImageMsg(cv::Mat(3, 4, CV_16UC1, cv::Scalar(0)), header());
  const auto info = dasp_ros::toCameraInfo({}, 4, 4, header());
  EXPECT_THROW(dasp_ros::toRgbdFrame(color, depth, info), std::invalid_argument);

  sensor_msgs::CameraInfo zero;
  EXPECT_THROW(dasp_ros::toIntrinsics(zero), std::invalid_argument);
  sensor_msgs::CameraInfo nan_info = info;
  nan_info.K[2] = std::nan("");
  EXPECT_THROW(dasp_ros::toIntrinsics(nan_info), std::invalid_argument);
}

// Sizes whose byte counts overflow 32 bits: a 65536 x 65537 bgr8 image with a few bytes of data
// passed the size check once (step x height wrapped to 65536 bytes) and crashed the nodelet
// manager in clone(). Every conversion must reject such messages with invalid_argument.
TEST(Conversions, SizesOverflowing32BitsAreRejected) {
  sensor_msgs::Image msg;
  msg.width = 65536;
  msg.height = 65537;
  msg.encoding = "bgr8";
  msg.step = 3 * 65536;  // 196608 x 65537 = 12885098496 bytes = 65536 + 3 * 2^32
  msg.data.assign(65536, 0);
  EXPECT_THROW(toColorMat(msg), std::invalid_argument);
  for (const char* encoding : {"rgb8", "bgra8", "rgba8", "mono8"}) {
    msg.encoding = encoding;
    msg.step = static_cast<uint32_t>(65536 * sensor_msgs::image_encodings::numChannels(encoding));
    EXPECT_THROW(toColorMat(msg), std::invalid_argument) << encoding;
  }
  msg.step = 2 * 65536;  // 16UC1: step x height = 2^33 + 2^17, wraps to 131072
  msg.data.assign(131072, 0);
  for (const char* encoding : {"16UC1", "mono16"}) {
    msg.encoding = encoding;
    EXPECT_THROW(dasp_ros::toDepthMat(msg), std::invalid_argument) << encoding;
  }
  msg.encoding = "32FC1";
  msg.step = 4 * 65536;  // wraps to 262144
  msg.data.assign(262144, 0);
  EXPECT_THROW(dasp_ros::toDepthMat(msg), std::invalid_argument);
  msg.encoding = "32SC1";
  EXPECT_THROW(dasp_ros::toLabelMat(msg), std::invalid_argument);
  // A row of more bytes than int holds, and a height beyond int (OpenCV's limits).
  msg.width = 0x80000000u;
  msg.height = 1;
  msg.step = 0xFFFFFFFFu;
  msg.encoding = "mono8";
  EXPECT_THROW(toColorMat(msg), std::invalid_argument);
  msg.width = 1;
  msg.height = 0x80000000u;
  msg.step = 1;
  EXPECT_THROW(toColorMat(msg), std::invalid_argument);
  // A step that is not a whole number of channels: cv::Mat would throw cv::Exception.
  msg.width = 2;
  msg.height = 2;
  msg.step = 5;
  msg.encoding = "16UC1";
  msg.data.assign(10, 0);
  EXPECT_THROW(dasp_ros::toDepthMat(msg), std::invalid_argument);
}

}  // namespace

namespace {

// PrimeSense Carmine 1.09 / Xtion colour stream as OpenNI2 reports it: 1.0225 x 0.7971 rad.
TEST(Conversions, IntrinsicsFromFieldOfView) {
  const dasp::Intrinsics k = dasp_ros::intrinsicsFromFieldOfView(1.0225, 0.7971, 640, 480);
  EXPECT_NEAR(k.fx, 320.0 / std::tan(0.51125), 1e-3);
  EXPECT_NEAR(k.fx, 570.3, 0.5);  // the focal length openni2_camera derives for these devices
  EXPECT_NEAR(k.fy, 240.0 / std::tan(0.39855), 1e-3);
  EXPECT_FLOAT_EQ(k.cx, 319.5f);
  EXPECT_FLOAT_EQ(k.cy, 239.5f);
  const dasp::Intrinsics half = dasp_ros::intrinsicsFromFieldOfView(1.0225, 0.7971, 320, 240);
  EXPECT_NEAR(half.fx, 0.5 * k.fx, 1e-3);
  EXPECT_FLOAT_EQ(half.cx, 159.5f);
  EXPECT_THROW(dasp_ros::intrinsicsFromFieldOfView(0.0, 0.8, 640, 480), std::invalid_argument);
  EXPECT_THROW(dasp_ros::intrinsicsFromFieldOfView(1.0, 3.2, 640, 480), std::invalid_argument);
  EXPECT_THROW(dasp_ros::intrinsicsFromFieldOfView(1.0, 0.8, 0, 480), std::invalid_argument);
}

TEST(Conversions, EdgesRoundTripAndMarkersAndCloud) {
  dasp::WeightedGraph graph;
  graph.node_count = 3;
  graph.edges = {{0, 1, 0.25f}, {1, 2, 0.75f}};
  const dasp::WeightedGraph back = dasp_ros::toWeightedGraph(dasp_ros::toEdgeMsgs(graph), 3);
  ASSERT_EQ(back.edges.size(), 2u);
  EXPECT_EQ(back.edges[1].a, 1);
  EXPECT_EQ(back.edges[1].weight, 0.75f);
  EXPECT_THROW(dasp_ros::toWeightedGraph(dasp_ros::toEdgeMsgs(graph), 2), std::invalid_argument);

  dasp::Superpixel sp;
  sp.id = 0;
  sp.position = {0.1f, -0.2f, 1.5f};
  sp.normal = {0.0f, 0.0f, -1.0f};
  sp.radius_m = 0.02f;
  sp.color = {1.0f, 0.5f, 0.0f};
  const visualization_msgs::MarkerArray markers = dasp_ros::toMarkerArray({sp}, header());
  ASSERT_EQ(markers.markers.size(), 2u);
  EXPECT_EQ(markers.markers[1].header.frame_id, header().frame_id);
  EXPECT_DOUBLE_EQ(markers.markers[1].scale.x, 2.0 * static_cast<double>(0.02f));
  // The disc's axis (local z) is the normal: rotating +z by the orientation gives -z.
  const auto& q = markers.markers[1].pose.orientation;
  const double z_of_axis = 1.0 - 2.0 * (q.x * q.x + q.y * q.y);
  EXPECT_NEAR(z_of_axis, -1.0, 1e-6);
  const sensor_msgs::PointCloud2 cloud = dasp_ros::toCentreCloud({sp}, header());
  EXPECT_EQ(cloud.width, 1u);
  EXPECT_EQ(cloud.header.stamp, header().stamp);
  float z = 0.0f;
  std::memcpy(&z, &cloud.data[cloud.fields[2].offset], sizeof(z));
  EXPECT_EQ(z, 1.5f);
}

}  // namespace
