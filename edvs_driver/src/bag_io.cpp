#include "edvs_driver/bag_io.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "ebslam_msgs/event_packet_conversions.h"

namespace edvs_driver {

BagReadResult readEventBag(const std::string& path, const std::string& topic) {
  BagReadResult result;
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Read);
    rosbag::View all(bag);
    std::vector<std::string> topics;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      const bool type_ok = ebslam_msgs::isEventArrayDatatype(c->datatype) ||
                           ebslam_msgs::isEventPacketDatatype(c->datatype);
      if (type_ok && (topic.empty() || c->topic == topic)) topics.push_back(c->topic);
    }
    if (topics.empty()) {
      throw std::runtime_error("bag " + path + " has no EventArray or EventPacket messages" +
                               (topic.empty() ? std::string() : " on topic " + topic));
    }
    std::set<std::string> unique(topics.begin(), topics.end());
    result.topics.assign(unique.begin(), unique.end());
    rosbag::View view(bag, rosbag::TopicQuery(result.topics));
    std::map<std::string, ebslam_msgs::EventPacketConverter> streams;  // decoder state per topic
    for (const rosbag::MessageInstance& m : view) {
      std::string error;
      const std::optional<ebslam::SensorSize> size =
          ebslam_msgs::appendRecordedEvents(m, streams[m.getTopic()], result.events, &error);
      if (!size) {
        if (!error.empty()) ++result.rejected_packets;
        continue;
      }
      if (result.messages == 0) result.sensor = *size;
      ++result.messages;
    }
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot read bag " + path + ": " + e.what());
  }
  return result;
}

void writeEventBag(const std::string& path, const ebslam::EventVector& events,
                   const ebslam::SensorSize& sensor, const BagWriteOptions& options) {
  if (options.batch_us <= 0 || options.max_events_per_message == 0) {
    throw std::invalid_argument("BagWriteOptions: batch_us and max_events_per_message must be > 0");
  }
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    std::size_t begin = 0;
    while (begin < events.size()) {
      std::size_t end = begin + 1;
      const std::int64_t window_end = events[begin].t_us + options.batch_us;
      while (end < events.size() && events[end].t_us < window_end &&
             end - begin < options.max_events_per_message) {
        ++end;
      }
      const ebslam::EventVector batch(events.begin() + static_cast<long>(begin),
                                      events.begin() + static_cast<long>(end));
      const ebslam_msgs::EventArray msg = ebslam_msgs::toMsg(batch, sensor, options.frame_id);
      // rosbag refuses times below TIME_MIN; files often start at t = 0.
      const ros::Time when = std::max(msg.header.stamp, ros::TIME_MIN);
      bag.write(options.topic, when, msg);
      begin = end;
    }
    bag.close();
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot write bag " + path + ": " + e.what());
  }
}

}  // namespace edvs_driver
