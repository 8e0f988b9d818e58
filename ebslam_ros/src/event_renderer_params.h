#pragma once
// Parameters of the EventRenderer nodelet.

#include <ros/node_handle.h>

#include <array>

namespace ebslam_ros {

/// Event image renderer (EventRenderer).
struct EventRendererConfig {
  double publish_rate_hz = 30.0;         ///< ~publish_rate: images per second of wall time [Hz]
  double accumulation_time_s = 0.033;    ///< ~accumulation_time: events of this much event time [s]
  std::array<int, 3> on_rgb{0, 0, 255};  ///< ~on_colour [r, g, b] 0..255 (rpg_dvs_ros: blue)
  std::array<int, 3> off_rgb{255, 0, 0};  ///< ~off_colour [r, g, b] 0..255 (red)
  /// ~queue_size: event messages queued while a render holds the node (1 ms packets of a
  /// megapixel camera: 1000 is one second)
  int queue_size = 1000;
};
EventRendererConfig loadEventRendererConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
