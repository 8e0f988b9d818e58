// rostest of dasp_ros/Dasp and dasp_ros/Sdasp: outputs of a sample frame against the core library
// called directly (content, frame, stamp), lazy outputs, and bad input injected case by case:
// each is reported on /rosout naming the topic, and the next good frame is processed.
#include <dasp/dasp.h>
#include <dasp/rgbd_io.h>
#include <dasp/sdasp.h>
#include <dasp/segmentation.h>
#include <dasp/superpixel_graph.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgproc.hpp>

#include "dasp_ros/conversions.h"

namespace {

using dasp_ros::toCameraInfo;
using dasp_ros::toColorImageMsg;
using dasp_ros::toDepthImageMsg;
using dasp_ros::toLabelMat;
const std::string kFrame = "camera_rgb_optical_frame";

std::string sampleDir() {
  std::string dir;
  ros::NodeHandle("~").getParam("sample_dir", dir);
  return dir;
}

// Everything the nodelets publish, by topic, and the log.
struct Outputs {
  std::mutex mutex;
  std::map<double, ebslam_msgs::SuperpixelArray> arrays;
  std::map<double, sensor_msgs::Image> labels, segment_labels, overlays, segment_overlays, ucms,
      injected_labels;
  std::map<double, ebslam_msgs::Segmentation> segmentations, injected_segmentations;
  std::map<double, visualization_msgs::MarkerArray> markers;
  std::map<double, sensor_msgs::PointCloud2> clouds;
  std::vector<std::string> log;
};

class SegmentationNodes : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh("camera");
    color_pub_ = nh.advertise<sensor_msgs::Image>("rgb/image_rect_color", 10);
    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 10);
    array_pub_ = nh.advertise<ebslam_msgs::SuperpixelArray>("injected/superpixels", 10);
    injected_labels_pub_ = nh.advertise<sensor_msgs::Image>("injected/superpixels/labels", 10);
    subscribe<ebslam_msgs::SuperpixelArray>(nh, "superpixels", &Outputs::arrays);
    subscribe<sensor_msgs::Image>(nh, "superpixels/labels", &Outputs::labels);
    subscribe<sensor_msgs::Image>(nh, "superpixels/overlay", &Outputs::overlays);
    subs_.push_back(nh.subscribe<visualization_msgs::MarkerArray>(
        "superpixels/markers", 20, [this](const visualization_msgs::MarkerArrayConstPtr& m) {
          if (m->markers.empty()) return;
          std::lock_guard<std::mutex> lock(out_.mutex);
          out_.markers[m->markers.front().header.stamp.toSec()] = *m;
        }));
    subscribe<sensor_msgs::PointCloud2>(nh, "superpixels/cloud", &Outputs::clouds);
    subscribe<ebslam_msgs::Segmentation>(nh, "segmentation", &Outputs::segmentations);
    subscribe<sensor_msgs::Image>(nh, "segments/labels", &Outputs::segment_labels);
    subscribe<sensor_msgs::Image>(nh, "segments/overlay", &Outputs::segment_overlays);
    subscribe<sensor_msgs::Image>(nh, "segments/ucm", &Outputs::ucms);
    subscribe<ebslam_msgs::Segmentation>(nh, "injected/segmentation",
                                         &Outputs::injected_segmentations);
    subscribe<sensor_msgs::Image>(nh, "injected/segments/labels", &Outputs::injected_labels);
    subs_.push_back(ros::NodeHandle().subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this](const rosgraph_msgs::LogConstPtr& m) {
          std::lock_guard<std::mutex> lock(out_.mutex);
          out_.log.push_back(m->msg);
        }));
    spinner_.start();
    ASSERT_TRUE(waitFor(
        [&] {
          return color_pub_.getNumSubscribers() > 0 && depth_pub_.getNumSubscribers() > 0 &&
                 info_pub_.getNumSubscribers() > 0 && array_pub_.getNumSubscribers() > 0 &&
                 injected_labels_pub_.getNumSubscribers() > 0 && subsConnected();
        },
        20.0))
        << "nodelets did not connect";
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // roscpp connection race

    dasp::RgbdFramePaths paths;
    paths.name = "sample0";
    paths.color = sampleDir() + "/sample0_rgb.png";
    paths.depth = sampleDir() + "/sample0_depth_mm.png";
    frame_ = dasp::loadRgbdFrame(paths);
  }

  template <typename M>
  void subscribe(ros::NodeHandle& nh, const std::string& topic,
                 std::map<double, M> Outputs::*field) {
    subs_.push_back(nh.subscribe<M>(topic, 20, [this, field](const boost::shared_ptr<const M>& m) {
      std::lock_guard<std::mutex> lock(out_.mutex);
      (out_.*field)[m->header.stamp.toSec()] = *m;
    }));
  }

  bool subsConnected() const {
    for (const ros::Subscriber& s : subs_) {
      if (s.getNumPublishers() == 0) return false;
    }
    return true;
  }

  static bool waitFor(const std::function<bool()>& condition, double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (condition()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return condition();
  }

  std_msgs::Header header(double stamp) const {
    std_msgs::Header h;
    h.stamp = ros::Time(stamp);
    h.frame_id = kFrame;
    return h;
  }

  void publish(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
               const sensor_msgs::CameraInfo& info) {
    info_pub_.publish(info);
    depth_pub_.publish(depth);
    color_pub_.publish(color);
  }

  void publishGood(double stamp) {
    const std_msgs::Header h = header(stamp);
    publish(toColorImageMsg(frame_.color, h), toDepthImageMsg(frame_.depth, h),
            toCameraInfo(frame_.intrinsics, frame_.color.cols, frame_.color.rows, h));
  }

  template <typename M>
  bool has(std::map<double, M> Outputs::*field, double stamp) {
    std::lock_guard<std::mutex> lock(out_.mutex);
    return (out_.*field).count(stamp) > 0;
  }

  // True once a /rosout message contains every one of the parts.
  bool logged(const std::vector<std::string>& parts) {
    std::lock_guard<std::mutex> lock(out_.mutex);
    for (const std::string& line : out_.log) {
      bool all = true;
      for (const std::string& p : parts) all = all && line.find(p) != std::string::npos;
      if (all) return true;
    }
    return false;
  }

  std::string logText() {
    std::lock_guard<std::mutex> lock(out_.mutex);
    std::string text;
    for (const std::string& line : out_.log) text += line + "\n";
    return text;
  }

  // A bad input is reported naming its topic, and the next good frame is segmented.
  void expectRejectedThenRecovers(const std::function<void()>& inject,
                                  const std::vector<std::string>& log_parts, double good_stamp,
                                  double bad_stamp = -1.0) {
    inject();
    EXPECT_TRUE(waitFor([&] { return logged(log_parts); }, 6.0))
        << "no log line with '" << log_parts.front() << "' ... '" << log_parts.back() << "'; log:\n"
        << logText();
    publishGood(good_stamp);
    EXPECT_TRUE(waitFor(
        [&] {
          return has(&Outputs::arrays, good_stamp) && has(&Outputs::segmentations, good_stamp);
        },
        10.0))
        << "good frame at " << good_stamp << " after bad input was not processed";
    if (bad_stamp >= 0.0) {
      EXPECT_FALSE(has(&Outputs::arrays, bad_stamp)) << "bad frame at " << bad_stamp << " was used";
    }
  }

  Outputs out_;
  ros::AsyncSpinner spinner_{2};
  std::vector<ros::Subscriber> subs_;
  ros::Publisher color_pub_, depth_pub_, info_pub_, array_pub_, injected_labels_pub_;
  dasp::RgbdFrame frame_;
};

