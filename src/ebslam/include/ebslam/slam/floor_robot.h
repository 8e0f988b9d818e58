#pragma once

// What a floor robot's base exchanges with its controller (thesis 7.4): velocity commands out,
// readings of its 360-degree ring of contact ("bump") sensors in. Robot frame: x forward, y
// left, angles counter-clockwise from forward [rad].

#include <cstdint>

namespace ebslam {

/// A commanded velocity in the robot frame: forward speed [m/s] and turn rate [rad/s].
struct VelocityCommand {
  double v_mps = 0.0;
  double omega_rps = 0.0;
};

/// One reading of the bump ring.
struct BumpReading {
  double t_s = 0.0;
  /// Bit k set: segment k is pressed; segment k is centred at k * 2 pi / segment_count (robot
  /// frame) and spans 2 pi / segment_count.
  std::uint32_t segments = 0;
  int segment_count = 8;
  /// Direction of the contact in the robot frame [rad] (mean of the pressed contacts'
  /// directions); meaningful only if contact().
  double direction_rad = 0.0;
  bool contact() const { return segments != 0; }
};

}  // namespace ebslam
