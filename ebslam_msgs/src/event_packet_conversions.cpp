#include "ebslam_msgs/event_packet_conversions.h"

#include <algorithm>
#include <stdexcept>

namespace ebslam_msgs {

namespace {
constexpr std::int64_t kMaxRosTimeUs = std::int64_t{4294967295} * 1000000 + 999999;
}  // namespace

bool isEventArrayDatatype(const std::string& datatype) {
  return datatype == "ebslam_msgs/EventArray" || datatype == "dvs_msgs/EventArray" ||
         datatype == "prophesee_event_msgs/EventArray";
}

bool isEventPacketDatatype(const std::string& datatype) {
  return datatype == "ebslam_msgs/EventPacket" || datatype == "event_camera_msgs/EventPacket";
}

ebslam::EventPacket toPacket(const EventPacket& msg) {
  ebslam::EventPacket p;
  p.stamp_ns = static_cast<std::int64_t>(msg.header.stamp.toNSec());
  p.frame_id = msg.header.frame_id;
  p.width = msg.width;
  p.height = msg.height;
  p.seq = msg.seq;
  p.time_base = msg.time_base;
  p.encoding = msg.encoding;
  p.is_bigendian = msg.is_bigendian;
  p.events = msg.events;
  return p;
}

EventPacket toMsg(const ebslam::EventPacket& packet) {
  EventPacket msg;
  msg.header.stamp.fromNSec(static_cast<std::uint64_t>(std::max<std::int64_t>(packet.stamp_ns, 0)));
  msg.header.frame_id = packet.frame_id;
  msg.width = packet.width;
  msg.height = packet.height;
  msg.seq = packet.seq;
  msg.time_base = packet.time_base;
  msg.encoding = packet.encoding;
  msg.is_bigendian = packet.is_bigendian;
  msg.events = packet.events;
  return msg;
}

void EventPacketConverter::reset() {
  decoder_.reset();
  clock_.reset();
}

EventPacketResult EventPacketConverter::append(const EventPacket& msg, ebslam::EventVector& out) {
  EventPacketResult result;
  result.sensor = ebslam::SensorSize{msg.width, msg.height};
  const std::optional<ebslam::EventEncoding> encoding = ebslam::eventEncodingFromName(msg.encoding);
  if (!encoding) {
    result.rejected = true;
    result.error = "unknown encoding \"" + msg.encoding.substr(0, 32) +
                   "\" (known: evt3, libcaer_cmp, libcaer, mono)";
    return result;
  }
  if (msg.width == 0 || msg.height == 0 || msg.width > 65536 || msg.height > 65536) {
    result.rejected = true;
    result.error = "sensor size " + std::to_string(msg.width) + "x" + std::to_string(msg.height) +
                   " is not in 1..65536";
    return result;
  }
  if (msg.is_bigendian) {
    // Every driver encodes on little-endian hosts; a big-endian byte order is not defined for
    // these encodings.
    result.rejected = true;
    result.error = "is_bigendian packets are not supported";
    return result;
  }
  if (!decoder_ || decoder_->encoding() != *encoding || decoder_->sensor().width != msg.width ||
      decoder_->sensor().height != msg.height) {
    decoder_.emplace(*encoding, result.sensor);
    clock_.reset();
  }
  decoded_.clear();
  result.stats = decoder_->decode(msg.events.data(), msg.events.size(), msg.time_base, decoded_);
  const std::size_t before = out.size();
  result.bad_time =
      clock_.append(*encoding, decoded_, static_cast<std::int64_t>(msg.header.stamp.toNSec()), out);
  // ros::Time ends in 2106; later times cannot be published.
  std::size_t kept = before;
  for (std::size_t i = before; i < out.size(); ++i) {
    if (out[i].t_us <= kMaxRosTimeUs) {
      out[kept++] = out[i];
    } else {
      ++result.bad_time;
    }
  }
  out.resize(kept);
  return result;
}

EventArray EventPacketConverter::toEventArray(const EventPacket& msg, EventPacketResult* result) {
  ebslam::EventVector events;
  EventPacketResult r = append(msg, events);
  EventArray out = toMsg(events, r.sensor, msg.header.frame_id);
  out.width = msg.width;
  out.height = msg.height;
  if (out.events.empty()) out.header.stamp = msg.header.stamp;
  if (result != nullptr) *result = std::move(r);
  return out;
}

EventPacket toMonoPacket(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                         const std::string& frame_id, std::uint64_t seq) {
  EventPacket msg;
  msg.header.frame_id = frame_id;
  msg.width = sensor.width;
  msg.height = sensor.height;
  msg.seq = seq;
  msg.encoding = "mono";
  if (events.empty()) return msg;
  toRosTime(events.back().t_us);
  msg.header.stamp = toRosTime(events.front().t_us);
  msg.time_base = static_cast<std::uint64_t>(events.front().t_us) * 1000;
  msg.events.resize(8 * events.size());
  std::uint8_t* p = msg.events.data();
  for (const ebslam::Event& e : events) {
    const std::int64_t dt_ns = (e.t_us - events.front().t_us) * 1000;
    if (dt_ns < 0 || dt_ns > 0xFFFFFFFFll) {
      throw std::invalid_argument("toMonoPacket: events must be in order and within 4.29 s");
    }
    if (!sensor.contains(e) || e.y > 0x7FFF) {
      throw std::invalid_argument("toMonoPacket: event outside the sensor");
    }
    const std::uint64_t word =
        static_cast<std::uint64_t>(dt_ns) | (static_cast<std::uint64_t>(e.x) << 32) |
        (static_cast<std::uint64_t>(e.y) << 48) | (static_cast<std::uint64_t>(e.polarity) << 63);
    for (int b = 0; b < 8; ++b) *p++ = static_cast<std::uint8_t>(word >> (8 * b));
  }
  return msg;
}

}  // namespace ebslam_msgs
