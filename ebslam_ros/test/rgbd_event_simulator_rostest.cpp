// rostest of the RgbdEventSimulator nodelet (rgbd_event_simulator.test): one simulated second on
// /clock from 500 s: events in the eDVS frame, depth and colour with camera_info in the depth
// frame stamped on the depth camera's clock (exposure + 12 ms) at 30 Hz, ground truth in map,
// and DepthEventFusion (loaded here) giving most events a depth in the room. A second simulator
// (loaded here) with ~loop drives 0.3 s forth and back with its time running on.
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "rostest_util.h"

namespace {

TEST(RgbdEventSimulator, PublishesEventsDepthColourGroundTruthAndClock) {
  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> arrays;
  std::vector<ebslam_msgs::DepthEventArray> fused;
  std::vector<sensor_msgs::Image> depth, colour;
  std::vector<sensor_msgs::CameraInfo> depth_info, colour_info;
  std::vector<geometry_msgs::PoseStamped> poses;
  std::vector<ros::Time> clock;
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  auto clock_sub = nh.subscribe<rosgraph_msgs::Clock>(
      "/clock", 1000, [&](const rosgraph_msgs::Clock::ConstPtr& m) { clock.push_back(m->clock); });
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "ground_truth/pose", 1000,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) { poses.push_back(*m); });
  auto depth_sub = nh.subscribe<sensor_msgs::Image>(
      "depth_registered/image_raw", 1000,
      [&](const sensor_msgs::Image::ConstPtr& m) { depth.push_back(*m); });
  auto colour_sub = nh.subscribe<sensor_msgs::Image>(
      "rgb/image_rect_color", 1000,
      [&](const sensor_msgs::Image::ConstPtr& m) { colour.push_back(*m); });
  auto depth_info_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "depth_registered/camera_info", 1000,
      [&](const sensor_msgs::CameraInfo::ConstPtr& m) { depth_info.push_back(*m); });
  auto colour_info_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "rgb/camera_info", 1000,
      [&](const sensor_msgs::CameraInfo::ConstPtr& m) { colour_info.push_back(*m); });
  auto fused_sub = nh.subscribe<ebslam_msgs::DepthEventArray>(
      "depth_events", 1000,
      [&](const ebslam_msgs::DepthEventArray::ConstPtr& m) { fused.push_back(*m); });
  // The simulator starts 0.5 s after the first subscriber to events: load the fusion now.
  auto events_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "events", 1000, [&](const ebslam_msgs::EventArray::ConstPtr& m) { arrays.push_back(*m); });
  nodelet::Loader loader(false);
  ASSERT_TRUE(loader.load("/fusion", "ebslam_ros/DepthEventFusion", {}, {}));

  // 1 s simulated; the last ground-truth pose is at 501 s. Generous: a loaded 2-core machine.
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(180.0);
  while (ros::WallTime::now() < end &&
         (poses.empty() || poses.back().header.stamp < ros::Time(500.999))) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  const ros::WallTime settle = ros::WallTime::now() + ros::WallDuration(2.0);
  while (ros::WallTime::now() < settle) {  // the fusion's last arrays (it may hold them 0.2 s)
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }

  // Events.
  ASSERT_GT(arrays.size(), 50u);
  std::size_t events = 0;
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkEventArrays(
      arrays, "edvs_optical_frame", 128, 128, ros::Time(500.0), ros::Time(501.0), &events));
  EXPECT_GT(events, 10000u);  // a hand-held rig in a textured room

  // Depth: 30 Hz, 16UC1 mm, stamped exposure + 12 ms on the depth camera's clock.
  ASSERT_GE(depth.size(), 25u);
  ASSERT_LE(depth.size(), 31u);
  for (std::size_t i = 0; i < depth.size(); ++i) {
    const sensor_msgs::Image& d = depth[i];
    EXPECT_EQ(d.header.frame_id, "camera_depth_optical_frame");
    EXPECT_EQ(d.encoding, "16UC1");
    EXPECT_EQ(d.width, 320u);
    EXPECT_EQ(d.height, 240u);
    ASSERT_EQ(d.data.size(), 320u * 240u * 2u);
    const double k = (d.header.stamp.toSec() - 500.0 - 0.012) * 30.0;
    EXPECT_NEAR(k, std::round(k), 30.0 * 1e-5) << d.header.stamp;
    EXPECT_GE(d.header.stamp.toSec(), 500.0);
    EXPECT_LE(d.header.stamp.toSec(), 501.02);
    if (i > 0) {
      EXPECT_GT(d.header.stamp, depth[i - 1].header.stamp);
    }
    std::size_t valid = 0;
    for (std::size_t p = 0; p < 320u * 240u; ++p) {
      std::uint16_t mm;
      std::memcpy(&mm, &d.data[2 * p], 2);
      valid += mm > 0;
      EXPECT_LE(mm, 4500);  // max_range_m 4 m plus noise
    }
    EXPECT_GT(valid, 320u * 240u / 4u);
  }
  ASSERT_EQ(depth_info.size(), depth.size());
  EXPECT_EQ(depth_info.front().header, depth.front().header);
  EXPECT_NEAR(depth_info.front().K[0], 260.0, 1e-9);
  ASSERT_EQ(colour.size(), depth.size());
  EXPECT_EQ(colour.back().header, depth.back().header);
  EXPECT_EQ(colour.back().encoding, "bgr8");
  EXPECT_EQ(colour.back().data.size(), 320u * 240u * 3u);
  ASSERT_EQ(colour_info.size(), depth.size());

  // Ground truth and clock.
  ASSERT_GT(poses.size(), 50u);
  EXPECT_EQ(poses.back().header.frame_id, "map");
  EXPECT_NEAR(poses.back().header.stamp.toSec(), 501.0, 1e-6);
  ASSERT_FALSE(clock.empty());
  EXPECT_NEAR(clock.back().toSec(), 501.0, 1e-6);
  const auto gt = buffer.lookupTransform("map", "ground_truth", poses.back().header.stamp);
  EXPECT_NEAR(gt.transform.translation.x, poses.back().pose.position.x, 1e-9);

  // Fusion: the input's stamps, many events with a depth inside the room (73-87 % of the
  // signal events on the freiburg1 runs, docs/results/dedvs.md).
  ASSERT_GT(fused.size(), 40u);
  std::size_t total = 0, with_depth = 0;
  for (const auto& f : fused) {
    EXPECT_EQ(f.header.frame_id, "edvs_optical_frame");
    ASSERT_FALSE(f.events.empty());
    EXPECT_EQ(f.header.stamp, f.events.back().ts);
    for (const auto& e : f.events) {
      ++total;
      if (std::isfinite(e.depth)) {
        ++with_depth;
        EXPECT_GT(e.depth, 0.3);
        EXPECT_LT(e.depth, 6.0);
      }
    }
  }
  ::testing::Test::RecordProperty(
      "events_with_depth_percent",
      static_cast<int>(100.0 * with_depth / std::max<std::size_t>(total, 1)));
  EXPECT_GT(with_depth, total / 3) << with_depth << " of " << total << " events with depth";
}

