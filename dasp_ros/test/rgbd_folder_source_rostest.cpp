// Receives frames from the RGB-D folder source nodelet, checks content, frame and stamp against the
// files on disk, then records them into a bag with the C++ rosbag API and reads the bag back.
#include <dasp/rgbd_io.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cstdio>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "dasp_ros/conversions.h"

namespace {

struct Received {
  std::vector<sensor_msgs::Image> color, depth;
  std::vector<sensor_msgs::CameraInfo> info;
};

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(RgbdFolderSource, PublishesTheFolderWithFrameAndStamp) {
  ros::NodeHandle nh;
  Received received;
  auto color_sub = nh.subscribe<sensor_msgs::Image>(
      "camera/rgb/image_rect_color", 10,
      [&](const sensor_msgs::ImageConstPtr& m) { received.color.push_back(*m); });
  auto depth_sub = nh.subscribe<sensor_msgs::Image>(
      "camera/depth_registered/image_raw", 10,
      [&](const sensor_msgs::ImageConstPtr& m) { received.depth.push_back(*m); });
  auto info_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "camera/rgb/camera_info", 10,
      [&](const sensor_msgs::CameraInfoConstPtr& m) { received.info.push_back(*m); });

  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while ((received.color.size() < 3 || received.depth.size() < 3 || received.info.size() < 3) &&
         ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_GE(received.color.size(), 3u) << "no colour images arrived";
  ASSERT_GE(received.depth.size(), 3u) << "no depth images arrived";
  ASSERT_GE(received.info.size(), 3u) << "no camera info arrived";

  // Each colour image has a depth image and camera info with the identical stamp and frame.
  std::map<ros::Time, const sensor_msgs::Image*> depth_by_stamp;
  for (const auto& d : received.depth) depth_by_stamp[d.header.stamp] = &d;
  const auto frames = dasp::listRgbdFolder(SAMPLE_SESSION_DIR);
  ASSERT_FALSE(frames.empty());
  // A message's frame is found by its content (never by the header's sequence number, which
  // roscpp renumbers per publisher): the folder's colour images must differ from each other for
  // that.
  std::vector<dasp::RgbdFrame> expected;
  for (const auto& paths : frames) expected.push_back(dasp::loadRgbdFrame(paths));
  for (std::size_t i = 0; i < expected.size(); ++i) {
    for (std::size_t j = i + 1; j < expected.size(); ++j) {
      ASSERT_FALSE(sameImage(expected[i].color, expected[j].color))
          << frames[i].name << " and " << frames[j].name << " have the same colour image";
    }
  }
  int matched = 0;
  int previous = -1;  // folder index of the previous colour image (in stamp order)
  ros::Time previous_stamp;
  for (const auto& color : received.color) {
    EXPECT_EQ(color.header.frame_id, "test_optical_frame");
    EXPECT_EQ(color.encoding, "bgr8");
    EXPECT_GT(color.header.stamp.toSec(), 0.0);
    const cv::Mat color_mat = dasp_ros::toColorMat(color);
    int index = -1;
    for (std::size_t i = 0; i < expected.size() && index < 0; ++i) {
      if (sameImage(color_mat, expected[i].color)) index = static_cast<int>(i);
    }
    ASSERT_GE(index, 0) << "colour image stamped " << color.header.stamp
                        << " is none of the folder's";
    // Folder order, looping, with increasing stamps.
    if (previous >= 0) {
      EXPECT_EQ(index, (previous + 1) % static_cast<int>(frames.size()))
          << "after " << frames[static_cast<std::size_t>(previous)].name;
      EXPECT_GT(color.header.stamp, previous_stamp);
    }
    previous = index;
    previous_stamp = color.header.stamp;
    const auto depth = depth_by_stamp.find(color.header.stamp);
    if (depth == depth_by_stamp.end()) continue;  // subscription started between the two
    EXPECT_EQ(depth->second->header.frame_id, "test_optical_frame");
    EXPECT_EQ(depth->second->encoding, "16UC1");
    const auto& name = frames[static_cast<std::size_t>(index)].name;
    EXPECT_TRUE(sameImage(dasp_ros::toDepthMat(*depth->second),
                          expected[static_cast<std::size_t>(index)].depth))
        << name;
    ++matched;
  }
  EXPECT_GE(matched, 2);
  for (const auto& info : received.info) {
    EXPECT_EQ(info.header.frame_id, "test_optical_frame");
    EXPECT_DOUBLE_EQ(info.K[0], 525.0);
    EXPECT_EQ(info.width, 640u);
    EXPECT_EQ(info.height, 480u);
  }

  // Record what arrived into a bag, read it back, and compare message for message.
  const std::string bag_path =
      "/tmp/dasp_ros_rgbd_folder_source_test_" + std::to_string(::getpid()) + ".bag";
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    bag.setCompression(rosbag::compression::LZ4);
    for (const auto& m : received.color)
      bag.write("/camera/rgb/image_rect_color", m.header.stamp, m);
    for (const auto& m : received.depth)
      bag.write("/camera/depth_registered/image_raw", m.header.stamp, m);
    for (const auto& m : received.info) bag.write("/camera/rgb/camera_info", m.header.stamp, m);
  }
  Received replayed;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (m.getTopic() == "/camera/rgb/image_rect_color")
        replayed.color.push_back(*m.instantiate<sensor_msgs::Image>());
      if (m.getTopic() == "/camera/depth_registered/image_raw")
        replayed.depth.push_back(*m.instantiate<sensor_msgs::Image>());
      if (m.getTopic() == "/camera/rgb/camera_info") {
        replayed.info.push_back(*m.instantiate<sensor_msgs::CameraInfo>());
      }
    }
  }
  std::remove(bag_path.c_str());
  ASSERT_EQ(replayed.color.size(), received.color.size());
  ASSERT_EQ(replayed.depth.size(), received.depth.size());
  ASSERT_EQ(replayed.info.size(), received.info.size());
  // A bag view is ordered by time; the messages of each topic were written in time order too.
  for (std::size_t i = 0; i < received.color.size(); ++i)
    EXPECT_EQ(replayed.color[i], received.color[i]);
  for (std::size_t i = 0; i < received.depth.size(); ++i)
    EXPECT_EQ(replayed.depth[i], received.depth[i]);
  for (std::size_t i = 0; i < received.info.size(); ++i)
    EXPECT_EQ(replayed.info[i], received.info[i]);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "rgbd_folder_source_rostest");
  ros::NodeHandle nh;  // keeps the node alive for the whole test
  return RUN_ALL_TESTS();
}
