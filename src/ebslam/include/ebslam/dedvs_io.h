#pragma once

// A simulated D-eDVS run as files (written by the dedvs_simulate tool, read by the fusion
// evaluation and the RgbdEventSimulator nodelet): events.bin (events with true depth [m]),
// depth/ (16-bit PNG [mm], 0 = no depth) and colour/ frames, frames.txt, rig_ and
// edvs_groundtruth.txt (TUM), sensors.yaml. Directory layout and the events.bin record format:
// docs/dedvs_core.md#run-files

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
