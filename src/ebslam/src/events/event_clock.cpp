#include "ebslam/events/event_clock.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

namespace {
// a + round(offset * factor) without overflow; nullopt when the result leaves int64.
std::optional<std::int64_t> addScaled(std::int64_t base, std::int64_t offset, double factor) {
  std::int64_t scaled = offset;
  if (factor != 1.0) {
    const double value = std::round(static_cast<double>(offset) * factor);
    // 9.2e18: the largest double below 2^63 that converts safely.
    if (!(std::fabs(value) < 9.2e18)) return std::nullopt;
    scaled = static_cast<std::int64_t>(value);
  }
  std::int64_t result = 0;
  if (__builtin_add_overflow(base, scaled, &result)) return std::nullopt;
  return result;
}
}  // namespace

EventClock::EventClock(double speed) : speed_(speed) {
  if (!(std::isfinite(speed) && speed > 0.0)) {
    throw std::invalid_argument("EventClock: speed must be finite and > 0, got " +
                                std::to_string(speed));
  }
}

void EventClock::anchor(std::int64_t t_us, std::int64_t published_us) {
  anchor_t_us_ = t_us;
  anchor_published_us_ =
      last_stamp_us_ && *last_stamp_us_ > published_us ? *last_stamp_us_ : published_us;
  anchored_ = true;
}

void EventClock::reset() {
  anchored_ = false;
  last_stamp_us_.reset();
  anchor_t_us_ = 0;
  anchor_published_us_ = 0;
}

std::optional<std::int64_t> EventClock::map(std::int64_t t_us) const {
  if (!anchored_) throw std::logic_error("EventClock::map before anchor()");
  std::int64_t offset = 0;
  if (__builtin_sub_overflow(t_us, anchor_t_us_, &offset)) return std::nullopt;
  return addScaled(anchor_published_us_, offset, 1.0 / speed_);
}

std::optional<std::int64_t> EventClock::stamp(std::int64_t t_us) {
  std::optional<std::int64_t> published = map(t_us);
  if (!published) return std::nullopt;
  if (last_stamp_us_ && *published < *last_stamp_us_) published = last_stamp_us_;
  last_stamp_us_ = published;
  return published;
}

std::optional<std::int64_t> EventClock::streamTime(std::int64_t published_us) const {
  if (!anchored_) throw std::logic_error("EventClock::streamTime before anchor()");
  std::int64_t offset = 0;
  if (__builtin_sub_overflow(published_us, anchor_published_us_, &offset)) return std::nullopt;
  return addScaled(anchor_t_us_, offset, speed_);
}

}  // namespace ebslam
