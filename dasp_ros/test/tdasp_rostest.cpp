// rostest of dasp_ros/Tdasp on the sample session (a moving camera over a table): outputs carry
// the input's stamp and frame, strand ids persist from frame to frame, the strand graph stays
// within ~strands/max_strands, and the stream is reset by the service, by a stamp going back and
// by a change of image size; bad input is reported naming the topic and the next frame is used;
// the outputs equal the core's (dasp/tdasp.h) run in this process on the same frames.
#include <dasp/rgbd_io.h>
#include <dasp/superpixel_graph.h>
#include <dasp/tdasp.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Trigger.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "dasp_ros/conversions.h"

namespace {

const std::string kFrame = "camera_rgb_optical_frame";

class Tdasp : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh("camera");
    color_pub_ = nh.advertise<sensor_msgs::Image>("rgb/image_rect_color", 10);
    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 10);
    subs_.push_back(nh.subscribe<ebslam_msgs::Segmentation>(
        "segmentation", 50, [this](const ebslam_msgs::SegmentationConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          segmentations_[m->header.stamp.toSec()] = *m;
        }));
    subs_.push_back(nh.subscribe<ebslam_msgs::SuperpixelArray>(
        "superpixels", 50, [this](const ebslam_msgs::SuperpixelArrayConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          arrays_[m->header.stamp.toSec()] = *m;
        }));
    subs_.push_back(nh.subscribe<sensor_msgs::Image>(
        "superpixels/labels", 50, [this](const sensor_msgs::ImageConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          superpixel_labels_[m->header.stamp.toSec()] = *m;
        }));
    subs_.push_back(nh.subscribe<sensor_msgs::Image>(
        "segments/labels", 50, [this](const sensor_msgs::ImageConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          segment_labels_[m->header.stamp.toSec()] = *m;
        }));
    subs_.push_back(ros::NodeHandle().subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this](const rosgraph_msgs::LogConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          log_.push_back(m->msg);
        }));
    subs_.push_back(ros::NodeHandle().subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 50, [this](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const auto& s : m->status) {
            for (const auto& kv : s.values) {
              if (kv.key == "strands in the graph")
                max_strands_seen_ = std::max(max_strands_seen_, std::stoi(kv.value));
            }
          }
        }));
    spinner_.start();
    ASSERT_TRUE(waitFor(
        [&] {
          for (const auto& s : subs_) {
            if (s.getNumPublishers() == 0) return false;
          }
          return color_pub_.getNumSubscribers() > 0 && depth_pub_.getNumSubscribers() > 0 &&
                 info_pub_.getNumSubscribers() > 0;
        },
        20.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    for (int i = 0; i < 6; ++i) {
      dasp::RgbdFramePaths p;
      p.name = "sample" + std::to_string(i);
      std::string dir;
      ros::NodeHandle("~").getParam("sample_dir", dir);
      p.color = dir + "/" + p.name + "_rgb.png";
      p.depth = dir + "/" + p.name + "_depth_mm.png";
      frames_.push_back(dasp::loadRgbdFrame(p));
    }
  }

  static bool waitFor(const std::function<bool()>& condition, double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (condition()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return condition();
  }

  void publish(const dasp::RgbdFrame& frame, double stamp) {
    std_msgs::Header h;
    h.stamp = ros::Time(stamp);
    h.frame_id = kFrame;
    info_pub_.publish(
        dasp_ros::toCameraInfo(frame.intrinsics, frame.color.cols, frame.color.rows, h));
    depth_pub_.publish(dasp_ros::toDepthImageMsg(frame.depth, h));
    color_pub_.publish(dasp_ros::toColorImageMsg(frame.color, h));
  }

  // Publishes and waits for its segmentation (frames one at a time, as a 30 Hz stream would be
  // if t-DASP kept up). Stamps are whole seconds: map keys from toSec() compare exactly.
  ebslam_msgs::Segmentation process(const dasp::RgbdFrame& frame, double stamp) {
    publish(frame, stamp);
    EXPECT_TRUE(waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          return segmentations_.count(stamp) > 0 && arrays_.count(stamp) > 0 &&
                 segment_labels_.count(stamp) > 0 && superpixel_labels_.count(stamp) > 0;
        },
        15.0))
        << "no output for the frame at " << stamp;
    std::lock_guard<std::mutex> lock(mutex_);
    return segmentations_[stamp];
  }

  bool logged(const std::string& a, const std::string& b) {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::any_of(log_.begin(), log_.end(), [&](const std::string& l) {
      return l.find(a) != std::string::npos && l.find(b) != std::string::npos;
    });
  }

  static double overlap(const ebslam_msgs::Segmentation& a, const ebslam_msgs::Segmentation& b) {
    const std::set<int32_t> previous(a.strand_ids.begin(), a.strand_ids.end());
    std::size_t kept = 0;
    for (int32_t id : b.strand_ids) kept += previous.count(id);
    return static_cast<double>(kept) / static_cast<double>(b.strand_ids.size());
  }

  std::mutex mutex_;
  std::map<double, ebslam_msgs::Segmentation> segmentations_;
  std::map<double, ebslam_msgs::SuperpixelArray> arrays_;
  std::map<double, sensor_msgs::Image> segment_labels_, superpixel_labels_;
  std::vector<std::string> log_;
  int max_strands_seen_ = 0;
  ros::AsyncSpinner spinner_{2};
  std::vector<ros::Subscriber> subs_;
  ros::Publisher color_pub_, depth_pub_, info_pub_;
  std::vector<dasp::RgbdFrame> frames_;
};

