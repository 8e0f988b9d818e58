#include "edvs_driver/conversions.h"

#include <limits>
#include <stdexcept>

namespace edvs_driver {

ros::Time toRosTime(std::int64_t t_us) {
  if (t_us < 0) {
    throw std::invalid_argument("event time " + std::to_string(t_us) +
                                " us is before the ROS epoch");
  }
  const std::int64_t sec = t_us / 1000000;
  if (sec > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("event time " + std::to_string(t_us) + " us exceeds ros::Time");
  }
  return ros::Time(static_cast<std::uint32_t>(sec),
                   static_cast<std::uint32_t>((t_us % 1000000) * 1000));
}

std::int64_t fromRosTime(const ros::Time& t) {
  return static_cast<std::int64_t>(t.sec) * 1000000 + static_cast<std::int64_t>(t.nsec / 1000);
}

ebslam_msgs::Event toMsg(const ebslam::Event& event) {
  ebslam_msgs::Event m;
  m.x = event.x;
  m.y = event.y;
  m.ts = toRosTime(event.t_us);
  m.polarity = event.polarity;
  return m;
}

ebslam::Event fromMsg(const ebslam_msgs::Event& msg) {
  ebslam::Event e;
  e.x = msg.x;
  e.y = msg.y;
  e.t_us = fromRosTime(msg.ts);
  e.polarity = msg.polarity;
  return e;
}

ebslam_msgs::EventArray toMsg(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                              const std::string& frame_id) {
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = frame_id;
  msg.width = sensor.width;
  msg.height = sensor.height;
  msg.events.reserve(events.size());
  for (const ebslam::Event& e : events) msg.events.push_back(toMsg(e));
  if (!msg.events.empty()) msg.header.stamp = msg.events.back().ts;
  return msg;
}

ebslam::SensorSize appendFromMsg(const ebslam_msgs::EventArray& msg, ebslam::EventVector& out) {
  out.reserve(out.size() + msg.events.size());
  for (const auto& m : msg.events) out.push_back(fromMsg(m));
  return ebslam::SensorSize{msg.width, msg.height};
}

}  // namespace edvs_driver
