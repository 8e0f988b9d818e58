#include "ebslam/slam/dedvs_fusion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ebslam {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

}  // namespace

void DepthFusionConfig::validate() const {
  require(std::isfinite(min_depth_m) && min_depth_m > 0.0 && std::isfinite(max_depth_m) &&
              max_depth_m > min_depth_m,
          "DepthFusionConfig: need 0 < min_depth_m < max_depth_m");
  require(std::isfinite(max_frame_age_s) && max_frame_age_s > 0.0,
          "DepthFusionConfig: max_frame_age_s must be positive");
  require(std::isfinite(max_surface_jump_ratio) && max_surface_jump_ratio > 0.0,
          "DepthFusionConfig: max_surface_jump_ratio must be positive");
  require(frames_kept >= 1 && frames_kept <= 100, "DepthFusionConfig: frames_kept in [1, 100]");
}

const char* toString(FusionStatus status) {
  switch (status) {
    case FusionStatus::kOk:
      return "ok";
    case FusionStatus::kNoDepthFrame:
      return "no depth frame yet";
    case FusionStatus::kOlderThanFrames:
      return "event older than every depth frame";
    case FusionStatus::kNewerThanFrames:
      return "event newer than the latest depth frame (clocks disagree or depth stalled)";
    case FusionStatus::kNoIntersection:
      return "ray meets no measured surface";
    case FusionStatus::kOutsideSensor:
      return "event outside the sensor";
  }
  return "unknown";
}

DepthEventFusion::DepthEventFusion(const DedvsSensors& sensors, const DepthFusionConfig& config)
    : sensors_(sensors), config_(config) {
  config_.validate();
  sensors_.edvs.validate();
  sensors_.depth.validate();
  require(sensors_.depth_from_edvs.matrix().allFinite(),
          "DepthEventFusion: depth_from_edvs is not finite");
  const CameraModel& edvs = sensors_.edvs;
  const PinholeCamera& depth = sensors_.depth;
  const Eigen::Matrix3d r = sensors_.depth_from_edvs.linear();
  const Eigen::Vector3d t = sensors_.depth_from_edvs.translation();
  depth_t_z_ = static_cast<float>(t.z());
  rays_.resize(static_cast<std::size_t>(edvs.width) * edvs.height);
  // Step along the ray uniformly in inverse depth w = 1 / s: the image point moves by about
  // f |t| dw, so dw = 0.25 / (f |t|) keeps the steps at a quarter depth pixel.
  const double focal = std::max(depth.fx, depth.fy);
  const double dw = 0.25 / (focal * std::max(t.norm(), 1e-3));
  const double w_near = 1.0 / config_.min_depth_m;
  const double w_far = 1.0 / config_.max_depth_m;
  const int steps = static_cast<int>(std::min(1e6, std::ceil((w_near - w_far) / dw))) + 1;
  for (int y = 0; y < edvs.height; ++y) {
    for (int x = 0; x < edvs.width; ++x) {
      Ray& ray = rays_[static_cast<std::size_t>(y) * edvs.width + x];
      ray.first = static_cast<std::uint32_t>(samples_.size());
      const std::optional<Eigen::Vector3d> direction = edvs.backprojectRay(Eigen::Vector2d(x, y));
      if (!direction) continue;
      ray.direction = direction->cast<float>();
      ray.unit = direction->normalized().cast<float>();
      const Eigen::Vector3d rotated = r * *direction;
      if (!(rotated.z() > 1e-6)) continue;
      ray.edvs_z_per_depth_z = static_cast<float>(1.0 / rotated.z());
      std::int64_t current = -1;
      double z_sum = 0.0;
      int z_count = 0;
      auto flush = [&]() {
        if (current >= 0 && ray.count < 65535) {
          samples_.push_back(
              {static_cast<std::uint32_t>(current), static_cast<float>(z_sum / z_count)});
          ++ray.count;
        }
      };
      for (int step = 0; step < steps; ++step) {
        const double w = w_near + (w_far - w_near) * step / std::max(1, steps - 1);
        const Eigen::Vector3d p = rotated / w + t;
        std::int64_t index = -1;
        if (p.z() > 0.0) {
          const long col = std::lround(depth.fx * p.x() / p.z() + depth.cx);
          const long row = std::lround(depth.fy * p.y() / p.z() + depth.cy);
          if (col >= 0 && row >= 0 && col < depth.width && row < depth.height) {
            index = static_cast<std::int64_t>(row) * depth.width + col;
          }
        }
        if (index != current) {
          flush();
          current = index;
          z_sum = 0.0;
          z_count = 0;
        }
        if (index >= 0) {
          z_sum += p.z();
          ++z_count;
        }
      }
      flush();
    }
  }
  samples_.shrink_to_fit();
}

