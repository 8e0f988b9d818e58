#include "ebslam_ros/conversions.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace {

using ebslam_ros::TimeAnchor;

ebslam::EventVector randomEvents(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  ebslam::EventVector events;
  std::int64_t t = 123456789;
  for (std::size_t i = 0; i < n; ++i) {
    t += static_cast<std::int64_t>(rng() % 5000);
    events.push_back({t, static_cast<std::uint16_t>(rng() % 128),
                      static_cast<std::uint16_t>(rng() % 128), (rng() & 1u) != 0});
  }
  return events;
}

TEST(Conversions, EventArrayRoundTripKeepsMicroseconds) {
  const auto events = randomEvents(1000, 1);
  for (double speed : {1.0, 2.0, 0.5}) {
    const TimeAnchor anchor{ros::Time(1700000000, 123456789), events.front().t_us, speed};
    const auto msg = ebslam_ros::toEventArrayMsg(events, {128, 128}, "edvs_optical_frame", anchor);
    EXPECT_EQ(msg.width, 128u);
    EXPECT_EQ(msg.header.frame_id, "edvs_optical_frame");
    EXPECT_EQ(msg.header.stamp, msg.events.back().ts);
    EXPECT_EQ(ebslam_ros::toEvents(msg, anchor), events) << "speed " << speed;
  }
}

TEST(Conversions, TimeAnchorMapsStreamTime) {
  const TimeAnchor anchor{ros::Time(100, 0), 5'000'000, 1.0};
  EXPECT_EQ(ebslam_ros::toRosTime(5'000'000, anchor), ros::Time(100, 0));
  EXPECT_EQ(ebslam_ros::toRosTime(6'500'001, anchor), ros::Time(101, 500001000));
  EXPECT_EQ(ebslam_ros::toStreamTime(ros::Time(99, 0), anchor), 4'000'000);
  EXPECT_THROW(ebslam_ros::toRosTime(-200'000'000, anchor), std::invalid_argument);
  EXPECT_THROW(ebslam_ros::toRosTime(0, TimeAnchor{ros::Time(1, 0), 0, 0.0}),
               std::invalid_argument);
}

TEST(Conversions, TimeOutsideRosTimeIsNoTime) {
  const TimeAnchor anchor{ros::Time(1700000000, 0), 1'000'000, 10.0};
  EXPECT_EQ(ebslam_ros::rosTimeOf(2'000'000, anchor), ros::Time(1700000000, 100000000));
  // Lines of a damaged text file: before 1970 (at 1x), beyond 2106 at 10x, and the int64 extremes
  // (whose difference to the anchor does not fit in 64 bits).
  EXPECT_FALSE(ebslam_ros::rosTimeOf(-9'000'000'000'000'000,
                                     TimeAnchor{ros::Time(1700000000, 0), 1'000'000, 1.0}));
  EXPECT_FALSE(ebslam_ros::rosTimeOf(90'000'000'000'000'000, anchor));
  EXPECT_FALSE(ebslam_ros::rosTimeOf(std::numeric_limits<std::int64_t>::min(), anchor));
  EXPECT_FALSE(ebslam_ros::rosTimeOf(std::numeric_limits<std::int64_t>::max(),
                                     TimeAnchor{ros::Time(10, 0), -1'000'000, 1.0}));
  EXPECT_THROW(ebslam_ros::toRosTime(90'000'000'000'000'000, anchor), std::invalid_argument);
}

TEST(Conversions, EventOutsideSensorIsRejected) {
  const TimeAnchor anchor{ros::Time(10, 0), 0, 1.0};
  auto msg = ebslam_ros::toEventArrayMsg(randomEvents(3, 2), {128, 128}, "f", anchor);
  msg.events[1].x = 128;
  EXPECT_THROW(ebslam_ros::toEvents(msg, anchor), std::invalid_argument);
}

}  // namespace
