// The event file player publishes exactly the events of its file: coordinates, polarity and
// time differences (scaled by the playback speed), with the configured frame and sensor size;
// from a file with damaged times, every valid event and none of the damaged ones. A player that
// cannot start stops with a FATAL reason naming the cause.
#include <ebslam/events/event_io.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "ebslam/events/event_clock.h"
#include "ebslam_msgs/event_conversions.h"

namespace {

// The player's clock at ~speed 2, anchored at the first published event: file time t_us was
// published at ts.
ebslam::EventClock speed2Clock(const ros::Time& ts, std::int64_t t_us) {
  ebslam::EventClock clock(2.0);
  clock.anchor(t_us, ebslam_msgs::toMicroseconds(ts));
  return clock;
}

// File time of a published ts (the published clock keeps microseconds: at speed 2 a file time
// comes back within 1 us).
std::int64_t streamTime(const ebslam::EventClock& clock, const ros::Time& ts) {
  return clock.streamTime(ebslam_msgs::toMicroseconds(ts)).value();
}

TEST(EventFilePlayer, PublishesTheFileExactly) {
  const ebslam::EventReadResult expected = ebslam::readEventFile(EVENT_FIXTURE);
  ASSERT_FALSE(expected.error.has_value());
  ASSERT_EQ(expected.events.size(), 400u);

  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> received;
  std::size_t count = 0;
  auto sub = nh.subscribe<ebslam_msgs::EventArray>("dvs/events", 1000,
                                                   [&](const ebslam_msgs::EventArrayConstPtr& msg) {
                                                     received.push_back(*msg);
                                                     count += msg->events.size();
                                                   });
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (count < expected.events.size() && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_EQ(count, expected.events.size()) << "not all events arrived";
  EXPECT_GT(received.size(), 3u) << "events should arrive in several paced batches";

  // The playback speed is 2: a microsecond of stream time is half a microsecond of ROS time.
  const ros::Time first_stamp = received.front().events.front().ts;
  const ebslam::EventClock clock = speed2Clock(first_stamp, expected.events.front().t_us);
  std::size_t i = 0;
  for (const auto& msg : received) {
    EXPECT_EQ(msg.header.frame_id, "test_edvs_frame");
    EXPECT_EQ(msg.width, 128u);
    EXPECT_EQ(msg.height, 128u);
    ASSERT_FALSE(msg.events.empty());
    EXPECT_EQ(msg.header.stamp, msg.events.back().ts);
    for (const auto& e : msg.events) {
      const ebslam::Event& want = expected.events[i++];
      EXPECT_EQ(e.x, want.x);
      EXPECT_EQ(e.y, want.y);
      EXPECT_EQ(e.polarity, want.polarity);
      EXPECT_NEAR(streamTime(clock, e.ts), want.t_us, 1) << "event " << i - 1;
    }
  }
}

// Collects the events published on `topic` until `expected` have arrived or 30 s have passed.
std::vector<ebslam_msgs::EventArray> receive(const std::string& topic, std::size_t expected) {
  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> received;
  std::size_t count = 0;
  auto sub = nh.subscribe<ebslam_msgs::EventArray>(topic, 1000,
                                                   [&](const ebslam_msgs::EventArrayConstPtr& msg) {
                                                     received.push_back(*msg);
                                                     count += msg->events.size();
                                                   });
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (count < expected && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  // Anything published beyond the expected events would arrive within this time.
  const ros::WallTime settle = ros::WallTime::now() + ros::WallDuration(0.3);
  while (ros::WallTime::now() < settle) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  return received;
}

TEST(EventFilePlayer, DropsDamagedTimesAndSkipsGaps) {
  // The fixture: four runs of 100 events, a line dated 285 years before 1970 after the first, one
  // about 95 years ahead after the second (in the range of ros::Time at speed 2), and a 30 s gap
  // in the recording before the fourth. ~max_gap is 10 s.
  const ebslam::EventReadResult file = ebslam::readEventFile(DAMAGED_TIMES_FIXTURE);
  ASSERT_FALSE(file.error.has_value());
  ASSERT_EQ(file.events.size(), 402u);
  ebslam::EventVector expected;
  for (const ebslam::Event& e : file.events) {
    if (std::llabs(e.t_us) < 1'000'000'000'000) expected.push_back(e);
  }
  ASSERT_EQ(expected.size(), 400u);

  const auto received = receive("dvs/damaged_events", expected.size());
  std::vector<ebslam_msgs::Event> events;
  for (const auto& msg : received) {
    EXPECT_EQ(msg.header.frame_id, "test_edvs_frame");
    events.insert(events.end(), msg.events.begin(), msg.events.end());
  }
  ASSERT_EQ(events.size(), expected.size()) << "every valid event, no damaged one";
  for (std::size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(events[i].x, expected[i].x) << "event " << i;
    EXPECT_EQ(events[i].y, expected[i].y) << "event " << i;
    EXPECT_EQ(events[i].polarity, expected[i].polarity) << "event " << i;
    if (i > 0) {
      EXPECT_GE(events[i].ts, events[i - 1].ts) << "event " << i;
    }
  }
  // The first three runs keep their times (speed 2), the damaged lines taking no time.
  const ebslam::EventClock clock = speed2Clock(events[0].ts, expected[0].t_us);
  for (std::size_t i = 0; i < 300; ++i) {
    EXPECT_NEAR(streamTime(clock, events[i].ts), expected[i].t_us, 1) << "event " << i;
  }
  // The gap is played without waiting its 15 s (at speed 2); the last run keeps its times.
  EXPECT_LT((events[300].ts - events[299].ts).toSec(), 1.0);
  const ebslam::EventClock after_gap = speed2Clock(events[300].ts, expected[300].t_us);
  for (std::size_t i = 300; i < events.size(); ++i) {
    EXPECT_NEAR(streamTime(after_gap, events[i].ts), expected[i].t_us, 1) << "event " << i;
  }
}

// Loads a player in this process with ~file = `file` (unset if empty); returns load()'s result.
bool loadPlayer(const std::string& name, const std::string& file) {
  ros::NodeHandle private_nh(name);
  if (!file.empty()) private_nh.setParam("file", file);
  static nodelet::Loader loader(false);
  return loader.load(name, "ebslam_ros/EventFilePlayer", {}, {});
}

TEST(EventFilePlayer, StopsWithAFatalReasonWhenItCannotStart) {
  ros::NodeHandle nh;
  std::vector<rosgraph_msgs::Log> fatal;
  auto sub =
      nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::LogConstPtr& m) {
        if (m->level == rosgraph_msgs::Log::FATAL) {
          fatal.push_back(*m);
        }
      });
  // A binary event file cut inside its header.
  const std::string truncated =
      (std::filesystem::temp_directory_path() /
       ("event_file_player_truncated_" + std::to_string(::getpid()) + ".bin"))
          .string();
  {
    ebslam::EventFileWriter writer(truncated, {128, 128});
    writer.write(ebslam::Event{1000, 1, 2, true});
    writer.close();
  }
  std::filesystem::resize_file(truncated, 20);  // the magic and part of the header

  EXPECT_FALSE(loadPlayer("/player_without_file", ""));
  EXPECT_FALSE(loadPlayer("/player_of_missing_file", "/nonexistent/events.bin"));
  EXPECT_FALSE(loadPlayer("/player_of_truncated_file", truncated));
  std::remove(truncated.c_str());
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(1.0);
  while (fatal.size() < 3 && ros::WallTime::now() < end) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_EQ(fatal.size(), 3u);
  EXPECT_NE(fatal[0].msg.find("/player_without_file/file is not set"), std::string::npos)
      << fatal[0].msg;
  EXPECT_NE(fatal[1].msg.find("/nonexistent/events.bin"), std::string::npos) << fatal[1].msg;
  EXPECT_NE(fatal[2].msg.find("truncated file header"), std::string::npos) << fatal[2].msg;
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_file_player_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
