// The localisation pass shared by the Event-based Particle Filter and EB-SLAM-2D (internal to the
// ebslam library).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ebslam/ebpf.h"

namespace ebslam::detail {

/// Scores the particles against `map` for `events` in batches of at most config.batch_size
/// (alg. 7; alg. 8's "update particles"), each batch diffused with b times the per-event variance
/// (eq. 6.39) times schedule.signal_fraction, and resamples every config.resample_every events.
/// After each batch, after_batch(pixel_index, b, resampled, batch_end) runs: the batch's pixel
/// indices (row-major into the camera image), its size, whether it resampled, and the index in
/// `events` one past the batch. `map` and `schedule` are read afresh for every batch, so the
/// callback may change them (EB-SLAM maps, both adapt G0). The events must have been validated.
template <typename AfterBatch>
void localiseInBatches(const Event* events, std::size_t count, const CeilingCamera& camera,
                       const EventFilterConfig& config, const G0Schedule& schedule,
                       const GridMap2f& map, ParticleSet2D& particles, std::uint64_t& processed,
                       int& since_resample, AfterBatch&& after_batch) {
  const float* ox = camera.offsetX().data();
  const float* oy = camera.offsetY().data();
  std::uint32_t index[64];  // batch_size <= 64 (validated with the config)
  std::size_t i = 0;
  while (i < count) {
    const int b = static_cast<int>(std::min<std::size_t>(config.batch_size, count - i));
    for (int j = 0; j < b; ++j) {
      const Event& e = events[i + j];
      index[j] = static_cast<std::uint32_t>(e.y) * camera.width() + e.x;
    }
    // Diffusion variance of b events, each carrying motion with probability signal_fraction.
    const double root_b = std::sqrt(static_cast<double>(b) * schedule.signal_fraction);
    particles.step(index, b, ox, oy, map, schedule.diffusion.sigma_xy_m * root_b,
                   schedule.diffusion.sigma_theta_rad * root_b, schedule.batch_decay[b - 1]);
    i += b;
    processed += b;
    since_resample += b;
    const bool resampled = since_resample >= config.resample_every;
    if (resampled) {
      particles.resampleSystematic(config.reset_scores_on_resample);
      since_resample -= config.resample_every;
    }
    after_batch(static_cast<const std::uint32_t*>(index), b, resampled, i);
  }
}

}  // namespace ebslam::detail
