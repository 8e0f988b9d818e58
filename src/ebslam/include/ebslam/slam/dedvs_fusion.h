#pragma once

// Depth for every eDVS event from the depth camera (thesis 8.2, fig. 8.5): the nearest crossing of
// the event pixel's ray with the measured surface, searched along its epipolar segment in the
// depth image (listed per eDVS pixel once per calibration). Frames: depth and 3D point in the eDVS
// optical frame (z along the optical axis); sensors.depth_from_edvs maps eDVS points into the
// depth frame. Time: depth frames on the event clock as stamp - depth_clock_offset_s; an event
// takes the frame nearest in time within max_frame_age_s. Details: docs/dedvs_core.md#depth-fusion

#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/slam/dedvs_sensors.h"

namespace ebslam {

struct DepthFusionConfig {
  double min_depth_m = 0.4;  ///< near end of the ray segments (eDVS z) [m]
  double max_depth_m = 5.0;  ///< far end [m]
  /// Largest time between an event and the depth frame it uses [s]; 1.5 frame periods at
  /// 30 Hz. Events farther from every frame get no depth.
  double max_frame_age_s = 0.05;
  /// Two neighbouring samples belong to one surface when their measured depths differ by at
  /// most this fraction of the nearer one plus the ray's own depth step between them.
  double max_surface_jump_ratio = 0.05;
  std::size_t frames_kept = 4;  ///< depth frames kept for the time association

  void validate() const;
};

/// Why an event got no depth (kOk: it got one).
enum class FusionStatus : std::uint8_t {
  kOk = 0,
  kNoDepthFrame,     ///< no frame yet
  kOlderThanFrames,  ///< event older than every kept frame by more than max_frame_age_s
  kNewerThanFrames,  ///< event newer than the latest frame by more than max_frame_age_s
  kNoIntersection,   ///< the ray meets no measured surface (holes, out of range)
  kOutsideSensor,    ///< event pixel outside the eDVS
};
const char* toString(FusionStatus status);

struct FusedEvent {
  Event event;
  float depth_m = 0.0f;   ///< eDVS z [m], NaN without depth
  Eigen::Vector3f point;  ///< eDVS optical frame [m], NaN without depth
  /// Unit viewing ray of the event's pixel in the eDVS optical frame, also without a depth (an
  /// event EB-SLAM-3D can score along its ray); NaN outside the sensor.
  Eigen::Vector3f ray = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  FusionStatus status = FusionStatus::kOk;
};

class DepthEventFusion {
 public:
  /// Precomputes the ray table. Throws std::invalid_argument for invalid sensors or config.
  explicit DepthEventFusion(const DedvsSensors& sensors, const DepthFusionConfig& config = {});

  /// Adds a depth frame (CV_16UC1 millimetres with 0 = none, or CV_32FC1 metres with 0/NaN =
  /// none) stamped on the depth camera's clock [s]. Throws std::invalid_argument for another
  /// type or size (the frame is not kept). Frames older than the latest are ignored and
  /// reported by the return value (false).
  bool addDepthFrame(const cv::Mat& depth, double stamp_s);
  void clearFrames() { frames_.clear(); }
  std::size_t frameCount() const { return frames_.size(); }

  /// Depth of one event; NaN and a status when it has none.
  FusedEvent fuse(const Event& event) const;
  /// Depth of an event against a given frame (metres, CV_32FC1 as stored internally), O(1).
  float depthAt(std::uint16_t x, std::uint16_t y, const float* depth_m) const;

  /// Bytes of the precomputed ray table.
  std::size_t tableBytes() const;
  /// Mean samples per ray.
  double meanSamplesPerRay() const;
  const DedvsSensors& sensors() const { return sensors_; }

 private:
  struct Sample {
    std::uint32_t pixel;  // index into the depth image
    float ray_depth_m;    // d_i: depth-camera z of the ray's point seen through that pixel
  };
  struct Ray {
    std::uint32_t first = 0;
    std::uint16_t count = 0;
    float edvs_z_per_depth_z = 0.0f;  // s = (d - t_z) * this
    // eDVS ray (x, y, 1); NaN where the pixel has no ray
    Eigen::Vector3f direction = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    Eigen::Vector3f unit = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  };
  struct Frame {
    double t_event_clock_s;
    cv::Mat depth_m;  // CV_32FC1, 0 = none
  };

  DedvsSensors sensors_;
  DepthFusionConfig config_;
  std::vector<Ray> rays_;
  std::vector<Sample> samples_;
  float depth_t_z_ = 0.0f;
  std::deque<Frame> frames_;
};

}  // namespace ebslam