TEST_F(SegmentationNodes, OutputsEqualTheCoreLibraryWithInputStampAndFrame) {
  const double stamp = 10.0;
  publishGood(stamp);
  ASSERT_TRUE(waitFor(
      [&] {
        return has(&Outputs::arrays, stamp) && has(&Outputs::labels, stamp) &&
               has(&Outputs::segmentations, stamp) && has(&Outputs::segment_labels, stamp) &&
               has(&Outputs::overlays, stamp) && has(&Outputs::markers, stamp) &&
               has(&Outputs::clouds, stamp) && has(&Outputs::segment_overlays, stamp) &&
               has(&Outputs::ucms, stamp);
      },
      20.0))
      << logText();

  const dasp::Superpixels expected = dasp::computeDasp(frame_, dasp::DaspConfig{});
  const dasp::WeightedGraph graph = dasp::buildSuperpixelGraph(expected);
  const dasp::SdaspConfig sdasp;
  ASSERT_EQ(sdasp.cut, dasp::CutRule::kAdaptive);  // the default: the per-frame cut
  const dasp::WeightedGraph ucg = dasp::ultrametricContourGraph(expected, sdasp);
  const float threshold = dasp::cutThreshold(ucg, sdasp);
  const std::vector<int> node_segments = dasp::segmentGraph(ucg, threshold);
  const cv::Mat segments = dasp::segmentPixels(expected.labels, node_segments);

  std::lock_guard<std::mutex> lock(out_.mutex);
  const ebslam_msgs::SuperpixelArray& array = out_.arrays[stamp];
  EXPECT_EQ(array.header.frame_id, kFrame);
  EXPECT_EQ(array.width, 640u);
  EXPECT_EQ(array.height, 480u);
  ASSERT_EQ(array.superpixels.size(), expected.superpixels.size());
  EXPECT_GT(array.superpixels.size(), 500u);
  for (std::size_t i = 0; i < expected.superpixels.size(); ++i) {
    const dasp::Superpixel& e = expected.superpixels[i];
    const ebslam_msgs::Superpixel& m = array.superpixels[i];
    ASSERT_EQ(m.id, i);
    EXPECT_EQ(m.pixel_count, static_cast<uint32_t>(e.pixel_count));
    EXPECT_EQ(m.u, e.u);
    EXPECT_EQ(m.position.z, e.position.z());
    EXPECT_EQ(m.normal.x, e.normal.x());
    EXPECT_EQ(m.radius, e.radius_m);
    EXPECT_EQ(m.density, e.density);
    EXPECT_EQ(m.area, e.area_m2);
    EXPECT_EQ(m.color.g, e.color.y());
  }
  ASSERT_EQ(array.edges.size(), graph.edges.size());
  for (std::size_t i = 0; i < graph.edges.size(); ++i) {
    EXPECT_EQ(array.edges[i].a, static_cast<uint32_t>(graph.edges[i].a));
    EXPECT_EQ(array.edges[i].b, static_cast<uint32_t>(graph.edges[i].b));
    EXPECT_EQ(array.edges[i].weight, graph.edges[i].weight);
  }

  const sensor_msgs::Image& labels = out_.labels[stamp];
  EXPECT_EQ(labels.header.frame_id, kFrame);
  EXPECT_EQ(labels.encoding, sensor_msgs::image_encodings::TYPE_32SC1);
  EXPECT_EQ(cv::countNonZero(toLabelMat(labels) != expected.labels), 0);

  const ebslam_msgs::Segmentation& segmentation = out_.segmentations[stamp];
  EXPECT_EQ(segmentation.header.frame_id, kFrame);
  EXPECT_EQ(segmentation.segment_ids,
            std::vector<int32_t>(node_segments.begin(), node_segments.end()));
  EXPECT_TRUE(segmentation.strand_ids.empty());
  EXPECT_FLOAT_EQ(segmentation.threshold, threshold);
  EXPECT_LE(segmentation.threshold, sdasp.adaptive_max_threshold);
  ASSERT_EQ(segmentation.ultrametric.size(), ucg.edges.size());
  for (std::size_t i = 0; i < ucg.edges.size(); ++i) {
    EXPECT_EQ(segmentation.ultrametric[i].weight, ucg.edges[i].weight);
  }
  const sensor_msgs::Image& segment_labels = out_.segment_labels[stamp];
  EXPECT_EQ(segment_labels.header.frame_id, kFrame);
  EXPECT_EQ(cv::countNonZero(toLabelMat(segment_labels) != segments), 0);
  const int segment_count = *std::max_element(node_segments.begin(), node_segments.end()) + 1;
  EXPECT_GT(segment_count, 1);
  EXPECT_LT(segment_count, static_cast<int>(expected.superpixels.size()) / 4);

  // Lazy outputs (this test subscribes to them).
  const sensor_msgs::Image& overlay = out_.overlays[stamp];
  EXPECT_EQ(overlay.header.frame_id, kFrame);
  EXPECT_EQ(overlay.encoding, "bgr8");
  EXPECT_EQ(overlay.width, 640u);
  const visualization_msgs::MarkerArray& markers = out_.markers[stamp];
  ASSERT_EQ(markers.markers.size(), expected.superpixels.size() + 1);
  EXPECT_EQ(markers.markers[0].action, visualization_msgs::Marker::DELETEALL);
  EXPECT_EQ(markers.markers[1].header.frame_id, kFrame);
  EXPECT_EQ(markers.markers[1].header.stamp.toSec(), stamp);
  EXPECT_NEAR(markers.markers[1].scale.x, 2.0 * expected.superpixels[0].radius_m, 1e-6);
  const sensor_msgs::PointCloud2& cloud = out_.clouds[stamp];
  EXPECT_EQ(cloud.header.frame_id, kFrame);
  EXPECT_EQ(cloud.width * cloud.height, expected.superpixels.size());
  const sensor_msgs::Image& ucm = out_.ucms[stamp];
  EXPECT_EQ(ucm.encoding, sensor_msgs::image_encodings::TYPE_32FC1);
  EXPECT_EQ(ucm.header.frame_id, kFrame);
  const sensor_msgs::Image& segment_overlay = out_.segment_overlays[stamp];
  EXPECT_EQ(segment_overlay.encoding, "bgr8");
  EXPECT_EQ(segment_overlay.header.frame_id, kFrame);
}

