// Every event input type through one consumer node (each .test runs the cases of its node with
// --gtest_filter), one node instance per case namespace (~cases). For each case the test publishes
// a real or synthetic stream on <case>/events with the message type a camera driver publishes
// (through topic_tools::ShapeShifter: the datatype string of the driver's own package, as a user's
// driver or bag sends it) and checks the node's output content, frame and stamps against what the
// decoded stream predicts:
//   dvs           DAVIS 640x480 events (the libcaer recording) as dvs_msgs/EventArray
//   prophesee     Prophesee 1280x720 events (the evt3 recording) as prophesee_event_msgs/EventArray
//   evt3, libcaer event_camera_msgs/EventPacket, the real recordings in test/data/event_packets
//   libcaer_cmp, mono  the libcaer recording re-encoded
//   rpg_davis240  the Event Camera Dataset's DAVIS240C shapes_rotation (../shared/data/rpg-events)
//                 as dvs_msgs/EventArray; skipped when that data is absent
//   synthetic128_dvs, synthetic128_mono, synthetic128_prophesee  a 128x128 ceiling for the pose
//                 filters (dvs / mono packets / prophesee)

#include <ebslam/events/event_denoiser.h>
#include <ebslam/events/event_io.h>
#include <ebslam/events/event_packet.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/EventPacket.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <topic_tools/shape_shifter.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "ebslam_msgs/event_packet_conversions.h"
#include "event_packet_encoders.h"
#include "rostest_util.h"

