#include "edvs/timestamp_unwrapper.h"
#include <algorithm>
#include <cmath>

namespace edvs {

void TimestampUnwrapper::reset() {
  started_ = false;
  last_raw_ = 0;
  last_unwrapped_ = 0;
  last_host_us_.reset();
  idle_since_last_ = false;
  wraps_ = 0;
  wraps_from_host_ = 0;
}

TimestampUnwrapper::Step TimestampUnwrapper::peek(std::int64_t raw_us,
                                                  std::optional<std::int64_t> host_us) const {
  Step s;
  if (host_us && last_host_us_)
    s.host_elapsed_us = std::max<std::int64_t>(0, *host_us - *last_host_us_);
  if (delta_) {
    s.step_us = std::max<std::int64_t>(0, raw_us);
    return s;
  }
  if (!started_) return s;
  s.step_us = raw_us - last_raw_;
  if (period_us_ > 0) {
    if (s.step_us < 0) {
      s.step_us += period_us_;
      s.wraps = 1;
    }
    // Whole periods that the raw values cannot show: the host clock says more time passed.
    if (idle_since_last_ && s.host_elapsed_us > period_us_ / 2) {
      // Rounded down with an eighth of a period of slack for read latency: a host-side stall
      // with events still queued somewhere must not invent a period; a missed one is worse
      // only by a period, and the next idle gap is judged afresh.
      const double missing =
          std::floor(static_cast<double>(s.host_elapsed_us - s.step_us + period_us_ / 8) /
                     static_cast<double>(period_us_));
      if (missing >= 1.0) {
        const auto k = static_cast<std::int64_t>(missing);
        s.step_us += k * period_us_;
        s.wraps += static_cast<std::uint64_t>(k);
        s.wraps_from_host = static_cast<std::uint64_t>(k);
      }
    }
  } else if (s.step_us < 0) {
    s.step_us = 0;  // a 64-bit device clock never runs backwards; clamp corrupt values
  }
  return s;
}

std::int64_t TimestampUnwrapper::commit(std::int64_t raw_us, std::optional<std::int64_t> host_us,
                                        const Step& step) {
  if (host_us) last_host_us_ = host_us;
  if (!started_ && !delta_) {
    last_unwrapped_ = raw_us;
  } else {
    last_unwrapped_ += std::max<std::int64_t>(0, step.step_us);
  }
  started_ = true;
  last_raw_ = raw_us;
  wraps_ += step.wraps;
  wraps_from_host_ += step.wraps_from_host;
  idle_since_last_ = false;
  return last_unwrapped_;
}

std::int64_t TimestampUnwrapper::unwrap(std::int64_t raw_us, std::optional<std::int64_t> host_us) {
  return commit(raw_us, host_us, peek(raw_us, host_us));
}

}  // namespace edvs
