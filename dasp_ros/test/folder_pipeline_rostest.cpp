// The bar "same results through ROS": frames played by RgbdFolderSource through Dasp and Sdasp
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

  // By header.seq: the source numbers its messages 0, 1, ... in folder order and loops, so frame
  // index = seq modulo the frame count, and frames missed before this node connected come again.
  // Both labels of one frame are compared from the same message (same seq): the two subscriptions
  // may connect at different times.
  const uint32_t n = static_cast<uint32_t>(paths.size());
  std::mutex mutex;
  std::map<uint32_t, sensor_msgs::Image> superpixel_labels, segment_labels;  // by seq
  std::map<uint32_t, uint32_t> complete;  // frame index -> first seq with both labels
  const auto note = [&](uint32_t seq) {
    if (superpixel_labels.count(seq) > 0 && segment_labels.count(seq) > 0) {
      complete.emplace(seq % n, seq);
    }
  };
  ros::NodeHandle nh("camera");
  ros::Subscriber a = nh.subscribe<sensor_msgs::Image>(
      "superpixels/labels", 50, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        superpixel_labels.emplace(m->header.seq, *m);
        note(m->header.seq);
      });
  ros::Subscriber b = nh.subscribe<sensor_msgs::Image>("segments/labels", 50,
                                                       [&](const sensor_msgs::ImageConstPtr& m) {
                                                         std::lock_guard<std::mutex> lock(mutex);
                                                         segment_labels.emplace(m->header.seq, *m);
                                                         note(m->header.seq);
                                                       });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      bool all = true;
      for (uint32_t i = 0; i < static_cast<uint32_t>(frames); ++i) {
        all = all && complete.count(i) > 0;
      }
      // And a second loop of the folder, to compare frames processed after others.
      const bool looped = !segment_labels.empty() && segment_labels.rbegin()->first >= 2 * n;
      if (all && looped) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::lock_guard<std::mutex> lock(mutex);
  const dasp::SdaspConfig sdasp;
  ASSERT_EQ(sdasp.cut, dasp::CutRule::kAdaptive);  // the Sdasp default: the per-frame cut
  for (int i = 0; i < frames; ++i) {
    SCOPED_TRACE(paths[static_cast<std::size_t>(i)].name);
    ASSERT_EQ(complete.count(static_cast<uint32_t>(i)), 1u)
        << "no message of this frame with both labels";
    const uint32_t seq = complete[static_cast<uint32_t>(i)];
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths[static_cast<std::size_t>(i)]);
    const dasp::Superpixels expected = dasp::computeDasp(frame, dasp::DaspConfig{});
    const dasp::WeightedGraph ucg = dasp::ultrametricContourGraph(expected, sdasp);
    const cv::Mat segments = dasp::segmentPixels(
        expected.labels, dasp::segmentGraph(ucg, dasp::cutThreshold(ucg, sdasp)));
    EXPECT_EQ(superpixel_labels[seq].header.frame_id, "camera_rgb_optical_frame");
    EXPECT_EQ(segment_labels[seq].header.frame_id, "camera_rgb_optical_frame");
    // Every message of this frame, from any loop of the folder: the nodes keep state across
    // frames (reused buffers), and that must not change a result.
    for (const auto& [received_seq, sp] : superpixel_labels) {
      if (received_seq % n != static_cast<uint32_t>(i)) continue;
      EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(sp) != expected.labels), 0)
          << "superpixel labels of seq " << received_seq;
    }
    for (const auto& [received_seq, seg] : segment_labels) {
      if (received_seq % n != static_cast<uint32_t>(i)) continue;
      EXPECT_EQ(cv::countNonZero(dasp_ros::toLabelMat(seg) != segments), 0)
          << "segment labels of seq " << received_seq;
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