namespace {

const std::string kPacketDir = EVENT_PACKETS_DIR;
const std::string kRpgEvents =
    std::string(SHARED_DATA_DIR) + "/rpg-events/shapes_rotation/events.txt";

// One case: the messages as published (serialised, with the driver's datatype) and the
// EventArrays the node sees after the input layer's conversion.
struct Stream {
  std::string datatype;
  std::string md5;
  std::string definition;
  std::vector<std::vector<std::uint8_t>> messages;
  std::vector<ebslam_msgs::EventArray> expected;
};

template <class M>
std::vector<std::uint8_t> serialize(const M& msg) {
  std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(msg));
  ros::serialization::OStream out(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::serialize(out, msg);
  return bytes;
}

void addArrays(Stream& s, const std::string& datatype,
               const std::vector<ebslam_msgs::EventArray>& arrays) {
  s.datatype = datatype;
  s.md5 = ros::message_traits::md5sum<ebslam_msgs::EventArray>();
  s.definition = ros::message_traits::definition<ebslam_msgs::EventArray>();
  for (const auto& a : arrays) {
    s.messages.push_back(serialize(a));
    s.expected.push_back(a);
  }
}

void addPackets(Stream& s, const std::vector<ebslam_msgs::EventPacket>& packets) {
  s.datatype = "event_camera_msgs/EventPacket";
  s.md5 = ros::message_traits::md5sum<ebslam_msgs::EventPacket>();
  s.definition = ros::message_traits::definition<ebslam_msgs::EventPacket>();
  ebslam_msgs::EventPacketConverter converter;
  for (const auto& p : packets) {
    s.messages.push_back(serialize(p));
    s.expected.push_back(converter.toEventArray(p));
  }
}

std::vector<ebslam_msgs::EventPacket> readPackets(const std::string& file) {
  std::vector<ebslam_msgs::EventPacket> out;
  for (const auto& p : ebslam::readEventPacketFile(kPacketDir + "/" + file)) {
    out.push_back(ebslam_msgs::toMsg(p));
  }
  return out;
}

// The recording's packets decoded one by one (as EventArrays, in ROS time).
std::vector<ebslam_msgs::EventArray> decoded(const std::string& file) {
  ebslam_msgs::EventPacketConverter converter;
  std::vector<ebslam_msgs::EventArray> arrays;
  for (const auto& p : readPackets(file)) arrays.push_back(converter.toEventArray(p));
  return arrays;
}

// The libcaer recording re-encoded packet by packet (time_base = first event, as the drivers).
std::vector<ebslam_msgs::EventPacket> reencoded(ebslam::EventEncoding encoding) {
  std::vector<ebslam_msgs::EventPacket> out;
  ebslam::EventPacketDecoder decoder(ebslam::EventEncoding::kLibcaer, {640, 480});
  for (auto p : readPackets("libcaer_rollover_640x480.evpk")) {
    ebslam::PacketEventVector events;
    decoder.decode(p.events.data(), p.events.size(), p.time_base, events);
    p.time_base = events.front().t_ns;
    p.events = encoding == ebslam::EventEncoding::kMono
                   ? test_encoders::mono(events, p.time_base)
                   : test_encoders::libcaerCmp(events, p.time_base);
    p.encoding = ebslam::eventEncodingName(encoding);
    out.push_back(p);
  }
  return out;
}

// 128x128 events on a few rows and columns (a ceiling's edges), 2000 per message at 100 Hz.
std::vector<ebslam_msgs::EventArray> synthetic128() {
  std::vector<ebslam_msgs::EventArray> arrays;
  std::mt19937 rng(3);
  std::int64_t t = 1'700'000'000'000'000;
  for (int m = 0; m < 10; ++m) {
    ebslam::EventVector events;
    for (int i = 0; i < 2000; ++i, t += 5) {
      const int line = static_cast<int>(rng() % 6);
      const int along = static_cast<int>(rng() % 128);
      const auto pos = static_cast<std::uint16_t>(20 + 18 * line);
      const bool row = (rng() & 1u) != 0;
      events.push_back({t, row ? static_cast<std::uint16_t>(along) : pos,
                        row ? pos : static_cast<std::uint16_t>(along), (rng() & 1u) != 0});
    }
    arrays.push_back(ebslam_msgs::toMsg(events, {128, 128}, "edvs_optical_frame"));
  }
  return arrays;
}

// The first 20000 events of shapes_rotation in arrays of 1000, as rpg_dvs_ros publishes them.
std::vector<ebslam_msgs::EventArray> rpgDavis240() {
  ebslam::EventReadOptions options;
  options.format = ebslam::EventFileFormat::kRpgText;
  options.sensor = ebslam::SensorSize{240, 180};
  const ebslam::EventReadResult read = ebslam::readEventFile(kRpgEvents, options);
  std::vector<ebslam_msgs::EventArray> arrays;
  const std::int64_t epoch_us = 1'700'000'000'000'000;  // the dataset starts near t = 0
  for (std::size_t begin = 0; begin + 1000 <= std::min<std::size_t>(20000, read.events.size());
       begin += 1000) {
    ebslam::EventVector batch(read.events.begin() + static_cast<long>(begin),
                              read.events.begin() + static_cast<long>(begin + 1000));
    for (auto& e : batch) e.t_us += epoch_us;
    arrays.push_back(ebslam_msgs::toMsg(batch, {240, 180}, "davis_optical_frame"));
  }
  return arrays;
}

bool haveRpg() { return std::ifstream(kRpgEvents).good(); }

Stream makeStream(const std::string& name) {
  Stream s;
  if (name == "dvs") {
    addArrays(s, "dvs_msgs/EventArray", decoded("libcaer_rollover_640x480.evpk"));
  } else if (name == "prophesee") {
    addArrays(s, "prophesee_event_msgs/EventArray", decoded("evt3_prophesee_1280x720.evpk"));
  } else if (name == "evt3") {
    addPackets(s, readPackets("evt3_prophesee_1280x720.evpk"));
  } else if (name == "libcaer") {
    addPackets(s, readPackets("libcaer_rollover_640x480.evpk"));
  } else if (name == "libcaer_cmp") {
    addPackets(s, reencoded(ebslam::EventEncoding::kLibcaerCmp));
  } else if (name == "mono") {
    addPackets(s, reencoded(ebslam::EventEncoding::kMono));
  } else if (name == "rpg_davis240") {
    addArrays(s, "dvs_msgs/EventArray", rpgDavis240());
  } else if (name == "synthetic128_dvs") {
    addArrays(s, "dvs_msgs/EventArray", synthetic128());
  } else if (name == "synthetic128_prophesee") {
    addArrays(s, "prophesee_event_msgs/EventArray", synthetic128());
  } else if (name == "synthetic128_mono") {
    std::vector<ebslam_msgs::EventPacket> packets;
    for (const auto& a : synthetic128()) {
      packets.push_back(
          ebslam_msgs::toMonoPacket(ebslam_msgs::fromMsg(a), {128, 128}, a.header.frame_id));
    }
    addPackets(s, packets);
  } else {
    ADD_FAILURE() << "unknown case " << name;
  }
  return s;
}

// Publishes the stream on <ns>/events with its datatype, once the node has subscribed.
class StreamPublisher {
 public:
  StreamPublisher(ros::NodeHandle& nh, const std::string& ns, const Stream& stream)
      : stream_(stream) {
    shape_.morph(stream.md5, stream.datatype, stream.definition, "");
    pub_ = shape_.advertise(nh, ns + "/events", 1000);
  }
  bool waitForSubscriber() {
    // ~input_type auto: the node follows the publisher's type within its 2 s probe.
    const bool ok = ebslam_ros_test::spinUntil([&] { return pub_.getNumSubscribers() > 0; }, 15.0);
    ros::WallDuration(0.3).sleep();
    return ok;
  }
  void publish(std::size_t i) {
    topic_tools::ShapeShifter msg;
    msg.morph(stream_.md5, stream_.datatype, stream_.definition, "");
    auto bytes = stream_.messages[i];
    ros::serialization::IStream in(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    msg.read(in);
    pub_.publish(msg);
  }

 private:
  const Stream& stream_;
  topic_tools::ShapeShifter shape_;
  ros::Publisher pub_;
};

std::vector<std::string> cases() {
  std::vector<std::string> names;
  ros::param::get("~cases", names);
  return names;
}

// --- EventDenoiser: one output per input, its header and size, and the events the core filter
// passes (default configuration) -----------------------------------------------------------

void denoiseCase(const std::string& name) {
  ros::NodeHandle nh;
  const Stream stream = makeStream(name);
  std::vector<ebslam_msgs::EventArray> outputs;
  auto sub = nh.subscribe<ebslam_msgs::EventArray>(
      name + "/events_denoised", 1000,
      [&](const ebslam_msgs::EventArray::ConstPtr& m) { outputs.push_back(*m); });
  StreamPublisher pub(nh, name, stream);
  ASSERT_TRUE(pub.waitForSubscriber()) << "the denoiser did not subscribe " << name;
  for (std::size_t i = 0; i < stream.messages.size(); ++i) pub.publish(i);
  ASSERT_TRUE(
      ebslam_ros_test::spinUntil([&] { return outputs.size() >= stream.expected.size(); }, 20.0))
      << outputs.size() << " of " << stream.expected.size() << " outputs";
  const auto& first = stream.expected.front();
  ebslam::BackgroundActivityFilter filter(ebslam::BackgroundActivityFilterConfig{},
                                          {first.width, first.height});
  std::size_t in = 0, passed = 0;
  for (std::size_t i = 0; i < stream.expected.size(); ++i) {
    const auto& exp = stream.expected[i];
    const auto& out = outputs[i];
    EXPECT_EQ(out.header.stamp, exp.header.stamp) << i;
    EXPECT_EQ(out.header.frame_id, exp.header.frame_id);
    EXPECT_EQ(out.width, exp.width);
    EXPECT_EQ(out.height, exp.height);
    ebslam::EventVector events = ebslam_msgs::fromMsg(exp);
    filter.filterInPlace(events);
    ASSERT_EQ(ebslam_msgs::fromMsg(out), events) << "message " << i;
    in += exp.events.size();
    passed += events.size();
  }
  EXPECT_GT(in, 0u);
  EXPECT_GT(passed, 0u) << "the recording's edges should pass the filter";
  std::printf("denoiser %s: %zu messages, %zu events in, %zu passed\n", name.c_str(),
              stream.expected.size(), in, passed);
}

TEST(EventInput, DenoiserOutputsWhatTheCoreFilterPasses) {
  for (const std::string& name : cases()) {
    if (name == "rpg_davis240") continue;  // RealDavis240ThroughTheDenoiser
    SCOPED_TRACE(name);
    denoiseCase(name);
  }
}

TEST(EventInput, RealDavis240ThroughTheDenoiser) {
  if (!haveRpg()) {
    GTEST_SKIP() << "reads the Event Camera Dataset's shapes_rotation in ../shared/data/rpg-events";
  }
  denoiseCase("rpg_davis240");
}

// --- EventRenderer: the image of the last ~accumulation_time of events, its size from the
// message -----------------------------------------------------------------------------------

sensor_msgs::Image expectedImage(const Stream& stream, double accumulation_s,
                                 const std::array<int, 3>& on, const std::array<int, 3>& off) {
  const auto& last = stream.expected.back();
  sensor_msgs::Image image;
  for (const auto& a : stream.expected) {
    if (!a.events.empty()) image.header.stamp = a.events.back().ts;
  }
  image.header.frame_id = last.header.frame_id;
  image.width = last.width;
  image.height = last.height;
  image.step = 3 * image.width;
  image.data.assign(static_cast<std::size_t>(image.step) * image.height, 0);
  const ros::Time oldest = image.header.stamp - ros::Duration(accumulation_s);
  for (const auto& a : stream.expected) {
    for (const auto& e : a.events) {
      if (e.ts < oldest) continue;
      const auto& rgb = e.polarity ? on : off;
      std::uint8_t* p = &image.data[static_cast<std::size_t>(e.y) * image.step + 3 * e.x];
      p[0] = static_cast<std::uint8_t>(rgb[2]);
      p[1] = static_cast<std::uint8_t>(rgb[1]);
      p[2] = static_cast<std::uint8_t>(rgb[0]);
    }
  }
  return image;
}

void renderCase(const std::string& name) {
  ros::NodeHandle nh;
  double accumulation_s = 0.05;
  ros::param::get("~accumulation_time", accumulation_s);
  const Stream stream = makeStream(name);
  sensor_msgs::Image::ConstPtr image;
  ros::Time newest;
  for (const auto& a : stream.expected) {
    if (!a.events.empty()) newest = a.events.back().ts;
  }
  auto sub = nh.subscribe<sensor_msgs::Image>(name + "/event_image", 5,
                                              [&](const sensor_msgs::Image::ConstPtr& m) {
                                                if (m->header.stamp == newest) image = m;
                                              });
  StreamPublisher pub(nh, name, stream);
  ASSERT_TRUE(pub.waitForSubscriber()) << "the renderer did not subscribe " << name;
  for (std::size_t i = 0; i < stream.messages.size(); ++i) pub.publish(i);
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return image != nullptr; }, 20.0))
      << "no image stamped with the last event";
  const sensor_msgs::Image expected =
      expectedImage(stream, accumulation_s, {255, 255, 255}, {255, 0, 0});
  EXPECT_EQ(image->header.frame_id, expected.header.frame_id);
  ASSERT_EQ(image->width, expected.width);
  ASSERT_EQ(image->height, expected.height);
  EXPECT_EQ(image->encoding, "bgr8");
  std::size_t lit = 0, differ = 0;
  for (std::size_t i = 0; i < expected.data.size(); i += 3) {
    lit += expected.data[i] || expected.data[i + 1] || expected.data[i + 2];
    differ += image->data[i] != expected.data[i] || image->data[i + 1] != expected.data[i + 1] ||
              image->data[i + 2] != expected.data[i + 2];
  }
  EXPECT_EQ(differ, 0u) << "pixels differing from the decoded events";
  EXPECT_GT(lit, 100u);
  std::printf("renderer %s: %ux%u, %zu event pixels\n", name.c_str(), image->width, image->height,
              lit);
}

