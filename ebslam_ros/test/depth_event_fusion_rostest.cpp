// rostest of the DepthEventFusion nodelet (depth_event_fusion.test): flat depth planes at known
// distances seen through the test calibration (test/data/dedvs_flat_calibration.yaml: eDVS and
// depth camera axes parallel, so the fused eDVS depth is the plane's distance), then bad input:
// holes, events older than every frame, depth of a wrong encoding or size, event and depth
// clocks that disagree, a wrong sensor size; the node must give NaN (no invented depth), say
// why, and go on. Also: a missing ~calibration stops the nodelet with a FATAL naming it, and a
// second nodelet's depth events equal the core's (ebslam/slam/dedvs_fusion.h) run in this
// process on the same frames and events.
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/transform_listener.h>

#include <ebslam/slam/dedvs_fusion.h>
#include <ebslam/slam/dedvs_sensors.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"

namespace {

constexpr int kDepthWidth = 160, kDepthHeight = 120;
constexpr double kFocal = 154.0, kCentre = 63.5;  // the calibration's eDVS
constexpr double kTimeout = 30.0;                 // [s] wall, generous for a loaded machine

bool waitFor(const std::function<bool()>& done, double timeout_s = kTimeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  ros::spinOnce();
  return done();
}

// 16UC1 image of `mm` millimetres everywhere, columns < hole_columns 0 (no depth).
sensor_msgs::Image depthMm(const ros::Time& stamp, std::uint16_t mm, int hole_columns = 0,
                           int width = kDepthWidth, int height = kDepthHeight) {
  sensor_msgs::Image image;
  image.header.stamp = stamp;
  image.header.frame_id = "camera_depth_optical_frame";
  image.width = width;
  image.height = height;
  image.encoding = "16UC1";
  image.step = width * 2;
  image.data.resize(static_cast<std::size_t>(image.step) * height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::uint16_t value = u < hole_columns ? 0 : mm;
      std::memcpy(&image.data[(v * width + u) * 2], &value, 2);
    }
  }
  return image;
}

// 32FC1 image of `m` metres, columns < hole_columns NaN.
sensor_msgs::Image depthM(const ros::Time& stamp, float m, int hole_columns) {
  sensor_msgs::Image image = depthMm(stamp, 0);
  image.encoding = "32FC1";
  image.step = kDepthWidth * 4;
  image.data.resize(static_cast<std::size_t>(image.step) * kDepthHeight);
  for (int v = 0; v < kDepthHeight; ++v) {
    for (int u = 0; u < kDepthWidth; ++u) {
      const float value = u < hole_columns ? std::numeric_limits<float>::quiet_NaN() : m;
      std::memcpy(&image.data[(v * kDepthWidth + u) * 4], &value, 4);
    }
  }
  return image;
}

struct Pixel {
  std::uint16_t x, y;
};
const std::vector<Pixel> kPixels = {{64, 64}, {20, 30}, {110, 100}, {100, 10}, {5, 64}};

ebslam_msgs::EventArray events(const ros::Time& t, std::uint32_t width = 128,
                               std::uint32_t height = 128) {
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = width;
  msg.height = height;
  for (std::size_t i = 0; i < kPixels.size(); ++i) {
    ebslam_msgs::Event e;
    e.x = kPixels[i].x;
    e.y = kPixels[i].y;
    e.ts = t + ros::Duration(1e-4 * static_cast<double>(i));
    e.polarity = i % 2 == 0;
    msg.events.push_back(e);
  }
  msg.header.stamp = msg.events.back().ts;
  return msg;
}

