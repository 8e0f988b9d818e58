#pragma once

// Event bags: ebslam_msgs/EventArray messages in a rosbag <-> events. Together with
// ebslam/events/event_io.h (binary, text, Event Camera Dataset text) this makes `bag` one more
// event file format for edvs_event_convert.

#include <cstdint>
#include <string>
#include <vector>

#include "ebslam/events/event.h"

namespace edvs_driver {

struct BagReadResult {
  ebslam::EventVector events;  ///< all events of the selected topics, in bag (time) order
  ebslam::SensorSize sensor;   ///< from the first message (width/height)
  std::size_t messages = 0;
  std::size_t rejected_packets = 0;  ///< EventPackets that could not be decoded (e.g. encoding)
  std::vector<std::string> topics;   ///< topics that contributed
};

/// Reads every event message on `topic`, or on every topic of an event type when `topic` is
/// empty: ebslam_msgs/EventArray, dvs_msgs/EventArray, prophesee_event_msgs/EventArray (one
/// definition and MD5) and event_camera_msgs/EventPacket (evt3, libcaer_cmp, libcaer, mono;
/// ebslam_msgs/event_packet_conversions.h). Event times are microseconds since the ROS epoch.
/// Throws std::runtime_error if the bag cannot be read or holds no such messages.
BagReadResult readEventBag(const std::string& path, const std::string& topic = "");

struct BagWriteOptions {
  std::string topic = "/events";
  std::string frame_id = "edvs_optical_frame";
  /// Events per message are grouped by time windows of this length [us] (and at most
  /// max_events_per_message), like the driver publishing at 1e6 / batch_us Hz.
  std::int64_t batch_us = 10000;
  std::size_t max_events_per_message = 100000;
};

/// Writes events (times: microseconds since the ROS epoch, >= 0) as EventArray messages; each
/// message is recorded at its header stamp (the time of its last event). Throws
/// std::invalid_argument for negative times or bad options, std::runtime_error on I/O failure.
void writeEventBag(const std::string& path, const ebslam::EventVector& events,
                   const ebslam::SensorSize& sensor, const BagWriteOptions& options = {});

}  // namespace edvs_driver