TEST_F(Tdasp, StrandsPersistStateIsBoundedAndTheStreamResets) {
  std::vector<ebslam_msgs::Segmentation> out;
  for (int i = 0; i < 6; ++i)
    out.push_back(process(frames_[static_cast<std::size_t>(i)], 10.0 + i));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const ebslam_msgs::SuperpixelArray& array = arrays_[15.0];
    EXPECT_EQ(array.header.frame_id, kFrame);
    EXPECT_EQ(array.superpixels.size(), out[5].segment_ids.size());
    EXPECT_EQ(out[5].strand_ids.size(), out[5].segment_ids.size());
    EXPECT_EQ(out[5].header.frame_id, kFrame);
    EXPECT_EQ(segment_labels_[15.0].header.frame_id, kFrame);
    EXPECT_EQ(segment_labels_[15.0].encoding, "32SC1");
  }
  // Most superpixels continue a strand of the previous frame; segment labels persist too.
  for (int i = 1; i < 6; ++i) EXPECT_GT(overlap(out[i - 1], out[i]), 0.5) << "frame " << i;
  const std::set<int32_t> labels4(out[4].segment_ids.begin(), out[4].segment_ids.end());
  std::size_t persisted = 0;
  for (int32_t l : out[5].segment_ids) persisted += labels4.count(l);
  EXPECT_GT(persisted, out[5].segment_ids.size() / 2);

  // Reset service: the next frame starts new strands only.
  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::call("/camera/tdasp/reset", trigger));
  EXPECT_TRUE(trigger.response.success);
  const ebslam_msgs::Segmentation after_reset = process(frames_[5], 20.0);
  EXPECT_EQ(overlap(out[5], after_reset), 0.0);
  const ebslam_msgs::Segmentation continued = process(frames_[4], 21.0);
  EXPECT_GT(overlap(after_reset, continued), 0.5);

  // Stamp going back (a looping bag): reset with a reason naming the topic.
  const ebslam_msgs::Segmentation looped = process(frames_[0], 5.0);
  EXPECT_EQ(overlap(continued, looped), 0.0);
  EXPECT_TRUE(
      waitFor([&] { return logged("/camera/rgb/image_rect_color", "stamp went back"); }, 5.0));

  // Image size change: reset.
  dasp::RgbdFrame small;
  cv::resize(frames_[1].color, small.color, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  cv::resize(frames_[1].depth, small.depth, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
  small.intrinsics = {262.5f, 262.5f, 159.5f, 119.5f};
  const ebslam_msgs::Segmentation resized = process(small, 6.0);
  EXPECT_EQ(overlap(looped, resized), 0.0);
  EXPECT_TRUE(waitFor([&] { return logged("/camera/rgb/image_rect_color", "size changed"); }, 5.0));

  // Bad input (all-zero depth) is reported; the next good frame continues the stream.
  dasp::RgbdFrame zero = small;
  zero.depth = cv::Mat(small.depth.size(), CV_16UC1, cv::Scalar(0));  // new buffer, small kept
  publish(zero, 7.0);
  EXPECT_TRUE(
      waitFor([&] { return logged("/camera/depth_registered/image_raw", "no valid depth"); }, 5.0));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(segmentations_.count(7.0), 0u);
  }
  const ebslam_msgs::Segmentation next = process(small, 8.0);
  EXPECT_GT(overlap(resized, next), 0.5);

  // Bounded: the strand graph never held more than ~strands/max_strands = 700.
  EXPECT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        return max_strands_seen_ > 0;
      },
      5.0));
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_LE(max_strands_seen_, 700);
}

