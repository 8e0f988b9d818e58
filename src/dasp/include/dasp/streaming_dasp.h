// Streaming (temporal-stable) Depth-Adaptive Superpixels (thesis §5.2.3, alg. 6): the first
// frame is seeded by SPDS, every later frame by Delta Density Sampling from the previous frame's
// superpixel centres, and each superpixel remembers the superpixel of the previous frame whose
// centre its seed continued (the relation C_DDS of eq. 5.9).
#pragma once

#include <cstdint>
#include <vector>

#include "dasp/dasp.h"
#include "dasp/delta_density.h"

namespace dasp {

/// Parameters of streaming DASP.
struct StreamingDaspConfig {
  /// DASP parameters of every frame (the seed is combined with the frame index).
  DaspConfig dasp;
  DeltaDensityConfig delta;
};

/// Superpixels of one frame of the stream and their links to the previous frame.
struct StreamingDaspFrame {
  std::int64_t frame_index = 0;  ///< 0 for the first frame after construction or reset()
  Superpixels superpixels;
  /// Per superpixel: index of the previous frame's superpixel whose centre seeded it (eq. 5.9),
  /// -1 if its seed was added by DDS, created by a DALIC split, or this is the first frame.
  std::vector<int> predecessor;
  /// Per superpixel: an id that is kept as long as the seed chain continues (the predecessor's
  /// id) and is new (never used before in this stream) otherwise.
  std::vector<std::int64_t> track_id;
  int seeds_kept = 0;     ///< seeds continued from the previous frame
  int seeds_added = 0;    ///< seeds added by DDS (first frame: all seeds)
  int seeds_removed = 0;  ///< previous centres dropped by DDS (density samples and invalid pixels)
};

/// Stream-ASP/DASP (alg. 6). Keeps only the previous frame's centres and ids, so that memory is
/// bounded on an endless stream.
class StreamingDasp {
 public:
  explicit StreamingDasp(const StreamingDaspConfig& config = {});
  /// Superpixels of the next frame. Throws std::invalid_argument like computeDasp.
  StreamingDaspFrame process(const RgbdFrame& frame);
  /// Forget the previous frame (the next frame is seeded by SPDS again).
  void reset();
  const StreamingDaspConfig& config() const { return config_; }

 private:
  StreamingDaspConfig config_;
  std::int64_t frame_index_ = 0;
  std::int64_t next_track_id_ = 0;
  std::vector<Seed> previous_centres_;
  std::vector<std::int64_t> previous_track_ids_;
};

}  // namespace dasp
