#pragma once

// Private ROS parameters of the driver nodelet -> the library's config structs, validated in
// this one place. Throws std::invalid_argument with the parameter name on a bad value.

#include <ros/node_handle.h>

#include <string>

#include "edvs/device.h"
#include "edvs/link_supervisor.h"

namespace edvs_driver {

struct DriverParams {
  edvs::DeviceConfig device;  ///< ~uri, ~format, ~firmware, ~sync_mode, ~on_bit
  /// ~reconnect_min_delay, ~reconnect_max_delay [s] (backoff), ~stall_reconnect_timeout [s]
  /// (no bytes -> reopen), ~bias_<name> (cas, injGnd, ...; -1 keeps the device's own value).
  edvs::SupervisorConfig link;
  std::string frame_id = "edvs_optical_frame";  ///< ~frame_id (REP-103 optical frame)
  std::string camera_name = "edvs";             ///< ~camera_name for camera_info_manager
  std::string camera_info_url;                  ///< ~camera_info_url ("" = uncalibrated)
  double publish_rate_hz = 100.0;  ///< ~publish_rate: EventArray messages per second (0 = off)
  int batch_size = 0;              ///< ~batch_size: also publish every N events (0 = off)
  double stall_warn_s = 1.0;       ///< ~stall_timeout: no bytes this long -> WARN [s]
};

/// Reads and validates the private parameters of `pnh`.
DriverParams loadDriverParams(const ros::NodeHandle& pnh);

/// Validates a fully filled DriverParams (also used for dynamic_reconfigure updates).
void validate(const DriverParams& params);

}  // namespace edvs_driver
