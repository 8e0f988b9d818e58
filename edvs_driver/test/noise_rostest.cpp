// rostest: the driver node on a noisy line and on a capture file.
//  - E2 through the pty emulator with 2 % garbage and 10 events cut in the middle: the
//    published stream keeps the true clock (last stamp within 1 ms of the truth relative to the
//    anchor, never backwards, lost < 1 %, nothing invented) and the diagnostics go WARN naming
//    the line noise while it lasts.
//  - A raw E3 capture (file://, rate=0) is published once and ends: diagnostics OK "capture
//    ended", no replay.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <fstream>
#include <mutex>

#include "ebslam_msgs/event_conversions.h"
#include "edvs/device.h"
#include "edvs/emulator.h"
#include "edvs/stream_check.h"

namespace {

class EventSink {
 public:
  EventSink(ros::NodeHandle& nh, const std::string& topic)
      : sub_(nh.subscribe(topic, 1000, &EventSink::callback, this)) {}
  void callback(const ebslam_msgs::EventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
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
  ros::Subscriber& subscriber() { return sub_; }

 private:
  std::mutex mutex_;
  ebslam::EventVector events_;
  ros::Subscriber sub_;
};

class DiagnosticsSink {
 public:
  DiagnosticsSink(ros::NodeHandle& nh, std::string node)
      : node_(std::move(node)),
        sub_(nh.subscribe("/diagnostics", 100, &DiagnosticsSink::callback, this)) {}
  void callback(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : msg->status) {
      if (s.name.find(node_) != std::string::npos) statuses_.push_back(s);
    }
  }
  bool seen(std::uint8_t level, const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : statuses_) {
      if (s.level == level && s.message.find(text) != std::string::npos) return true;
    }
    return false;
  }
  std::string all() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string text;
    for (const auto& s : statuses_) text += std::to_string(s.level) + " " + s.message + "; ";
    return text;
  }

 private:
  std::string node_;
  std::mutex mutex_;
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses_;
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

std::string uriPath(const std::string& param) {
  std::string uri;
  if (!ros::param::get(param, uri)) return "";
  return edvs::parseDeviceUri(uri).path;
}

}  // namespace

TEST(EdvsDriverNoise, NoisyLineKeepsTheClockAndDiagnosticsWarn) {
  ros::NodeHandle nh;
  const std::string link = uriPath("/noisy/edvs_noisy/uri");
  ASSERT_FALSE(link.empty());
  EventSink sink(nh, "/noisy/events");
  DiagnosticsSink diagnostics(nh, "edvs_noisy");
  ASSERT_TRUE(waitFor([&] { return sink.subscriber().getNumPublishers() > 0; }, 20.0));

  constexpr std::size_t kCount = 60000;  // 3 s at 20 k events/s
  edvs::EmulatorConfig ec;
  ec.link_path = link;
  ec.seed = 3;
  ec.rate_hz = 20000;
  ec.max_events = kCount;
  ec.line_bytes_per_second = 1200000;  // 12 Mbit/s
  ec.garbage_probability = 0.02;
  for (std::size_t i = 1; i <= 10; ++i) ec.cut_events.push_back(i * 5000 + i * 37);
  edvs::Emulator emulator(ec);
  const std::size_t whole = kCount - ec.cut_events.size();
  // Diagnostics (1 Hz) go WARN with the noise counts while garbage arrives.
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.seen(diagnostic_msgs::DiagnosticStatus::WARN, "line noise"); },
      20.0))
      << diagnostics.all();
  ASSERT_TRUE(waitFor([&] { return emulator.eventsSent() >= whole; }, 30.0));
  waitFor([&] { return sink.size() >= whole; }, 5.0);
  ros::WallDuration(0.5).sleep();

  const ebslam::EventVector sent = emulator.sentEvents();
  const ebslam::EventVector got = sink.events();
  // Stamps are anchor + device time: compare relative to the first event (offset found from it).
  const auto c = edvs::compareStreams(sent, got, true, 0, 64);
  std::printf(
      "noisy line E2, garbage 2 %%, %zu cut: sent %zu published %zu lost %zu invented %zu final "
      "error %lld us backwards %zu\n",
      emulator.eventsCut(), c.sent, c.published, c.lost, c.invented,
      static_cast<long long>(c.final_error_us), c.backwards);
  EXPECT_EQ(emulator.eventsCut(), 10u);
  EXPECT_EQ(c.backwards, 0u);
  EXPECT_LE(std::abs(c.final_error_us), 1000);
  EXPECT_LT(c.lostShare(), 0.01);
  EXPECT_LE(c.invented, 2u);
}

TEST(EdvsDriverNoise, CaptureFileEndsAtItsEnd) {
  ros::NodeHandle nh;
  const std::string path = uriPath("/capture/edvs_capture/uri");
  ASSERT_FALSE(path.empty());
  EventSink sink(nh, "/capture/events");
  DiagnosticsSink diagnostics(nh, "edvs_capture");
  ASSERT_TRUE(waitFor([&] { return sink.subscriber().getNumPublishers() > 0; }, 20.0));
  const ebslam::EventVector events = edvs::generateEvents(4, 5000, 3000);
  const auto bytes = edvs::encodeEvents(events, edvs::EventFormat::kAbs24);
  {
    const std::string tmp = path + ".part";
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    std::rename(tmp.c_str(), path.c_str());  // appears complete
  }
  ASSERT_TRUE(waitFor([&] { return sink.size() >= events.size(); }, 20.0)) << sink.size();
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.seen(diagnostic_msgs::DiagnosticStatus::OK, "capture ended"); },
      10.0))
      << diagnostics.all();
  ros::WallDuration(2.0).sleep();  // a replay would publish the events again
  const ebslam::EventVector got = sink.events();
  EXPECT_EQ(got.size(), events.size());
  std::remove(path.c_str());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "edvs_noise_rostest");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