std::size_t DepthEventFusion::tableBytes() const {
  return rays_.size() * sizeof(Ray) + samples_.size() * sizeof(Sample);
}

double DepthEventFusion::meanSamplesPerRay() const {
  return rays_.empty() ? 0.0 : static_cast<double>(samples_.size()) / rays_.size();
}

bool DepthEventFusion::addDepthFrame(const cv::Mat& depth, double stamp_s) {
  require(depth.rows == sensors_.depth.height && depth.cols == sensors_.depth.width,
          "DepthEventFusion: depth image is " + std::to_string(depth.cols) + "x" +
              std::to_string(depth.rows) + ", the calibration's depth camera is " +
              std::to_string(sensors_.depth.width) + "x" + std::to_string(sensors_.depth.height));
  require(depth.type() == CV_16UC1 || depth.type() == CV_32FC1,
          "DepthEventFusion: depth image must be CV_16UC1 (mm) or CV_32FC1 (m)");
  require(std::isfinite(stamp_s), "DepthEventFusion: depth stamp not finite");
  const double t = stamp_s - sensors_.depth_clock_offset_s;
  if (!frames_.empty() && t <= frames_.back().t_event_clock_s) return false;
  Frame frame;
  frame.t_event_clock_s = t;
  if (depth.type() == CV_16UC1) {
    depth.convertTo(frame.depth_m, CV_32F, 1e-3);
  } else {
    frame.depth_m = depth.clone();
    cv::patchNaNs(frame.depth_m, 0.0);
  }
  if (!frame.depth_m.isContinuous()) frame.depth_m = frame.depth_m.clone();
  frames_.push_back(std::move(frame));
  while (frames_.size() > config_.frames_kept) frames_.pop_front();
  return true;
}

float DepthEventFusion::depthAt(std::uint16_t x, std::uint16_t y, const float* depth_m) const {
  const Ray& ray = rays_[static_cast<std::size_t>(y) * sensors_.edvs.width + x];
  const Sample* samples = samples_.data() + ray.first;
  const float jump = static_cast<float>(config_.max_surface_jump_ratio);
  float previous_diff = 0.0f;
  float previous_measured = 0.0f;
  float previous_ray = 0.0f;
  bool have_previous = false;
  for (std::uint32_t i = 0; i < ray.count; ++i) {
    const float measured = depth_m[samples[i].pixel];
    if (!(measured > 0.0f)) {
      have_previous = false;
      continue;
    }
    const float ray_depth = samples[i].ray_depth_m;
    const float diff = measured - ray_depth;
    if (have_previous && previous_diff >= 0.0f && diff <= 0.0f &&
        std::abs(measured - previous_measured) <=
            jump * std::min(measured, previous_measured) + (ray_depth - previous_ray)) {
      const float denominator = previous_diff - diff;
      const float a = denominator > 0.0f ? previous_diff / denominator : 0.5f;
      const float depth_z = previous_ray + a * (ray_depth - previous_ray);
      return (depth_z - depth_t_z_) * ray.edvs_z_per_depth_z;
    }
    previous_diff = diff;
    previous_measured = measured;
    previous_ray = ray_depth;
    have_previous = true;
  }
  return kNaN;
}

FusedEvent DepthEventFusion::fuse(const Event& event) const {
  FusedEvent fused;
  fused.event = event;
  fused.depth_m = kNaN;
  fused.point = Eigen::Vector3f::Constant(kNaN);
  if (event.x >= sensors_.edvs.width || event.y >= sensors_.edvs.height) {
    fused.status = FusionStatus::kOutsideSensor;
    return fused;
  }
  fused.ray = rays_[static_cast<std::size_t>(event.y) * sensors_.edvs.width + event.x].unit;
  if (frames_.empty()) {
    fused.status = FusionStatus::kNoDepthFrame;
    return fused;
  }
  const double t = static_cast<double>(event.t_us) * 1e-6;
  const Frame* best = nullptr;
  double best_gap = std::numeric_limits<double>::infinity();
  for (const Frame& frame : frames_) {
    const double gap = std::abs(frame.t_event_clock_s - t);
    if (gap < best_gap) {
      best_gap = gap;
      best = &frame;
    }
  }
  if (best_gap > config_.max_frame_age_s) {
    fused.status = t < frames_.front().t_event_clock_s ? FusionStatus::kOlderThanFrames
                                                       : FusionStatus::kNewerThanFrames;
    return fused;
  }
  const float depth = depthAt(event.x, event.y, best->depth_m.ptr<float>(0));
  if (std::isnan(depth)) {
    fused.status = FusionStatus::kNoIntersection;
    return fused;
  }
  fused.depth_m = depth;
  fused.point =
      rays_[static_cast<std::size_t>(event.y) * sensors_.edvs.width + event.x].direction * depth;
  fused.status = FusionStatus::kOk;
  return fused;
}

}  // namespace ebslam
