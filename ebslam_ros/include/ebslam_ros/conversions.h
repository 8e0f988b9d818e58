#pragma once
// Conversions between ebslam core events (64-bit microseconds on the stream's own clock) and
// ebslam_msgs (ROS time). A TimeAnchor maps the stream clock to ROS time:
//   ros_time = anchor.ros_time + (t_us - anchor.t_us) / anchor.speed
// speed > 1 plays a recording faster than it was recorded.

#include <ebslam/event.h>
#include <ebslam_msgs/EventArray.h>
#include <ros/time.h>

#include <optional>

namespace ebslam_ros {

/// ROS time -> microseconds since the ROS epoch (rounded to the nearest microsecond, exact
/// integer arithmetic). The event filters run on this clock.
std::int64_t toMicroseconds(const ros::Time& stamp);
/// Microseconds since the ROS epoch -> ROS time; throws std::invalid_argument outside
/// ros::Time's range.
ros::Time fromMicroseconds(std::int64_t t_us);

struct TimeAnchor {
  ros::Time ros_time;     ///< ROS time of the anchor event
  std::int64_t t_us = 0;  ///< stream time of the anchor event [us]
  double speed = 1.0;     ///< playback speed factor (> 0)
};

/// The ROS time of stream time t_us, or nullopt when it would be negative or beyond ros::Time
/// (e.g. a damaged timestamp in a file). Throws std::invalid_argument for speed <= 0.
std::optional<ros::Time> rosTimeOf(std::int64_t t_us, const TimeAnchor& anchor);
/// Throws std::invalid_argument when the resulting time would be negative or beyond ros::Time.
ros::Time toRosTime(std::int64_t t_us, const TimeAnchor& anchor);
/// Inverse of toRosTime, rounded to the nearest microsecond.
std::int64_t toStreamTime(const ros::Time& stamp, const TimeAnchor& anchor);

ebslam_msgs::Event toEventMsg(const ebslam::Event& event, const TimeAnchor& anchor);
ebslam::Event toEvent(const ebslam_msgs::Event& msg, const TimeAnchor& anchor);

/// Events -> EventArray: header.stamp = time of the last event (the anchor time when empty).
ebslam_msgs::EventArray toEventArrayMsg(const ebslam::EventVector& events,
                                        const ebslam::SensorSize& sensor,
                                        const std::string& frame_id, const TimeAnchor& anchor);
/// EventArray -> events; throws std::invalid_argument for an event outside width x height.
ebslam::EventVector toEvents(const ebslam_msgs::EventArray& msg, const TimeAnchor& anchor);

}  // namespace ebslam_ros
