// libFuzzer target: bytes -> a stream of ebslam_msgs/EventArray messages -> what
// EventParticleFilter and EventSlam2d run on each before their filter (EventInputGuard on a
// 128 x 128 eDVS) and the event conversion every event consumer runs (ebslam_msgs::fromMsg).
// Promises: no crash; the guard passes only events inside the sensor, never stamped 0, in
// non-decreasing time within a segment and across segments unless a segment restarts.
#include <ebslam_msgs/EventArray.h>

#include <cstdint>
#include <cstdlib>
#include <limits>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/event_input.h"
#include "fuzz_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  // First byte: the node's ~max_backward (0 .. 25.5 ms); ~gap_warning 1 s (the default).
  const std::int64_t max_backward_us = 100 * static_cast<std::int64_t>(data[0]);
  ebslam_ros::EventInputGuard guard({128, 128}, max_backward_us, 1000000);
  std::size_t pos = 1;
  std::int64_t last_t_us = std::numeric_limits<std::int64_t>::min();
  while (pos < size) {
    ebslam_msgs::EventArray msg;
    const std::size_t used =
        fuzz::readMessage<ebslam_msgs::EventArray_>(data + pos, size - pos, msg);
    if (used == 0) break;
    pos += used;
    const ebslam::EventVector events = ebslam_msgs::fromMsg(msg);
    if (events.size() != msg.events.size()) std::abort();
    const ebslam_ros::EventInputResult result = guard.take(msg);
    if (result.size_mismatch && !result.segments.empty()) std::abort();
    std::size_t passed = 0;
    for (const ebslam_ros::EventSegment& segment : result.segments) {
      if (segment.events.empty()) std::abort();
      if (segment.restart) {
        if (segment.jump_back_us <= max_backward_us) std::abort();
        last_t_us = std::numeric_limits<std::int64_t>::min();
      }
      for (const ebslam::Event& e : segment.events) {
        if (e.x >= 128 || e.y >= 128 || e.t_us == 0 || e.t_us < last_t_us) std::abort();
        last_t_us = e.t_us;
      }
      passed += segment.events.size();
    }
    if (!result.size_mismatch && passed + result.outside + result.zero_time != msg.events.size()) {
      std::abort();
    }
  }
  return 0;
}
