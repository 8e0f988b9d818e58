// The event file player publishes exactly the events of its file: coordinates, polarity and
// time differences (scaled by the playback speed), with the configured frame and sensor size.
#include <ebslam/event_io.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <vector>

#include "ebslam_ros/conversions.h"

namespace {

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
  const ebslam_ros::TimeAnchor anchor{first_stamp, expected.events.front().t_us, 2.0};
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
      EXPECT_EQ(ebslam_ros::toStreamTime(e.ts, anchor), want.t_us) << "event " << i - 1;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_file_player_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