class Fixture {
 public:
  Fixture() {
    events_pub_ = nh_.advertise<ebslam_msgs::EventArray>("events", 100);
    depth_pub_ = nh_.advertise<sensor_msgs::Image>("depth_registered/image_raw", 100);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("depth_registered/camera_info", 10);
    out_sub_ = nh_.subscribe<ebslam_msgs::DepthEventArray>(
        "depth_events", 100,
        [this](const ebslam_msgs::DepthEventArray::ConstPtr& m) { out_.push_back(*m); });
    cloud_sub_ = nh_.subscribe<sensor_msgs::PointCloud2>(
        "depth_events/cloud", 100,
        [this](const sensor_msgs::PointCloud2::ConstPtr& m) { clouds_.push_back(*m); });
    log_sub_ = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 1000,
                                                 [this](const rosgraph_msgs::Log::ConstPtr& m) {
                                                   if (m->level >= rosgraph_msgs::Log::WARN)
                                                     logs_.push_back(m->msg);
                                                 });
  }
  bool connected() {
    return waitFor([this] {
      return events_pub_.getNumSubscribers() > 0 && depth_pub_.getNumSubscribers() > 0 &&
             info_pub_.getNumSubscribers() > 0 && out_sub_.getNumPublishers() > 0 &&
             cloud_sub_.getNumPublishers() > 0;
    });
  }
  // The output for the input stamped `stamp` (none after the timeout).
  std::optional<ebslam_msgs::DepthEventArray> output(const ros::Time& stamp,
                                                     double timeout = kTimeout) {
    std::optional<ebslam_msgs::DepthEventArray> found;
    waitFor(
        [&] {
          for (const auto& m : out_) {
            if (m.header.stamp == stamp) found = m;
          }
          return found.has_value();
        },
        timeout);
    return found;
  }
  bool logged(const std::string& text) {
    return waitFor([&] {
      for (const std::string& m : logs_) {
        if (m.find(text) != std::string::npos) return true;
      }
      return false;
    });
  }

  ros::NodeHandle nh_;
  ros::Publisher events_pub_, depth_pub_, info_pub_;
  ros::Subscriber out_sub_, cloud_sub_, log_sub_;
  std::vector<ebslam_msgs::DepthEventArray> out_;
  std::vector<sensor_msgs::PointCloud2> clouds_;
  std::vector<std::string> logs_;
};

// Every event of `out` (the input `in`) at eDVS depth `depth` [m] on the plane z = depth, except
// those at pixels with x < hole_x, which have none.
void expectPlane(const ebslam_msgs::DepthEventArray& out, const ebslam_msgs::EventArray& in,
                 double depth, int hole_x) {
  EXPECT_EQ(out.header.stamp, in.header.stamp);
  EXPECT_EQ(out.header.frame_id, "edvs_optical_frame");
  EXPECT_EQ(out.width, 128u);
  EXPECT_EQ(out.height, 128u);
  ASSERT_EQ(out.events.size(), in.events.size());
  for (std::size_t i = 0; i < in.events.size(); ++i) {
    const ebslam_msgs::DepthEvent& d = out.events[i];
    EXPECT_EQ(d.x, in.events[i].x);
    EXPECT_EQ(d.y, in.events[i].y);
    EXPECT_EQ(d.ts, in.events[i].ts);
    EXPECT_EQ(d.polarity, in.events[i].polarity);
    if (d.x < hole_x) {
      EXPECT_TRUE(std::isnan(d.depth)) << "pixel " << d.x << "," << d.y << " in a hole";
      EXPECT_TRUE(std::isnan(d.point.z));
      continue;
    }
    // 1 % of the depth: the 16-bit millimetres and the linear interpolation on the ray.
    EXPECT_NEAR(d.depth, depth, 0.01 * depth) << "pixel " << d.x << "," << d.y;
    EXPECT_NEAR(d.point.z, d.depth, 1e-5);
    EXPECT_NEAR(d.point.x, (d.x - kCentre) / kFocal * d.depth, 1e-3);
    EXPECT_NEAR(d.point.y, (d.y - kCentre) / kFocal * d.depth, 1e-3);
  }
}

void expectNoDepth(const ebslam_msgs::DepthEventArray& out) {
  for (const ebslam_msgs::DepthEvent& d : out.events) {
    EXPECT_TRUE(std::isnan(d.depth));
    EXPECT_TRUE(std::isnan(d.point.x) && std::isnan(d.point.y) && std::isnan(d.point.z));
  }
}

