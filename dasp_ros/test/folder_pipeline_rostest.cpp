// Same results through ROS: frames played by RgbdFolderSource through Dasp and Sdasp
// give exactly the superpixel and segment labels of the core library on the same files with the
// same (default) parameters, which is what dasp_segment and dasp_sdasp segment compute and write.
#include <dasp/dasp.h>
#include <dasp/rgbd_io.h>
#include <dasp/sdasp.h>
#include <dasp/segmentation.h>
#include <ebslam_msgs/Segmentation.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <chrono>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "dasp_ros/conversions.h"

namespace {

TEST(FolderPipeline, LabelsEqualTheCoreLibraryFrameByFrame) {
  ros::NodeHandle pnh("~");
  std::string folder;
  int frames = 3;
  // Required: a renamed parameter must fail the test, not quietly test something else.
  ASSERT_TRUE(pnh.getParam("folder", folder)) << "~folder not set";
  ASSERT_TRUE(pnh.getParam("frames", frames)) << "~frames not set";
  const std::vector<dasp::RgbdFramePaths> paths = dasp::listRgbdFolder(folder);
  ASSERT_GE(static_cast<int>(paths.size()), frames);

  // Frames are identified by their stamp, never by the header's sequence number (roscpp renumbers
  // it per publisher across processes, and image_transport publishes nothing while nobody
  // subscribes, so it says nothing about the folder position). The source stamps the colour image
  // and both label images of one frame alike; the colour image's content names the folder frame.
  // Frames whose colour image this node missed (its subscription connected later) are left out: the
  // source loops.
  const std::size_t n = paths.size();
  std::vector<cv::Mat> colours;
  for (const dasp::RgbdFramePaths& p : paths) colours.push_back(dasp::loadRgbdFrame(p).color);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      ASSERT_FALSE(colours[i].size() == colours[j].size() &&
                   cv::countNonZero(cv::Mat(colours[i] != colours[j]).reshape(1)) == 0)
          << paths[i].name << " and " << paths[j].name << " have the same colour image";
    }
  }
  const auto frameOf = [&](const sensor_msgs::Image& colour) -> int {
    const cv::Mat mat = dasp_ros::toColorMat(colour);
    for (std::size_t i = 0; i < n; ++i) {
      if (mat.size() == colours[i].size() &&
          cv::countNonZero(cv::Mat(mat != colours[i]).reshape(1)) == 0) {
        return static_cast<int>(i);
      }
    }
    return -1;
  };
  std::mutex mutex;
  std::map<ros::Time, sensor_msgs::Image> superpixel_labels, segment_labels;  // by stamp
  std::map<ros::Time, int> frame_of_stamp;  // stamp -> folder frame index (from the colour image)
  ros::NodeHandle nh("camera");
  ros::Subscriber colour_sub = nh.subscribe<sensor_msgs::Image>(
      "rgb/image_rect_color", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        const int index = frameOf(*m);
        std::lock_guard<std::mutex> lock(mutex);
        frame_of_stamp.emplace(m->header.stamp, index);
      });
  ros::Subscriber a = nh.subscribe<sensor_msgs::Image>(
      "superpixels/labels", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        superpixel_labels.emplace(m->header.stamp, *m);
      });
  ros::Subscriber b = nh.subscribe<sensor_msgs::Image>(
      "segments/labels", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        segment_labels.emplace(m->header.stamp, *m);
      });
  // Stamps with the colour image and both labels, by folder frame index (mutex held).
  const auto complete = [&]() {
    std::map<int, std::vector<ros::Time>> by_frame;
    for (const auto& [stamp, index] : frame_of_stamp) {
      if (index >= 0 && superpixel_labels.count(stamp) > 0 && segment_labels.count(stamp) > 0) {
        by_frame[index].push_back(stamp);
      }
    }
    return by_frame;
  };
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(75);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      const auto by_frame = complete();
      bool all = true;
      std::size_t total = 0;
      for (const auto& [index, stamps] : by_frame) total += stamps.size();
      for (int i = 0; i < frames; ++i) all = all && by_frame.count(i) > 0;
      // And a second loop of the folder, to compare frames processed after others.
      if (all && total >= 2 * n) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::lock_guard<std::mutex> lock(mutex);
  const auto by_frame = complete();
  std::size_t total = 0;
  for (const auto& [index, stamps] : by_frame) total += stamps.size();
  EXPECT_GE(total, 2 * n) << "fewer complete frames than two loops of the folder";
  const dasp::SdaspConfig sdasp;
  ASSERT_EQ(sdasp.cut, dasp::CutRule::kAdaptive);  // the Sdasp default: the per-frame cut
  for (int i = 0; i < frames; ++i) {
    SCOPED_TRACE(paths[static_cast<std::size_t>(i)].name);
    ASSERT_EQ(by_frame.count(i), 1u) << "no message of this frame with both labels";
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths[static_cast<std::size_t>(i)]);
    const dasp::Superpixels expected = dasp::computeDasp(frame, dasp::DaspConfig{});
    const dasp::WeightedGraph ucg = dasp::ultrametricContourGraph(expected, sdasp);
    const cv::Mat segments = dasp::segmentPixels(
        expected.labels, dasp::segmentGraph(ucg, dasp::cutThreshold(ucg, sdasp)));
    // Every message of this frame, from any loop of the folder: the nodes keep state across
    // frames (reused buffers), and that must not change a result.
    for (const ros::Time& stamp : by_frame.at(i)) {
      const sensor_msgs::Image& sp = superpixel_labels.at(stamp);
      const sensor_msgs::Image& seg = segment_labels.at(stamp);
      EXPECT_EQ(sp.header.frame_id, "camera_rgb_optical_frame");
      EXPECT_EQ(seg.header.frame_id, "camera_rgb_optical_frame");
      EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(sp) != expected.labels), 0)
          << "superpixel labels stamped " << stamp;
      EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(seg) != segments), 0)
          << "segment labels stamped " << stamp;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "folder_pipeline_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
