// rostest: the driver node against the pty emulator. The emulator streams a known seeded
// sequence; the node's published events must equal it exactly (pixels, polarity, timestamps
// relative to the anchor). The output is recorded to a bag, played back and compared. Then
// the device vanishes and comes back: the node recovers and its diagnostics say so.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <mutex>

#include "ebslam_msgs/event_conversions.h"
#include "edvs/device.h"
#include "edvs/emulator.h"
#include "edvs_driver/bag_io.h"

namespace {

std::string linkPath() {
  std::string uri;
  if (!ros::param::get("/edvs_driver/uri", uri)) return "";
  return edvs::parseDeviceUri(uri).path;
}

/// Collects EventArray messages from a topic. The subscriber is the last member: it is
/// subscribed after the buffers exist and unsubscribed (which waits for a callback in flight on
/// the spinner threads) before they are destroyed. Declared first, it let late messages of the
/// driver land in destroyed vectors at the end of a test (an abort in one clean-clone run).
class EventSink {
 public:
  EventSink(ros::NodeHandle& nh, const std::string& topic)
      : sub_(nh.subscribe(topic, 1000, &EventSink::callback, this)) {}
  void callback(const ebslam_msgs::EventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back(*msg);
    ebslam_msgs::appendFromMsg(*msg, events_);
  }
  std::size_t size() {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_.size();
  }
  ebslam::EventVector events() {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_;
  }
  std::vector<ebslam_msgs::EventArray> messages() {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  ros::Subscriber& subscriber() { return sub_; }

 private:
  std::mutex mutex_;
  std::vector<ebslam_msgs::EventArray> messages_;
  ebslam::EventVector events_;
  ros::Subscriber sub_;
};

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

}  // namespace

TEST(EdvsDriverNode, PublishesExactlyTheKnownSequenceAndBagPlaybackIsIdentical) {
  ros::NodeHandle nh;
  const std::string link = linkPath();
  ASSERT_FALSE(link.empty()) << "no /edvs_driver/uri parameter";
  EventSink sink(nh, "events");
  ASSERT_TRUE(waitFor([&] { return sink.subscriber().getNumPublishers() > 0; }, 20.0))
      << "the driver does not advertise events";
  ros::WallDuration(1.0).sleep();  // the driver retries while no device exists; it must not die

  constexpr std::uint32_t kSeed = 5;
  constexpr double kRate = 5000;
  constexpr std::size_t kCount = 2000;
  edvs::EmulatorConfig ec;
  ec.link_path = link;
  ec.seed = kSeed;
  ec.rate_hz = kRate;
  ec.max_events = kCount;
  const std::int64_t before_us = ebslam_msgs::toMicroseconds(ros::Time::now());
  auto emulator = std::make_unique<edvs::Emulator>(ec);
  ASSERT_TRUE(waitFor([&] { return sink.size() >= kCount; }, 30.0))
      << "received " << sink.size() << " of " << kCount << " events";
  ros::WallDuration(0.3).sleep();
  const std::int64_t after_us = ebslam_msgs::toMicroseconds(ros::Time::now());

  const ebslam::EventVector got = sink.events();
  const ebslam::EventVector expected = edvs::generateEvents(kSeed, kRate, kCount);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].x, expected[i].x) << i;
    ASSERT_EQ(got[i].y, expected[i].y) << i;
    ASSERT_EQ(got[i].polarity, expected[i].polarity) << i;
    // Timestamps: anchor + device time since the first event, to the microsecond.
    ASSERT_EQ(got[i].t_us - got[0].t_us, expected[i].t_us - expected[0].t_us) << i;
  }
  // The anchor is host ROS time at the stream's start.
  EXPECT_GE(got.front().t_us, before_us);
  EXPECT_LE(got.front().t_us, after_us);
  const auto messages = sink.messages();
  for (const auto& m : messages) {
    EXPECT_EQ(m.header.frame_id, "edvs_test_frame");
    EXPECT_EQ(m.width, 128u);
    EXPECT_EQ(m.height, 128u);
    ASSERT_FALSE(m.events.empty());
    EXPECT_EQ(m.header.stamp, m.events.back().ts);
  }

  // Record the node's output into a bag (C++ rosbag API), then play it back on a topic.
  const std::string bag_path = (std::filesystem::temp_directory_path() /
                                ("edvs_rostest_" + std::to_string(::getpid()) + ".bag"))
                                   .string();
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    for (const auto& m : messages) bag.write("/edvs/events", m.header.stamp, m);
  }
  EventSink playback(nh, "events_playback");
  ros::Publisher pub = nh.advertise<ebslam_msgs::EventArray>("events_playback", 1000);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 10.0));
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& mi : rosbag::View(bag)) {
      pub.publish(mi.instantiate<ebslam_msgs::EventArray>());
    }
  }
  ASSERT_TRUE(waitFor([&] { return playback.size() >= got.size(); }, 10.0));
  EXPECT_EQ(playback.events(), got);
  EXPECT_EQ(edvs_driver::readEventBag(bag_path).events, got);
  std::filesystem::remove(bag_path);
  emulator.reset();  // unplugged
}

