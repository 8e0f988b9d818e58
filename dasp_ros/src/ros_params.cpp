#include "dasp_ros/ros_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <cmath>
#include <stdexcept>

namespace dasp_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

RgbdFolderSourceConfig loadRgbdFolderSourceConfig(const ros::NodeHandle& nh) {
  RgbdFolderSourceConfig config;
  config.folder = param<std::string>(nh, "folder", config.folder);
  config.rate_hz = param<double>(nh, "rate", config.rate_hz);
  config.loop = param<bool>(nh, "loop", config.loop);
  config.wait_for_subscribers =
      param<bool>(nh, "wait_for_subscribers", config.wait_for_subscribers);
  config.frame_id = param<std::string>(nh, "frame_id", config.frame_id);
  config.intrinsics.fx = static_cast<float>(param<double>(nh, "fx", config.intrinsics.fx));
  config.intrinsics.fy = static_cast<float>(param<double>(nh, "fy", config.intrinsics.fy));
  config.intrinsics.cx = static_cast<float>(param<double>(nh, "cx", config.intrinsics.cx));
  config.intrinsics.cy = static_cast<float>(param<double>(nh, "cy", config.intrinsics.cy));
  config.calibration_width = param<int>(nh, "calibration_width", config.calibration_width);
  config.calibration_height = param<int>(nh, "calibration_height", config.calibration_height);

  if (config.folder.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("folder") + " is not set");
  }
  if (config.frame_id.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("frame_id") + " is empty");
  }
  requirePositive(config.rate_hz, nh, "rate");
  requirePositive(config.intrinsics.fx, nh, "fx");
  requirePositive(config.intrinsics.fy, nh, "fy");
  if (!std::isfinite(config.intrinsics.cx) || !std::isfinite(config.intrinsics.cy)) {
    throw std::invalid_argument("parameters cx, cy must be finite");
  }
  if (config.calibration_width <= 0 || config.calibration_height <= 0) {
    throw std::invalid_argument("parameters " + nh.resolveName("calibration_width") + ", " +
                                nh.resolveName("calibration_height") + " must be positive");
  }
  return config;
}

std::optional<dasp::Intrinsics> RgbdFolderSourceConfig::intrinsicsFor(int width, int height) const {
  if (width == calibration_width && height == calibration_height) return intrinsics;
  // Same aspect ratio: width / calibration_width == height / calibration_height, exactly.
  if (static_cast<long>(width) * calibration_height !=
      static_cast<long>(height) * calibration_width) {
    return std::nullopt;
  }
  const float scale = static_cast<float>(width) / static_cast<float>(calibration_width);
  dasp::Intrinsics scaled;
  scaled.fx = intrinsics.fx * scale;
  scaled.fy = intrinsics.fy * scale;
  // Pixel centres: pixel i covers [i, i + 1) of the image, so centres scale about -0.5.
  scaled.cx = (intrinsics.cx + 0.5f) * scale - 0.5f;
  scaled.cy = (intrinsics.cy + 0.5f) * scale - 0.5f;
  return scaled;
}

}  // namespace dasp_ros

