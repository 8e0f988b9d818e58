#pragma once

// Synthesised hand-held camera paths for the EB-SLAM-3D evaluation, covering motions the TUM
// paths lack: a fast full turn about the vertical axis, a low sweep over a floor, fast shaking,
// an orbit about an object at close range.
// World frame as the TUM freiburg1 motion capture and dedvs_scene.h (z up, floor at z = 0,
// metres); poses are the camera's optical frame (x right, y down, z forward) in the world. Every
// path adds a hand tremor (sums of sinusoids with seeded random frequencies and phases).

#include <cstdint>
#include <string>

#include "ebslam/events/trajectory.h"

namespace ebslam {

enum class HandheldMotion {
  /// 1.4 m high, 10 deg down; slow pans for 5 s, a full 360 deg turn about the vertical in 4 s
  /// (mean 90 deg/s, peak 180 deg/s), then slow pans again.
  kYawTurn,
  /// 0.55 m above the floor, 60 deg down; side-to-side sweeps of +-0.5 m at 0.25 Hz while
  /// advancing 5 cm/s, yawing +-10 deg with the sweep.
  kFloorSweep,
  /// 1.3 m high, 35 deg down towards the room's centre; shaking of +-3 cm and +-4 deg at 2.5-4 Hz
  /// on top of a slow drift.
  kShake,
  /// Orbiting an object on the table (centre (0, 0, 0.85) m) at 0.4-0.8 m, the depth camera's
  /// near limit: 0.35 m above it, horizontal radius 0.45 +- 0.2 m (period 7 s), always looking at
  /// it, one revolution every 12 s (30 deg/s), starting on the -x side.
  kOrbit,
};

/// "yaw_turn", "floor_sweep", "shake", "orbit".
const char* toString(HandheldMotion motion);
/// Inverse of toString; throws std::invalid_argument for another name.
HandheldMotion handheldMotionFromString(const std::string& name);

/// The path at `rate_hz` poses per second over [0, duration_s]. Throws std::invalid_argument for
/// a non-positive duration or rate.
Trajectory makeHandheldMotion(HandheldMotion motion, double duration_s, std::uint64_t seed,
                              double rate_hz = 100.0);

}  // namespace ebslam
