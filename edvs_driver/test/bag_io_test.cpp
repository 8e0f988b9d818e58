// Event bags (bag_io.h) and the driver's parameter validation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <rosbag/bag.h>
#include <topic_tools/shape_shifter.h>

#include <filesystem>

#include "ebslam/events/event_packet.h"
#include "ebslam_msgs/event_packet_conversions.h"

#include "ebslam/events/event_io.h"
#include "edvs/emulator.h"
#include "edvs_driver/bag_io.h"
#include "edvs_driver/ros_params.h"

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          (name + "_" + std::to_string(::getpid()) + "_" +
           std::to_string(std::chrono::steady_clock::now().time_since_epoch().count())))
      .string();
}

ebslam::EventVector sampleEvents(std::int64_t offset_us) {
  ebslam::EventVector events = edvs::generateEvents(5, 20000, 2000);
  for (auto& e : events) e.t_us += offset_us;
  return events;
}

}  // namespace

TEST(BagIo, WriteReadRoundTripAndConvertThroughBinary) {
  const ebslam::EventVector events = sampleEvents(1000);
  const std::string bag = tempPath("events.bag");
  edvs_driver::BagWriteOptions options;
  options.topic = "/edvs/events";
  options.batch_us = 5000;
  edvs_driver::writeEventBag(bag, events, ebslam::SensorSize{128, 128}, options);
  const auto read = edvs_driver::readEventBag(bag);
  EXPECT_EQ(read.events, events);
  EXPECT_EQ(read.sensor.width, 128u);
  ASSERT_EQ(read.topics.size(), 1u);
  EXPECT_EQ(read.topics[0], "/edvs/events");
  const double span_ms = (events.back().t_us - events.front().t_us) / 1000.0;
  EXPECT_NEAR(static_cast<double>(read.messages), span_ms / 5.0, span_ms / 5.0 * 0.2 + 2);
  EXPECT_THROW(edvs_driver::readEventBag(bag, "/other"), std::runtime_error);

  // bag -> project binary -> bag: identical events.
  const std::string bin = tempPath("events.ebe");
  ebslam::writeEventFile(bin, read.events, read.sensor, ebslam::EventFileFormat::kBinary);
  const auto from_bin = ebslam::readEventFile(bin);
  ASSERT_FALSE(from_bin.error.has_value());
  const std::string bag2 = tempPath("events2.bag");
  edvs_driver::writeEventBag(bag2, from_bin.events, from_bin.sensor);
  EXPECT_EQ(edvs_driver::readEventBag(bag2, "/events").events, events);
  for (const auto& p : {bag, bin, bag2}) std::filesystem::remove(p);

  EXPECT_THROW(edvs_driver::readEventBag("/nonexistent/x.bag"), std::runtime_error);
  options.batch_us = 0;
  EXPECT_THROW(edvs_driver::writeEventBag(bag, events, {}, options), std::invalid_argument);
}

// Writes msg into the bag under another package's datatype (same MD5), as a recorder of that
// driver's topic does.
template <class M>
void writeAs(rosbag::Bag& bag, const std::string& topic, const std::string& datatype,
             const M& msg) {
  std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(msg));
  ros::serialization::OStream out(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::serialize(out, msg);
  topic_tools::ShapeShifter shape;
  shape.morph(ros::message_traits::md5sum<M>(), datatype, ros::message_traits::definition<M>(), "");
  ros::serialization::IStream in(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  shape.read(in);
  bag.write(topic, std::max(msg.header.stamp, ros::TIME_MIN), shape);
}

// Bags of prophesee_ros_driver (prophesee_event_msgs/EventArray) and of libcaer_driver /
// metavision_driver (event_camera_msgs/EventPacket: the real evt3 and libcaer recordings) read
// as the driver recorded them: every event, decoder state per topic.
TEST(BagIo, ReadsPropheseeArraysAndEventPackets) {
  const std::string dir = EVENT_PACKETS_DIR;
  const auto evt3 = ebslam::readEventPacketFile(dir + "/evt3_prophesee_1280x720.evpk");
  const auto libcaer = ebslam::readEventPacketFile(dir + "/libcaer_rollover_640x480.evpk");
  ebslam_msgs::EventPacketConverter expect_evt3, expect_libcaer;
  ebslam::EventVector evt3_events, libcaer_events;
  const std::string bag_path = tempPath("drivers.bag");
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    // Interleaved topics: each keeps its own decoder.
    for (std::size_t i = 0; i < std::max(evt3.size(), libcaer.size()); ++i) {
      if (i < evt3.size()) {
        const auto msg = ebslam_msgs::toMsg(evt3[i]);
        ASSERT_FALSE(expect_evt3.append(msg, evt3_events).rejected);
        writeAs(bag, "/prophesee/events", "event_camera_msgs/EventPacket", msg);
      }
      if (i < libcaer.size()) {
        const auto msg = ebslam_msgs::toMsg(libcaer[i]);
        ASSERT_FALSE(expect_libcaer.append(msg, libcaer_events).rejected);
        writeAs(bag, "/davis/events", "event_camera_msgs/EventPacket", msg);
      }
    }
    // The evt3 events once more as prophesee_ros_driver publishes them.
    ebslam::EventVector first(evt3_events.begin(), evt3_events.begin() + 5000);
    writeAs(bag, "/prophesee_driver/cd_events_buffer", "prophesee_event_msgs/EventArray",
            ebslam_msgs::toMsg(first, {1280, 720}, "prophesee_optical_frame"));
  }
  EXPECT_EQ(evt3_events.size(), 34134u);
  EXPECT_EQ(libcaer_events.size(), 38422u);
  const auto p = edvs_driver::readEventBag(bag_path, "/prophesee/events");
  EXPECT_EQ(p.events, evt3_events);
  EXPECT_EQ(p.sensor.width, 1280u);
  EXPECT_EQ(p.sensor.height, 720u);
  EXPECT_EQ(p.messages, evt3.size());
  const auto d = edvs_driver::readEventBag(bag_path, "/davis/events");
  EXPECT_EQ(d.events, libcaer_events);
  EXPECT_EQ(d.sensor.width, 640u);
  EXPECT_EQ(d.rejected_packets, 0u);
  const auto a = edvs_driver::readEventBag(bag_path, "/prophesee_driver/cd_events_buffer");
  EXPECT_EQ(a.events, ebslam::EventVector(evt3_events.begin(), evt3_events.begin() + 5000));
  EXPECT_EQ(edvs_driver::readEventBag(bag_path).topics.size(), 3u);
  std::filesystem::remove(bag_path);
}

TEST(RosParams, ValidateNamesTheParameter) {
  edvs_driver::DriverParams p;
  EXPECT_NO_THROW(edvs_driver::validate(p));
  auto expectBad = [](edvs_driver::DriverParams q, const std::string& name) {
    try {
      edvs_driver::validate(q);
      ADD_FAILURE() << "accepted bad " << name;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  auto q = p;
  q.publish_rate_hz = 0;
  q.batch_size = 0;
  expectBad(q, "publish_rate");
  q = p;
  q.frame_id = "";
  expectBad(q, "frame_id");
  q = p;
  q.link.reconnect_max_s = 0.1;
  expectBad(q, "reconnect_max_delay");
  q = p;
  q.link.biases[2] = std::int64_t{1} << 24;
  expectBad(q, "bias_reqPd");
  q = p;
  q.link.stall_reconnect_s = 0.5;
  expectBad(q, "stall_reconnect_timeout");
}
