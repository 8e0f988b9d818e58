#pragma once

// What the D-eDVS depth fusion needs to know of the rig (thesis 8.2): the eDVS and depth camera
// intrinsics, their extrinsics and clocks (sensors.yaml, written by the simulator and by the
// calibration), and the depth frames it fuses. Frames: REP 103 optical frames, metres;
// p_depth = depth_from_edvs * p_edvs (R, t of eq. 8.4). Details: docs/dedvs_core.md

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "ebslam/slam/camera_model.h"

namespace ebslam {

/// Pinhole intrinsics of the depth camera (OpenCV convention: pixel centres at integers).
struct PinholeCamera {
  int width = 320;
  int height = 240;
  double fx = 260.0;  ///< [px]; 520 at 640 x 480 (the thesis' PrimeSense reference value)
  double fy = 260.0;
  double cx = 159.5;
  double cy = 119.5;

  void validate() const;
  /// Scales to another resolution (both axes by the same factor).
  PinholeCamera scaled(double factor) const;
};

/// One frame of the depth camera.
struct DepthFrame {
  double t_s = 0.0;      ///< true exposure time [s, trajectory clock]
  double stamp_s = 0.0;  ///< the camera's own timestamp: t_s + clock_offset_s
  cv::Mat depth_mm;      ///< CV_16UC1, millimetres, 0 = no depth
  cv::Mat colour;        ///< CV_8UC3, BGR, registered to the depth image
  cv::Mat true_depth_m;  ///< CV_32FC1, noiseless z [m], NaN where the ray hits nothing
};

/// The sensor description of a run (what the fusion needs, plus the truth to check it).
struct DedvsSensors {
  CameraModel edvs;
  PinholeCamera depth;
  Eigen::Isometry3d depth_from_edvs = Eigen::Isometry3d::Identity();
  double depth_clock_offset_s = 0.0;
  double depth_frame_rate_hz = 30.0;
};

/// sensors.yaml (cv::FileStorage YAML): edvs_{width,height,focal_px,cx,cy,kappa1,kappa2},
/// depth_{width,height,fx,fy,cx,cy}, depth_from_edvs (4x4), depth_clock_offset_s,
/// depth_frame_rate_hz. The calibration tool writes the same keys.
void writeDedvsSensors(const std::string& path, const DedvsSensors& sensors);
DedvsSensors readDedvsSensors(const std::string& path);

}  // namespace ebslam
