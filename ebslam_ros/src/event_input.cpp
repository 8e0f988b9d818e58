#include "ebslam_ros/event_input.h"

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/master.h>
#include <ros/names.h>
#include <ros/this_node.h>

#include <boost/make_shared.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros_common/ros_param_helpers.h"

namespace ebslam_ros {
namespace {

constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();

// The stream-time rule both guards apply to an event stamped `t_us` [us]: a step back of at most
// `max_backward_us` is clamped (sensor and transport jitter), a larger one starts a new segment
// (a restart); the first event's gap after the previous message is reported. Returns the event's
// time in the stream.
template <typename Result>
std::int64_t placeInStream(std::int64_t t_us, std::int64_t max_backward_us,
                           std::int64_t gap_warning_us, bool first, std::int64_t last_t_us,
                           Result& result) {
  if (last_t_us == kNoTime) return t_us;
  if (t_us < last_t_us) {
    if (last_t_us - t_us <= max_backward_us) {
      ++result.clamped;
      return last_t_us;
    }
    if (!result.segments.back().events.empty()) result.segments.emplace_back();
    result.segments.back().restart = true;
    result.segments.back().jump_back_us = last_t_us - t_us;
  } else if (first && t_us - last_t_us > gap_warning_us) {
    result.gap_us = t_us - last_t_us;
  }
  return t_us;
}

}  // namespace

EventInputResult EventInputGuard::take(const ebslam_msgs::EventArray& msg) {
  EventInputResult result;
  if (msg.events.empty()) return result;
  if (msg.width != sensor_.width || msg.height != sensor_.height) {
    result.size_mismatch = true;
    return result;
  }
  result.segments.emplace_back();
  result.segments.back().events.reserve(msg.events.size());
  bool first = true;
  for (const ebslam_msgs::Event& e : msg.events) {
    if (e.x >= sensor_.width || e.y >= sensor_.height) {
      ++result.outside;
      continue;
    }
    std::int64_t t_us = ebslam_msgs::toMicroseconds(e.ts);
    if (t_us == 0) {  // also stamps under 0.5 us, which round to 0
      ++result.zero_time;
      continue;
    }
    last_t_us_ = placeInStream(t_us, max_backward_us_, gap_warning_us_, first, last_t_us_, result);
    first = false;
    result.segments.back().events.push_back({last_t_us_, e.x, e.y, static_cast<bool>(e.polarity)});
  }
  if (result.segments.back().events.empty()) result.segments.pop_back();
  return result;
}

DepthEventInputResult DepthEventInputGuard::take(const ebslam_msgs::DepthEventArray& msg,
                                                 std::int64_t max_backward_us,
                                                 std::int64_t gap_warning_us) {
  DepthEventInputResult result;
  result.segments.emplace_back();
  result.segments.back().events.reserve(msg.events.size());
  bool first = true;
  for (const ebslam_msgs::DepthEvent& e : msg.events) {
    if (!std::isfinite(e.depth) || !std::isfinite(e.point.x) || !std::isfinite(e.point.y) ||
        !std::isfinite(e.point.z)) {
      ++result.no_depth;
      continue;
    }
    std::int64_t t_us = ebslam_msgs::toMicroseconds(e.ts);
    if (t_us == 0) {  // also stamps under 0.5 us, which round to 0
      ++result.zero_time;
      continue;
    }
    last_t_us_ = placeInStream(t_us, max_backward_us, gap_warning_us, first, last_t_us_, result);
    first = false;
    result.segments.back().events.push_back(
        {last_t_us_, Eigen::Vector3f(e.point.x, e.point.y, e.point.z)});
  }
  if (result.segments.back().events.empty()) result.segments.pop_back();
  return result;
}

namespace {
constexpr double kProbePeriodS = 2.0;  // auto: how often the master is asked for the topic type
constexpr double kErrorPeriodS = 5.0;  // undecodable packets: one error per this many seconds
}  // namespace

std::optional<EventInputType> eventInputTypeFromName(const std::string& name) {
  if (name == "auto") return EventInputType::kAuto;
  if (name == "dvs") return EventInputType::kDvs;
  if (name == "prophesee") return EventInputType::kProphesee;
  if (name == "event_packet") return EventInputType::kEventPacket;
  return std::nullopt;
}

const char* eventInputTypeName(EventInputType type) {
  switch (type) {
    case EventInputType::kAuto:
      return "auto";
    case EventInputType::kDvs:
      return "dvs";
    case EventInputType::kProphesee:
      return "prophesee";
    case EventInputType::kEventPacket:
      return "event_packet";
  }
  return "unknown";
}

std::optional<EventInputType> eventInputTypeOfDatatype(const std::string& datatype) {
  if (ebslam_msgs::isEventArrayDatatype(datatype)) return EventInputType::kDvs;
  if (ebslam_msgs::isEventPacketDatatype(datatype)) return EventInputType::kEventPacket;
  return std::nullopt;
}

EventInputType readEventInputType(const ros::NodeHandle& private_nh) {
  const auto name = ebslam_ros_common::param<std::string>(private_nh, "input_type", "auto");
  const std::optional<EventInputType> type = eventInputTypeFromName(name);
  if (!type) {
    throw std::invalid_argument(private_nh.resolveName("input_type") + " = \"" + name +
                                "\": must be auto, dvs, prophesee or event_packet");
  }
  return *type;
}

void EventSubscriber::subscribe(const ros::NodeHandle& nh, const std::string& topic,
                                std::uint32_t queue_size, EventInputType type, Callback callback,
                                const ros::TransportHints& hints, const std::string& name) {
  shutdown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    nh_ = nh;
    topic_ = topic;
    resolved_topic_ = nh.resolveName(topic);
    name_ = name.empty() ? ros::this_node::getName() : name;
    queue_size_ = queue_size;
    hints_ = hints;
    callback_ = std::move(callback);
    requested_ = type;
    last_reported_type_.clear();
  }
  // auto: the publishers' type when the master knows one, else EventArray until a publisher
  // says otherwise; a fixed type: that one (a publisher of another type is reported).
  if (requested_ != EventInputType::kAuto) {
    subscribeAs(requested_ == EventInputType::kEventPacket ? EventInputType::kEventPacket
                                                           : EventInputType::kDvs);
  }
  probe();
  probe_timer_ = nh_.createWallTimer(ros::WallDuration(kProbePeriodS),
                                     [this](const ros::WallTimerEvent&) { probe(); });
}

