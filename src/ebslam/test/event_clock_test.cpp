#include "ebslam/events/event_clock.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>

namespace {

using ebslam::EventClock;
constexpr std::int64_t kEpochUs = 1'700'000'000'000'000;  // a ROS time in 2023 [us]

TEST(EventClock, MapsStreamTimeExactlyAtSpeedOne) {
  EventClock clock;
  clock.anchor(5'000'000, kEpochUs);
  EXPECT_EQ(clock.map(5'000'000), kEpochUs);
  EXPECT_EQ(clock.map(6'500'001), kEpochUs + 1'500'001);
  EXPECT_EQ(clock.map(4'000'000), kEpochUs - 1'000'000);  // map() is not clamped
  EXPECT_EQ(clock.streamTime(kEpochUs + 7), 5'000'007);
}

TEST(EventClock, RoundTripWithinHalfTheSpeed) {
  std::mt19937_64 rng(3);
  for (const double speed : {1.0, 0.5, 2.0, 10.0}) {
    EventClock clock(speed);
    clock.anchor(123'456, kEpochUs);
    std::uniform_int_distribution<std::int64_t> t(0, 600'000'000);
    for (int i = 0; i < 1000; ++i) {
      const std::int64_t t_us = t(rng);
      const std::int64_t back = *clock.streamTime(*clock.map(t_us));
      if (speed == 1.0) {
        ASSERT_EQ(back, t_us);
      } else {
        ASSERT_LE(std::abs(back - t_us), static_cast<std::int64_t>(speed / 2.0 + 0.5))
            << "speed " << speed;
      }
    }
  }
  EventClock fast(10.0);
  fast.anchor(0, kEpochUs);
  EXPECT_EQ(fast.map(1'000'000), kEpochUs + 100'000);
}

TEST(EventClock, StampNeverRunsBackwardsAlsoAcrossAnchors) {
  EventClock clock;
  clock.anchor(1000, kEpochUs);
  EXPECT_EQ(clock.stamp(1000), kEpochUs);
  EXPECT_EQ(clock.stamp(1500), kEpochUs + 500);
  EXPECT_EQ(clock.stamp(1200), kEpochUs + 500);  // jitter back: clamped
  EXPECT_EQ(clock.stamp(1600), kEpochUs + 600);
  // A reconnect: the device clock restarts at 0, the host clock was read before the last stamp.
  clock.unanchor();
  EXPECT_FALSE(clock.anchored());
  clock.anchor(0, kEpochUs + 100);
  EXPECT_EQ(clock.anchorPublished(), kEpochUs + 600);  // moved up to the last stamp
  EXPECT_EQ(clock.stamp(0), kEpochUs + 600);
  EXPECT_EQ(clock.stamp(10), kEpochUs + 610);
  EXPECT_EQ(clock.lastStamp(), kEpochUs + 610);
  // reset() forgets the clamp: an independent stream may start earlier.
  clock.reset();
  EXPECT_FALSE(clock.lastStamp());
  clock.anchor(0, 5);
  EXPECT_EQ(clock.stamp(0), 5);
}

TEST(EventClock, OverflowIsReportedNotWrapped) {
  EventClock clock;
  clock.anchor(-1'000'000, kEpochUs);
  EXPECT_FALSE(clock.map(std::numeric_limits<std::int64_t>::max()));
  EXPECT_FALSE(clock.stamp(std::numeric_limits<std::int64_t>::max()));
  EXPECT_FALSE(clock.lastStamp());  // a failed stamp is not remembered
  EventClock slow(1e-12);
  slow.anchor(0, 0);
  EXPECT_FALSE(slow.map(std::numeric_limits<std::int64_t>::max() / 2));
  EventClock wrap;
  wrap.anchor(std::numeric_limits<std::int64_t>::max(), 0);
  EXPECT_FALSE(wrap.map(std::numeric_limits<std::int64_t>::min()));
}

TEST(EventClock, Misuse) {
  EXPECT_THROW(EventClock(0.0), std::invalid_argument);
  EXPECT_THROW(EventClock(-1.0), std::invalid_argument);
  EXPECT_THROW(EventClock(std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(EventClock(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EventClock clock;
  EXPECT_THROW(clock.map(0), std::logic_error);
  EXPECT_THROW(clock.stamp(0), std::logic_error);
  EXPECT_THROW(clock.streamTime(0), std::logic_error);
}

}  // namespace