namespace dasp_ros {
namespace {

void require(bool condition, const ros::NodeHandle& nh, const std::string& name,
             const std::string& what) {
  if (!condition) throw std::invalid_argument("parameter " + nh.resolveName(name) + " " + what);
}

float floatParam(const ros::NodeHandle& nh, const std::string& name, float default_value) {
  return static_cast<float>(param<double>(nh, name, default_value));
}

void requireNonNegative(float value, const ros::NodeHandle& nh, const std::string& name) {
  require(std::isfinite(value) && value >= 0.0f, nh, name,
          "= " + std::to_string(value) + " must be finite and >= 0");
}

RgbdInputConfig loadRgbdInputConfig(const ros::NodeHandle& nh) {
  RgbdInputConfig input;
  input.approximate_sync = param<bool>(nh, "approximate_sync", input.approximate_sync);
  input.queue_size = param<int>(nh, "queue_size", input.queue_size);
  require(input.queue_size >= 1, nh, "queue_size", "must be >= 1");
  return input;
}

dasp::DaspConfig loadDaspConfig(const ros::NodeHandle& nh) {
  dasp::DaspConfig c;
  c.size_mode = parseSizeMode(param<std::string>(nh, "size_mode", "count"));
  c.superpixel_count = param<int>(nh, "superpixel_count", c.superpixel_count);
  c.radius_m = floatParam(nh, "radius", c.radius_m);
  c.iterations = param<int>(nh, "iterations", c.iterations);
  c.weight_spatial = floatParam(nh, "weight_spatial", c.weight_spatial);
  c.weight_color = floatParam(nh, "weight_color", c.weight_color);
  c.weight_normal = floatParam(nh, "weight_normal", c.weight_normal);
  c.window_multiple = floatParam(nh, "window_multiple", c.window_multiple);
  c.enforce_connectivity = param<bool>(nh, "enforce_connectivity", c.enforce_connectivity);
  c.min_size_fraction = floatParam(nh, "min_size_fraction", c.min_size_fraction);
  c.normal_step_px = param<int>(nh, "normal_step_px", c.normal_step_px);
  c.depth_jump_ratio = floatParam(nh, "depth_jump_ratio", c.depth_jump_ratio);
  c.seed = static_cast<std::uint64_t>(param<int>(nh, "seed", static_cast<int>(c.seed)));
  c.threads = param<int>(nh, "threads", c.threads);
  dasp::DaspExperimental& x = c.experimental;
  x.weight_depth = floatParam(nh, "weight_depth", x.weight_depth);
  x.depth_exponent = floatParam(nh, "depth_exponent", x.depth_exponent);
  x.max_slant_factor = floatParam(nh, "max_slant_factor", x.max_slant_factor);

  require(c.superpixel_count >= 1, nh, "superpixel_count", "must be >= 1");
  require(std::isfinite(c.radius_m) && c.radius_m > 0.0f, nh, "radius", "must be positive [m]");
  require(c.iterations >= 1, nh, "iterations", "must be >= 1");
  for (const char* name : {"weight_spatial", "weight_color", "weight_normal", "weight_depth"}) {
    requireNonNegative(floatParam(nh, name, 0.0f), nh, name);
  }
  require(std::isfinite(c.window_multiple) && c.window_multiple > 0.0f, nh, "window_multiple",
          "must be positive");
  require(c.min_size_fraction >= 0.0f && c.min_size_fraction < 1.0f, nh, "min_size_fraction",
          "must be in [0, 1)");
  require(std::isfinite(x.max_slant_factor) && x.max_slant_factor >= 1.0f, nh, "max_slant_factor",
          "must be >= 1");
  const float a = x.depth_exponent;
  require(a == 0.0f || a == 0.5f || a == 1.0f || a == 1.5f || a == 2.0f, nh, "depth_exponent",
          "must be one of 0, 0.5, 1, 1.5, 2");
  require(c.normal_step_px >= 1, nh, "normal_step_px", "must be >= 1 [px]");
  require(std::isfinite(c.depth_jump_ratio) && c.depth_jump_ratio > 0.0f, nh, "depth_jump_ratio",
          "must be positive");
  require(param<int>(nh, "seed", 0) >= 0, nh, "seed", "must be >= 0");
  require(c.threads >= 0, nh, "threads", "must be >= 0 (0 = all cores)");
  return c;
}

dasp::SuperpixelGraphConfig loadGraphConfig(const ros::NodeHandle& nh,
                                            dasp::SuperpixelGraphConfig g = {}) {
  g.min_border_pairs = param<int>(nh, "graph/min_border_pairs", g.min_border_pairs);
  g.weight_color = floatParam(nh, "graph/weight_color", g.weight_color);
  g.weight_position = floatParam(nh, "graph/weight_position", g.weight_position);
  g.weight_normal = floatParam(nh, "graph/weight_normal", g.weight_normal);
  g.radius_m = floatParam(nh, "graph/radius", g.radius_m);
  require(g.min_border_pairs >= 0, nh, "graph/min_border_pairs", "must be >= 0");
  requireNonNegative(g.weight_color, nh, "graph/weight_color");
  requireNonNegative(g.weight_position, nh, "graph/weight_position");
  requireNonNegative(g.weight_normal, nh, "graph/weight_normal");
  requireNonNegative(g.radius_m, nh, "graph/radius");
  return g;
}

dasp::SpectralConfig loadSpectralConfig(const ros::NodeHandle& nh) {
  dasp::SpectralConfig s;
  s.eigenvector_count = param<int>(nh, "spectral/eigenvector_count", s.eigenvector_count);
  require(s.eigenvector_count >= 1, nh, "spectral/eigenvector_count", "must be >= 1");
  return s;
}

}  // namespace

dasp::SizeMode parseSizeMode(const std::string& text) {
  if (text == "count") return dasp::SizeMode::kCount;
  if (text == "radius") return dasp::SizeMode::kRadius;
  throw std::invalid_argument("size_mode '" + text + "' must be 'count' or 'radius'");
}

OpenNi2SourceConfig loadOpenNi2SourceConfig(const ros::NodeHandle& nh) {
  OpenNi2SourceConfig c;
  c.device_uri = param<std::string>(nh, "device_uri", c.device_uri);
  c.width = param<int>(nh, "width", c.width);
  c.height = param<int>(nh, "height", c.height);
  c.fps = param<int>(nh, "fps", c.fps);
  c.frame_id = param<std::string>(nh, "frame_id", c.frame_id);
  c.camera_info_url = param<std::string>(nh, "camera_info_url", c.camera_info_url);
  c.retry_min_s = param<double>(nh, "retry_min", c.retry_min_s);
  c.retry_max_s = param<double>(nh, "retry_max", c.retry_max_s);
  require((c.width == 640 && c.height == 480) || (c.width == 320 && c.height == 240), nh, "width",
          "and height must be 640x480 or 320x240");
  require(c.fps > 0, nh, "fps", "must be positive [Hz]");
  require(!c.frame_id.empty(), nh, "frame_id", "is empty");
  requirePositive(c.retry_min_s, nh, "retry_min");
  require(std::isfinite(c.retry_max_s) && c.retry_max_s >= c.retry_min_s, nh, "retry_max",
          "must be >= retry_min [s]");
  return c;
}

DaspNodeConfig loadDaspNodeConfig(const ros::NodeHandle& nh) {
  DaspNodeConfig config;
  config.input = loadRgbdInputConfig(nh);
  config.dasp = loadDaspConfig(nh);
  config.graph = loadGraphConfig(nh);
  return config;
}

SdaspNodeConfig loadSdaspNodeConfig(const ros::NodeHandle& nh) {
  SdaspNodeConfig config;
  config.queue_size = param<int>(nh, "queue_size", config.queue_size);
  require(config.queue_size >= 1, nh, "queue_size", "must be >= 1");
  config.sdasp.graph = loadGraphConfig(nh, config.sdasp.graph);
  config.sdasp.spectral = loadSpectralConfig(nh);
  dasp::SdaspConfig& s = config.sdasp;
  const std::string cut = param<std::string>(nh, "cut", cutRuleName(s.cut));
  try {
    s.cut = parseCutRule(cut);
  } catch (const std::invalid_argument&) {
    require(false, nh, "cut", "= " + cut + " must be adaptive or global");
  }
  s.threshold = floatParam(nh, "threshold", s.threshold);
  s.adaptive_scale = floatParam(nh, "adaptive_scale", s.adaptive_scale);
  s.adaptive_quantile = floatParam(nh, "adaptive_quantile", s.adaptive_quantile);
  s.adaptive_max_threshold = floatParam(nh, "adaptive_max_threshold", s.adaptive_max_threshold);
  const std::string problem = checkSdaspCut(s);
  if (!problem.empty()) throw std::invalid_argument(problem);
  config.ucm_encoding = param<std::string>(nh, "ucm_encoding", config.ucm_encoding);
  require(config.ucm_encoding == "32FC1" || config.ucm_encoding == "mono8", nh, "ucm_encoding",
          "must be 32FC1 or mono8");
  return config;
}

dasp::CutRule parseCutRule(const std::string& text) {
  if (text == "adaptive") return dasp::CutRule::kAdaptive;
  if (text == "global") return dasp::CutRule::kGlobal;
  throw std::invalid_argument("cut rule must be adaptive or global, not " + text);
}

std::string cutRuleName(dasp::CutRule rule) {
  return rule == dasp::CutRule::kAdaptive ? "adaptive" : "global";
}

std::string checkSdaspCut(const dasp::SdaspConfig& s) {
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!std::isfinite(s.threshold)) return "parameter threshold must be finite";
  if (!positive(s.adaptive_scale)) return "parameter adaptive_scale must be > 0";
  if (!(s.adaptive_quantile >= 0.0f && s.adaptive_quantile <= 1.0f)) {
    return "parameter adaptive_quantile must lie in [0, 1]";
  }
  if (!positive(s.adaptive_max_threshold)) return "parameter adaptive_max_threshold must be > 0";
  return "";
}