void EventSubscriber::shutdown() {
  probe_timer_.stop();
  probe_timer_ = ros::WallTimer();
  ros::Subscriber old;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    old = subscriber_;
    subscriber_ = ros::Subscriber();
    subscribed_.reset();
  }
  // Outside the lock: shutting down waits for a callback in progress, which takes the lock.
  old.shutdown();
}

std::optional<EventInputType> EventSubscriber::subscribed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return subscribed_;
}

EventSubscriber::Counters EventSubscriber::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

// Called from subscribe() and the probe timer only (never concurrently).
void EventSubscriber::subscribeAs(EventInputType type) {
  if (subscribed() == type) return;
  // The old subscription goes first: roscpp refuses two subscriptions of one topic with
  // different MD5 sums in one process.
  ros::Subscriber old;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    old = subscriber_;
    subscriber_ = ros::Subscriber();
    subscribed_.reset();
  }
  old.shutdown();  // outside the lock: it waits for a callback in progress, which takes the lock
  ros::Subscriber fresh;
  try {
    if (type == EventInputType::kEventPacket) {
      fresh = nh_.subscribe<ebslam_msgs::EventPacket>(topic_, queue_size_,
                                                      &EventSubscriber::onPacket, this, hints_);
    } else {
      fresh = nh_.subscribe<ebslam_msgs::EventArray>(topic_, queue_size_, callback_,
                                                     ros::VoidConstPtr(), hints_);
    }
  } catch (const ros::Exception& error) {
    // Another nodelet of this process still holds the topic with the other type (it switches
    // too, at its next probe): try again at ours.
    ROS_WARN("%s: cannot subscribe %s yet: %s", name_.c_str(), resolved_topic_.c_str(),
             error.what());
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (type == EventInputType::kEventPacket) converter_.reset();
    subscriber_ = fresh;
    subscribed_ = type;
  }
  if (requested_ == EventInputType::kAuto) {
    ROS_INFO("%s: reading %s as %s", name_.c_str(), resolved_topic_.c_str(),
             type == EventInputType::kEventPacket ? "event_camera_msgs/EventPacket"
                                                  : "EventArray (dvs_msgs, prophesee_event_msgs)");
  }
}

