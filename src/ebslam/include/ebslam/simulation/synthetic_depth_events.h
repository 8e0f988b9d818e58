#pragma once

// A small synthetic depth-event source for EB-SLAM-3D's tests, benchmarks and evaluation without
// the D-eDVS simulator: a pinhole event sensor moves through a closed box room with random straight
// texture edges and fires an event whenever an edge point's projection enters another pixel, with
// PrimeSense-like depth noise (sigma = k D^2) as in the D-eDVS (8.2). A geometric model of where
// events happen, not of DVS pixels. Details: docs/ebslam_core.md#synthetic-depth-events

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "ebslam/events/trajectory.h"
#include "ebslam/slam/ebslam3d.h"

namespace ebslam {

/// Pinhole event sensor with a depth range: pixel u covers [u, u + 1), principal point (cx, cy).
struct SyntheticDepthSensor {
  int width = 128;
  int height = 128;
  double focal_px = 160.0;  ///< the eDVS of the D-eDVS (8.2: f = 160 initial value)
  double cx = 64.0;
  double cy = 64.0;
  double min_depth_m = 0.4;  ///< PrimeSense range (8.4: reliable up to about 2.5 m at 30 Hz)
  double max_depth_m = 4.0;
  double depth_noise_per_m2 = 0.0015;  ///< depth sigma = k D^2 [1/m]
};

struct SyntheticRoomConfig {
  double margin_m = 1.5;          ///< room faces this far beyond the path's bounding box [m]
  int edges_per_square_m = 3;     ///< texture edges per m^2 of face
  double point_spacing_m = 0.01;  ///< sampling along an edge [m]
  std::uint64_t seed = 1;
};

/// Edge points [m] of a textured box room around the positions of `path` (world frame).
/// Throws std::invalid_argument for an empty path or a non-positive spacing / margin.
std::vector<Eigen::Vector3f> makeSyntheticRoom(const Trajectory& path,
                                               const SyntheticRoomConfig& config = {});

struct SyntheticEventConfig {
  double step_s = 0.001;      ///< simulation step [s]
  double noise_share = 0.02;  ///< noise events per edge event (random pixel and depth)
  std::uint64_t seed = 1;
};

/// Depth events of a sensor whose pose (sensor -> world, optical frame: z forward) follows
/// `path` (interpolated) over [t0_s, t1_s], timestamps t_us = round(t * 1e6). Throws
/// std::invalid_argument for an invalid range or config (std::out_of_range from
/// interpolatePose outside the path).
PointEventVector simulateDepthEvents(const std::vector<Eigen::Vector3f>& scene,
                                     const SyntheticDepthSensor& sensor, const Trajectory& path,
                                     double t0_s, double t1_s,
                                     const SyntheticEventConfig& config = {});

}  // namespace ebslam
