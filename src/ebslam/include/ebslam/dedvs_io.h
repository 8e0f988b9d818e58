#pragma once

// A simulated D-eDVS run as files (written by the dedvs_simulate tool, read by the fusion
// evaluation and the RgbdEventSimulator nodelet). Directory layout:
//   events.bin          events with ground truth (format below)
//   depth/NNNNNN.png    depth frames, 16-bit PNG, millimetres, 0 = no depth
//   colour/NNNNNN.png   registered colour, 8-bit BGR PNG
//   frames.txt          one line per frame: `index t_true_s stamp_s` (stamp on the camera clock)
//   rig_groundtruth.txt  TUM trajectory, depth optical frame -> world
//   edvs_groundtruth.txt TUM trajectory, eDVS optical frame -> world
//   sensors.yaml        the sensors (read back with readDedvsSensors)
//
// events.bin: magic "DEDVSEV1" (8 bytes), uint32 width, uint32 height, uint64 count, then
// `count` little-endian records of 16 bytes: int64 t_us, uint16 x, uint16 y, float32 true
// depth [m] (NaN = no surface), with x's bit 15 = polarity, y's bit 15 = noise event, y's
// bit 14 = depth edge.

#include <string>
#include <vector>

#include "ebslam/dedvs_simulator.h"

namespace ebslam {

/// The sensor description of a run (what the fusion needs, plus the truth to check it).
struct DedvsSensors {
  CameraModel edvs;
  PinholeCamera depth;
  Eigen::Isometry3d depth_from_edvs = Eigen::Isometry3d::Identity();
  double depth_clock_offset_s = 0.0;
  double depth_frame_rate_hz = 30.0;
};

DedvsSensors sensorsOf(const DedvsSimulatorConfig& config);

/// Writes `run` into `directory` (created if missing). Throws std::runtime_error on I/O
/// failure.
void writeDedvsRun(const std::string& directory, const DedvsRun& run, const DedvsSensors& sensors);

/// Event file alone. Throws std::runtime_error if the file cannot be read or is malformed.
void writeTrueDepthEvents(const std::string& path, const std::vector<TrueDepthEvent>& events,
                          int width, int height);
std::vector<TrueDepthEvent> readTrueDepthEvents(const std::string& path);

/// Reads a run written by writeDedvsRun (true depth images are not stored: left empty).
/// Throws std::runtime_error naming the file for anything missing or malformed.
DedvsRun readDedvsRun(const std::string& directory, DedvsSensors* sensors = nullptr);

/// sensors.yaml (cv::FileStorage YAML): edvs_{width,height,focal_px,cx,cy,kappa1,kappa2},
/// depth_{width,height,fx,fy,cx,cy}, depth_from_edvs (4x4), depth_clock_offset_s,
/// depth_frame_rate_hz. The calibration tool writes the same keys.
void writeDedvsSensors(const std::string& path, const DedvsSensors& sensors);
DedvsSensors readDedvsSensors(const std::string& path);

}  // namespace ebslam
