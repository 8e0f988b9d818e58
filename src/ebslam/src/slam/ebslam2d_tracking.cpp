#include "ebslam/slam/ebslam2d_tracking.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {
namespace {

// Mean of M at the ceiling offsets of `pixels` mapped through the pose (c, s: cos, sin of its
// heading); points outside the map count as 0.
template <typename PixelOf>
double meanAt(const CeilingCamera& camera, const GridMap2f& map, const Pose2& pose, double c,
              double s, std::size_t count, PixelOf pixel_of) {
  const std::vector<float>& ox = camera.offsetX();
  const std::vector<float>& oy = camera.offsetY();
  double sum = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t p = pixel_of(i);
    const double x = pose.x + c * ox[p] - s * oy[p];
    const double y = pose.y + s * ox[p] + c * oy[p];
    sum += map.lookup(x, y);
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace

void TrackingMonitorConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("TrackingMonitorConfig: " + what);
  };
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (min_events < 1) fail("min_events must be >= 1");
  if (!positive(time_constant_s)) fail("time_constant_s must be positive");
  if (!positive(lost_contrast)) fail("lost_contrast must be positive");
  if (!positive(reference_time_constant_s)) fail("reference_time_constant_s must be positive");
  if (!(std::isfinite(warmup_s) && warmup_s >= 0.0)) fail("warmup_s must be >= 0");
  if (!(positive(lost_ratio) && lost_ratio <= 1.0)) fail("lost_ratio must be in (0, 1]");
  if (!(std::isfinite(recovered_ratio) && recovered_ratio >= lost_ratio)) {
    fail("recovered_ratio must be >= lost_ratio");
  }
  if (!(std::isfinite(lost_ratio_high) && lost_ratio_high >= 1.0)) {
    fail("lost_ratio_high must be >= 1");
  }
  if (!(std::isfinite(recovered_ratio_high) && recovered_ratio_high >= recovered_ratio &&
        recovered_ratio_high <= lost_ratio_high)) {
    fail("recovered_ratio_high must lie in [recovered_ratio, lost_ratio_high]");
  }
  if (!(std::isfinite(recovered_contrast) && recovered_contrast >= lost_contrast)) {
    fail("recovered_contrast must be >= lost_contrast");
  }
  if (!(std::isfinite(lost_after_s) && lost_after_s >= 0.0)) fail("lost_after_s must be >= 0");
  if (!(std::isfinite(recovered_after_s) && recovered_after_s >= 0.0)) {
    fail("recovered_after_s must be >= 0");
  }
  if (!(std::isfinite(min_footprint_fraction) && min_footprint_fraction >= 0.0)) {
    fail("min_footprint_fraction must be >= 0");
  }
  if (footprint_stride_px < 1) fail("footprint_stride_px must be >= 1");
}

TrackingMonitor::TrackingMonitor(const TrackingMonitorConfig& config, const CeilingCamera& camera)
    : config_(config), camera_(camera) {
  config_.validate();
  const int w = camera_.width();
  const int h = camera_.height();
  const int stride = config_.footprint_stride_px;
  for (int y = stride / 2; y < h; y += stride) {
    for (int x = stride / 2; x < w; x += stride) {
      footprint_.push_back(static_cast<std::uint32_t>(y * w + x));
    }
  }
}

void TrackingMonitor::reset() {
  state_ = TrackingState::kTracking;
  average_ = 0.0;
  reference_ = 0.0;
  last_ = 0.0;
  last_time_s_ = -1.0;
  first_time_s_ = -1.0;
  below_since_s_ = -1.0;
  above_since_s_ = -1.0;
}

TrackingState TrackingMonitor::update(double now_s, const Event* events, std::size_t count,
                                      const Pose2& estimate, const GridMap2f& map) {
  if (count < static_cast<std::size_t>(config_.min_events) || map.cellCount() == 0 ||
      !std::isfinite(estimate.x) || !std::isfinite(estimate.y) || !std::isfinite(estimate.theta)) {
    return state_;
  }
  // The map's largest value grows slowly: rescanned every 20 verdicts.
  if (map_max_scan_++ % 20 == 0) {
    map_max_ = *std::max_element(map.data.begin(), map.data.end());
  }
  const double c = std::cos(estimate.theta);
  const double s = std::sin(estimate.theta);
  const double background = meanAt(camera_, map, estimate, c, s, footprint_.size(),
                                   [this](std::size_t i) { return footprint_[i]; });
  if (!(background > config_.min_footprint_fraction * map_max_) || background <= 0.0) {
    return state_;
  }
  const auto width = static_cast<std::uint32_t>(camera_.width());
  const double on_events = meanAt(camera_, map, estimate, c, s, count, [&](std::size_t i) {
    return static_cast<std::uint32_t>(events[i].y) * width + events[i].x;
  });
  last_ = on_events / background;
  ++verdicts_;
  if (last_time_s_ < 0.0) {
    average_ = last_;
    reference_ = last_;
    first_time_s_ = now_s;
  } else if (now_s - first_time_s_ < config_.warmup_s) {
    // Warm-up: the reference is the plain average so far; no verdict yet.
    const double dt = std::max(0.0, now_s - last_time_s_);
    average_ += (1.0 - std::exp(-dt / config_.time_constant_s)) * (last_ - average_);
    reference_ += (average_ - reference_) / static_cast<double>(verdicts_);
    last_time_s_ = now_s;
    return state_;
  } else {
    const double dt = std::max(0.0, now_s - last_time_s_);
    average_ += (1.0 - std::exp(-dt / config_.time_constant_s)) * (last_ - average_);
    // The reference learns only while tracking: a collapse must not lower its own yardstick.
    if (state_ == TrackingState::kTracking && below_since_s_ < 0.0) {
      reference_ +=
          (1.0 - std::exp(-dt / config_.reference_time_constant_s)) * (average_ - reference_);
    }
  }
  last_time_s_ = now_s;
  if (average_ < std::max(config_.lost_contrast, config_.lost_ratio * reference_) ||
      average_ > config_.lost_ratio_high * reference_) {
    if (below_since_s_ < 0.0) below_since_s_ = now_s;
  } else {
    below_since_s_ = -1.0;
  }
  if (average_ > std::max(config_.recovered_contrast, config_.recovered_ratio * reference_) &&
      average_ < config_.recovered_ratio_high * reference_) {
    if (above_since_s_ < 0.0) above_since_s_ = now_s;
  } else {
    above_since_s_ = -1.0;
  }
  if (state_ == TrackingState::kTracking && below_since_s_ >= 0.0 &&
      now_s - below_since_s_ >= config_.lost_after_s) {
    state_ = TrackingState::kLost;
    ++collapses_;
  } else if (state_ == TrackingState::kLost && above_since_s_ >= 0.0 &&
             now_s - above_since_s_ >= config_.recovered_after_s) {
    state_ = TrackingState::kTracking;
  }
  return state_;
}

}  // namespace ebslam
