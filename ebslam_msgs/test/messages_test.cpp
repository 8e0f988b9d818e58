// MD5 compatibility with dvs_msgs and serialisation round trips of every message.
#include <gtest/gtest.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>

#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/EventPacket.h>
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <cmath>
#include <cstring>
#include <vector>

namespace {

// Serialises `in` into a buffer, checks the serialised length, and deserialises into a fresh
// message.
template <typename M>
M roundTrip(const M& in) {
  const uint32_t size = ros::serialization::serializationLength(in);
  std::vector<uint8_t> buffer(size);
  ros::serialization::OStream out_stream(buffer.data(), size);
  ros::serialization::serialize(out_stream, in);
  EXPECT_EQ(out_stream.getLength(), 0u) << "serialiser did not fill the buffer exactly";
  M out;
  ros::serialization::IStream in_stream(buffer.data(), size);
  ros::serialization::deserialize(in_stream, out);
  return out;
}

std_msgs::Header makeHeader(const char* frame) {
  std_msgs::Header header;
  header.stamp = ros::Time(1234, 567890000);
  header.frame_id = frame;
  return header;
}

ebslam_msgs::Event makeEvent(uint16_t x, uint16_t y, uint32_t sec, uint32_t nsec, bool polarity) {
  ebslam_msgs::Event event;
  event.x = x;
  event.y = y;
  event.ts = ros::Time(sec, nsec);
  event.polarity = polarity;
  return event;
}

TEST(Messages, Md5MatchesDvsMsgs) {
  // dvs_msgs/Event and dvs_msgs/EventArray as published by the rpg_dvs_ros driver.
  EXPECT_STREQ(ros::message_traits::md5sum<ebslam_msgs::Event>(),
               "40d339b261445b8ce9a6fef01267cd5d");
  EXPECT_STREQ(ros::message_traits::md5sum<ebslam_msgs::EventArray>(),
               "5e8beee5a6c107e504c2e78903c224b8");
}

TEST(Messages, Md5MatchesPropheseeAndEventCameraMsgs) {
  // prophesee_event_msgs/EventArray (prophesee_ros_driver) is field for field dvs_msgs': the
  // same sums. event_camera_msgs/EventPacket (ROS 1 definition, libcaer_driver and
  // metavision_driver); both sums computed with genmsg from the upstream .msg files.
  EXPECT_STREQ(ros::message_traits::md5sum<ebslam_msgs::EventArray>(),
               "5e8beee5a6c107e504c2e78903c224b8");
  EXPECT_STREQ(ros::message_traits::md5sum<ebslam_msgs::EventPacket>(),
               "8a6101b351a64529ac77bd8b71074e52");
}

TEST(Messages, EventPacketRoundTrip) {
  ebslam_msgs::EventPacket in;
  in.header = makeHeader("prophesee_optical_frame");
  in.width = 1280;
  in.height = 720;
  in.seq = 59068;
  in.time_base = 1702306974272224018ull;
  in.encoding = "evt3";
  in.events = {0x00, 0x80, 0x05, 0x60, 0xFF};
  const auto out = roundTrip(in);
  EXPECT_EQ(out, in);
  EXPECT_EQ(out.time_base, 1702306974272224018ull);
}

TEST(Messages, EventArrayRoundTrip) {
  ebslam_msgs::EventArray in;
  in.header = makeHeader("edvs_optical_frame");
  in.width = 128;
  in.height = 128;
  in.events = {makeEvent(0, 0, 1, 2, true), makeEvent(127, 127, 3, 999999999, false),
               makeEvent(5, 77, 4, 0, true)};
  const auto out = roundTrip(in);
  EXPECT_EQ(out, in);
  ASSERT_EQ(out.events.size(), 3u);
  EXPECT_EQ(out.events[1].x, 127);
  EXPECT_EQ(out.events[1].ts, ros::Time(3, 999999999));
  EXPECT_FALSE(out.events[1].polarity);
  EXPECT_EQ(out.header.frame_id, "edvs_optical_frame");
}

TEST(Messages, DepthEventArrayRoundTrip) {
  ebslam_msgs::DepthEventArray in;
  in.header = makeHeader("edvs_optical_frame");
  in.width = 128;
  in.height = 128;
  ebslam_msgs::DepthEvent event;
  event.x = 12;
  event.y = 34;
  event.ts = ros::Time(10, 20);
  event.polarity = true;
  event.depth = 1.25f;
  event.point.x = -0.1f;
  event.point.y = 0.2f;
  event.point.z = 1.25f;
  in.events.push_back(event);
  event.depth = std::nanf("");  // no depth known: NaN must survive serialisation
  event.point.x = event.point.y = event.point.z = std::nanf("");
  in.events.push_back(event);
  const auto out = roundTrip(in);
  ASSERT_EQ(out.events.size(), 2u);
  EXPECT_EQ(out.events[0], in.events[0]);
  EXPECT_TRUE(std::isnan(out.events[1].depth));
  EXPECT_TRUE(std::isnan(out.events[1].point.z));
  EXPECT_EQ(out.events[1].x, 12);
}

TEST(Messages, SuperpixelArrayRoundTrip) {
  ebslam_msgs::SuperpixelArray in;
  in.header = makeHeader("camera_rgb_optical_frame");
  in.width = 640;
  in.height = 480;
  for (uint32_t i = 0; i < 3; ++i) {
    ebslam_msgs::Superpixel sp;
    sp.id = i;
    sp.u = 10.5f * i;
    sp.v = 20.25f;
    sp.pixel_count = 100 + i;
    sp.color.r = 0.5f;
    sp.color.g = 0.25f;
    sp.color.b = 0.125f;
    sp.color.a = 1.0f;
    sp.position.x = 0.1 * i;
    sp.position.z = 1.5;
    sp.normal.z = -1.0;
    sp.radius = 0.02f;
    sp.area = 0.0012f;
    sp.thickness = 0.001f;
    sp.eccentricity = 1.3f;
    in.superpixels.push_back(sp);
  }
  ebslam_msgs::SuperpixelEdge edge;
  edge.a = 0;
  edge.b = 2;
  edge.weight = 0.75f;
  in.edges.push_back(edge);
  const auto out = roundTrip(in);
  EXPECT_EQ(out, in);
  EXPECT_EQ(out.superpixels[2].pixel_count, 102u);
  EXPECT_EQ(out.edges[0].b, 2u);
}

TEST(Messages, SegmentationRoundTrip) {
  ebslam_msgs::Segmentation in;
  in.header = makeHeader("camera_rgb_optical_frame");
  in.segment_ids = {0, 0, 1, -1};
  in.strand_ids = {17, 18, 19, 20};
  ebslam_msgs::SuperpixelEdge edge;
  edge.a = 1;
  edge.b = 2;
  edge.weight = 0.9f;
  in.ultrametric.push_back(edge);
  in.threshold = 0.4f;
  const auto out = roundTrip(in);
  EXPECT_EQ(out, in);
  EXPECT_EQ(out.segment_ids[3], -1);
  EXPECT_FLOAT_EQ(out.threshold, 0.4f);
}

TEST(Messages, TruncatedBufferIsRejected) {
  ebslam_msgs::EventArray in;
  in.header = makeHeader("edvs_optical_frame");
  in.events.resize(4);
  const uint32_t size = ros::serialization::serializationLength(in);
  std::vector<uint8_t> buffer(size);
  ros::serialization::OStream out_stream(buffer.data(), size);
  ros::serialization::serialize(out_stream, in);
  ebslam_msgs::EventArray out;
  ros::serialization::IStream in_stream(buffer.data(), size - 3);
  EXPECT_THROW(ros::serialization::deserialize(in_stream, out),
               ros::serialization::StreamOverrunException);
}

}  // namespace
