#pragma once

// Maps a source's own clock (eDVS device clock, event file, simulated time; Event::t_us [us]) to
// the published clock, integer us since the ROS epoch: published_us = anchor_published_us +
// round((t_us - anchor_t_us) / speed), anchored once per stream. stamp() never goes back (also
// across re-anchoring); map() is unclamped. ROS-free; the ROS side is
// ebslam_msgs/event_conversions.h. Details: docs/ebslam_core.md#event-clock

#include <cstdint>
#include <optional>

namespace ebslam {

class EventClock {
 public:
  /// Throws std::invalid_argument unless speed is finite and > 0.
  explicit EventClock(double speed = 1.0);

  /// Maps stream time t_us to published time published_us from now on. The anchor is moved
  /// forward to the last stamp() result when it would lie before it, so a new stream never
  /// starts before the previous one ended.
  void anchor(std::int64_t t_us, std::int64_t published_us);
  /// Forgets the anchor (the next stream needs a new one: a reconnect); the clamp is kept.
  void unanchor() { anchored_ = false; }
  /// Forgets the anchor and the clamp (a new, independent stream).
  void reset();
  bool anchored() const { return anchored_; }
  double speed() const { return speed_; }
  /// The published time of the anchor [us since the ROS epoch]; 0 before the first anchor.
  std::int64_t anchorPublished() const { return anchor_published_us_; }

  /// Published time of stream time t_us, unclamped; nullopt when it overflows 64 bit.
  /// Throws std::logic_error before the first anchor().
  std::optional<std::int64_t> map(std::int64_t t_us) const;
  /// map(t_us), but never before the previous stamp() result; nullopt (and nothing remembered)
  /// when map() overflows.
  std::optional<std::int64_t> stamp(std::int64_t t_us);
  /// The last stamp() result (nullopt before the first).
  std::optional<std::int64_t> lastStamp() const { return last_stamp_us_; }
  /// Inverse of map(): the stream time of published time published_us (rounded to the nearest
  /// microsecond; nullopt on overflow). Throws std::logic_error before the first anchor().
  std::optional<std::int64_t> streamTime(std::int64_t published_us) const;

 private:
  double speed_;
  bool anchored_ = false;
  std::int64_t anchor_t_us_ = 0;
  std::int64_t anchor_published_us_ = 0;
  std::optional<std::int64_t> last_stamp_us_;
};

}  // namespace ebslam
