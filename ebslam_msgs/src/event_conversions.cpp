#include "ebslam_msgs/event_conversions.h"

#include <algorithm>
#include <stdexcept>

namespace ebslam_msgs {

namespace {
constexpr std::int64_t kMaxRosTimeUs = std::int64_t{4294967295} * 1000000 + 999999;
}  // namespace

std::int64_t toMicroseconds(const ros::Time& stamp) {
  return static_cast<std::int64_t>((stamp.toNSec() + 500) / 1000);
}

std::optional<ros::Time> rosTimeOf(std::int64_t t_us) {
  if (t_us < 0 || t_us > kMaxRosTimeUs) return std::nullopt;
  return ros::Time(static_cast<std::uint32_t>(t_us / 1000000),
                   static_cast<std::uint32_t>((t_us % 1000000) * 1000));
}

ros::Time toRosTime(std::int64_t t_us) {
  const std::optional<ros::Time> time = rosTimeOf(t_us);
  if (!time) {
    throw std::invalid_argument("event time " + std::to_string(t_us) +
                                " us is outside the range of ros::Time");
  }
  return *time;
}

Event toMsg(const ebslam::Event& event) {
  Event msg;
  msg.x = event.x;
  msg.y = event.y;
  msg.ts = toRosTime(event.t_us);
  msg.polarity = event.polarity;
  return msg;
}

ebslam::Event fromMsg(const Event& msg) {
  return ebslam::Event{toMicroseconds(msg.ts), msg.x, msg.y, static_cast<bool>(msg.polarity)};
}

EventArray toMsg(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                 const std::string& frame_id) {
  EventArray msg;
  msg.header.frame_id = frame_id;
  msg.width = sensor.width;
  msg.height = sensor.height;
  msg.events.reserve(events.size());
  for (const ebslam::Event& event : events) msg.events.push_back(toMsg(event));
  if (!msg.events.empty()) msg.header.stamp = msg.events.back().ts;
  return msg;
}

ebslam::SensorSize appendFromMsg(const EventArray& msg, ebslam::EventVector& out) {
  // Geometric growth: reserving exactly the new size on every message would copy the whole
  // buffer per message (quadratic for a consumer that appends a long recording).
  const std::size_t needed = out.size() + msg.events.size();
  if (needed > out.capacity()) out.reserve(std::max(needed, 2 * out.capacity()));
  for (const Event& m : msg.events) out.push_back(fromMsg(m));
  return ebslam::SensorSize{msg.width, msg.height};
}

ebslam::EventVector fromMsg(const EventArray& msg) {
  ebslam::EventVector events;
  appendFromMsg(msg, events);
  return events;
}

}  // namespace ebslam_msgs