// Called from subscribe() and the probe timer only (never concurrently).
void EventSubscriber::probe() {
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return;  // master unreachable: try again later
  for (const ros::master::TopicInfo& info : topics) {
    if (info.name != resolved_topic_) continue;
    const std::optional<EventInputType> type = eventInputTypeOfDatatype(info.datatype);
    const bool new_type = info.datatype != last_reported_type_;
    last_reported_type_ = info.datatype;
    if (!type) {
      if (new_type) {
        ROS_ERROR(
            "%s: %s carries %s, which is no event message (dvs_msgs/EventArray, "
            "prophesee_event_msgs/EventArray, event_camera_msgs/EventPacket)",
            name_.c_str(), resolved_topic_.c_str(), info.datatype.c_str());
      }
    } else if (requested_ == EventInputType::kAuto) {
      subscribeAs(*type);
    } else if (*type != subscribed() && new_type) {
      ROS_ERROR("%s: %s carries %s, but ~input_type is %s: set ~input_type to auto or %s",
                name_.c_str(), resolved_topic_.c_str(), info.datatype.c_str(),
                eventInputTypeName(requested_),
                *type == EventInputType::kEventPacket ? "event_packet" : "dvs");
    }
    break;
  }
  // A subscription that failed (another nodelet held the topic with the other type) is retried.
  if (!subscribed()) {
    subscribeAs(requested_ == EventInputType::kEventPacket ? EventInputType::kEventPacket
                                                           : EventInputType::kDvs);
  }
}

void EventSubscriber::onPacket(const ebslam_msgs::EventPacket::ConstPtr& msg) {
  ebslam_msgs::EventArray::Ptr events;
  Callback callback;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ebslam_msgs::EventPacketResult result;
    events = boost::make_shared<ebslam_msgs::EventArray>(converter_.toEventArray(*msg, &result));
    ++counters_.packets;
    counters_.packet_events += events->events.size();
    counters_.dropped_bytes += result.stats.dropped_bytes;
    counters_.outside += result.stats.outside;
    counters_.bad_time += result.bad_time;
    const ros::WallTime now = ros::WallTime::now();
    const bool due = last_error_.isZero() || (now - last_error_).toSec() >= kErrorPeriodS;
    if (result.rejected) {
      ++counters_.rejected_packets;
      if (due) {
        last_error_ = now;
        ROS_ERROR("%s: EventPacket on %s dropped: %s (%zu dropped so far)", name_.c_str(),
                  resolved_topic_.c_str(), result.error.c_str(), counters_.rejected_packets);
      }
      return;
    }
    if (due &&
        (result.stats.dropped_bytes > 0 || result.stats.outside > 0 || result.bad_time > 0)) {
      last_error_ = now;
      ROS_WARN(
          "%s: %s EventPacket: %zu bytes undecodable, %zu events outside %ux%u, %zu events "
          "outside ros::Time (so far: %zu bytes, %zu + %zu events)",
          name_.c_str(), msg->encoding.c_str(), result.stats.dropped_bytes, result.stats.outside,
          msg->width, msg->height, result.bad_time, counters_.dropped_bytes, counters_.outside,
          counters_.bad_time);
    }
    callback = callback_;
  }
  callback(events);
}

void addDecoderDiagnostics(const EventSubscriber& subscriber,
                           diagnostic_updater::DiagnosticStatusWrapper& status) {
  const EventSubscriber::Counters c = subscriber.counters();
  const std::optional<EventInputType> type = subscriber.subscribed();
  status.add("input type", type ? eventInputTypeName(*type) : "not subscribed");
  status.add("event packets", c.packets);
  status.add("events decoded", c.packet_events);
  status.add("undecodable packets", c.rejected_packets);
  status.add("undecodable bytes", c.dropped_bytes);
  status.add("decoded events outside the sensor", c.outside);
  status.add("decoded events outside ros::Time", c.bad_time);
}

}  // namespace ebslam_ros
