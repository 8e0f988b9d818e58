#pragma once
// Checks an incoming EventArray before an event filter sees it (ROS-free apart from the message
// type). Event time = `ts` in us since the ROS epoch. Bad input never reaches the filter and is
// counted: wrong size -> message rejected; events outside -> dropped; a step back of at most
// max_backward_us -> clamped; more -> a new segment with `restart`; a long pause -> `gap_us`;
// time 0 (an unset stamp, never a real event's time) -> dropped, so that one such event neither
// restarts the filter nor makes the next real event look like a pause of decades.
// Details: docs/ros_nodes_notes.md#event-input-checks

#include <ebslam/events/event.h>
#include <ebslam/slam/ebslam3d.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/EventPacket.h>
#include <ros/node_handle.h>
#include <ros/subscriber.h>
#include <ros/timer.h>
#include <ros/transport_hints.h>

#include <boost/function.hpp>
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "ebslam_msgs/event_packet_conversions.h"

namespace diagnostic_updater {
class DiagnosticStatusWrapper;
}

namespace ebslam_ros {

struct EventSegment {
  ebslam::EventVector events;
  bool restart = false;           ///< time jumped back before this segment: reset the filter first
  std::int64_t jump_back_us = 0;  ///< how far (restart only) [us]
};

struct EventInputResult {
  bool size_mismatch = false;  ///< message rejected: width x height differs from the sensor
  std::vector<EventSegment> segments;
  std::size_t outside = 0;    ///< events dropped for lying outside width x height
  std::size_t clamped = 0;    ///< events whose time was clamped to their predecessor's
  std::size_t zero_time = 0;  ///< events dropped for ts = 0 (unset; below 0.5 us counts as 0)
  std::int64_t gap_us = 0;    ///< pause before this message when longer than the warning [us]
};

class EventInputGuard {
 public:
  EventInputGuard(const ebslam::SensorSize& sensor, std::int64_t max_backward_us,
                  std::int64_t gap_warning_us)
      : sensor_(sensor), max_backward_us_(max_backward_us), gap_warning_us_(gap_warning_us) {}

  /// Splits `msg` into the segments to process (none for an empty or rejected message).
  EventInputResult take(const ebslam_msgs::EventArray& msg);
  /// Forgets the stream's time (after a reset by the user).
  void restart() { last_t_us_ = kNoTime; }
  const ebslam::SensorSize& sensor() const { return sensor_; }

 private:
  static constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();
  ebslam::SensorSize sensor_;
  std::int64_t max_backward_us_;
  std::int64_t gap_warning_us_;
  std::int64_t last_t_us_ = kNoTime;
};

/// Depth events (D-eDVS) for EventSlam3d, checked like EventArray's: no depth (NaN depth or
/// point) -> skipped; time 0 -> dropped; small steps back clamped, large ones restart; pauses.
struct DepthEventSegment {
  ebslam::PointEventVector events;
  bool restart = false;           ///< time jumped back before this segment: reset the filter first
  std::int64_t jump_back_us = 0;  ///< how far (restart only) [us]
};

struct DepthEventInputResult {
  std::vector<DepthEventSegment> segments;
  std::size_t no_depth = 0;   ///< events without depth (normal for pixels the depth sensor misses)
  std::size_t clamped = 0;    ///< events whose time was clamped to their predecessor's
  std::size_t zero_time = 0;  ///< events dropped for ts = 0 (unset; below 0.5 us counts as 0)
  std::int64_t gap_us = 0;    ///< pause before this message when longer than the warning [us]
};

class DepthEventInputGuard {
 public:
  /// Splits `msg` into the segments to process; the limits [us] as EventInputGuard's (passed each
  /// time: they are node parameters).
  DepthEventInputResult take(const ebslam_msgs::DepthEventArray& msg, std::int64_t max_backward_us,
                             std::int64_t gap_warning_us);
  /// Forgets the stream's time (after a reset by the user).
  void restart() { last_t_us_ = kNoTime; }

