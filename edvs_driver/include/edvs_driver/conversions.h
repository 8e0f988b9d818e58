#pragma once

// ROS messages <-> core types for this package (the only place they meet).
//
// Time: ebslam::Event::t_us published by the driver is ROS time in microseconds since the ROS
// epoch (see the time semantics in README.md); ros::Time carries it exactly (nanoseconds).

#include <ros/time.h>

#include <cstdint>
#include <string>

#include "ebslam/event.h"
#include "ebslam_msgs/Event.h"
#include "ebslam_msgs/EventArray.h"

namespace edvs_driver {

/// Microseconds since the ROS epoch -> ros::Time. Throws std::invalid_argument for negative
/// times or times beyond ros::Time's range (year 2106).
ros::Time toRosTime(std::int64_t t_us);
/// ros::Time -> microseconds, rounding nanoseconds down to the microsecond.
std::int64_t fromRosTime(const ros::Time& t);

ebslam_msgs::Event toMsg(const ebslam::Event& event);
ebslam::Event fromMsg(const ebslam_msgs::Event& msg);

/// One EventArray: events in order, width/height from `sensor`, header.frame_id = frame_id,
/// header.stamp = time of the last event (ebslam_msgs convention; zero for an empty batch).
ebslam_msgs::EventArray toMsg(const ebslam::EventVector& events, const ebslam::SensorSize& sensor,
                              const std::string& frame_id);
/// Appends the events of `msg` to `out`; returns the sensor size the message declares.
ebslam::SensorSize appendFromMsg(const ebslam_msgs::EventArray& msg, ebslam::EventVector& out);

}  // namespace edvs_driver