TEST(DepthEventFusion, FusesPlanesAndRejectsBadInput) {
  Fixture f;
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ASSERT_TRUE(f.connected());
  ros::WallDuration(0.5).sleep();  // roscpp counts a subscriber before its side is ready
  const ros::Time base = ros::Time::now();

  sensor_msgs::CameraInfo info;
  info.header.stamp = base;
  info.header.frame_id = "camera_depth_optical_frame";
  info.width = kDepthWidth;
  info.height = kDepthHeight;
  info.K = {130.0, 0.0, 79.5, 0.0, 130.0, 59.5, 0.0, 0.0, 1.0};
  f.info_pub_.publish(info);

  // A plane 1.5 m away (16UC1 mm); events 5 ms after the frame.
  f.depth_pub_.publish(depthMm(base, 1500));
  const ebslam_msgs::EventArray e1 = events(base + ros::Duration(0.005));
  f.events_pub_.publish(e1);
  const std::optional<ebslam_msgs::DepthEventArray> o1 = f.output(e1.header.stamp);
  ASSERT_TRUE(o1.has_value());
  expectPlane(*o1, e1, 1.5, 0);
  ASSERT_TRUE(waitFor([&] { return !f.clouds_.empty(); }));
  EXPECT_EQ(f.clouds_.front().header.frame_id, "edvs_optical_frame");
  EXPECT_EQ(f.clouds_.front().header.stamp, e1.header.stamp);
  EXPECT_EQ(f.clouds_.front().width * f.clouds_.front().height, kPixels.size());
  sensor_msgs::PointCloud2ConstIterator<float> z(f.clouds_.front(), "z");
  EXPECT_NEAR(*z, 1.5, 0.015);

  // The next frame, 2 m (32FC1 m) with a hole (NaN) in the left quarter: the event at x = 5
  // (depth column 30) looks into it.
  f.depth_pub_.publish(depthM(base + ros::Duration(1.0 / 30.0), 2.0f, 40));
  const ebslam_msgs::EventArray e2 = events(base + ros::Duration(0.036));
  f.events_pub_.publish(e2);
  const std::optional<ebslam_msgs::DepthEventArray> o2 = f.output(e2.header.stamp);
  ASSERT_TRUE(o2.has_value());
  expectPlane(*o2, e2, 2.0, 10);

  // Static tf depth camera -> eDVS from the calibration (eDVS 4 cm above: -y).
  ASSERT_TRUE(waitFor([&] {
    return buffer.canTransform("camera_depth_optical_frame", "edvs_optical_frame", ros::Time(0));
  }));
  const auto tf =
      buffer.lookupTransform("camera_depth_optical_frame", "edvs_optical_frame", ros::Time(0));
  EXPECT_NEAR(tf.transform.translation.y, -0.04, 1e-9);
  EXPECT_NEAR(tf.transform.rotation.w, 1.0, 1e-9);

  // Events older than every kept frame: no depth, a reason.
  const ebslam_msgs::EventArray old = events(base - ros::Duration(1.0));
  f.events_pub_.publish(old);
  const std::optional<ebslam_msgs::DepthEventArray> o3 = f.output(old.header.stamp);
  ASSERT_TRUE(o3.has_value());
  EXPECT_EQ(o3->events.size(), old.events.size());
  expectNoDepth(*o3);
  EXPECT_TRUE(f.logged("older than every kept depth frame"));

  // Depth of a wrong encoding and of a wrong size (both 0.9 m): dropped with a reason; events
  // just after them keep the 2 m frame (within ~max_frame_age), never the dropped 0.9 m.
  sensor_msgs::Image rgb = depthMm(base + ros::Duration(2.0 / 30.0), 900);
  rgb.encoding = "rgb8";
  f.depth_pub_.publish(rgb);
  f.depth_pub_.publish(depthMm(base + ros::Duration(2.0 / 30.0), 900, 0, 100, 100));
  EXPECT_TRUE(f.logged("encoding 'rgb8' dropped"));
  EXPECT_TRUE(f.logged("depth image of 100x100"));
  const ebslam_msgs::EventArray e4 = events(base + ros::Duration(0.07));
  f.events_pub_.publish(e4);
  const std::optional<ebslam_msgs::DepthEventArray> o4 = f.output(e4.header.stamp);
  ASSERT_TRUE(o4.has_value());
  expectPlane(*o4, e4, 2.0, 10);

  // Depth frames arrive, but the events' clock is 0.5 s ahead: no depth, the clocks disagree.
  f.depth_pub_.publish(depthMm(base + ros::Duration(0.1), 1500));
  f.depth_pub_.publish(depthMm(base + ros::Duration(0.1 + 1.0 / 30.0), 1500));
  const ebslam_msgs::EventArray ahead = events(base + ros::Duration(0.6));
  f.events_pub_.publish(ahead);
  const std::optional<ebslam_msgs::DepthEventArray> o5 = f.output(ahead.header.stamp);
  ASSERT_TRUE(o5.has_value());
  expectNoDepth(*o5);
  EXPECT_TRUE(f.logged("newer than the latest depth frame"));
  EXPECT_TRUE(f.logged("depth frames arrive, so the event and depth clocks disagree"));

  // An EventArray of another sensor: dropped (no output), a reason.
  const ebslam_msgs::EventArray wrong = events(base + ros::Duration(0.65), 240, 180);
  f.events_pub_.publish(wrong);
  EXPECT_TRUE(f.logged("EventArray of a 240x180 sensor dropped"));
  EXPECT_FALSE(f.output(wrong.header.stamp, 1.0).has_value());

  // And the node goes on: a plane 1.2 m away.
  f.depth_pub_.publish(depthMm(base + ros::Duration(0.7), 1200));
  const ebslam_msgs::EventArray e6 = events(base + ros::Duration(0.705));
  f.events_pub_.publish(e6);
  const std::optional<ebslam_msgs::DepthEventArray> o6 = f.output(e6.header.stamp);
  ASSERT_TRUE(o6.has_value());
  expectPlane(*o6, e6, 1.2, 0);
}

