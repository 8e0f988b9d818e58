#pragma once

// 64-bit device time from the eDVS's wrapping (16/24/32-bit) or delta timestamps.

#include <cstdint>
#include <optional>

namespace edvs {

/// Unwraps an N-bit device clock to 64-bit microseconds that never run backwards: each raw value
/// is the smallest forward step from the previous one (modulo the wrap period). Whole periods a
/// quiet gap hid are added back from host time, but only when the line was seen idle in between
/// (noteIdle()): while a backlog is read, host time says nothing about device time.
class TimestampUnwrapper {
 public:
  /// period_us: wrap period (2^bits) [us]; 0 means the input is already a 64-bit time.
  /// delta: raw values are deltas to add (kDelta format) instead of clock readings.
  explicit TimestampUnwrapper(std::int64_t period_us = 0, bool delta = false)
      : period_us_(period_us), delta_(delta) {}

  /// raw_us: device time as sent (kDelta: the delta); host_us: host receive time [us] of the
  /// bytes or std::nullopt when unknown. Returns the unwrapped time.
  std::int64_t unwrap(std::int64_t raw_us, std::optional<std::int64_t> host_us);

  /// The two halves of unwrap(): the forward step [us] that `raw_us` would add (including whole
  /// periods inferred from host time) and the host time elapsed since the last committed value
  /// (-1 if unknown), without changing any state...
  struct Step {
    std::int64_t step_us = 0;
    std::int64_t host_elapsed_us = -1;
    std::uint64_t wraps = 0;
    std::uint64_t wraps_from_host = 0;
  };
  Step peek(std::int64_t raw_us, std::optional<std::int64_t> host_us) const;
  /// ...and accepting it.
  std::int64_t commit(std::int64_t raw_us, std::optional<std::int64_t> host_us, const Step& step);

  bool started() const { return started_; }
  std::int64_t last() const { return last_unwrapped_; }
  std::uint64_t wraps() const { return wraps_; }
  std::uint64_t wrapsFromHostTime() const { return wraps_from_host_; }
  /// The line delivered no bytes at some point since the last committed value: the device had
  /// nothing queued, so host time since then is device time too.
  void noteIdle() { idle_since_last_ = true; }
  void reset();

 private:
  std::int64_t period_us_;
  bool delta_;
  bool idle_since_last_ = false;
  bool started_ = false;
  std::int64_t last_raw_ = 0;
  std::int64_t last_unwrapped_ = 0;
  std::optional<std::int64_t> last_host_us_;
  std::uint64_t wraps_ = 0;
  std::uint64_t wraps_from_host_ = 0;
};

}  // namespace edvs