TEST_F(SegmentationNodes, BadInputIsReportedNamingTheTopicAndTheNextGoodFrameIsProcessed) {
  const std::string color_topic = "/camera/rgb/image_rect_color";
  const std::string depth_topic = "/camera/depth_registered/image_raw";
  const std::string info_topic = "/camera/rgb/camera_info";
  double stamp = 100.0;
  auto info = [&](double s) {
    return toCameraInfo(frame_.intrinsics, frame_.color.cols, frame_.color.rows, header(s));
  };
  auto color = [&](double s) { return toColorImageMsg(frame_.color, header(s)); };
  auto depth = [&](double s) { return toDepthImageMsg(frame_.depth, header(s)); };

  // Colour as mono16.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        sensor_msgs::Image c = depth(stamp);
        c.encoding = "mono16";
        publish(c, depth(stamp), info(stamp));
      },
      {color_topic, "mono16"}, stamp + 0.5, stamp);
  // Depth as bgr8.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        sensor_msgs::Image d = color(stamp);
        publish(color(stamp), d, info(stamp));
      },
      {depth_topic, "bgr8"}, stamp + 0.5, stamp);
  // Depth of another size than colour.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        cv::Mat small;
        cv::resize(frame_.depth, small, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
        publish(color(stamp), toDepthImageMsg(small, header(stamp)), info(stamp));
      },
      {depth_topic, "differs from the colour"}, stamp + 0.5, stamp);
  // Zero camera_info.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        sensor_msgs::CameraInfo zero;
        zero.header = header(stamp);
        publish(color(stamp), depth(stamp), zero);
      },
      {info_topic, "focal"}, stamp + 0.5, stamp);
  // All-zero depth.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        const cv::Mat zero = cv::Mat::zeros(frame_.depth.size(), CV_16UC1);
        publish(color(stamp), toDepthImageMsg(zero, header(stamp)), info(stamp));
      },
      {depth_topic, "no valid depth pixel in the 16UC1"}, stamp + 0.5, stamp);
  // NaN depth in metres (32FC1).
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        const cv::Mat nan(frame_.depth.size(), CV_32FC1,
                          cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
        sensor_msgs::Image d = *cv_bridge::CvImage(header(stamp), "32FC1", nan).toImageMsg();
        publish(color(stamp), d, info(stamp));
      },
      {depth_topic, "no valid depth pixel in the 32FC1"}, stamp + 0.5, stamp);
  // Empty colour image.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        sensor_msgs::Image c;
        c.header = header(stamp);
        c.encoding = "bgr8";
        publish(c, depth(stamp), info(stamp));
      },
      {color_topic, "empty"}, stamp + 0.5, stamp);
  // Stamps going backwards: reported, and the older frame is still segmented with its stamp.
  const double back = 50.0;
  expectRejectedThenRecovers([&] { publishGood(back); }, {color_topic, "went back"}, stamp + 1.5);
  EXPECT_TRUE(has(&Outputs::arrays, back));
  stamp += 2;
  // camera_info missing: the images alone never form a frame; the node says which input is silent.
  stamp += 1;
  expectRejectedThenRecovers(
      [&] {
        for (int i = 0; i < 30; ++i) {
          const double s = stamp + 0.01 * i;
          depth_pub_.publish(depth(s));
          color_pub_.publish(color(s));
          std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
      },
      {info_topic, "silent"}, stamp + 0.5, stamp);
}

