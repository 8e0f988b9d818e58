#pragma once
// The one place where private ROS parameters become configuration structs. Each loader reads
// every parameter (defaults are the struct's member initialisers), validates the values, and
// throws std::invalid_argument naming the parameter when a value makes no sense.

#include <dasp/dasp.h>
#include <dasp/sdasp.h>
#include <dasp/tdasp.h>
#include <ros/node_handle.h>

#include <optional>
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
  dasp::Intrinsics intrinsics;     ///< ~fx, ~fy, ~cx, ~cy [px], for the calibration size
  int calibration_width = 640;     ///< ~calibration_width: image width of ~fx..~cy [px]
  int calibration_height = 480;    ///< ~calibration_height: image height of ~fx..~cy [px]

  /// The intrinsics for frames of width x height pixels: those of the calibration size, scaled
  /// when the frame has the same aspect ratio (a 320x240 frame of a 640x480 calibration: focal
  /// lengths halved, principal point (c + 0.5) / 2 - 0.5), nullopt for another aspect ratio.
  std::optional<dasp::Intrinsics> intrinsicsFor(int width, int height) const;
};

RgbdFolderSourceConfig loadRgbdFolderSourceConfig(const ros::NodeHandle& private_nh);

/// How the synchronised RGB-D inputs are matched (colour image, registered depth, camera_info).
struct RgbdInputConfig {
  /// ~approximate_sync: match by nearest stamps (drivers that stamp colour and depth apart);
  /// false: identical stamps (registered PrimeSense drivers, the folder source, bags of them)
  bool approximate_sync = false;
  int queue_size = 5;  ///< ~queue_size: messages per input kept while waiting for a match
};

/// Parameters of dasp_ros/Dasp.
struct DaspNodeConfig {
  RgbdInputConfig input;
  /// ~size_mode ("count" | "radius"), ~superpixel_count, ~radius [m], ~iterations,
  /// ~weight_spatial, ~weight_color, ~weight_normal, ~window_multiple, ~normal_step_px,
  /// ~enforce_connectivity, ~min_size_fraction, ~depth_jump_ratio, ~seed, ~threads:
  /// dasp::DaspConfig's fields; ~weight_depth, ~depth_exponent, ~max_slant_factor: its
  /// `experimental` fields
  dasp::DaspConfig dasp;
  /// ~graph/min_border_pairs, ~graph/weight_color, ~graph/weight_position,
  /// ~graph/weight_normal, ~graph/radius [m]: neighbourhood graph of the `edges` field
  dasp::SuperpixelGraphConfig graph;
};

/// Parameters of dasp_ros/Sdasp.
struct SdaspNodeConfig {
  int queue_size = 5;  ///< ~queue_size
  /// ~graph/..., ~spectral/eigenvector_count, ~cut (adaptive|global), ~threshold [1] (global
  /// cut), ~adaptive_scale, ~adaptive_quantile, ~adaptive_max_threshold [1] (adaptive cut); the
  /// cut parameters are also dynamic_reconfigure parameters (cfg/SdaspNodelet.cfg).
  dasp::SdaspConfig sdasp;
  /// ~ucm_encoding: "32FC1" (merge level; -1 off boundaries, +inf never merged) or "mono8"
  /// (255 (1 - sqrt(min(level, 1))): dark strokes on white, as dasp_sdasp draws it)
  std::string ucm_encoding = "32FC1";
};

/// Parameters of dasp_ros/Tdasp.
struct TdaspNodeConfig {
  RgbdInputConfig input;
  /// DASP parameters (names as for Dasp), ~dds/smoothing_radius_multiple,
  /// ~strands/max_color_change, ~strands/max_normal_change, ~strands/max_position_change,
  /// ~strands/max_strands, ~graph/..., ~spectral/eigenvector_count,
  /// ~hysteresis/force, ~hysteresis/normal, ~hysteresis/grant
  dasp::TdaspConfig tdasp;
};

/// Parameters of dasp_ros/OpenNi2Source.
struct OpenNi2SourceConfig {
  std::string device_uri;  ///< ~device_uri: OpenNI2 URI (or .oni file); empty = first device
  int width = 640;         ///< ~width [px]: 640 (with height 480) or 320 (with 240)
  int height = 480;        ///< ~height [px]
  int fps = 30;            ///< ~fps [Hz]
  std::string frame_id = "camera_rgb_optical_frame";  ///< ~frame_id
  /// ~camera_info_url: camera_info_manager URL of a calibration; empty = from the field of view
  std::string camera_info_url;
  double retry_min_s = 1.0;   ///< ~retry_min [s]: first wait after a failed connection
  double retry_max_s = 30.0;  ///< ~retry_max [s]: the wait doubles up to this
};

OpenNi2SourceConfig loadOpenNi2SourceConfig(const ros::NodeHandle& private_nh);
DaspNodeConfig loadDaspNodeConfig(const ros::NodeHandle& private_nh);
SdaspNodeConfig loadSdaspNodeConfig(const ros::NodeHandle& private_nh);
TdaspNodeConfig loadTdaspNodeConfig(const ros::NodeHandle& private_nh);

/// "adaptive" -> kAdaptive, "global" -> kGlobal; throws std::invalid_argument otherwise.
dasp::CutRule parseCutRule(const std::string& text);
std::string cutRuleName(dasp::CutRule rule);

/// The one check of Sdasp's cut parameters (at start and on every reconfigure): "" when valid,
/// otherwise what is wrong. threshold finite, adaptive_scale > 0, adaptive_quantile in [0, 1],
/// adaptive_max_threshold > 0.
std::string checkSdaspCut(const dasp::SdaspConfig& sdasp);

/// "count" -> kCount, "radius" -> kRadius; throws std::invalid_argument otherwise.
dasp::SizeMode parseSizeMode(const std::string& text);

}  // namespace dasp_ros
