// Event bags (bag_io.h) and the driver's parameter validation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

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
