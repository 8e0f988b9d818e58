#pragma once

// Private ROS parameters of the driver nodelet -> the library's config structs, validated in
// this one place. Throws std::invalid_argument with the parameter name on a bad value.

#include <ros/node_handle.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "edvs_driver/device.h"

namespace edvs_driver {

struct DriverParams {
  DeviceConfig device;                          ///< ~uri, ~format, ~firmware, ~sync_mode, ~on_bit
  std::string frame_id = "edvs_optical_frame";  ///< ~frame_id (REP-103 optical frame)
  std::string camera_name = "edvs";             ///< ~camera_name for camera_info_manager
  std::string camera_info_url;                  ///< ~camera_info_url ("" = uncalibrated)
  double publish_rate_hz = 100.0;  ///< ~publish_rate: EventArray messages per second (0 = off)
  int batch_size = 0;              ///< ~batch_size: also publish every N events (0 = off)
  double reconnect_min_s = 0.5;    ///< ~reconnect_min_delay: first retry delay [s]
  double reconnect_max_s = 8.0;    ///< ~reconnect_max_delay: backoff cap [s]
  double stall_warn_s = 1.0;       ///< ~stall_timeout: no bytes this long -> WARN [s]
  double stall_reconnect_s = 5.0;  ///< ~stall_reconnect_timeout: no bytes -> reopen [s]
  /// ~bias_<name> (cas, injGnd, ...): 24-bit value, or -1 to leave the device's own value.
  std::array<std::optional<std::int64_t>, kNumBiases> biases{};
};

/// Reads and validates the private parameters of `pnh`.
DriverParams loadDriverParams(const ros::NodeHandle& pnh);

/// Validates a fully filled DriverParams (also used for dynamic_reconfigure updates).
void validate(const DriverParams& params);

}  // namespace edvs_driver
