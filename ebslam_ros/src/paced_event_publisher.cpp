#include "ebslam_ros/paced_event_publisher.h"

#include <ebslam_msgs/EventArray.h>
#include <rosgraph_msgs/Clock.h>

#include <ros/master.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <cmath>
#include <set>
#include <utility>

namespace ebslam_ros {
namespace {

// Topics with at least one subscriber, from the master's system state; empty if unreachable.
std::set<std::string> subscribedTopics() {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  std::set<std::string> topics;
  if (!ros::master::execute("getSystemState", args, result, payload, false)) return topics;
  if (payload.getType() != XmlRpc::XmlRpcValue::TypeArray || payload.size() < 2) return topics;
  XmlRpc::XmlRpcValue& subscribers = payload[1];
  for (int i = 0; i < subscribers.size(); ++i) {
    if (subscribers[i].size() >= 2 && subscribers[i][1].size() > 0) {
      topics.insert(static_cast<std::string>(subscribers[i][0]));
    }
  }
  return topics;
}

}  // namespace

PacedEventPublisher::PacedEventPublisher(ros::NodeHandle& nh, PacedEventOptions options,
                                         const std::atomic<bool>& stop,
                                         MessageEndCallback on_message_end)
    : options_(std::move(options)),
      stop_(stop),
      on_message_end_(std::move(on_message_end)),
      events_pub_(nh.advertise<ebslam_msgs::EventArray>("events", 1000)) {
  if (options_.publish_clock) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
}

bool PacedEventPublisher::start(std::int64_t begin_us) {
  const bool waited = options_.wait_for_subscribers || !options_.start_when_subscribed.empty();
  if (options_.wait_for_subscribers) {
    while (!stop_ && events_pub_.getNumSubscribers() == 0) ros::WallDuration(0.05).sleep();
  }
  for (bool all = options_.start_when_subscribed.empty(); !stop_ && !all;) {
    const std::set<std::string> subscribed = subscribedTopics();
    std::string missing;
    for (const std::string& topic : options_.start_when_subscribed) {
      if (subscribed.count(topic) == 0) missing += " " + topic;
    }
    all = missing.empty();
    if (!all) {
      ROS_INFO_THROTTLE(5.0, "waiting for subscribers to:%s", missing.c_str());
      ros::WallDuration(0.1).sleep();
    }
  }
  // roscpp and the master count a subscriber before its side of the connection is ready.
  if (waited) ros::WallDuration(0.5).sleep();
  if (stop_) return false;
  const double stamp_speed = options_.publish_clock ? 1.0 : options_.speed;
  const ros::Time anchor_time =
      options_.publish_clock ? ros::Time(options_.clock_start_s) : ros::Time::now();
  clock_ = ebslam::EventClock(stamp_speed);
  clock_.anchor(begin_us, ebslam_msgs::toMicroseconds(anchor_time));
  wall_start_ = ros::WallTime::now();
  begin_us_ = begin_us;
  last_end_us_ = begin_us;
  next_boundary_us_ = begin_us + periodUs();
  if (options_.publish_clock) {
    rosgraph_msgs::Clock clock;
    clock.clock = anchor_time;
    clock_pub_.publish(clock);
  }
  return true;
}

void PacedEventPublisher::add(const ebslam::Event& event) {
  sendUntil(event.t_us);
  pending_.push_back(event);
}

void PacedEventPublisher::sendUntil(std::int64_t t_us) {
  while (t_us >= next_boundary_us_) sendNext();
}

void PacedEventPublisher::sendNext() {
  const std::int64_t end_us = next_boundary_us_;
  last_end_us_ = end_us;
  next_boundary_us_ += periodUs();
  const ros::WallTime due =
      wall_start_ +
      ros::WallDuration(1e-6 * static_cast<double>(end_us - begin_us_) / options_.speed);
  while (!stop_) {
    const ros::WallTime now = ros::WallTime::now();
    if (now >= due) break;
    (due - now).sleep();
  }
  if (stop_) throw Stopped{};
  const ros::Time stamp_end = rosTime(end_us);
  if (options_.publish_clock) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp_end;
    clock_pub_.publish(clock);
  }
  if (!pending_.empty()) {
    for (ebslam::Event& e : pending_) e.t_us = clock_.stamp(e.t_us).value_or(-1);
    ebslam_msgs::EventArray msg = ebslam_msgs::toMsg(pending_, options_.sensor, options_.frame_id);
    ++messages_;
    events_pub_.publish(msg);
    pending_.clear();
  }
  if (on_message_end_) on_message_end_(1e-6 * static_cast<double>(end_us), stamp_end);
}

void PacedEventPublisher::finish(std::int64_t end_us) {
  if (last_end_us_ < end_us || !pending_.empty()) {
    next_boundary_us_ = std::min(next_boundary_us_, end_us);
    sendNext();
  }
}

ros::Time PacedEventPublisher::rosTime(std::int64_t t_us) const {
  return ebslam_msgs::toRosTime(clock_.map(t_us).value_or(-1));
}

std::int64_t PacedEventPublisher::periodUs() const {
  return std::llround(1e6 / options_.publish_rate_hz);
}

}  // namespace ebslam_ros
