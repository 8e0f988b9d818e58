#pragma once

// D-eDVS calibration (thesis 8.2, eq. 8.5) from a recorded bag, and the simulated calibration
// bag that proves it without hardware. The bag carries the sensors' topics as record.launch
// records them: eDVS events (ebslam_msgs/EventArray), the colour image (bgr8, rgb8, mono8 or
// bgra8), the depth image registered to it (16UC1 mm or 32FC1 m) and its camera_info. The
// LED finding, pairing and solving are the core's (ebslam/calibration/dedvs_rgbd_led.h,
// ebslam/calibration/dedvs_calibration.h); this file only reads and writes bags.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "ebslam/calibration/dedvs_calibration.h"
#include "ebslam/calibration/dedvs_rgbd_led.h"
#include "ebslam/simulation/dedvs_io.h"

namespace ebslam_ros {

struct CalibrationBagTopics {
  std::string events = "/edvs/events";
  std::string colour = "/camera/rgb/image_rect_color";
  std::string depth = "/camera/depth_registered/image_raw";
  std::string camera_info = "/camera/depth_registered/camera_info";
  std::string colour_info = "/camera/rgb/camera_info";  ///< written, not read
  std::string edvs_info = "/edvs/camera_info";          ///< written, not read
};

struct SimulatedCalibrationBagOptions {
  /// The calibration run (plate poses, LED, sensors, outlier events, seeds).
  ebslam::LedCalibrationRunConfig run;
  CalibrationBagTopics topics;
  /// ROS time of simulated time 0 [s] (a plausible wall-clock time).
  double clock_origin_s = 1.7e9;
  double event_message_rate_hz = 100.0;  ///< EventArray messages per second (the driver's)
  std::string compression = "none";      ///< none, lz4 or bz2
};

struct SimulatedCalibrationBag {
  ebslam::DedvsSensors truth;  ///< the simulated sensors and their true calibration
  std::size_t events = 0;      ///< outliers included
  std::size_t outlier_events = 0;
  std::size_t frames = 0;
  double duration_s = 0.0;
};

/// Simulates a calibration run and writes it to `path` as the real topics carry it (frames
/// stamped on the depth camera's clock). Throws std::invalid_argument for invalid options,
/// rosbag::BagException on I/O failure.
SimulatedCalibrationBag writeSimulatedCalibrationBag(const std::string& path,
                                                     const SimulatedCalibrationBagOptions& options);

struct BagCalibrationOptions {
  CalibrationBagTopics topics;
  double led_frequency_hz = 250.0;  ///< the LED's known frequency [Hz]
  /// Depth camera clock: event time = frame stamp - depth_clock_offset_s [s]; written into
  /// the result's sensors.
  double depth_clock_offset_s = 0.0;
  /// Measure the offset instead (ebslam::estimateDepthClockOffset: the plate's motion in the
  /// frames against the event rate) and use it.
  bool measure_clock_offset = false;
  ebslam::RgbdLedConfig rgbd;            ///< led_frequency_hz is set from above
  ebslam::LedExtractionConfig edvs;      ///< frequency and sensor size are set from the bag
  ebslam::LedPairingConfig pairing;      ///< depth_clock_offset_s is set from above
  ebslam::DedvsCalibrationConfig solve;  ///< initial eDVS size is set from the bag
  /// Above this worst-direction rotation standard deviation the result carries pose advice
  /// [deg] (ebslam::advisePoseDiversity).
  double max_rotation_std_deg = 0.033;
};

struct BagCalibration {
  std::size_t events = 0;
  std::size_t frames = 0;      ///< colour frames paired with a depth frame
  double frame_rate_hz = 0.0;  ///< median over the frame stamps
  /// The measured clock offset (measure_clock_offset) [s]; empty if not measured or not
  /// measurable.
  std::optional<double> measured_clock_offset_s;
  ebslam::LedPairing pairing;  ///< poses: pairing.correspondences
  /// The solution; empty when there were too few poses to solve.
  std::optional<ebslam::DedvsCalibrationResult> result;
  /// Why the calibration failed or cannot be trusted, in words a user can act on; empty on
  /// success.
  std::string problem;
  /// The poses' coverage of the eDVS image, and what to do with the LED plate when the
  /// rotation comes out uncertain (ebslam::advisePoseDiversity; empty when it is determined):
  /// the calibration is still written, with this warning.
  ebslam::LedPoseCoverage coverage;
  std::string pose_advice;
};

/// Reads the bag and calibrates. Throws std::runtime_error naming the topic for a bag without
/// events, frames or camera_info, or with an unsupported image encoding; rosbag::BagException
/// when the file cannot be read.
BagCalibration calibrateFromBag(const std::string& path, const BagCalibrationOptions& options);

}  // namespace ebslam_ros
