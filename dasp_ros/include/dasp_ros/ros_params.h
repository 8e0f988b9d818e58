#pragma once
// The one place where private ROS parameters become configuration structs. Each loader reads
// every parameter (defaults are the struct's member initialisers), validates the values, and
// throws std::invalid_argument naming the parameter when a value makes no sense.

#include <dasp/dasp.h>
#include <ros/node_handle.h>

#include <string>

namespace dasp_ros {

/// Configuration of the RGB-D image-folder source.
struct RgbdFolderSourceConfig {
  std::string folder;     ///< ~folder: frames <name>_rgb.png + <name>_depth_mm.png
  double rate_hz = 30.0;  ///< ~rate: frames per second [Hz], PrimeSense rate
  bool loop = false;      ///< ~loop: start again after the last frame
  /// ~wait_for_subscribers: hold the first frame until something has subscribed to rgb/image
  /// for 0.5 s (so that a recorder started alongside gets every frame)
  bool wait_for_subscribers = false;
  std::string frame_id =
      "camera_rgb_optical_frame";  ///< ~frame_id: optical frame of colour and registered depth
  dasp::Intrinsics intrinsics;     ///< ~fx, ~fy, ~cx, ~cy [px]
};

RgbdFolderSourceConfig loadRgbdFolderSourceConfig(const ros::NodeHandle& private_nh);

}  // namespace dasp_ros