TEST_F(SegmentationNodes, SdaspReportsLabelsThatDoNotMatchTheirSuperpixelArray) {
  publishGood(20.0);
  ASSERT_TRUE(
      waitFor([&] { return has(&Outputs::arrays, 20.0) && has(&Outputs::labels, 20.0); }, 20.0));
  ebslam_msgs::SuperpixelArray array;
  sensor_msgs::Image labels;
  {
    std::lock_guard<std::mutex> lock(out_.mutex);
    array = out_.arrays[20.0];
    labels = out_.labels[20.0];
  }
  // Half the superpixels missing from the array: labels name superpixels it does not hold.
  ebslam_msgs::SuperpixelArray truncated = array;
  truncated.header.stamp = ros::Time(21.0);
  truncated.superpixels.resize(array.superpixels.size() / 2);
  truncated.edges.clear();
  sensor_msgs::Image labels21 = labels;
  labels21.header.stamp = ros::Time(21.0);
  array_pub_.publish(truncated);
  injected_labels_pub_.publish(labels21);
  EXPECT_TRUE(waitFor(
      [&] {
        return logged({"/camera/injected/superpixels", "do not index the"});
      },
      6.0))
      << logText();
  // Label image of another size.
  sensor_msgs::Image small = labels;
  small.header.stamp = ros::Time(22.0);
  small.height = 240;
  small.data.resize(small.step * small.height);
  ebslam_msgs::SuperpixelArray array22 = array;
  array22.header.stamp = ros::Time(22.0);
  array_pub_.publish(array22);
  injected_labels_pub_.publish(small);
  EXPECT_TRUE(waitFor(
      [&] {
        return logged({"/camera/injected/superpixels/labels", "size"});
      },
      6.0))
      << logText();
  // The matching pair is segmented as Sdasp on the live stream did.
  array.header.stamp = labels.header.stamp = ros::Time(23.0);
  array_pub_.publish(array);
  injected_labels_pub_.publish(labels);
  ASSERT_TRUE(waitFor(
      [&] {
        return has(&Outputs::injected_segmentations, 23.0) && has(&Outputs::segmentations, 20.0);
      },
      10.0));
  std::lock_guard<std::mutex> lock(out_.mutex);
  EXPECT_EQ(out_.injected_segmentations[23.0].segment_ids, out_.segmentations[20.0].segment_ids);
  EXPECT_EQ(out_.injected_segmentations.count(21.0) + out_.injected_segmentations.count(22.0), 0u);
}

