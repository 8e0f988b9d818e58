#pragma once

// A simulated D-eDVS run as files (written by the dedvs_simulate tool, read by the fusion
// evaluation and the RgbdEventSimulator nodelet): events.bin (events with true depth [m]),
// depth/ (16-bit PNG [mm], 0 = no depth) and colour/ frames, frames.txt, rig_ and
// edvs_groundtruth.txt (TUM), sensors.yaml. Directory layout and the events.bin record format:
// docs/dedvs_core.md#run-files

#include <string>
#include <vector>

#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/dedvs_sensors.h"

namespace ebslam {

/// The sensor description of a simulated rig (its true calibration).
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

}  // namespace ebslam
