#pragma once
// Checks an incoming EventArray before an event filter sees it (ROS-free apart from the message
// type). Event time = `ts` in us since the ROS epoch. Bad input never reaches the filter and is
// counted: wrong size -> message rejected; events outside -> dropped; a step back of at most
// max_backward_us -> clamped; more -> a new segment with `restart`; a long pause -> `gap_us`.
// Details: docs/ros_nodes_notes.md#event-input-checks

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
