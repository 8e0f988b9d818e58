// Round trips of event_conversions.h and the time convention's range errors.
#include "ebslam_msgs/event_packet_conversions.h"

#include <gtest/gtest.h>

#include <ebslam/events/event_clock.h>

#include <cstdint>
#include <random>
#include <stdexcept>

namespace {

ebslam::EventVector randomEvents(std::int64_t t0_us, std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pixel(0, 127), step(0, 50), polarity(0, 1);
  ebslam::EventVector events;
  std::int64_t t = t0_us;
  for (std::size_t i = 0; i < n; ++i) {
    t += step(rng);
    events.push_back({t, static_cast<std::uint16_t>(pixel(rng)),
                      static_cast<std::uint16_t>(pixel(rng)), polarity(rng) == 1});
  }
  return events;
}

TEST(EventConversions, TimeRoundTripIsExactInMicroseconds) {
  for (const std::int64_t t : {std::int64_t{0}, std::int64_t{1}, std::int64_t{999999},
                               std::int64_t{1700000000123456}, std::int64_t{4294967295999999}}) {
    EXPECT_EQ(ebslam_msgs::toMicroseconds(ebslam_msgs::toRosTime(t)), t);
  }
  EXPECT_EQ(ebslam_msgs::toRosTime(1500001), ros::Time(1, 500001000));
  // Stamps from other sources (nanoseconds) round to the nearest microsecond.
  EXPECT_EQ(ebslam_msgs::toMicroseconds(ros::Time(1, 499)), 1000000);
  EXPECT_EQ(ebslam_msgs::toMicroseconds(ros::Time(1, 500)), 1000001);
  EXPECT_EQ(ebslam_msgs::toMicroseconds(ros::Time(4294967295, 999999999)),
            std::int64_t{4294967296} * 1000000);
}

TEST(EventConversions, OutsideRosTimeIsAnError) {
  EXPECT_FALSE(ebslam_msgs::rosTimeOf(-1));
  EXPECT_FALSE(ebslam_msgs::rosTimeOf(std::int64_t{4294967296} * 1000000));
  EXPECT_THROW(ebslam_msgs::toRosTime(-1), std::invalid_argument);
  EXPECT_THROW(ebslam_msgs::toRosTime(std::int64_t{4294967296} * 1000000), std::invalid_argument);
  EXPECT_THROW(ebslam_msgs::toMsg(ebslam::EventVector{{-5, 1, 1, true}}, {128, 128}, "f"),
               std::invalid_argument);
}

TEST(EventConversions, EventArrayRoundTrip) {
  const ebslam::EventVector events = randomEvents(1700000000000000, 500, 7);
  const auto msg = ebslam_msgs::toMsg(events, ebslam::SensorSize{128, 96}, "edvs_optical_frame");
  EXPECT_EQ(msg.width, 128u);
  EXPECT_EQ(msg.height, 96u);
  EXPECT_EQ(msg.header.frame_id, "edvs_optical_frame");
  EXPECT_EQ(msg.header.stamp, msg.events.back().ts);  // stamp = last event
  EXPECT_EQ(ebslam_msgs::fromMsg(msg), events);
  ebslam::EventVector appended{{1, 2, 3, false}};
  const ebslam::SensorSize size = ebslam_msgs::appendFromMsg(msg, appended);
  EXPECT_EQ(size.width, 128u);
  EXPECT_EQ(size.height, 96u);
  ASSERT_EQ(appended.size(), events.size() + 1);
  EXPECT_EQ(appended[1], events[0]);
  EXPECT_TRUE(ebslam_msgs::toMsg({}, ebslam::SensorSize{}, "f").header.stamp.isZero());
}

// A source's own clock -> EventClock -> messages -> back: what the event file player and the
// simulator publish and a subscriber reads.
TEST(EventConversions, SourceClockThroughMessagesRoundTrip) {
  const ebslam::EventVector events = randomEvents(123456789, 1000, 1);
  for (const double speed : {1.0, 2.0, 0.5}) {
    ebslam::EventClock clock(speed);
    clock.anchor(events.front().t_us,
                 ebslam_msgs::toMicroseconds(ros::Time(1700000000, 123456000)));
    ebslam::EventVector published = events;
    for (ebslam::Event& e : published) e.t_us = *clock.stamp(e.t_us);
    const auto msg = ebslam_msgs::toMsg(published, {128, 128}, "edvs_optical_frame");
    EXPECT_EQ(msg.events.front().ts, ros::Time(1700000000, 123456000));
    const ebslam::EventVector received = ebslam_msgs::fromMsg(msg);
    ASSERT_EQ(received.size(), events.size());
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::int64_t back = *clock.streamTime(received[i].t_us);
      ASSERT_LE(std::abs(back - events[i].t_us), speed > 1.0 ? 1 : 0) << "speed " << speed;
      ASSERT_EQ(received[i].x, events[i].x);
      ASSERT_EQ(received[i].polarity, events[i].polarity);
    }
  }
}

