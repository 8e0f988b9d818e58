#pragma once
// The upward-looking event camera of the floor-robot nodelets (EB-PF, EB-SLAM-2D, the event and
// closed-loop simulators): ~camera/*, ~camera_info_url, ~camera_info_wait and ~ceiling_distance.

#include <ros/node_handle.h>

#include <ebslam/slam/camera_model.h>

#include <string>

namespace ebslam_ros {

/// The upward-looking event camera (thesis 6.5.1): lens and ceiling distance.
struct CeilingSensorConfig {
  /// ~camera/{width, height, focal_px, cx, cy, kappa1, kappa2}; ~camera/preset (edvs128,
  /// davis240, davis346, vga, hd720) scales that lens to the preset's size (same horizontal
  /// field of view). The fallback when no CameraInfo is found (resolveCameraInfo).
  ebslam::CameraModel camera;
  double ceiling_distance_m = 2.59;  ///< ~ceiling_distance: sensor to ceiling D [m]
  /// ~camera_info_url: camera_info_manager URL (file:///abs/path.yaml, package://pkg/path.yaml)
  /// of the sensor's calibration; read instead of the camera_info topic.
  std::string camera_info_url;
  /// ~camera_info_wait [s]: how long the nodelet waits at start for one message on camera_info
  /// when a publisher of it is known to the master (latched or periodic). 0: do not wait.
  double camera_info_wait_s = 5.0;
  /// Where `camera` came from: "camera_info topic", "camera_info_url" or "parameters".
  std::string camera_source = "parameters";
};

CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& private_nh);

/// The sensor's geometry from sensor_msgs/CameraInfo, the parameters only as fallback: from
/// config.camera_info_url if set, else from one message on `camera_info` (resolved in nh, the
/// nodelet's public handle, so that launch-file remappings apply) when the master knows a
/// publisher of it, waiting up to config.camera_info_wait_s. Sets config.camera and
/// config.camera_source. Throws std::invalid_argument for an unreadable URL, a publisher that
/// sends nothing in time, or a CameraInfo the cores cannot use (conversions.h toCameraModel).
void resolveCameraInfo(const ros::NodeHandle& nh, CeilingSensorConfig& config);

/// One INFO line: the camera in use and where it came from.
void logCameraSource(const std::string& nodelet_name, const CeilingSensorConfig& config);

/// The calibration file of a camera_info_manager URL (file://, package://, or a plain absolute
/// path). Throws std::invalid_argument for another scheme or an unknown package.
std::string cameraInfoUrlPath(const std::string& url);

}  // namespace ebslam_ros