// The node against its core: after a reset, the six sample frames through the node and through
// dasp::TemporalDasp built here from the node's parameters (the .test file's values over the
// core's defaults). Superpixels, their graph and label image equal to the bit; strand ids, segment
// ids and the segment label image equal up to the node's per-stream offset (which keeps ids
// unique over resets), one offset for the whole stream.
TEST_F(Tdasp, OutputsEqualTheCoreOnTheSameFrames) {
  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::call("/camera/tdasp/reset", trigger));
  ros::NodeHandle p("/camera/tdasp");
  std::vector<std::string> names;
  ASSERT_TRUE(ros::param::getParamNames(names));
  for (const std::string& name : names) {
    if (name.rfind("/camera/tdasp/", 0) != 0) continue;
    const std::string key = name.substr(std::string("/camera/tdasp/").size());
    EXPECT_TRUE(key == "superpixel_count" || key == "strands/max_strands")
        << name << ": a parameter this test does not mirror";
  }
  dasp::TdaspConfig config;
  config.superpixels.dasp.superpixel_count =
      p.param("superpixel_count", config.superpixels.dasp.superpixel_count);
  config.strands.max_strands = p.param("strands/max_strands", config.strands.max_strands);
  dasp::TemporalDasp core(config);
  std::optional<std::int64_t> strand_offset, label_offset;
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const double stamp = 30.0 + i;
    const ebslam_msgs::Segmentation segmentation =
        process(frames_[static_cast<std::size_t>(i)], stamp);
    const dasp::TdaspFrame expected = core.process(frames_[static_cast<std::size_t>(i)]);
    std_msgs::Header header;
    header.stamp = ros::Time(stamp);
    header.frame_id = kFrame;
    const dasp::Superpixels& superpixels = expected.superpixels.superpixels;
    ebslam_msgs::SuperpixelArray array = dasp_ros::toSuperpixelArrayMsg(superpixels, header);
    array.edges =
        dasp_ros::toEdgeMsgs(dasp::buildSuperpixelGraph(superpixels, config.strands.graph));
    sensor_msgs::Image labels = dasp_ros::toLabelImageMsg(superpixels.labels, header);
    std::lock_guard<std::mutex> lock(mutex_);
    // Stamp and frame checked on their own; the content compared under the expected header (roscpp
    // renumbers the rest of the header per publisher).
    ebslam_msgs::SuperpixelArray node_array = arrays_[stamp];
    sensor_msgs::Image node_labels = superpixel_labels_[stamp];
    EXPECT_EQ(node_array.header.stamp, header.stamp);
    EXPECT_EQ(node_array.header.frame_id, kFrame);
    EXPECT_EQ(node_labels.header.stamp, header.stamp);
    EXPECT_EQ(node_labels.header.frame_id, kFrame);
    node_array.header = array.header;
    node_labels.header = labels.header;
    EXPECT_TRUE(node_array == array) << "superpixels: node " << node_array.superpixels.size()
                                     << ", core " << array.superpixels.size();
    EXPECT_TRUE(node_labels == labels) << "superpixel label image";
    ASSERT_EQ(segmentation.strand_ids.size(), expected.strand_id.size());
    ASSERT_EQ(segmentation.segment_ids.size(), expected.segment_label.size());
    ASSERT_FALSE(expected.strand_id.empty());
    if (!strand_offset) {
      strand_offset = segmentation.strand_ids[0] - expected.strand_id[0];
      label_offset = segmentation.segment_ids[0] - expected.segment_label[0];
      EXPECT_GE(*strand_offset, 0);
      EXPECT_GE(*label_offset, 0);
    }
    std::size_t strands_differing = 0, segments_differing = 0;
    for (std::size_t k = 0; k < expected.strand_id.size(); ++k) {
      strands_differing += segmentation.strand_ids[k] != expected.strand_id[k] + *strand_offset;
      segments_differing +=
          segmentation.segment_ids[k] != expected.segment_label[k] + *label_offset;
    }
    EXPECT_EQ(strands_differing, 0u) << "of " << expected.strand_id.size() << " strand ids";
    EXPECT_EQ(segments_differing, 0u) << "of " << expected.segment_label.size() << " segment ids";
    EXPECT_EQ(segmentation.threshold, config.hysteresis.normal);
    // Segment label image: the core's label plus the offset, -1 (no superpixel) kept.
    cv::Mat shifted = expected.segment_labels + static_cast<int>(*label_offset);
    shifted.setTo(-1, expected.segment_labels < 0);
    const cv::Mat node = dasp_ros::toLabelMat(segment_labels_[stamp]);
    ASSERT_EQ(node.size(), shifted.size());
    EXPECT_EQ(cv::countNonZero(node != shifted), 0) << "segment label image";
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "tdasp_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