// EventPacket: events -> mono packet -> events is exact, across several packets of one stream.
TEST(EventPacketConversions, MonoRoundTrip) {
  ebslam_msgs::EventPacketConverter converter;
  ebslam::EventVector all, back;
  for (std::uint32_t k = 0; k < 3; ++k) {
    const ebslam::EventVector events =
        randomEvents(std::int64_t{1700000000000000} + 100000 * k, 500, 5 + k);
    all.insert(all.end(), events.begin(), events.end());
    const ebslam_msgs::EventPacket msg =
        ebslam_msgs::toMonoPacket(events, {346, 260}, "davis_optical_frame", k);
    EXPECT_EQ(msg.header.stamp, ebslam_msgs::toRosTime(events.front().t_us));
    const ebslam_msgs::EventPacketResult r = converter.append(msg, back);
    EXPECT_FALSE(r.rejected);
    EXPECT_EQ(r.sensor.width, 346u);
    EXPECT_EQ(r.stats.dropped_bytes + r.stats.outside + r.bad_time, 0u);
  }
  EXPECT_EQ(back, all);
}

TEST(EventPacketConversions, PacketMessageRoundTripAndEventArray) {
  const ebslam::EventVector events = randomEvents(1700000000000000, 50, 9);
  const ebslam_msgs::EventPacket msg = ebslam_msgs::toMonoPacket(events, {640, 480}, "cam");
  EXPECT_EQ(ebslam_msgs::toMsg(ebslam_msgs::toPacket(msg)), msg);
  ebslam_msgs::EventPacketConverter converter;
  ebslam_msgs::EventPacketResult r;
  const ebslam_msgs::EventArray array = converter.toEventArray(msg, &r);
  EXPECT_EQ(array.width, 640u);
  EXPECT_EQ(array.height, 480u);
  EXPECT_EQ(array.header.frame_id, "cam");
  EXPECT_EQ(array.header.stamp, ebslam_msgs::toRosTime(events.back().t_us));
  EXPECT_EQ(ebslam_msgs::fromMsg(array), events);
}

TEST(EventPacketConversions, BadPacketsAreRejectedWithAReason) {
  ebslam_msgs::EventPacket msg =
      ebslam_msgs::toMonoPacket(randomEvents(1700000000000000, 5, 1), {128, 128}, "cam");
  ebslam_msgs::EventPacketConverter converter;
  ebslam::EventVector out;
  msg.encoding = "evt2";
  EXPECT_TRUE(converter.append(msg, out).rejected);
  msg.encoding = "mono";
  msg.width = 0;
  const ebslam_msgs::EventPacketResult r = converter.append(msg, out);
  EXPECT_TRUE(r.rejected);
  EXPECT_NE(r.error.find("sensor size"), std::string::npos);
  msg.width = 128;
  msg.events.resize(msg.events.size() - 3);  // a cut-off last event
  const ebslam_msgs::EventPacketResult cut = converter.append(msg, out);
  EXPECT_FALSE(cut.rejected);
  EXPECT_EQ(cut.stats.dropped_bytes, 5u);
  EXPECT_EQ(out.size(), 4u);
  EXPECT_THROW(ebslam_msgs::toMonoPacket({{1, 200, 0, true}}, {128, 128}, "cam"),
               std::invalid_argument);
}

}  // namespace
