#pragma once

#include <cstdint>
#include <vector>

namespace ebslam {

/// One address-event of a dynamic vision sensor.
///
/// Time is in microseconds on a 64-bit clock that never runs backwards within one stream: for
/// the eDVS driver it is the device clock unwrapped to 64 bit, for the simulator the simulated
/// time since the start of the trajectory. Pixel (0,0) is the top-left pixel (x to the right,
/// y down), as in dvs_msgs.
struct Event {
  std::int64_t t_us = 0;  ///< timestamp [microseconds]
  std::uint16_t x = 0;    ///< pixel column, 0 = left
  std::uint16_t y = 0;    ///< pixel row, 0 = top
  bool polarity = false;  ///< true = ON (brightness increased), false = OFF

  friend bool operator==(const Event& a, const Event& b) {
    return a.t_us == b.t_us && a.x == b.x && a.y == b.y && a.polarity == b.polarity;
  }
  friend bool operator!=(const Event& a, const Event& b) { return !(a == b); }
};

using EventVector = std::vector<Event>;

/// Size of the sensor the events come from [pixels]; the eDVS is 128 x 128.
struct SensorSize {
  std::uint32_t width = 128;
  std::uint32_t height = 128;
  bool contains(const Event& e) const { return e.x < width && e.y < height; }
};

}  // namespace ebslam
