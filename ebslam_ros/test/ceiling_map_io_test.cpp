#include "ebslam_ros/ceiling_map_io.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

namespace {

std::string tempPrefix(const std::string& name) {
  return ::testing::TempDir() + "ebslam_ros_map_" + name + "_" + std::to_string(::getpid());
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// A map_server map: dark pixels are edges, row 0 at the top (largest y), origin = lower-left
// corner; the loaded map has rows growing with y and its origin at pixel (0, 0)'s centre.
TEST(CeilingMapIo, ReadsMapServerLayout) {
  const std::string prefix = tempPrefix("server");
  cv::Mat image(40, 30, CV_8UC1, cv::Scalar(254));
  image.at<std::uint8_t>(0, 5) = 0;  // top row = largest y
  ASSERT_TRUE(cv::imwrite(prefix + ".png", image));
  writeText(prefix + ".yaml", "image: " + prefix.substr(prefix.find_last_of('/') + 1) +
                                  ".png\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\n"
                                  "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const ebslam_ros::CeilingEdgeMap map = ebslam_ros::loadCeilingMap(prefix + ".yaml");
  EXPECT_DOUBLE_EQ(map.resolution_m, 0.05);
  EXPECT_DOUBLE_EQ(map.origin_centre_m.x(), -0.975);
  EXPECT_DOUBLE_EQ(map.origin_centre_m.y(), 2.025);
  EXPECT_EQ(cv::countNonZero(map.edges), 1);
  EXPECT_EQ(map.edges.at<std::uint8_t>(39, 5), 255);
}

TEST(CeilingMapIo, SaveThenLoadRoundTrips) {
  const std::string prefix = tempPrefix("round");
  cv::Mat image(20, 10, CV_8UC1, cv::Scalar(255));
  image.at<std::uint8_t>(3, 4) = 0;  // dark = likely to fire = edge
  ebslam_ros::saveMapServerMap(prefix, image, 0.03, {-0.3, -0.6});
  const ebslam_ros::CeilingEdgeMap map = ebslam_ros::loadCeilingMap(prefix + ".yaml");
  EXPECT_EQ(map.edges.at<std::uint8_t>(3, 4), 255);
  EXPECT_EQ(cv::countNonZero(map.edges), 1);
  EXPECT_NEAR(map.origin_centre_m.x(), -0.285, 1e-12);
  EXPECT_NEAR(map.origin_centre_m.y(), -0.585, 1e-12);
}

TEST(CeilingMapIo, ReadsTheSimulatorLayout) {
  const std::string prefix = tempPrefix("sim");
  cv::Mat edges(10, 10, CV_8UC1, cv::Scalar(0));
  edges.at<std::uint8_t>(2, 7) = 255;
  ASSERT_TRUE(cv::imwrite(prefix + "_edges.png", edges));
  writeText(prefix + ".yaml", "# comment\nedges: " + prefix +
                                  "_edges.png\nresolution_m: 0.01\norigin_x_m: -3\n"
                                  "origin_y_m: 4.5\nkappa: [0, 0]\n");
  const ebslam_ros::CeilingEdgeMap map = ebslam_ros::loadCeilingMap(prefix + ".yaml");
  EXPECT_EQ(map.edges.at<std::uint8_t>(2, 7), 255);
  EXPECT_DOUBLE_EQ(map.origin_centre_m.y(), 4.5);
}

TEST(CeilingMapIo, BadMapsThrowWithTheReason) {
  const std::string prefix = tempPrefix("bad");
  EXPECT_THROW(ebslam_ros::loadCeilingMap(prefix + "_missing.yaml"), std::runtime_error);
  writeText(prefix + ".yaml", "image: nothing_here.png\nresolution: 0.05\norigin: [0, 0, 0]\n");
  try {
    ebslam_ros::loadCeilingMap(prefix + ".yaml");
    FAIL() << "missing image accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("nothing_here.png"), std::string::npos);
  }
  writeText(prefix + "_text.png", "not an image");
  writeText(prefix + ".yaml",
            "image: " + prefix + "_text.png\nresolution: 0.05\norigin: [0, 0, 0]\n");
  EXPECT_THROW(ebslam_ros::loadCeilingMap(prefix + ".yaml"), std::runtime_error);
  cv::Mat wide(4, 4, CV_16UC1, cv::Scalar(0));
  ASSERT_TRUE(cv::imwrite(prefix + "_16.png", wide));
  writeText(prefix + ".yaml",
            "image: " + prefix + "_16.png\nresolution: 0.05\norigin: [0, 0, 0]\n");
  EXPECT_THROW(ebslam_ros::loadCeilingMap(prefix + ".yaml"), std::runtime_error);
  cv::Mat blank(4, 4, CV_8UC1, cv::Scalar(255));
  ASSERT_TRUE(cv::imwrite(prefix + "_blank.png", blank));
  writeText(prefix + ".yaml",
            "image: " + prefix + "_blank.png\nresolution: 0.05\norigin: [0, 0, 0]\n");
  EXPECT_THROW(ebslam_ros::loadCeilingMap(prefix + ".yaml"), std::runtime_error);  // no edges
  writeText(prefix + ".yaml",
            "image: " + prefix + "_blank.png\nresolution: 0.05\norigin: [0, 0, 1]\n");
  EXPECT_THROW(ebslam_ros::loadCeilingMap(prefix + ".yaml"), std::runtime_error);  // yaw
}

}  // namespace