TEST(EventInput, RendererDrawsTheDecodedEvents) {
  for (const std::string& name : cases()) {
    SCOPED_TRACE(name);
    if (name == "rpg_davis240") continue;  // RealDavis240 below
    renderCase(name);
  }
}

TEST(EventInput, RealDavis240ThroughTheRenderer) {
  if (!haveRpg()) {
    GTEST_SKIP() << "reads the Event Camera Dataset's shapes_rotation in ../shared/data/rpg-events";
  }
  renderCase("rpg_davis240");
}

// --- EventParticleFilter / EventSlam2d: a pose per message, stamped with its last event, in map;
// the same events give the same poses whatever type carried them --------------------------

TEST(EventInput, PoseFiltersGiveTheSamePosesForEveryType) {
  ros::NodeHandle nh;
  std::vector<std::vector<geometry_msgs::PoseWithCovarianceStamped>> results;
  for (const std::string& name : cases()) {
    SCOPED_TRACE(name);
    const Stream stream = makeStream(name);
    std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
    auto sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
        name + "/pose", 100,
        [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poses.push_back(*m); });
    StreamPublisher pub(nh, name, stream);
    ASSERT_TRUE(pub.waitForSubscriber()) << "the filter did not subscribe " << name;
    for (std::size_t i = 0; i < stream.messages.size(); ++i) {
      pub.publish(i);
      const ros::Time stamp = stream.expected[i].events.back().ts;
      ASSERT_TRUE(ebslam_ros_test::spinUntil(
          [&] { return !poses.empty() && poses.back().header.stamp == stamp; }, 5.0))
          << "no pose stamped with message " << i << "'s last event";
      EXPECT_EQ(poses.back().header.frame_id, "map");
    }
    results.push_back(poses);
  }
  // Seeded filters on identical events: identical poses.
  for (std::size_t k = 1; k < results.size(); ++k) {
    ASSERT_EQ(results[k].size(), results[0].size());
    for (std::size_t i = 0; i < results[0].size(); ++i) {
      EXPECT_EQ(results[k][i].header.stamp, results[0][i].header.stamp);
      EXPECT_EQ(results[k][i].pose.pose.position.x, results[0][i].pose.pose.position.x);
      EXPECT_EQ(results[k][i].pose.pose.position.y, results[0][i].pose.pose.position.y);
      EXPECT_EQ(results[k][i].pose.pose.orientation.z, results[0][i].pose.pose.orientation.z);
    }
  }
}