 private:
  static constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();
  std::int64_t last_t_us_ = kNoTime;
};

/// The event message types every event consumer reads on its input topic (~input_type):
///   dvs:          dvs_msgs/EventArray (rpg_dvs_ros) = ebslam_msgs/EventArray (same MD5);
///   prophesee:    prophesee_event_msgs/EventArray (prophesee_ros_driver), field for field the
///                 same message, so the same MD5 and the same subscription as dvs;
///   event_packet: event_camera_msgs/EventPacket = ebslam_msgs/EventPacket (libcaer_driver,
///                 metavision_driver; encodings evt3, libcaer_cmp, libcaer, mono);
///   auto:         the type the master reports for the topic's publishers (checked every 2 s,
///                 so a publisher of another type started later is followed); EventArray
///                 while no publisher is known.
/// Details: ebslam_ros/README.md#event-input-types
enum class EventInputType { kAuto, kDvs, kProphesee, kEventPacket };

std::optional<EventInputType> eventInputTypeFromName(const std::string& name);
const char* eventInputTypeName(EventInputType type);
/// The input type a publisher's datatype selects (kDvs for every EventArray type, kEventPacket
/// for both EventPacket types); nullopt for any other type.
std::optional<EventInputType> eventInputTypeOfDatatype(const std::string& datatype);
/// ~input_type of a consumer (default "auto"); throws std::invalid_argument naming the resolved
/// parameter for another value. Read inside the nodelet's startOrFail (ros_param_helpers.h).
EventInputType readEventInputType(const ros::NodeHandle& private_nh);

/// The one event subscription of every event consumer: subscribes `topic` as the message type
/// ~input_type selects and hands each message to `callback` as an ebslam_msgs::EventArray
/// (EventPackets decoded, with decoder state per stream: ebslam_msgs::EventPacketConverter;
/// width x height from the packet). EventArrays arrive unchanged (zero copy between nodelets).
/// Undecodable packets are dropped with a throttled error; their counts are in counters().
class EventSubscriber {
 public:
  using Callback = boost::function<void(const ebslam_msgs::EventArray::ConstPtr&)>;

  struct Counters {
    std::size_t packets = 0;           ///< EventPackets received
    std::size_t packet_events = 0;     ///< events decoded from them
    std::size_t rejected_packets = 0;  ///< undecodable (unknown encoding, bad size, big endian)
    std::size_t dropped_bytes = 0;     ///< bytes of packets that decode to no event
    std::size_t outside = 0;           ///< decoded events outside the packet's width x height
    std::size_t bad_time = 0;          ///< decoded events outside ros::Time
  };

  EventSubscriber() = default;
  EventSubscriber(const EventSubscriber&) = delete;
  EventSubscriber& operator=(const EventSubscriber&) = delete;
  ~EventSubscriber() { shutdown(); }

  /// Subscribes `topic` (resolved in nh) as `type` (readEventInputType). `name` prefixes log
  /// messages (the nodelet's name).
  void subscribe(const ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue_size,
                 EventInputType type, Callback callback,
                 const ros::TransportHints& hints = ros::TransportHints(),
                 const std::string& name = "");
  void shutdown();
  /// The message type subscribed now: kDvs (any EventArray) or kEventPacket; nullopt before
  /// subscribe().
  std::optional<EventInputType> subscribed() const;
  EventInputType requested() const { return requested_; }
  Counters counters() const;
  /// The topic's resolved name.
  const std::string& topic() const { return resolved_topic_; }

 private:
  void subscribeAs(EventInputType type);
  void probe();
  void onPacket(const ebslam_msgs::EventPacket::ConstPtr& msg);

  mutable std::mutex mutex_;
  ros::NodeHandle nh_;
  std::string topic_, resolved_topic_, name_;
  std::uint32_t queue_size_ = 1;
  ros::TransportHints hints_;
  Callback callback_;
  EventInputType requested_ = EventInputType::kAuto;
  std::optional<EventInputType> subscribed_;
  ros::Subscriber subscriber_;
  ros::WallTimer probe_timer_;
  std::string last_reported_type_;
  ebslam_msgs::EventPacketConverter converter_;
  Counters counters_;
  ros::WallTime last_error_;
};

/// The subscription's type and decoder counters on a consumer's diagnostics: "input type",
/// "event packets", "events decoded", "undecodable packets", "undecodable bytes", "decoded
/// events outside the sensor", "decoded events outside ros::Time" (0 for EventArray input).
void addDecoderDiagnostics(const EventSubscriber& subscriber,
                           diagnostic_updater::DiagnosticStatusWrapper& status);

}  // namespace ebslam_ros
