#pragma once
// Checks an incoming EventArray before an event filter sees it (ROS-free apart from the message
// type, so it is unit-tested without a master). Time convention: event time = the event's `ts`
// as microseconds since the ROS epoch (ebslam_msgs/event_conversions.h), the stamp of every pose
// computed from it.
//
// What it does with bad input, so that a filter never throws on it and nothing passes silently:
//  - a message whose width x height differs from the sensor's: rejected whole (counted);
//  - events outside width x height: dropped (counted);
//  - events earlier than their predecessor by at most `max_backward_us`: time clamped to the
//    predecessor's (counted; sensor and transport jitter);
//  - earlier by more: the stream restarted (a looping bag, a driver reconnect): the events from
//    there on start a new segment with `restart` set, the caller resets its filter;
//  - a pause longer than `gap_warning_us` before a message: reported in `gap_us`.

#include <ebslam/event.h>
#include <ebslam_msgs/EventArray.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace ebslam_ros {

struct EventSegment {
  ebslam::EventVector events;
  bool restart = false;           ///< time jumped back before this segment: reset the filter first
  std::int64_t jump_back_us = 0;  ///< how far (restart only) [us]
};

struct EventInputResult {
  bool size_mismatch = false;  ///< message rejected: width x height differs from the sensor
  std::vector<EventSegment> segments;
  std::size_t outside = 0;  ///< events dropped for lying outside width x height
  std::size_t clamped = 0;  ///< events whose time was clamped to their predecessor's
  std::int64_t gap_us = 0;  ///< pause before this message when longer than the warning [us]
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

}  // namespace ebslam_ros
