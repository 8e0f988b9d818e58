#include "ebslam_ros/event_input.h"

#include <cmath>
#include <limits>

#include "ebslam_msgs/event_conversions.h"

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

}  // namespace ebslam_ros