TEST(DepthEventFusion, StopsWithAFatalReasonWithoutCalibration) {
  ros::NodeHandle nh;
  std::vector<std::string> fatal;
  auto sub =
      nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::LogConstPtr& m) {
        if (m->level == rosgraph_msgs::Log::FATAL) fatal.push_back(m->msg);
      });
  nodelet::Loader loader(false);
  EXPECT_FALSE(loader.load("/fusion_without_calibration", "ebslam_ros/DepthEventFusion", {}, {}));
  ros::NodeHandle("/fusion_of_missing_file").setParam("calibration", "/nonexistent/sensors.yaml");
  EXPECT_FALSE(loader.load("/fusion_of_missing_file", "ebslam_ros/DepthEventFusion", {}, {}));
  ASSERT_TRUE(waitFor([&] { return fatal.size() >= 2; }, 10.0));
  EXPECT_NE(fatal[0].find("/fusion_without_calibration/calibration is not set"), std::string::npos)
      << fatal[0];
  EXPECT_NE(fatal[1].find("/fusion_of_missing_file/calibration"), std::string::npos) << fatal[1];
  EXPECT_NE(fatal[1].find("/nonexistent/sensors.yaml"), std::string::npos) << fatal[1];
}

// A depth scene that changes from frame to frame: a tilted wall, a box moving across it (a depth
// step the rays must not bridge) and a hole (no depth) moving the other way; 16UC1 millimetres on
// even frames, 32FC1 metres on odd ones.
cv::Mat sceneDepth(int k) {
  const bool metres = k % 2 == 1;
  cv::Mat depth(kDepthHeight, kDepthWidth, metres ? CV_32FC1 : CV_16UC1);
  for (int v = 0; v < kDepthHeight; ++v) {
    for (int u = 0; u < kDepthWidth; ++u) {
      double z = 1.3 + 0.006 * u + 0.002 * v + 0.02 * k;  // [m]
      const bool box = u >= 30 + 4 * k && u < 80 + 4 * k && v >= 30 && v < 90;
      const bool hole = u >= 110 - 3 * k && u < 125 - 3 * k && v >= 10 && v < 50;
      if (box) z = 0.8 + 0.001 * v;
      if (metres) {
        depth.at<float>(v, u) =
            hole ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(z);
      } else {
        depth.at<std::uint16_t>(v, u) =
            hole ? 0 : static_cast<std::uint16_t>(std::lround(z * 1000.0));
      }
    }
  }
  return depth;
}

sensor_msgs::Image toImageMsg(const cv::Mat& depth, const ros::Time& stamp) {
  sensor_msgs::Image image;
  image.header.stamp = stamp;
  image.header.frame_id = "camera_depth_optical_frame";
  image.width = static_cast<std::uint32_t>(depth.cols);
  image.height = static_cast<std::uint32_t>(depth.rows);
  image.encoding = depth.type() == CV_32FC1 ? "32FC1" : "16UC1";
  image.step = static_cast<std::uint32_t>(depth.cols * depth.elemSize());
  image.data.assign(depth.datastart, depth.dataend);
  return image;
}

