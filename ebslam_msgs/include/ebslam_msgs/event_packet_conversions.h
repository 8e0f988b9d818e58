#pragma once

// The conversions of ebslam_msgs/EventPacket (field for field event_camera_msgs/EventPacket, the
// message of libcaer_driver and metavision_driver) beside event_conversions.h's of EventArray:
// decoding a stream of packets (evt3, libcaer_cmp, libcaer, mono) into events in the same time
// convention (ROS time, t_us since the ROS epoch), writing events as a `mono` packet, and reading
// any recorded event message (EventArray or EventPacket) from a bag.
// Details: docs/ros_nodes_notes.md#event-conversions

#include <ebslam/events/event.h>
#include <ebslam/events/event_packet.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/EventPacket.h>

#include <cstdint>
#include <optional>
#include <string>

#include "ebslam_msgs/event_conversions.h"

namespace ebslam_msgs {

/// ebslam_msgs/EventPacket (= event_camera_msgs/EventPacket) <-> the ROS-free packet.
ebslam::EventPacket toPacket(const EventPacket& msg);
EventPacket toMsg(const ebslam::EventPacket& packet);

/// What one EventPacket gave (see EventPacketConverter).
struct EventPacketResult {
  bool rejected = false;  ///< the whole packet was dropped (unknown encoding or bad size): `error`
  std::string error;
  ebslam::SensorSize sensor;        ///< width x height of the packet
  ebslam::PacketDecodeStats stats;  ///< decoder counts (dropped bytes, events outside)
  std::size_t bad_time = 0;         ///< events dropped: time outside ros::Time
};

/// Decodes one stream of EventPacket messages (evt3, libcaer, libcaer_cmp, mono; the decoders of
/// ebslam/events/event_packet.h) into events in ROS time [us]: libcaer(_cmp) times are host
/// time already; evt3 and mono sensor time is anchored at the first packet's header.stamp (and
/// again after the sensor clock restarts). Keeps decoder state per stream: one converter per
/// subscribed topic; a new encoding or sensor size restarts it. Never throws for message
/// content: a packet that cannot be decoded is rejected with a reason.
class EventPacketConverter {
 public:
  /// Appends the events of msg to out.
  EventPacketResult append(const EventPacket& msg, ebslam::EventVector& out);
  /// msg as one EventArray (header: msg's frame and, as for every EventArray, the stamp of the
  /// last event; msg's stamp when it holds none; width x height from msg).
  EventArray toEventArray(const EventPacket& msg, EventPacketResult* result = nullptr);
  void reset();

 private:
  std::optional<ebslam::EventPacketDecoder> decoder_;
  ebslam::EventPacketClock clock_;
  ebslam::PacketEventVector decoded_;
};

/// Event messages in a bag: ebslam_msgs/EventArray, dvs_msgs/EventArray,
/// prophesee_event_msgs/EventArray (one MD5), ebslam_msgs/EventPacket and
/// event_camera_msgs/EventPacket (one MD5).
bool isEventArrayDatatype(const std::string& datatype);
bool isEventPacketDatatype(const std::string& datatype);

/// Appends the events of one recorded event message (a rosbag::MessageInstance, or anything with
/// its getDataType() and instantiate<M>(); a template so that this library needs no rosbag) to
/// out; `converter` decodes the packets of that message's stream (one per topic). Returns the
/// message's sensor size, nullopt for a message of another type or an undecodable packet (then
/// *error, when given, says why).
template <class RecordedMessage>
std::optional<ebslam::SensorSize> appendRecordedEvents(const RecordedMessage& m,
                                                       EventPacketConverter& converter,
                                                       ebslam::EventVector& out,
                                                       std::string* error = nullptr) {
  const std::string datatype = m.getDataType();
  if (isEventArrayDatatype(datatype)) {
    const auto msg = m.template instantiate<EventArray>();
    if (msg) return appendFromMsg(*msg, out);
  } else if (isEventPacketDatatype(datatype)) {
    const auto msg = m.template instantiate<EventPacket>();
    if (msg) {
      const EventPacketResult result = converter.append(*msg, out);
      if (!result.rejected) return result.sensor;
      if (error != nullptr) *error = result.error;
    }
  }
  return std::nullopt;
}

/// Events (t_us since the ROS epoch, in order) -> one `mono` EventPacket (time_base and
/// header.stamp = the first event's time, as the drivers stamp a packet). Throws
/// std::invalid_argument for events more than 4.29 s apart (mono's 32-bit ns offsets) or
/// outside the sensor or ros::Time.
EventPacket toMonoPacket(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                         const std::string& frame_id, std::uint64_t seq = 0);

}  // namespace ebslam_msgs
