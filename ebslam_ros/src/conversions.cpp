#include "ebslam_ros/conversions.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam_ros {

std::int64_t toMicroseconds(const ros::Time& stamp) {
  return static_cast<std::int64_t>((stamp.toNSec() + 500) / 1000);
}

ros::Time fromMicroseconds(std::int64_t t_us) {
  if (t_us < 0 || t_us > std::int64_t{4294967295} * 1000000) {
    throw std::invalid_argument("time " + std::to_string(t_us) +
                                " us is outside the range of ros::Time");
  }
  return ros::Time().fromNSec(static_cast<std::uint64_t>(t_us) * 1000);
}

std::optional<ros::Time> rosTimeOf(std::int64_t t_us, const TimeAnchor& anchor) {
  if (!(anchor.speed > 0.0)) throw std::invalid_argument("time anchor speed must be positive");
  std::int64_t offset_us = 0;
  if (__builtin_sub_overflow(t_us, anchor.t_us, &offset_us)) return std::nullopt;
  const double offset_s = static_cast<double>(offset_us) * 1e-6 / anchor.speed;
  const double seconds = anchor.ros_time.toSec() + offset_s;
  if (!(seconds >= 0.0 && seconds <= 4294967295.0)) return std::nullopt;
  // Integer nanoseconds keep microsecond resolution exact at large absolute times.
  const std::int64_t offset_ns = std::llround(offset_s * 1e9);
  return ros::Time().fromNSec(anchor.ros_time.toNSec() + offset_ns);
}

ros::Time toRosTime(std::int64_t t_us, const TimeAnchor& anchor) {
  const std::optional<ros::Time> time = rosTimeOf(t_us, anchor);
  if (!time) {
    throw std::invalid_argument("event time " + std::to_string(t_us) +
                                " us maps outside the range of ros::Time");
  }
  return *time;
}

std::int64_t toStreamTime(const ros::Time& stamp, const TimeAnchor& anchor) {
  if (!(anchor.speed > 0.0)) throw std::invalid_argument("time anchor speed must be positive");
  const double offset_ns = static_cast<double>(static_cast<std::int64_t>(stamp.toNSec()) -
                                               static_cast<std::int64_t>(anchor.ros_time.toNSec()));
  return anchor.t_us + std::llround(offset_ns * anchor.speed * 1e-3);
}

ebslam_msgs::Event toEventMsg(const ebslam::Event& event, const TimeAnchor& anchor) {
  ebslam_msgs::Event msg;
  msg.x = event.x;
  msg.y = event.y;
  msg.ts = toRosTime(event.t_us, anchor);
  msg.polarity = event.polarity;
  return msg;
}

ebslam::Event toEvent(const ebslam_msgs::Event& msg, const TimeAnchor& anchor) {
  ebslam::Event event;
  event.t_us = toStreamTime(msg.ts, anchor);
  event.x = msg.x;
  event.y = msg.y;
  event.polarity = msg.polarity;
  return event;
}

ebslam_msgs::EventArray toEventArrayMsg(const ebslam::EventVector& events,
                                        const ebslam::SensorSize& sensor,
                                        const std::string& frame_id, const TimeAnchor& anchor) {
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = frame_id;
  msg.width = sensor.width;
  msg.height = sensor.height;
  msg.events.reserve(events.size());
  for (const ebslam::Event& event : events) msg.events.push_back(toEventMsg(event, anchor));
  msg.header.stamp = msg.events.empty() ? anchor.ros_time : msg.events.back().ts;
  return msg;
}

ebslam::EventVector toEvents(const ebslam_msgs::EventArray& msg, const TimeAnchor& anchor) {
  ebslam::EventVector events;
  events.reserve(msg.events.size());
  for (const ebslam_msgs::Event& e : msg.events) {
    if (e.x >= msg.width || e.y >= msg.height) {
      throw std::invalid_argument("event (" + std::to_string(e.x) + ", " + std::to_string(e.y) +
                                  ") outside the " + std::to_string(msg.width) + "x" +
                                  std::to_string(msg.height) + " sensor");
    }
    events.push_back(toEvent(e, anchor));
  }
  return events;
}

}  // namespace ebslam_ros
