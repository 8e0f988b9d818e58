// No WARN/ERROR floods (log_flood.test): 1000 bad messages to each of EventSlam2d and
// EventDenoiser (EventArray), EventSlam3d (DepthEventArray) and Dasp (RGB-D triples), of several
// kinds each, then the WARN/ERROR lines each manager sent to /rosout are counted. Every
// per-message problem may be reported at most once per throttle period per kind, so a node logs
// at most kinds x (1 + duration / period) lines; unthrottled logging would give about 1000.
// Each node must also have reported every kind at least once (the log says what happened), and
// its diagnostics must show that it received the messages (the counts are not low because the
// messages were lost).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"
#include "rostest_util.h"

namespace {

constexpr int kMessages = 1000;
constexpr std::int64_t kT0 = 1700000000000000;  // [us]

struct Logs {
  std::mutex mutex;
  std::map<std::string, std::vector<rosgraph_msgs::Log>> by_node;         // WARN and above
  std::map<std::string, std::map<std::string, std::string>> diagnostics;  // status name -> values
};

ebslam_msgs::EventArray eventArray(std::int64_t t_us, int count) {
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = msg.height = 128;
  for (int i = 0; i < count; ++i) {
    ebslam_msgs::Event e;
    e.x = static_cast<std::uint16_t>((13 * i) % 128);
    e.y = static_cast<std::uint16_t>((29 * i) % 128);
    e.ts = ebslam_msgs::toRosTime(t_us + 10 * i);
    e.polarity = i % 2 == 0;
    msg.events.push_back(e);
  }
  msg.header.stamp = msg.events.back().ts;
  return msg;
}

ebslam_msgs::DepthEventArray depthArray(const ebslam_msgs::EventArray& plain) {
  ebslam_msgs::DepthEventArray msg;
  msg.header = plain.header;
  msg.width = plain.width;
  msg.height = plain.height;
  for (const auto& e : plain.events) {
    ebslam_msgs::DepthEvent d;
    d.x = e.x;
    d.y = e.y;
    d.ts = e.ts;
    d.polarity = e.polarity;
    d.depth = 2.5f;
    d.point.x = 0.01f * (e.x - 64.0f);
    d.point.y = 0.01f * (e.y - 64.0f);
    d.point.z = 2.5f;
    msg.events.push_back(d);
  }
  return msg;
}

// Bad EventArray number k: time back by 25 ms against the previous message (every message), and
// in turn an event stamped 0, a wrong sensor size, events outside the sensor, a wrong frame.
ebslam_msgs::EventArray badEvents(int k) {
  ebslam_msgs::EventArray msg = eventArray(kT0 - 25000 * k, 50);
  switch (k % 4) {
    case 0:
      msg.events[25].ts = ros::Time();
      break;
    case 1:
      msg.width = msg.height = 240;
      break;
    case 2:
      for (auto& e : msg.events) e.x = 200;
      break;
    default:
      msg.header.frame_id = "some_other_frame";
  }
  return msg;
}

ebslam_msgs::DepthEventArray badDepthEvents(int k) {
  ebslam_msgs::DepthEventArray msg = depthArray(eventArray(kT0 - 25000 * k, 50));
  switch (k % 3) {
    case 0:
      msg.events[25].ts = ros::Time();
      break;
    case 1:
      msg.header.frame_id = "some_other_frame";
      break;
    default:
      break;  // only the jump back
  }
  return msg;
}

TEST(LogFlood, ThousandBadMessagesGiveAFewLogLinesPerKind) {
  ros::NodeHandle nh;
  Logs logs;
  auto rosout_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 10000,
                                                     [&](const rosgraph_msgs::Log::ConstPtr& m) {
                                                       if (m->level < rosgraph_msgs::Log::WARN)
                                                         return;
                                                       std::lock_guard<std::mutex> lock(logs.mutex);
                                                       logs.by_node[m->name].push_back(*m);
                                                     });
  auto diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(logs.mutex);
        for (const auto& status : m->status) {
          for (const auto& kv : status.values) logs.diagnostics[status.name][kv.key] = kv.value;
        }
      });
  ros::Publisher events_pub = nh.advertise<ebslam_msgs::EventArray>("/flood/events", 1000);
  ros::Publisher depth_pub =
      nh.advertise<ebslam_msgs::DepthEventArray>("/flood/depth_events", 1000);
  ros::Publisher colour_pub = nh.advertise<sensor_msgs::Image>("/camera/rgb/image_rect_color", 100);
  ros::Publisher depth_image_pub =
      nh.advertise<sensor_msgs::Image>("/camera/depth_registered/image_raw", 100);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/camera/rgb/camera_info", 100);
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] {
        return events_pub.getNumSubscribers() >= 2 && depth_pub.getNumSubscribers() >= 1 &&
               colour_pub.getNumSubscribers() >= 1 && depth_image_pub.getNumSubscribers() >= 1 &&
               info_pub.getNumSubscribers() >= 1;
      },
      60.0))
      << "the nodelets did not subscribe";
  // Connected to the /rosout publishers of the four managers and of this node.
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return rosout_sub.getNumPublishers() >= 5; }, 60.0))
      << "connected to " << rosout_sub.getNumPublishers() << " /rosout publishers of 5";
  std::map<std::string, std::size_t> before;
  {
    std::lock_guard<std::mutex> lock(logs.mutex);
    for (const auto& [name, lines] : logs.by_node) before[name] = lines.size();
  }

  const ros::WallTime start = ros::WallTime::now();
  for (int k = 0; k < kMessages; ++k) {
    events_pub.publish(badEvents(k));
    depth_pub.publish(badDepthEvents(k));
    // RGB-D triples with one bad part each: a size whose byte count overflows 32 bits, an
    // unsupported encoding, a depth image of another size, a camera_info without focal lengths.
    std_msgs::Header header;
    header.stamp = ros::Time(1700000000 + k, 0);
    header.frame_id = "camera_rgb_optical_frame";
    sensor_msgs::Image colour;
    colour.header = header;
    colour.width = 4;
    colour.height = 3;
    colour.encoding = "bgr8";
    colour.step = 12;
    colour.data.assign(36, 100);
    sensor_msgs::Image depth;
    depth.header = header;
    depth.width = 4;
    depth.height = 3;
    depth.encoding = "16UC1";
    depth.step = 8;
    depth.data.assign(24, 7);
    sensor_msgs::CameraInfo info;
    info.header = header;
    info.width = 4;
    info.height = 3;
    info.K = {5.0, 0.0, 1.5, 0.0, 5.0, 1.0, 0.0, 0.0, 1.0};
    switch (k % 4) {
      case 0:
        colour.width = 65536;
        colour.height = 65537;
        colour.step = 3 * 65536;
        break;
      case 1:
        colour.encoding = "yuv422";
        break;
      case 2:
        depth.height = 2;
        depth.data.resize(16);
        break;
      default:
        info.K.fill(0.0);
    }
    colour_pub.publish(colour);
    depth_image_pub.publish(depth);
    info_pub.publish(info);
    ros::WallDuration(0.005).sleep();  // 200 Hz: within every subscriber queue
    ros::spinOnce();
  }
  // Positive signal: each node's diagnostics count the messages (updated once a second); nine in
  // ten is enough to show that the counts below are not low for want of messages.
  const long long enough = kMessages * 9 / 10;
  const auto count = [&](const std::string& status_part, const std::string& key) -> long long {
    std::lock_guard<std::mutex> lock(logs.mutex);
    for (const auto& [name, values] : logs.diagnostics) {
      if (name.find(status_part) == std::string::npos) continue;
      const auto it = values.find(key);
      if (it != values.end()) return std::stoll(it->second);
    }
    return -1;
  };
  EXPECT_TRUE(ebslam_ros_test::spinUntil(
      [&] {
        return count("slam2d", "messages") >= enough && count("denoiser", "messages") >= enough &&
               count("slam3d", "messages") >= enough && count("dasp", "frames rejected") >= enough;
      },
      60.0))
      << "slam2d " << count("slam2d", "messages") << ", denoiser " << count("denoiser", "messages")
      << ", slam3d " << count("slam3d", "messages") << ", dasp rejected "
      << count("dasp", "frames rejected");
  const double duration = (ros::WallTime::now() - start).toSec();
  // Lines still in transit would only lower the counts below the bound; the counters above
  // were read after the nodes had handled every message (and logged before counting it).
  ebslam_ros_test::spinUntil([] { return false; }, 1.0);

  // Per node: kinds of bad input, the throttle period [s], and a text each kind's line contains.
  struct Expectation {
    std::string node;
    double period_s;
    std::vector<std::string> kinds;
  };
  const std::vector<Expectation> expectations{
      {"/slam2d_manager",
       5.0,
       {"jumped back", "stamped 0", "sensor dropped", "outside the", "in frame"}},
      {"/denoiser_manager", 5.0, {"jumped back", "sensor dropped", "outside the"}},
      {"/slam3d_manager", 5.0, {"jumped back", "stamped 0", "in frame"}},
      {"/camera/dasp_manager", 1.0, {"too small for", "yuv422", "registered", "focal lengths"}},
  };
  std::lock_guard<std::mutex> lock(logs.mutex);
  for (const Expectation& e : expectations) {
    SCOPED_TRACE(e.node);
    const auto& all = logs.by_node[e.node];
    const std::vector<rosgraph_msgs::Log> lines(
        all.begin() + static_cast<std::ptrdiff_t>(std::min(before[e.node], all.size())), all.end());
    const double bound =
        static_cast<double>(e.kinds.size()) * (1.0 + std::ceil(duration / e.period_s));
    std::string text;
    for (const auto& l : lines) text += "  " + l.msg.substr(0, 200) + "\n";
    EXPECT_LE(static_cast<double>(lines.size()), bound)
        << lines.size() << " WARN/ERROR lines in " << duration << " s:\n"
        << text;
    for (const std::string& kind : e.kinds) {
      bool found = false;
      for (const auto& l : lines) found = found || l.msg.find(kind) != std::string::npos;
      EXPECT_TRUE(found) << "no line about '" << kind << "':\n" << text;
    }
    std::printf("%s: %zu WARN/ERROR lines for %d bad messages in %.1f s (bound %.0f)\n",
                e.node.c_str(), lines.size(), kMessages, duration, bound);
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "log_flood_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
