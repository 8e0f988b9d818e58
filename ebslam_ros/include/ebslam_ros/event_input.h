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

}  // namespace ebslam_ros
