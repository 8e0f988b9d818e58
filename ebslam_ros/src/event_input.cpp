#include "ebslam_ros/event_input.h"

#include <cmath>

#include "ebslam_msgs/event_conversions.h"

namespace ebslam_ros {

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
    if (last_t_us_ != kNoTime) {
      if (t_us < last_t_us_) {
        if (last_t_us_ - t_us <= max_backward_us_) {
          t_us = last_t_us_;
          ++result.clamped;
        } else {
          if (!result.segments.back().events.empty()) result.segments.emplace_back();
          result.segments.back().restart = true;
          result.segments.back().jump_back_us = last_t_us_ - t_us;
        }
      } else if (first && t_us - last_t_us_ > gap_warning_us_) {
        result.gap_us = t_us - last_t_us_;
      }
    }
    first = false;
    last_t_us_ = t_us;
    result.segments.back().events.push_back({t_us, e.x, e.y, static_cast<bool>(e.polarity)});
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
    if (last_t_us_ != kNoTime) {
      if (t_us < last_t_us_) {
        if (last_t_us_ - t_us <= max_backward_us) {
          t_us = last_t_us_;  // sensor and transport jitter
          ++result.clamped;
        } else {
          if (!result.segments.back().events.empty()) result.segments.emplace_back();
          result.segments.back().restart = true;
          result.segments.back().jump_back_us = last_t_us_ - t_us;
        }
      } else if (first && t_us - last_t_us_ > gap_warning_us) {
        result.gap_us = t_us - last_t_us_;
      }
    }
    first = false;
    last_t_us_ = t_us;
    result.segments.back().events.push_back(
        {t_us, Eigen::Vector3f(e.point.x, e.point.y, e.point.z)});
  }
  if (result.segments.back().events.empty()) result.segments.pop_back();
  return result;
}

}  // namespace ebslam_ros