TEST(EdvsDriverNode, RecoversAfterTheDeviceVanishesAndDiagnosticsSaySo) {
  ros::NodeHandle nh;
  const std::string link = linkPath();
  EventSink sink(nh, "events");
  std::mutex diag_mutex;
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses;
  ros::Subscriber diag = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(diag_mutex);
        for (const auto& s : msg->status) {
          if (s.name.find("eDVS") != std::string::npos) statuses.push_back(s);
        }
      });
  auto value = [](const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
    for (const auto& kv : s.values) {
      if (kv.key == key) return kv.value;
    }
    return std::string();
  };
  // Index of the first status at or after `from` with this level whose message contains text.
  auto find = [&](std::uint8_t level, const std::string& text, std::size_t from) {
    std::lock_guard<std::mutex> lock(diag_mutex);
    for (std::size_t i = from; i < statuses.size(); ++i) {
      if (statuses[i].level == level && statuses[i].message.find(text) != std::string::npos) {
        return i;
      }
    }
    return std::string::npos;
  };
  using diagnostic_msgs::DiagnosticStatus;
  // The previous test unplugged its device: the node reports that.
  ASSERT_TRUE(waitFor(
      [&] { return find(DiagnosticStatus::ERROR, "disconnected", 0) != std::string::npos; }, 10.0));
  std::size_t mark = 0;
  {
    std::lock_guard<std::mutex> lock(diag_mutex);
    mark = statuses.size();
  }

  edvs::EmulatorConfig ec;
  ec.link_path = link;
  ec.seed = 8;
  ec.rate_hz = 5000;
  // Long enough on both sides for the 1 Hz diagnostics to see each state.
  ec.vanish_after_events = 10000;  // 2 s of streaming
  ec.return_after_ms = 2500;
  edvs::Emulator emulator(ec);
  ASSERT_TRUE(waitFor([&] { return sink.size() >= 900; }, 20.0)) << sink.size();
  // Streaming (OK), then vanished (ERROR), then back (OK, naming the reconnects) in this order.
  std::size_t streaming = std::string::npos;
  ASSERT_TRUE(waitFor(
      [&] {
        streaming = find(DiagnosticStatus::OK, "streaming", mark);
        return streaming != std::string::npos;
      },
      10.0))
      << "diagnostics never reported streaming";
  std::size_t lost = std::string::npos;
  ASSERT_TRUE(waitFor(
      [&] {
        // The 1 Hz diagnostics sample the state: under load the short "disconnected" phase can
        // fall between two samples and only the reconnect attempts ("connecting") are seen.
        lost = std::min(find(DiagnosticStatus::ERROR, "disconnected", streaming),
                        find(DiagnosticStatus::WARN, "connecting", streaming));
        return lost != std::string::npos;
      },
      10.0))
      << "diagnostics never reported the lost device; seen: " << [&] {
           std::lock_guard<std::mutex> lock(diag_mutex);
           std::string all;
           for (std::size_t i = streaming; i < statuses.size(); ++i) {
             all += std::to_string(statuses[i].level) + " " + statuses[i].message + "; ";
           }
           return all;
         }();
  {
    std::lock_guard<std::mutex> lock(diag_mutex);
    EXPECT_NE(value(statuses[lost], "last disconnect").find("device lost"), std::string::npos);
  }
  ASSERT_TRUE(waitFor([&] { return emulator.appearances() == 2; }, 10.0));
  const std::size_t before = sink.size();
  ASSERT_TRUE(waitFor([&] { return sink.size() >= before + 1000; }, 20.0))
      << "no events after the device came back";
  std::size_t recovered = std::string::npos;
  ASSERT_TRUE(waitFor(
      [&] {
        recovered = find(DiagnosticStatus::OK, "recovered after", lost);
        return recovered != std::string::npos;
      },
      10.0))
      << "diagnostics never reported the recovery";
  {
    std::lock_guard<std::mutex> lock(diag_mutex);
    const auto& s = statuses[recovered];
    EXPECT_GE(std::stoi(value(s, "reconnects")), 2);  // after test 1's unplug and this one
    EXPECT_GE(std::stoi(value(s, "disconnects")), 2);
  }
  // Time never ran backwards across the reconnect.
  const ebslam::EventVector events = sink.events();
  for (std::size_t i = 1; i < events.size(); ++i) ASSERT_GE(events[i].t_us, events[i - 1].t_us);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "edvs_driver_rostest");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