TEST(RgbdEventSimulator, LoopDrivesTheSpanForthAndBackWithTimeRunningOn) {
  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> arrays;
  std::vector<sensor_msgs::Image> depth;
  std::vector<geometry_msgs::PoseStamped> poses;
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/looping/ground_truth/pose", 1000,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) { poses.push_back(*m); });
  auto depth_sub = nh.subscribe<sensor_msgs::Image>(
      "/looping/depth_registered/image_raw", 1000,
      [&](const sensor_msgs::Image::ConstPtr& m) { depth.push_back(*m); });
  auto events_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "/looping/events", 1000,
      [&](const ebslam_msgs::EventArray::ConstPtr& m) { arrays.push_back(*m); });
  ros::NodeHandle looping("/looping");
  looping.setParam("t_end", 0.3);
  looping.setParam("loop", true);
  looping.setParam("seed", 2);
  looping.setParam("depth_width", 320);
  looping.setParam("wait_for_subscribers", true);
  // Stamps from 700 s (the first test's simulator is done with /clock; this process runs on wall
  // time either way).
  looping.setParam("publish_clock", true);
  looping.setParam("clock_start", 700.0);
  nodelet::Loader loader(false);
  const std::vector<std::string> topics = {"events",
                                           "depth_registered/image_raw",
                                           "depth_registered/camera_info",
                                           "rgb/image_rect_color",
                                           "rgb/camera_info",
                                           "ground_truth/pose",
                                           "ground_truth/path"};
  nodelet::M_string remappings;
  for (const std::string& topic : topics) remappings["/" + topic] = "/looping/" + topic;
  ASSERT_TRUE(loader.load("/looping", "ebslam_ros/RgbdEventSimulator", remappings, {}));
  // Three and a half passes: 1.05 simulated s from 700 s.
  ebslam_ros_test::spinUntil(
      [&] { return !poses.empty() && poses.back().header.stamp >= ros::Time(701.05); }, 120.0);
  loader.clear();
  ASSERT_FALSE(poses.empty());
  ASSERT_GE(poses.back().header.stamp, ros::Time(701.05)) << "the simulation stopped";
  std::size_t events = 0;
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkEventTimesRunOn(arrays, &events));
  EXPECT_GT(events, 1000u);
  // Depth frames at 30 Hz go on across the passes, their stamps increasing.
  ASSERT_GE(depth.size(), 25u);
  for (std::size_t i = 1; i < depth.size(); ++i) {
    ASSERT_GT(depth[i].header.stamp, depth[i - 1].header.stamp);
  }
  EXPECT_GT((depth.back().header.stamp - depth.front().header.stamp).toSec(), 0.8);
  // Ground truth every 10 ms over passes of 0.3 s; the rig moves more than 1 cm in the span.
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkForthAndBack(poses, ros::Time(700.0), 300, 0.01));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "rgbd_event_simulator_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
