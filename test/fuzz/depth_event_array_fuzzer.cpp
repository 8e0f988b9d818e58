// libFuzzer target: bytes -> a stream of ebslam_msgs/DepthEventArray messages -> what EventSlam3d
// runs on each before its filter (DepthEventInputGuard). Promises: no crash; the guard passes
// only events with a finite point, never stamped 0, in non-decreasing time within a segment and
// across segments unless a segment restarts; every event is passed or counted.
#include <ebslam_msgs/DepthEventArray.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "ebslam_ros/event_input.h"
#include "fuzz_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::int64_t max_backward_us = 100 * static_cast<std::int64_t>(data[0]);
  ebslam_ros::DepthEventInputGuard guard;
  std::size_t pos = 1;
  std::int64_t last_t_us = std::numeric_limits<std::int64_t>::min();
  while (pos < size) {
    ebslam_msgs::DepthEventArray msg;
    const std::size_t used =
        fuzz::readMessage<ebslam_msgs::DepthEventArray_>(data + pos, size - pos, msg);
    if (used == 0) break;
    pos += used;
    const ebslam_ros::DepthEventInputResult result = guard.take(msg, max_backward_us, 1000000);
    std::size_t passed = 0;
    for (const ebslam_ros::DepthEventSegment& segment : result.segments) {
      if (segment.events.empty()) std::abort();
      if (segment.restart) {
        if (segment.jump_back_us <= max_backward_us) std::abort();
        last_t_us = std::numeric_limits<std::int64_t>::min();
      }
      for (const ebslam::PointEvent& e : segment.events) {
        if (!e.point.allFinite() || e.t_us == 0 || e.t_us < last_t_us) std::abort();
        last_t_us = e.t_us;
      }
      passed += segment.events.size();
    }
    if (passed + result.no_depth + result.zero_time != msg.events.size()) std::abort();
  }
  return 0;
}