// Runs last: it changes the nodes' parameters.
TEST_F(SegmentationNodes, ZDynamicReconfigureChangesTheNextFrame) {
  dynamic_reconfigure::Reconfigure dasp_request;
  dynamic_reconfigure::IntParameter count;
  count.name = "superpixel_count";
  count.value = 300;
  dasp_request.request.config.ints.push_back(count);
  ASSERT_TRUE(ros::service::call("/camera/dasp/set_parameters", dasp_request));
  dynamic_reconfigure::Reconfigure sdasp_request;
  dynamic_reconfigure::DoubleParameter threshold;
  threshold.name = "threshold";
  threshold.value = 0.3;
  sdasp_request.request.config.doubles.push_back(threshold);
  dynamic_reconfigure::StrParameter cut;
  cut.name = "cut";
  cut.value = "global";
  sdasp_request.request.config.strs.push_back(cut);
  ASSERT_TRUE(ros::service::call("/camera/sdasp/set_parameters", sdasp_request));

  publishGood(30.0);
  ASSERT_TRUE(waitFor(
      [&] { return has(&Outputs::labels, 30.0) && has(&Outputs::segmentations, 30.0); }, 20.0));
  dasp::DaspConfig config;
  config.superpixel_count = 300;
  const dasp::Superpixels expected = dasp::computeDasp(frame_, config);
  dasp::SdaspConfig sdasp;
  sdasp.cut = dasp::CutRule::kGlobal;
  sdasp.threshold = 0.3f;
  const std::vector<int> node_segments =
      dasp::segmentGraph(dasp::ultrametricContourGraph(expected, sdasp), sdasp.threshold);
  std::lock_guard<std::mutex> lock(out_.mutex);
  EXPECT_EQ(cv::countNonZero(toLabelMat(out_.labels[30.0]) != expected.labels), 0);
  EXPECT_EQ(out_.arrays[30.0].superpixels.size(), expected.superpixels.size());
  EXPECT_FLOAT_EQ(out_.segmentations[30.0].threshold, 0.3f);
  EXPECT_EQ(out_.segmentations[30.0].segment_ids,
            std::vector<int32_t>(node_segments.begin(), node_segments.end()));
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "segmentation_nodes_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
