#pragma once

// The one conversion between ebslam core events and ebslam_msgs/Event(Array), for every node and
// tool that publishes, subscribes or records events. An event's `ts` is ROS time (wall or
// /clock); Event::t_us holds it as integer us since the ROS epoch (a source with its own clock
// maps it there with ebslam::EventClock). EventArray: header.stamp = ts of the last event,
// frame_id = the sensor's optical frame, width x height = the sensor.
// Details: docs/ros_nodes_notes.md#event-conversions

#include <ebslam/events/event.h>
#include <ebslam_msgs/Event.h>
#include <ebslam_msgs/EventArray.h>
#include <ros/time.h>

#include <cstdint>
#include <optional>
#include <string>

namespace ebslam_msgs {

/// ROS time -> microseconds since the ROS epoch, rounded to the nearest microsecond.
std::int64_t toMicroseconds(const ros::Time& stamp);
/// Microseconds since the ROS epoch -> ROS time; nullopt outside ros::Time's range
/// (before 1970 or after 2106).
std::optional<ros::Time> rosTimeOf(std::int64_t t_us);
/// As rosTimeOf, but throws std::invalid_argument outside ros::Time's range.
ros::Time toRosTime(std::int64_t t_us);

/// One event; t_us in microseconds since the ROS epoch (throws as toRosTime).
Event toMsg(const ebslam::Event& event);
ebslam::Event fromMsg(const Event& msg);

/// Events (t_us since the ROS epoch, in order) -> one EventArray: header.stamp = ts of the last
/// event (zero for no events; the caller stamps an empty array), header.frame_id = frame_id,
/// width x height = sensor. Throws std::invalid_argument for a time outside ros::Time.
EventArray toMsg(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                 const std::string& frame_id);
/// Appends the events of msg to out (no checks: validating width x height and time order is the
/// consumer's, e.g. ebslam_ros' EventInputGuard); returns the sensor size msg declares.
ebslam::SensorSize appendFromMsg(const EventArray& msg, ebslam::EventVector& out);
/// The events of msg (as appendFromMsg).
ebslam::EventVector fromMsg(const EventArray& msg);

}  // namespace ebslam_msgs