TdaspNodeConfig loadTdaspNodeConfig(const ros::NodeHandle& nh) {
  TdaspNodeConfig config;
  config.input = loadRgbdInputConfig(nh);
  dasp::TdaspConfig& t = config.tdasp;
  t.superpixels.dasp = loadDaspConfig(nh);
  t.superpixels.delta.smoothing_radius_multiple = floatParam(
      nh, "dds/smoothing_radius_multiple", t.superpixels.delta.smoothing_radius_multiple);
  requireNonNegative(t.superpixels.delta.smoothing_radius_multiple, nh,
                     "dds/smoothing_radius_multiple");
  t.strands.max_color_change =
      floatParam(nh, "strands/max_color_change", t.strands.max_color_change);
  t.strands.max_normal_change =
      floatParam(nh, "strands/max_normal_change", t.strands.max_normal_change);
  t.strands.max_position_change =
      floatParam(nh, "strands/max_position_change", t.strands.max_position_change);
  t.strands.max_strands = param<int>(nh, "strands/max_strands", t.strands.max_strands);
  requireNonNegative(t.strands.max_color_change, nh, "strands/max_color_change");
  requireNonNegative(t.strands.max_normal_change, nh, "strands/max_normal_change");
  requireNonNegative(t.strands.max_position_change, nh, "strands/max_position_change");
  require(t.strands.max_strands >= 1, nh, "strands/max_strands", "must be >= 1");
  t.strands.graph = loadGraphConfig(nh);
  t.spectral = loadSpectralConfig(nh);
  t.hysteresis.force = floatParam(nh, "hysteresis/force", t.hysteresis.force);
  t.hysteresis.normal = floatParam(nh, "hysteresis/normal", t.hysteresis.normal);
  t.hysteresis.grant = floatParam(nh, "hysteresis/grant", t.hysteresis.grant);
  require(std::isfinite(t.hysteresis.force) && std::isfinite(t.hysteresis.grant) &&
              t.hysteresis.force <= t.hysteresis.normal &&
              t.hysteresis.normal <= t.hysteresis.grant,
          nh, "hysteresis/normal", "thresholds must be finite and force <= normal <= grant");
  return config;
}

}  // namespace dasp_ros