// The node against its core (fusion_core in the .test file, ~max_wait long enough that every
// EventArray waits for the frame it is meant to meet): per depth frame k at t_k, one EventArray
// of events in (t_k - T, t_k) (nearest frame k - 1 or k) and one in [t_k, t_k + 0.45 T], random
// pixels (a few outside the sensor), published after the frame; the core gets the same frame and
// then the same events. Every event's depth and point equal the core's to the bit (or both NaN).
TEST(DepthEventFusion, DepthEventsEqualTheCoreOnTheSameFramesAndEvents) {
  ros::NodeHandle nh("core");
  ros::Publisher events_pub = nh.advertise<ebslam_msgs::EventArray>("events", 100);
  ros::Publisher depth_pub = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 100);
  std::vector<ebslam_msgs::DepthEventArray> out;
  ros::Subscriber sub = nh.subscribe<ebslam_msgs::DepthEventArray>(
      "depth_events", 100,
      [&](const ebslam_msgs::DepthEventArray::ConstPtr& m) { out.push_back(*m); });
  ASSERT_TRUE(waitFor([&] {
    return events_pub.getNumSubscribers() > 0 && depth_pub.getNumSubscribers() > 0 &&
           sub.getNumPublishers() > 0;
  }));
  ros::WallDuration(0.5).sleep();  // roscpp counts a subscriber before its side is ready

  std::string calibration;
  ASSERT_TRUE(ros::param::get("/fusion_core/calibration", calibration));
  const ebslam::DedvsSensors sensors = ebslam::readDedvsSensors(calibration);
  ros::NodeHandle p("/fusion_core");
  ebslam::DepthFusionConfig config;
  config.min_depth_m = p.param("min_depth", config.min_depth_m);
  config.max_depth_m = p.param("max_depth", config.max_depth_m);
  config.max_frame_age_s = p.param("max_frame_age", config.max_frame_age_s);
  config.max_surface_jump_ratio = p.param("max_surface_jump_ratio", config.max_surface_jump_ratio);
  config.frames_kept =
      static_cast<std::size_t>(p.param("frames_kept", static_cast<int>(config.frames_kept)));
  ebslam::DepthEventFusion core(sensors, config);

  const double period = 1.0 / sensors.depth_frame_rate_hz;
  const ros::Time base = ros::Time::now() + ros::Duration(1000.0);  // after the other tests
  std::mt19937 random(7);
  std::uniform_int_distribution<int> pixel(0, 129);  // 128, 129: outside the 128 x 128 eDVS
  std::size_t compared = 0, with_depth = 0, differing = 0;
  for (int k = 0; k < 12; ++k) {
    const ros::Time t_k = base + ros::Duration(k * period);
    const cv::Mat depth = sceneDepth(k);
    depth_pub.publish(toImageMsg(depth, t_k));
    core.addDepthFrame(depth, t_k.toSec());
    for (const auto& [from, to] : {std::pair{-0.95, -0.05}, std::pair{0.0, 0.45}}) {
      ebslam_msgs::EventArray in;
      in.header.frame_id = "edvs_optical_frame";
      in.width = in.height = 128;
      constexpr int kEvents = 300;
      for (int i = 0; i < kEvents; ++i) {
        ebslam_msgs::Event e;
        e.x = static_cast<std::uint16_t>(pixel(random));
        e.y = static_cast<std::uint16_t>(pixel(random));
        e.ts = t_k + ros::Duration((from + (to - from) * i / (kEvents - 1)) * period);
        e.polarity = (i % 3) == 0;
        in.events.push_back(e);
      }
      in.header.stamp = in.events.back().ts;
      events_pub.publish(in);
      const std::size_t index = out.size();
      ASSERT_TRUE(waitFor([&] { return out.size() > index; })) << "frame " << k;
      const ebslam_msgs::DepthEventArray& node = out[index];
      ASSERT_EQ(node.header.stamp, in.header.stamp) << "frame " << k;
      ASSERT_EQ(node.events.size(), in.events.size());
      for (std::size_t i = 0; i < in.events.size(); ++i) {
        const ebslam::FusedEvent c = core.fuse(ebslam_msgs::fromMsg(in.events[i]));
        const ebslam_msgs::DepthEvent& d = node.events[i];
        const auto same = [](float a, float b) {
          return (std::isnan(a) && std::isnan(b)) || a == b;
        };
        const bool equal = d.x == in.events[i].x && d.y == in.events[i].y &&
                           d.ts == in.events[i].ts && d.polarity == in.events[i].polarity &&
                           same(d.depth, c.depth_m) && same(d.point.x, c.point.x()) &&
                           same(d.point.y, c.point.y()) && same(d.point.z, c.point.z());
        ++compared;
        with_depth += std::isfinite(c.depth_m) ? 1 : 0;
        if (!equal && differing++ < 3) {
          ADD_FAILURE() << "frame " << k << ", event " << i << " (" << d.x << ", " << d.y
                        << "): node depth " << d.depth << ", core " << c.depth_m << " ("
                        << ebslam::toString(c.status) << ")";
        }
      }
    }
  }
  EXPECT_EQ(differing, 0u) << "of " << compared << " events";
  // The scene gives most events a depth and some none (hole, outside, box edges).
  EXPECT_GT(with_depth, compared / 2);
  EXPECT_LT(with_depth, compared);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "depth_event_fusion_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
