#include "ebslam_ros/event_input.h"

#include <gtest/gtest.h>

#include "ebslam_msgs/event_conversions.h"

namespace {

using ebslam_ros::EventInputGuard;
using ebslam_ros::EventInputResult;

constexpr std::int64_t kBase = 1700000000000000;  // [us since the ROS epoch]

ebslam_msgs::Event event(std::int64_t t_us, int x, int y, bool polarity = true) {
  ebslam_msgs::Event e;
  e.ts = ebslam_msgs::toRosTime(t_us);
  e.x = static_cast<std::uint16_t>(x);
  e.y = static_cast<std::uint16_t>(y);
  e.polarity = polarity;
  return e;
}

ebslam_msgs::EventArray array(std::vector<ebslam_msgs::Event> events, std::uint32_t size = 128) {
  ebslam_msgs::EventArray msg;
  msg.width = msg.height = size;
  msg.events = std::move(events);
  return msg;
}

TEST(EventInput, PassesGoodEventsAndDropsOutsideOnes) {
  EventInputGuard guard({128, 128}, 1000, 1000000);
  const EventInputResult r =
      guard.take(array({event(kBase, 1, 2), event(kBase + 5, 128, 3), event(kBase + 9, 127, 127)}));
  EXPECT_FALSE(r.size_mismatch);
  EXPECT_EQ(r.outside, 1u);
  ASSERT_EQ(r.segments.size(), 1u);
  ASSERT_EQ(r.segments[0].events.size(), 2u);
  EXPECT_EQ(r.segments[0].events[0].t_us, kBase);
  EXPECT_EQ(r.segments[0].events[1].x, 127);
  EXPECT_FALSE(r.segments[0].restart);
}

TEST(EventInput, EmptyAndWrongSizeGiveNothing) {
  EventInputGuard guard({128, 128}, 1000, 1000000);
  EXPECT_TRUE(guard.take(array({})).segments.empty());
  const EventInputResult wrong = guard.take(array({event(kBase, 1, 2)}, 240));
  EXPECT_TRUE(wrong.size_mismatch);
  EXPECT_TRUE(wrong.segments.empty());
  const EventInputResult all_outside = guard.take(array({event(kBase, 200, 2)}));
  EXPECT_EQ(all_outside.outside, 1u);
  EXPECT_TRUE(all_outside.segments.empty());
}

TEST(EventInput, ClampsJitterAndSplitsAtAJumpBack) {
  EventInputGuard guard({128, 128}, 1000, 1000000);
  const EventInputResult r =
      guard.take(array({event(kBase + 5000, 1, 1), event(kBase + 4500, 2, 2),
                        event(kBase + 6000, 3, 3), event(kBase, 4, 4), event(kBase + 10, 5, 5)}));
  EXPECT_EQ(r.clamped, 1u);
  ASSERT_EQ(r.segments.size(), 2u);
  ASSERT_EQ(r.segments[0].events.size(), 3u);
  EXPECT_EQ(r.segments[0].events[1].t_us, kBase + 5000);  // clamped
  EXPECT_TRUE(r.segments[1].restart);
  EXPECT_EQ(r.segments[1].jump_back_us, 6000);
  EXPECT_EQ(r.segments[1].events.size(), 2u);
  // Across messages as well.
  const EventInputResult next = guard.take(array({event(kBase - 20000000, 1, 1)}));
  ASSERT_EQ(next.segments.size(), 1u);
  EXPECT_TRUE(next.segments[0].restart);
}

TEST(EventInput, ReportsAPause) {
  EventInputGuard guard({128, 128}, 1000, 1000000);
  guard.take(array({event(kBase, 1, 1)}));
  EXPECT_EQ(guard.take(array({event(kBase + 500000, 1, 1)})).gap_us, 0);
  EXPECT_EQ(guard.take(array({event(kBase + 5500000, 1, 1)})).gap_us, 5000000);
  guard.restart();
  EXPECT_FALSE(guard.take(array({event(kBase, 1, 1)})).segments[0].restart);
}

// An event stamped 0 (unset) amid a stream is dropped and counted: no restart, and the next
// real event is no pause of 1.7e9 s.
TEST(EventInput, DropsEventsOfTimeZero) {
  EventInputGuard guard({128, 128}, 1000, 1000000);
  guard.take(array({event(kBase, 1, 1)}));
  const EventInputResult r =
      guard.take(array({event(kBase + 10, 1, 1), event(0, 2, 2), event(kBase + 20, 3, 3)}));
  EXPECT_EQ(r.zero_time, 1u);
  EXPECT_EQ(r.gap_us, 0);
  ASSERT_EQ(r.segments.size(), 1u);
  EXPECT_FALSE(r.segments[0].restart);
  ASSERT_EQ(r.segments[0].events.size(), 2u);
  const EventInputResult alone = guard.take(array({event(0, 4, 4)}));
  EXPECT_EQ(alone.zero_time, 1u);
  EXPECT_TRUE(alone.segments.empty());
  const EventInputResult next = guard.take(array({event(kBase + 30, 1, 1)}));
  EXPECT_EQ(next.gap_us, 0);
  ASSERT_EQ(next.segments.size(), 1u);
  EXPECT_FALSE(next.segments[0].restart);
}

}  // namespace
