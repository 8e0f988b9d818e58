// The bar "same results through ROS": frames played by RgbdFolderSource through Dasp and Sdasp
// give exactly the superpixel and segment labels of the core library on the same files with the
// same (default) parameters, which is what dasp_segment and dasp_sdasp segment compute and write.
#include <dasp/dasp.h>
#include <dasp/rgbd_io.h>
#include <dasp/segmentation.h>
#include <ebslam_msgs/Segmentation.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <chrono>
#include <map>
#include <mutex>
#include <thread>

#include "dasp_ros/conversions.h"

namespace {

TEST(FolderPipeline, LabelsEqualTheCoreLibraryFrameByFrame) {
  ros::NodeHandle pnh("~");
  std::string folder;
  int frames = 3;
  pnh.getParam("folder", folder);
  pnh.getParam("frames", frames);
  const std::vector<dasp::RgbdFramePaths> paths = dasp::listRgbdFolder(folder);
  ASSERT_GE(static_cast<int>(paths.size()), frames);

  // By frame index = header.seq modulo the frame count: the source numbers its messages 0, 1, ...
  // in folder order and loops, so that frames missed before this node connected come again.
  const uint32_t n = static_cast<uint32_t>(paths.size());
  std::mutex mutex;
  std::map<uint32_t, sensor_msgs::Image> superpixel_labels, segment_labels;
  ros::NodeHandle nh("camera");
  ros::Subscriber a = nh.subscribe<sensor_msgs::Image>(
      "superpixels/labels", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        superpixel_labels.emplace(m->header.seq % n, *m);
      });
  ros::Subscriber b = nh.subscribe<sensor_msgs::Image>(
      "segments/labels", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        segment_labels.emplace(m->header.seq % n, *m);
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      bool all = true;
      for (uint32_t i = 0; i < static_cast<uint32_t>(frames); ++i) {
        all = all && segment_labels.count(i) > 0 && superpixel_labels.count(i) > 0;
      }
      if (all) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::lock_guard<std::mutex> lock(mutex);
  const dasp::SdaspConfig sdasp;
  for (int i = 0; i < frames; ++i) {
    SCOPED_TRACE(paths[static_cast<std::size_t>(i)].name);
    ASSERT_EQ(superpixel_labels.count(static_cast<uint32_t>(i)), 1u);
    ASSERT_EQ(segment_labels.count(static_cast<uint32_t>(i)), 1u);
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths[static_cast<std::size_t>(i)]);
    const dasp::Superpixels expected = dasp::computeDasp(frame, dasp::DaspConfig{});
    const cv::Mat segments = dasp::segmentPixels(
        expected.labels,
        dasp::segmentGraph(dasp::ultrametricContourGraph(expected, sdasp), sdasp.threshold));
    const sensor_msgs::Image& sp = superpixel_labels[static_cast<uint32_t>(i)];
    const sensor_msgs::Image& seg = segment_labels[static_cast<uint32_t>(i)];
    EXPECT_EQ(sp.header.frame_id, "camera_rgb_optical_frame");
    EXPECT_EQ(seg.header.frame_id, "camera_rgb_optical_frame");
    EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(sp) != expected.labels), 0);
    EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(seg) != segments), 0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "folder_pipeline_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