// --- DepthEventFusion: the flat test calibration over a plane 1.5 m away; every event of every
// message fused at that depth, stamped and framed as its input, the same for every type -------

TEST(EventInput, FusionFusesEveryTypeAlike) {
  ros::NodeHandle nh;
  std::vector<std::vector<ebslam_msgs::DepthEventArray>> results;
  for (const std::string& name : cases()) {
    SCOPED_TRACE(name);
    Stream stream = makeStream(name);
    stream.messages.resize(2);  // 2 x 2000 events over 20 ms
    stream.expected.resize(2);
    std::vector<ebslam_msgs::DepthEventArray> outputs;
    auto sub = nh.subscribe<ebslam_msgs::DepthEventArray>(
        name + "/depth_events", 100,
        [&](const ebslam_msgs::DepthEventArray::ConstPtr& m) { outputs.push_back(*m); });
    auto depth_pub = nh.advertise<sensor_msgs::Image>(name + "/depth_registered/image_raw", 10);
    auto info_pub =
        nh.advertise<sensor_msgs::CameraInfo>(name + "/depth_registered/camera_info", 10, true);
    StreamPublisher pub(nh, name, stream);
    ASSERT_TRUE(pub.waitForSubscriber()) << "the fusion did not subscribe " << name;
    ASSERT_TRUE(
        ebslam_ros_test::spinUntil([&] { return depth_pub.getNumSubscribers() > 0; }, 10.0));
    const ros::Time first = stream.expected.front().events.front().ts;
    sensor_msgs::CameraInfo info;
    info.header.stamp = first;
    info.header.frame_id = "camera_depth_optical_frame";
    info.width = 160;
    info.height = 120;
    info.K = {130.0, 0.0, 79.5, 0.0, 130.0, 59.5, 0.0, 0.0, 1.0};
    info_pub.publish(info);
    for (const double dt : {-0.005, 0.028}) {  // frames before and after the events
      sensor_msgs::Image image;
      image.header.stamp = first + ros::Duration(dt);
      image.header.frame_id = "camera_depth_optical_frame";
      image.width = 160;
      image.height = 120;
      image.encoding = "16UC1";
      image.step = 320;
      image.data.resize(320 * 120);
      const std::uint16_t mm = 1500;
      for (std::size_t i = 0; i < 160 * 120; ++i) std::memcpy(&image.data[2 * i], &mm, 2);
      depth_pub.publish(image);
    }
    ros::WallDuration(0.2).sleep();
    for (std::size_t i = 0; i < stream.messages.size(); ++i) pub.publish(i);
    ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return outputs.size() >= 2; }, 20.0))
        << outputs.size() << " outputs";
    for (std::size_t i = 0; i < 2; ++i) {
      const auto& in = stream.expected[i];
      const auto& out = outputs[i];
      EXPECT_EQ(out.header.stamp, in.header.stamp);
      EXPECT_EQ(out.header.frame_id, in.header.frame_id);
      ASSERT_EQ(out.events.size(), in.events.size());
      for (std::size_t k = 0; k < in.events.size(); ++k) {
        EXPECT_EQ(out.events[k].ts, in.events[k].ts);
        EXPECT_EQ(out.events[k].x, in.events[k].x);
        ASSERT_NEAR(out.events[k].depth, 1.5, 0.015) << k;
      }
    }
    results.push_back(outputs);
  }
  for (std::size_t k = 1; k < results.size(); ++k) {
    ASSERT_EQ(results[k].size(), results[0].size());
    for (std::size_t i = 0; i < results[0].size(); ++i) EXPECT_EQ(results[k][i], results[0][i]);
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_input_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
