#pragma once
// Rate limit of one kind of log message on the wall clock, for problems that can repeat with
// every message. ROS_*_THROTTLE runs on ROS time, which a looping bag sends back (every loop logs
// again) and a paused /clock stops; the wall clock does neither. Counts what it held back, so
// that the next message can say how often the problem occurred meanwhile.

#include <ros/time.h>

#include <cstdint>

namespace ebslam_ros {

class WallThrottle {
 public:
  explicit WallThrottle(double period_s) : period_s_(period_s) {}

  /// Notes one occurrence; true when it is to be logged now (the first one, then at most once
  /// per period). suppressed() is then the number of occurrences held back before it.
  bool due() {
    const ros::WallTime now = ros::WallTime::now();
    if (!last_.isZero() && (now - last_).toSec() < period_s_) {
      ++pending_;
      return false;
    }
    last_ = now;
    suppressed_ = pending_;
    pending_ = 0;
    return true;
  }
  std::uint64_t suppressed() const { return suppressed_; }
  double period() const { return period_s_; }

 private:
  double period_s_;
  ros::WallTime last_;
  std::uint64_t pending_ = 0, suppressed_ = 0;
};

}  // namespace ebslam_ros
