#include "ebslam_ros/ros_params.h"

#include "ebslam_ros/flat_yaml.h"

#include <ebslam_msgs/ros_param_helpers.h>
#include <ros/names.h>

#include <ebslam/simulation/dedvs_io.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace ebslam_ros {
namespace {

using ebslam_msgs::param;
using ebslam_msgs::requirePositive;

[[noreturn]] void fail(const ros::NodeHandle& nh, const std::string& name, const std::string& why) {
  ebslam_msgs::failParam(nh, name, why);
}

std::array<double, 3> triple(const ros::NodeHandle& nh, const std::string& name,
                             const std::array<double, 3>& default_value) {
  std::vector<double> values;
  ebslam_msgs::markParamRead(nh, name);
  if (!nh.getParam(name, values)) {
    if (nh.hasParam(name)) fail(nh, name, "must be a list of three numbers");
    return default_value;
  }
  if (values.size() != 3) fail(nh, name, "must be a list of three numbers");
  for (double v : values) {
    if (!std::isfinite(v)) fail(nh, name, "must hold finite numbers");
  }
  return {values[0], values[1], values[2]};
}

void requireFrame(const ros::NodeHandle& nh, const std::string& name, const std::string& frame) {
  if (frame.empty()) fail(nh, name, "is empty");
  if (frame.front() == '/') fail(nh, name, "= '" + frame + "' must not start with '/' (tf2)");
}

// Runs a core validate() and names the node's parameter namespace in its message.
template <typename Config>
void validateCore(const ros::NodeHandle& nh, const Config& config) {
  try {
    config.validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument("parameters of " + nh.getNamespace() + ": " + error.what());
  }
}

}  // namespace

CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& nh) {
  CeilingSensorConfig config;
  ebslam::CameraModel& c = config.camera;
  c.width = param<int>(nh, "camera/width", c.width);
  c.height = param<int>(nh, "camera/height", c.height);
  c.focal_px = param<double>(nh, "camera/focal_px", c.focal_px);
  c.principal_point.x() = param<double>(nh, "camera/cx", c.principal_point.x());
  c.principal_point.y() = param<double>(nh, "camera/cy", c.principal_point.y());
  c.kappa1 = param<double>(nh, "camera/kappa1", c.kappa1);
  c.kappa2 = param<double>(nh, "camera/kappa2", c.kappa2);
  config.ceiling_distance_m = param<double>(nh, "ceiling_distance", config.ceiling_distance_m);
  if (c.width < 1 || c.height < 1 || c.width > 65535 || c.height > 65535) {
    fail(nh, "camera/width", "and camera/height must be in 1..65535");
  }
  requirePositive(config.ceiling_distance_m, nh, "ceiling_distance");
  validateCore(nh, c);
  return config;
}

ebslam::EventFilterConfig loadEventFilterConfig(const ros::NodeHandle& nh,
                                                const ebslam::EventFilterConfig& defaults) {
  ebslam::EventFilterConfig f = defaults;
  f.num_particles = param<int>(nh, "num_particles", f.num_particles);
  f.batch_size = param<int>(nh, "batch_size", f.batch_size);
  f.resample_every = param<int>(nh, "resample_every", f.resample_every);
  f.beta = param<double>(nh, "beta", f.beta);
  f.g0 = param<double>(nh, "g0", f.g0);
  f.experimental.diffusion_scale =
      param<double>(nh, "diffusion_scale", f.experimental.diffusion_scale);
  f.initial_spread_m = param<double>(nh, "initial_spread", f.initial_spread_m);
  f.initial_spread_rad = param<double>(nh, "initial_spread_rad", f.initial_spread_rad);
  f.experimental.reset_scores_on_resample =
      param<bool>(nh, "reset_scores_on_resample", f.experimental.reset_scores_on_resample);
  f.experimental.adapt_g0 = param<bool>(nh, "adapt_g0", f.experimental.adapt_g0);
  f.latency_compensation_s = param<double>(nh, "latency_compensation", f.latency_compensation_s);
  const std::string estimate = param<std::string>(
      nh, "estimate", f.estimate == ebslam::PoseEstimateMode::kBestParticle ? "best" : "mean");
  if (estimate == "mean") {
    f.estimate = ebslam::PoseEstimateMode::kWeightedMean;
  } else if (estimate == "best") {
    f.estimate = ebslam::PoseEstimateMode::kBestParticle;
  } else {
    fail(nh, "estimate", "= '" + estimate + "' is not one of mean, best");
  }
  const int seed = param<int>(nh, "seed", static_cast<int>(f.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  f.seed = static_cast<std::uint64_t>(seed);
  validateCore(nh, f);
  return f;
}

namespace {

// The frames, tf and input-timing parameters that the pose nodelets share (PoseFilterNodeConfig,
// EventSlam3dNodeConfig), loaded and validated.
template <typename PoseNodeConfig>
void loadPoseNodeFramesAndInput(const ros::NodeHandle& nh, PoseNodeConfig& config) {
  config.map_frame = param<std::string>(nh, "map_frame", config.map_frame);
  config.odom_frame = param<std::string>(nh, "odom_frame", config.odom_frame);
  config.base_frame = param<std::string>(nh, "base_frame", config.base_frame);
  config.sensor_frame = param<std::string>(nh, "sensor_frame", config.sensor_frame);
  config.odom_from_tf = param<bool>(nh, "odom_from_tf", config.odom_from_tf);
  config.mount_from_tf = param<bool>(nh, "mount_from_tf", config.mount_from_tf);
  config.mount_xyz = triple(nh, "mount_xyz", config.mount_xyz);
  config.mount_rpy = triple(nh, "mount_rpy", config.mount_rpy);
  config.publish_tf = param<bool>(nh, "publish_tf", config.publish_tf);
  config.path_length = param<int>(nh, "path_length", config.path_length);
  config.queue_size = param<int>(nh, "queue_size", config.queue_size);
  config.max_backward_s = param<double>(nh, "max_backward", config.max_backward_s);
  config.gap_warning_s = param<double>(nh, "gap_warning", config.gap_warning_s);
  config.max_events_per_update =
      param<int>(nh, "max_events_per_update", config.max_events_per_update);
  requireFrame(nh, "map_frame", config.map_frame);
  requireFrame(nh, "odom_frame", config.odom_frame);
  requireFrame(nh, "base_frame", config.base_frame);
  requireFrame(nh, "sensor_frame", config.sensor_frame);
  if (config.map_frame == config.odom_frame || config.odom_frame == config.base_frame ||
      config.base_frame == config.sensor_frame || config.map_frame == config.base_frame ||
      config.map_frame == config.sensor_frame || config.odom_frame == config.sensor_frame) {
    fail(nh, "map_frame", "odom_frame, base_frame and sensor_frame must be four different frames");
  }
  if (config.path_length < 1) fail(nh, "path_length", "must be at least 1");
  if (config.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  if (!std::isfinite(config.max_backward_s) || config.max_backward_s < 0.0) {
    fail(nh, "max_backward", "must be a non-negative number of seconds");
  }
  requirePositive(config.gap_warning_s, nh, "gap_warning");
  if (config.max_events_per_update < 1000) fail(nh, "max_events_per_update", "must be >= 1000");
}

}  // namespace

PoseFilterNodeConfig loadPoseFilterNodeConfig(const ros::NodeHandle& nh) {
  PoseFilterNodeConfig config;
  config.sensor = loadCeilingSensorConfig(nh);
  const std::array<double, 3> start = triple(nh, "initial_pose", {0.0, 0.0, 0.0});
  config.initial_pose = {start[0], start[1], start[2]};
  loadPoseNodeFramesAndInput(nh, config);
  config.denoise = param<bool>(nh, "denoise", config.denoise);
  config.denoiser = loadBackgroundActivityFilterConfig(ros::NodeHandle(nh, "denoiser"));
  return config;
}

EventParticleFilterNodeConfig loadEventParticleFilterNodeConfig(const ros::NodeHandle& nh) {
  EventParticleFilterNodeConfig config;
  config.node = loadPoseFilterNodeConfig(nh);
  config.filter.filter = loadEventFilterConfig(nh, config.filter.filter);
  config.filter.gamma = param<double>(nh, "gamma", config.filter.gamma);
  validateCore(nh, config.filter);
  config.map_yaml = param<std::string>(nh, "map", config.map_yaml);
  if (config.map_yaml.empty()) fail(nh, "map", "is not set (a ceiling map yaml)");
  return config;
}

EventSlam2dNodeConfig loadEventSlam2dNodeConfig(const ros::NodeHandle& nh) {
  EventSlam2dNodeConfig config;
  config.node = loadPoseFilterNodeConfig(nh);
  ebslam::Ebslam2dConfig& s = config.slam;
  s.filter = loadEventFilterConfig(nh, s.filter);
  s.noise_aware_diffusion = param<bool>(nh, "noise_aware_diffusion", s.noise_aware_diffusion);
  s.cell_size_wtrig = param<double>(nh, "cell_size", s.cell_size_wtrig);
  s.map_size_m = param<double>(nh, "map_size", s.map_size_m);
  s.splat_sigma_wtrig = param<double>(nh, "splat_sigma", s.splat_sigma_wtrig);
  s.normalisation_step_px = param<double>(nh, "normalisation_step", s.normalisation_step_px);
  s.normalisation_prior_px = param<double>(nh, "normalisation_prior", s.normalisation_prior_px);
  const std::string splat = param<std::string>(nh, "splat", "expected_pose");
  if (splat == "expected_pose") {
    s.splat = ebslam::OccurrenceSplat::kExpectedPose;
  } else if (splat == "all_particles") {
    s.splat = ebslam::OccurrenceSplat::kAllParticles;
  } else {
    fail(nh, "splat", "= '" + splat + "' is not one of expected_pose, all_particles");
  }
  validateCore(nh, s);
  config.map_publish_period_s =
      param<double>(nh, "map_publish_period", config.map_publish_period_s);
  requirePositive(config.map_publish_period_s, nh, "map_publish_period");
  config.map_period_on_stamps =
      param<bool>(nh, "map_period_on_stamps", config.map_period_on_stamps);
  return config;
}

ebslam::Ebslam3dConfig loadEbslam3dConfig(const ros::NodeHandle& nh,
                                          const ebslam::Ebslam3dConfig& defaults) {
  ebslam::Ebslam3dConfig c = defaults;
  c.num_particles = param<int>(nh, "num_particles", c.num_particles);
  c.batch_size = param<int>(nh, "batch_size", c.batch_size);
  c.resample_every = param<int>(nh, "resample_every", c.resample_every);
  c.event_share = param<double>(nh, "event_share", c.event_share);
  c.sigma_position_m = param<double>(nh, "sigma_position", c.sigma_position_m);
  c.sigma_rotation_rad = param<double>(nh, "sigma_rotation", c.sigma_rotation_rad);
  c.sigma_position_per_sqrt_s =
      param<double>(nh, "sigma_position_time", c.sigma_position_per_sqrt_s);
  c.sigma_rotation_per_sqrt_s =
      param<double>(nh, "sigma_rotation_time", c.sigma_rotation_per_sqrt_s);
  c.diffusion_min_scale = param<double>(nh, "diffusion_min_scale", c.diffusion_min_scale);
  c.diffusion_max_scale = param<double>(nh, "diffusion_max_scale", c.diffusion_max_scale);
  c.reference_angular_speed =
      param<double>(nh, "reference_angular_speed", c.reference_angular_speed);
  c.reference_linear_speed = param<double>(nh, "reference_linear_speed", c.reference_linear_speed);
  c.max_event_rate = param<double>(nh, "max_event_rate", c.max_event_rate);
  c.score_alpha = param<double>(nh, "score_alpha", c.score_alpha);
  c.voxel_size_m = param<double>(nh, "voxel_size", c.voxel_size_m);
  c.splat_lambda = param<double>(nh, "splat_lambda", c.splat_lambda);
  c.focal_px = param<double>(nh, "focal_px", c.focal_px);
  c.min_range_m = param<double>(nh, "min_range", c.min_range_m);
  c.max_range_m = param<double>(nh, "max_range", c.max_range_m);
  const double map_mb =
      param<double>(nh, "max_map_mb", static_cast<double>(c.max_map_bytes) / (1024.0 * 1024.0));
  if (!std::isfinite(map_mb) || map_mb < 0.0 || map_mb > 1024.0 * 1024.0) {
    fail(nh, "max_map_mb", "must be a number of MiB in [0, 1048576] (0 = unbounded)");
  }
  c.max_map_bytes = static_cast<std::size_t>(std::llround(map_mb * 1024.0 * 1024.0));
  const std::string splat = param<std::string>(
      nh, "splat",
      c.splat == ebslam::MapSplat3d::kAllParticles ? "all_particles" : "expected_pose");
  if (splat == "expected_pose") {
    c.splat = ebslam::MapSplat3d::kExpectedPose;
  } else if (splat == "all_particles") {
    c.splat = ebslam::MapSplat3d::kAllParticles;
  } else {
    fail(nh, "splat", "= '" + splat + "' is not one of expected_pose, all_particles");
  }
  const int seed = param<int>(nh, "seed", static_cast<int>(c.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  c.seed = static_cast<std::uint64_t>(seed);
  // The core names its fields; name the parameters where the mapping is not obvious.
  requirePositive(c.voxel_size_m, nh, "voxel_size");
  requirePositive(c.splat_lambda, nh, "splat_lambda");
  requirePositive(c.focal_px, nh, "focal_px");
  if (!(c.min_range_m >= 0.0) || !std::isfinite(c.max_range_m) ||
      !(c.min_range_m < c.max_range_m)) {
    fail(nh, "min_range", "and ~max_range must satisfy 0 <= min_range < max_range [m]");
  }
  validateCore(nh, c);
  return c;
}

EventSlam3dNodeConfig loadEventSlam3dNodeConfig(const ros::NodeHandle& nh) {
  EventSlam3dNodeConfig config;
  // ~preset chooses the values the other parameters start from.
  const std::string preset = param<std::string>(nh, "preset", "default");
  ebslam::Ebslam3dConfig base;
  if (preset == "default") {
    base = ebslam::Ebslam3dConfig::defaults();
  } else if (preset == "fast") {
    base = ebslam::Ebslam3dConfig::fast();
  } else if (preset == "thesis") {
    base = ebslam::Ebslam3dConfig::thesis();
  } else {
    fail(nh, "preset", "= '" + preset + "' is not one of default, fast, thesis");
  }
  config.slam = loadEbslam3dConfig(nh, base);
  std::vector<double> start;
  ebslam_msgs::markParamRead(nh, "initial_pose");
  if (nh.getParam("initial_pose", start)) {
    if (start.size() != 6) fail(nh, "initial_pose", "must be [x, y, z, roll, pitch, yaw]");
    for (double v : start) {
      if (!std::isfinite(v)) fail(nh, "initial_pose", "must hold finite numbers");
    }
    std::copy(start.begin(), start.end(), config.initial_pose.begin());
  } else if (nh.hasParam("initial_pose")) {
    fail(nh, "initial_pose", "must be a list [x, y, z, roll, pitch, yaw]");
  }
  loadPoseNodeFramesAndInput(nh, config);
  config.map_threshold = param<double>(nh, "map_threshold", config.map_threshold);
  config.map_publish_period_s =
      param<double>(nh, "map_publish_period", config.map_publish_period_s);
  config.map_file = param<std::string>(nh, "map_file", config.map_file);
  if (!std::isfinite(config.map_threshold) || config.map_threshold < 0.0) {
    fail(nh, "map_threshold", "must be a non-negative number");
  }
  requirePositive(config.map_publish_period_s, nh, "map_publish_period");
  return config;
}

ebslam::BackgroundActivityFilterConfig loadBackgroundActivityFilterConfig(
    const ros::NodeHandle& nh) {
  ebslam::BackgroundActivityFilterConfig c;
  const double window_s = param<double>(nh, "window", 1e-6 * static_cast<double>(c.window_us));
  requirePositive(window_s, nh, "window");
  if (window_s > 1000.0) fail(nh, "window", "must be at most 1000 s");
  c.window_us = static_cast<std::int64_t>(std::llround(window_s * 1e6));
  if (c.window_us < 1) fail(nh, "window", "must be at least 1 us");
  c.min_support = param<int>(nh, "min_support", c.min_support);
  if (c.min_support < 1 || c.min_support > 8) fail(nh, "min_support", "must be in 1..8");
  c.polarity_match = param<bool>(nh, "polarity_match", c.polarity_match);
  c.refractory_filter = param<bool>(nh, "refractory_filter", c.refractory_filter);
  const double refractory_s =
      param<double>(nh, "refractory_period", 1e-6 * static_cast<double>(c.refractory_period_us));
  if (!std::isfinite(refractory_s) || refractory_s < 0.0 || refractory_s > 1000.0) {
    fail(nh, "refractory_period", "must be a number of seconds in [0, 1000]");
  }
  c.refractory_period_us = static_cast<std::int64_t>(std::llround(refractory_s * 1e6));
  validateCore(nh, c);
  return c;
}

EventDenoiserNodeConfig loadEventDenoiserNodeConfig(const ros::NodeHandle& nh) {
  EventDenoiserNodeConfig config;
  config.filter = loadBackgroundActivityFilterConfig(nh);
  config.queue_size = param<int>(nh, "queue_size", config.queue_size);
  if (config.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  config.max_backward_s = param<double>(nh, "max_backward", config.max_backward_s);
  if (!std::isfinite(config.max_backward_s) || config.max_backward_s < 0.0) {
    fail(nh, "max_backward", "must be a non-negative number of seconds");
  }
  return config;
}

EventRendererConfig loadEventRendererConfig(const ros::NodeHandle& nh) {
  EventRendererConfig c;
  c.publish_rate_hz = param<double>(nh, "publish_rate", c.publish_rate_hz);
  c.accumulation_time_s = param<double>(nh, "accumulation_time", c.accumulation_time_s);
  requirePositive(c.publish_rate_hz, nh, "publish_rate");
  requirePositive(c.accumulation_time_s, nh, "accumulation_time");
  for (const auto& [name, colour] :
       {std::pair<const char*, std::array<int, 3>*>{"on_colour", &c.on_rgb},
        {"off_colour", &c.off_rgb}}) {
    const std::array<double, 3> value =
        triple(nh, name, {double((*colour)[0]), double((*colour)[1]), double((*colour)[2])});
    for (int k = 0; k < 3; ++k) {
      if (value[k] < 0.0 || value[k] > 255.0) fail(nh, name, "must hold three values in 0..255");
      (*colour)[k] = static_cast<int>(value[k]);
    }
  }
  return c;
}

const std::vector<std::string> kScenarioKeys = {
    "trajectory", "raw_camera_poses",   "smoothing",     "t_begin",        "t_end",
    "texture",    "texture_resolution", "texture_seed",  "line_intensity", "seed",
    "contrast",   "mismatch",           "refractory_us", "noise_rate",     "ceiling_distance"};

namespace {

// A parameter of the simulator: the ~parameter when set, else the scenario's value, else the
// default. Scenario values are parsed here and named with file and key when malformed.
class ScenarioParams {
 public:
  ScenarioParams(const ros::NodeHandle& nh, const std::string& default_scenario) : nh_(nh) {
    const bool explicit_scenario = nh.hasParam("scenario");
    path_ = param<std::string>(nh, "scenario", default_scenario);
    if (path_.empty() || (!explicit_scenario && !std::ifstream(path_))) {
      path_.clear();
      return;
    }
    try {
      values_ = readFlatYaml(path_, "scenario");
    } catch (const std::runtime_error& error) {
      fail(nh, "scenario", std::string("unusable: ") + error.what());
    }
    for (const auto& [key, value] : values_) {
      if (std::find(kScenarioKeys.begin(), kScenarioKeys.end(), key) == kScenarioKeys.end()) {
        fail(nh, "scenario", "'" + path_ + "': unknown key '" + key + "'");
      }
    }
  }
  const std::string& path() const { return path_; }

  double number(const std::string& name, double default_value) const {
    if (nh_.hasParam(name) || !values_.count(name)) return param<double>(nh_, name, default_value);
    std::istringstream in(values_.at(name));
    double value = 0.0;
    std::string rest;
    if (!(in >> value) || (in >> rest)) bad(name, "a number");
    return value;
  }
  int integer(const std::string& name, int default_value) const {
    if (nh_.hasParam(name) || !values_.count(name)) return param<int>(nh_, name, default_value);
    std::istringstream in(values_.at(name));
    long value = 0;
    std::string rest;
    if (!(in >> value) || (in >> rest) || value < std::numeric_limits<int>::min() ||
        value > std::numeric_limits<int>::max()) {
      bad(name, "an integer");
    }
    return static_cast<int>(value);
  }
  bool boolean(const std::string& name, bool default_value) const {
    if (nh_.hasParam(name) || !values_.count(name)) return param<bool>(nh_, name, default_value);
    const std::string& text = values_.at(name);
    if (text == "true" || text == "True") return true;
    if (text == "false" || text == "False") return false;
    bad(name, "true or false");
    return false;
  }
  // A file name: relative to the scenario file when it comes from there.
  std::string file(const std::string& name, const std::string& default_value,
                   const std::string& keep = "") const {
    if (nh_.hasParam(name) || !values_.count(name)) {
      return param<std::string>(nh_, name, default_value);
    }
    const std::string& text = values_.at(name);
    return text == keep ? text : resolveBesideYaml(text, path_);
  }

 private:
  [[noreturn]] void bad(const std::string& name, const std::string& what) const {
    fail(nh_, "scenario",
         "'" + path_ + "': " + name + " = '" + values_.at(name) + "' must be " + what);
  }
  const ros::NodeHandle& nh_;
  std::string path_;
  std::map<std::string, std::string> values_;
};

}  // namespace

namespace {

// ~start_when_subscribed: space-separated topic names, relative ones resolved in the node's
// namespace (the parent of its private one).
std::vector<std::string> topicList(const ros::NodeHandle& nh, const std::string& name) {
  std::istringstream words(param<std::string>(nh, name, ""));
  const std::string node_namespace = ros::names::parentNamespace(nh.getNamespace());
  std::vector<std::string> topics;
  for (std::string topic; words >> topic;) {
    try {
      topics.push_back(ros::names::resolve(node_namespace, topic, false));
    } catch (const ros::InvalidNameException& error) {
      fail(nh, name, "'" + topic + "' is not a valid topic name (" + error.what() + ")");
    }
  }
  return topics;
}

}  // namespace

EventSimulatorNodeConfig loadEventSimulatorNodeConfig(const ros::NodeHandle& nh,
                                                      const std::string& default_scenario) {
  EventSimulatorNodeConfig c;
  const ScenarioParams scenario(nh, default_scenario);
  c.scenario = scenario.path();
  c.trajectory = scenario.file("trajectory", "");
  c.raw_camera_poses = scenario.boolean("raw_camera_poses", c.raw_camera_poses);
  c.smoothing_half_window_s = scenario.number("smoothing", c.smoothing_half_window_s);
  c.texture = scenario.file("texture", c.texture, "lines");
  c.metres_per_texel = scenario.number("texture_resolution", c.metres_per_texel);
  const int texture_seed = scenario.integer("texture_seed", static_cast<int>(c.lines.seed));
  c.lines.foreground = scenario.number("line_intensity", c.lines.foreground);
  const CeilingSensorConfig sensor = loadCeilingSensorConfig(nh);
  c.simulator.camera = sensor.camera;
  c.ceiling_height_m = scenario.number("ceiling_distance", sensor.ceiling_distance_m);
  ebslam::EventModelConfig& e = c.simulator.events;
  const int seed = scenario.integer("seed", static_cast<int>(e.seed));
  e.contrast_threshold_on = e.contrast_threshold_off =
      scenario.number("contrast", e.contrast_threshold_on);
  e.threshold_mismatch_sigma = scenario.number("mismatch", e.threshold_mismatch_sigma);
  e.refractory_period_us = scenario.number("refractory_us", e.refractory_period_us);
  e.noise_rate_hz_per_pixel = scenario.number("noise_rate", e.noise_rate_hz_per_pixel);
  c.t_begin_s = scenario.number("t_begin", c.t_begin_s);
  c.t_end_s = scenario.number("t_end", c.t_end_s);
  c.speed = param<double>(nh, "speed", c.speed);
  c.loop = param<bool>(nh, "loop", c.loop);
  c.publish_rate_hz = param<double>(nh, "publish_rate", c.publish_rate_hz);
  c.publish_clock = param<bool>(nh, "publish_clock", c.publish_clock);
  c.clock_start_s = param<double>(nh, "clock_start", c.clock_start_s);
  c.wait_for_subscribers = param<bool>(nh, "wait_for_subscribers", c.wait_for_subscribers);
  c.start_when_subscribed = topicList(nh, "start_when_subscribed");
  c.frame_id = param<std::string>(nh, "frame_id", c.frame_id);
  c.map_frame = param<std::string>(nh, "map_frame", c.map_frame);
  c.ground_truth_frame = param<std::string>(nh, "ground_truth_frame", c.ground_truth_frame);
  c.align_frame = param<std::string>(nh, "align_frame", c.align_frame);
  c.path_length = param<int>(nh, "path_length", c.path_length);
  if (c.trajectory.empty()) fail(nh, "trajectory", "is not set (nor in a ~scenario file)");
  if (!c.align_frame.empty()) {
    requireFrame(nh, "align_frame", c.align_frame);
    if (c.align_frame == c.map_frame || c.align_frame == c.ground_truth_frame) {
      fail(nh, "align_frame", "must differ from ~map_frame and ~ground_truth_frame");
    }
  }
  requirePositive(c.ceiling_height_m, nh, "ceiling_distance");
  if (texture_seed < 0) fail(nh, "texture_seed", "must not be negative");
  if (seed < 0) fail(nh, "seed", "must not be negative");
  c.lines.seed = static_cast<std::uint64_t>(texture_seed);
  e.seed = static_cast<std::uint64_t>(seed);
  requirePositive(c.metres_per_texel, nh, "texture_resolution");
  requirePositive(c.speed, nh, "speed");
  requirePositive(c.publish_rate_hz, nh, "publish_rate");
  requirePositive(c.clock_start_s, nh, "clock_start");
  if (!(c.lines.foreground >= 0.0 && c.lines.foreground <= 1.0)) {
    fail(nh, "line_intensity", "must be in [0, 1]");
  }
  if (!std::isfinite(c.smoothing_half_window_s) || c.smoothing_half_window_s < 0.0) {
    fail(nh, "smoothing", "must be >= 0 s");
  }
  if (!std::isfinite(c.t_begin_s) || c.t_begin_s < 0.0) fail(nh, "t_begin", "must be >= 0 s");
  requireFrame(nh, "frame_id", c.frame_id);
  requireFrame(nh, "map_frame", c.map_frame);
  requireFrame(nh, "ground_truth_frame", c.ground_truth_frame);
  if (c.path_length < 1) fail(nh, "path_length", "must be at least 1");
  validateCore(nh, c.simulator);
  return c;
}

EventFilePlayerConfig loadEventFilePlayerConfig(const ros::NodeHandle& nh) {
  EventFilePlayerConfig config;
  config.file = param<std::string>(nh, "file", config.file);
  const std::string format = param<std::string>(nh, "format", "");
  const int width = param<int>(nh, "width", 0);
  const int height = param<int>(nh, "height", 0);
  config.frame_id = param<std::string>(nh, "frame_id", config.frame_id);
  config.publish_rate_hz = param<double>(nh, "publish_rate", config.publish_rate_hz);
  config.speed = param<double>(nh, "speed", config.speed);
  config.loop = param<bool>(nh, "loop", config.loop);
  config.max_gap_s = param<double>(nh, "max_gap", config.max_gap_s);
  config.wait_for_subscribers =
      param<bool>(nh, "wait_for_subscribers", config.wait_for_subscribers);

  if (config.file.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("file") + " is not set");
  }
  if (!format.empty()) {
    config.format = ebslam::parseEventFileFormat(format);
    if (!config.format) {
      throw std::invalid_argument("parameter " + nh.resolveName("format") + " = '" + format +
                                  "' is not one of binary, text, rpg");
    }
  }
  if (width < 0 || height < 0 || (width == 0) != (height == 0) || width > 65535 || height > 65535) {
    throw std::invalid_argument("parameters " + nh.resolveName("width") + ", " +
                                nh.resolveName("height") +
                                " must both be 0 (from the file) or both in 1..65535");
  }
  if (width > 0) {
    config.sensor =
        ebslam::SensorSize{static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
  }
  if (config.frame_id.empty()) {
    throw std::invalid_argument("parameter " + nh.resolveName("frame_id") + " is empty");
  }
  requirePositive(config.publish_rate_hz, nh, "publish_rate");
  requirePositive(config.speed, nh, "speed");
  requirePositive(config.max_gap_s, nh, "max_gap");
  return config;
}

DepthEventFusionNodeConfig loadDepthEventFusionNodeConfig(const ros::NodeHandle& nh) {
  DepthEventFusionNodeConfig c;
  c.calibration = param<std::string>(nh, "calibration", c.calibration);
  if (c.calibration.empty()) {
    fail(nh, "calibration",
         "is not set (a D-eDVS sensors yaml, format in ebslam/simulation/dedvs_io.h)");
  }
  try {
    c.sensors = ebslam::readDedvsSensors(c.calibration);
  } catch (const std::exception& error) {
    fail(nh, "calibration", "= '" + c.calibration + "' is unusable: " + error.what());
  }
  ebslam::DepthFusionConfig& f = c.fusion;
  f.min_depth_m = param<double>(nh, "min_depth", f.min_depth_m);
  f.max_depth_m = param<double>(nh, "max_depth", f.max_depth_m);
  f.max_frame_age_s = param<double>(nh, "max_frame_age", f.max_frame_age_s);
  f.max_surface_jump_ratio = param<double>(nh, "max_surface_jump_ratio", f.max_surface_jump_ratio);
  const int frames_kept = param<int>(nh, "frames_kept", static_cast<int>(f.frames_kept));
  if (frames_kept < 1 || frames_kept > 100) fail(nh, "frames_kept", "must be in 1..100");
  f.frames_kept = static_cast<std::size_t>(frames_kept);
  requirePositive(f.min_depth_m, nh, "min_depth");
  requirePositive(f.max_depth_m, nh, "max_depth");
  if (!(f.max_depth_m > f.min_depth_m)) fail(nh, "max_depth", "must exceed ~min_depth");
  requirePositive(f.max_frame_age_s, nh, "max_frame_age");
  requirePositive(f.max_surface_jump_ratio, nh, "max_surface_jump_ratio");
  validateCore(nh, f);
  c.edvs_camera_info = param<bool>(nh, "edvs_camera_info", c.edvs_camera_info);
  c.edvs_frame = param<std::string>(nh, "edvs_frame", c.edvs_frame);
  c.depth_frame = param<std::string>(nh, "depth_frame", c.depth_frame);
  requireFrame(nh, "edvs_frame", c.edvs_frame);
  requireFrame(nh, "depth_frame", c.depth_frame);
  if (c.edvs_frame == c.depth_frame) fail(nh, "edvs_frame", "must differ from ~depth_frame");
  c.publish_tf = param<bool>(nh, "publish_tf", c.publish_tf);
  c.tf_parent = param<std::string>(nh, "tf_parent", c.tf_parent);
  if (c.tf_parent != "depth" && c.tf_parent != "edvs") {
    fail(nh, "tf_parent", "must be 'depth' or 'edvs'");
  }
  c.max_wait_s = param<double>(nh, "max_wait", c.max_wait_s);
  if (!std::isfinite(c.max_wait_s) || c.max_wait_s < 0.0 || c.max_wait_s > 10.0) {
    fail(nh, "max_wait", "must be a number of seconds in [0, 10]");
  }
  c.queue_size = param<int>(nh, "queue_size", c.queue_size);
  if (c.queue_size < 1) fail(nh, "queue_size", "must be at least 1");
  return c;
}

RgbdEventSimulatorNodeConfig loadRgbdEventSimulatorNodeConfig(
    const ros::NodeHandle& nh, const std::string& default_trajectory) {
  RgbdEventSimulatorNodeConfig c;
  c.trajectory = param<std::string>(nh, "trajectory", default_trajectory);
  if (c.trajectory.empty()) fail(nh, "trajectory", "is not set (a TUM trajectory of the rig)");
  c.t_begin_s = param<double>(nh, "t_begin", c.t_begin_s);
  c.t_end_s = param<double>(nh, "t_end", c.t_end_s);
  if (!std::isfinite(c.t_begin_s) || c.t_begin_s < 0.0) fail(nh, "t_begin", "must be >= 0 s");
  if (!std::isfinite(c.t_end_s)) fail(nh, "t_end", "must be a number of seconds");
  c.speed = param<double>(nh, "speed", c.speed);
  requirePositive(c.speed, nh, "speed");
  c.publish_rate_hz = param<double>(nh, "publish_rate", c.publish_rate_hz);
  requirePositive(c.publish_rate_hz, nh, "publish_rate");
  c.loop = param<bool>(nh, "loop", c.loop);
  c.publish_clock = param<bool>(nh, "publish_clock", c.publish_clock);
  c.clock_start_s = param<double>(nh, "clock_start", c.clock_start_s);
  requirePositive(c.clock_start_s, nh, "clock_start");
  c.wait_for_subscribers = param<bool>(nh, "wait_for_subscribers", c.wait_for_subscribers);
  c.start_when_subscribed = topicList(nh, "start_when_subscribed");
  const int seed = param<int>(nh, "seed", static_cast<int>(c.simulator.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  c.simulator.seed = c.simulator.events.seed = c.room.seed = static_cast<std::uint64_t>(seed);
  const int depth_width = param<int>(nh, "depth_width", c.simulator.depth.camera.width);
  if (depth_width != 320 && depth_width != 640) fail(nh, "depth_width", "must be 320 or 640");
  c.simulator.depth.camera = c.simulator.depth.camera.scaled(
      depth_width / static_cast<double>(c.simulator.depth.camera.width));
  c.room.texture_contrast = param<double>(nh, "texture_contrast", c.room.texture_contrast);
  c.simulator.events.noise_rate_hz_per_pixel =
      param<double>(nh, "noise_rate", c.simulator.events.noise_rate_hz_per_pixel);
  c.simulator.depth.frame_rate_hz =
      param<double>(nh, "depth_rate", c.simulator.depth.frame_rate_hz);
  requirePositive(c.simulator.depth.frame_rate_hz, nh, "depth_rate");
  c.simulator.depth.clock_offset_s =
      param<double>(nh, "depth_clock_offset", c.simulator.depth.clock_offset_s);
  if (!std::isfinite(c.simulator.depth.clock_offset_s) ||
      std::abs(c.simulator.depth.clock_offset_s) > 1.0) {
    fail(nh, "depth_clock_offset", "must be a number of seconds in [-1, 1]");
  }
  c.edvs_frame = param<std::string>(nh, "edvs_frame", c.edvs_frame);
  c.depth_frame = param<std::string>(nh, "depth_frame", c.depth_frame);
  c.map_frame = param<std::string>(nh, "map_frame", c.map_frame);
  c.ground_truth_frame = param<std::string>(nh, "ground_truth_frame", c.ground_truth_frame);
  requireFrame(nh, "edvs_frame", c.edvs_frame);
  requireFrame(nh, "depth_frame", c.depth_frame);
  requireFrame(nh, "map_frame", c.map_frame);
  requireFrame(nh, "ground_truth_frame", c.ground_truth_frame);
  if (c.map_frame == c.ground_truth_frame)
    fail(nh, "ground_truth_frame", "must differ from ~map_frame");
  c.path_length = param<int>(nh, "path_length", c.path_length);
  if (c.path_length < 1) fail(nh, "path_length", "must be at least 1");
  c.write_calibration = param<std::string>(nh, "write_calibration", c.write_calibration);
  validateCore(nh, c.room);
  validateCore(nh, c.simulator);
  return c;
}

ExplorationNodeConfig loadExplorationNodeConfig(const ros::NodeHandle& nh) {
  ExplorationNodeConfig c;
  ebslam::ExplorationConfig& e = c.exploration;
  e.hex_spacing_m = param<double>(nh, "hex_spacing", e.hex_spacing_m);
  e.grid_extent_m = param<double>(nh, "grid_extent", e.grid_extent_m);
  e.robot_radius_m = param<double>(nh, "robot_radius", e.robot_radius_m);
  e.bump_cone_depth_m = param<double>(nh, "bump_cone_depth", e.bump_cone_depth_m);
  e.bump_cone_half_angle_rad =
      param<double>(nh, "bump_cone_half_angle", e.bump_cone_half_angle_rad);
  e.weight_z = param<double>(nh, "weight_z", e.weight_z);
  e.weight_e = param<double>(nh, "weight_e", e.weight_e);
  e.alpha = param<double>(nh, "alpha", e.alpha);
  e.planner_max_nodes = param<int>(nh, "planner_max_nodes", e.planner_max_nodes);
  e.planner_time_budget_s = param<double>(nh, "planner_time_budget", e.planner_time_budget_s);
  e.near_blocked_cost = param<double>(nh, "near_blocked_cost", e.near_blocked_cost);
  e.oscillation_window = param<int>(nh, "oscillation_window", e.oscillation_window);
  e.oscillation_max_cells = param<int>(nh, "oscillation_max_cells", e.oscillation_max_cells);
  e.commit_min_cells = param<int>(nh, "commit_min_cells", e.commit_min_cells);
  e.escape_blocked_cost = param<double>(nh, "escape_blocked_cost", e.escape_blocked_cost);
  e.min_path_cells = param<int>(nh, "min_path_cells", e.min_path_cells);
  e.max_path_cells = param<int>(nh, "max_path_cells", e.max_path_cells);
  e.waypoint_tolerance_m = param<double>(nh, "waypoint_tolerance", e.waypoint_tolerance_m);
  e.lookahead_m = param<double>(nh, "lookahead", e.lookahead_m);
  e.turn_in_place_rad = param<double>(nh, "turn_in_place", e.turn_in_place_rad);
  e.heading_gain = param<double>(nh, "heading_gain", e.heading_gain);
  e.max_speed_mps = param<double>(nh, "max_speed", e.max_speed_mps);
  e.max_turn_rate_rps = param<double>(nh, "max_turn_rate", e.max_turn_rate_rps);
  e.backout_time_s = param<double>(nh, "backout_time", e.backout_time_s);
  e.backout_speed_mps = param<double>(nh, "backout_speed", e.backout_speed_mps);
  e.max_bumps_in_a_row = param<int>(nh, "max_bumps_in_a_row", e.max_bumps_in_a_row);
  e.pose_timeout_s = param<double>(nh, "pose_timeout", e.pose_timeout_s);
  e.pose_jump_m = param<double>(nh, "pose_jump", e.pose_jump_m);
  e.pose_jump_rad = param<double>(nh, "pose_jump_rad", e.pose_jump_rad);
  validateCore(nh, e);
  c.control_rate_hz = param<double>(nh, "control_rate", c.control_rate_hz);
  requirePositive(c.control_rate_hz, nh, "control_rate");
  if (c.control_rate_hz > 1000.0) fail(nh, "control_rate", "must be at most 1000 Hz");
  c.map_frame = param<std::string>(nh, "map_frame", c.map_frame);
  requireFrame(nh, "map_frame", c.map_frame);
  c.use_localisation_map = param<bool>(nh, "use_localisation_map", c.use_localisation_map);
  c.markers_period_s = param<double>(nh, "markers_period", c.markers_period_s);
  requirePositive(c.markers_period_s, nh, "markers_period");
  if (nh.hasParam("initial_pose")) {
    const std::array<double, 3> start = triple(nh, "initial_pose", {0.0, 0.0, 0.0});
    c.initial_pose = ebslam::Pose2{start[0], start[1], start[2]};
  } else {
    ebslam_msgs::markParamRead(nh, "initial_pose");
  }
  return c;
}

ClosedLoopSimulatorNodeConfig loadClosedLoopSimulatorNodeConfig(
    const ros::NodeHandle& nh, const std::string& default_floor_plan) {
  ClosedLoopSimulatorNodeConfig c;
  c.floor_plan = param<std::string>(nh, "floor_plan", default_floor_plan);
  if (c.floor_plan.empty()) fail(nh, "floor_plan", "is not set (a floor-plan file)");
  ebslam::ClosedLoopSimulatorConfig& s = c.simulator;
  const CeilingSensorConfig sensor = loadCeilingSensorConfig(nh);
  s.events.camera = sensor.camera;
  s.ceiling_height_m = sensor.ceiling_distance_m;
  // Real time on a shared machine: the rates of the long evaluation runs (docs/results/
  // exploration.md) rather than the simulator's finest defaults.
  s.events.render_rate_hz = 100.0;
  s.events.max_step_motion_px = 0.5;
  // The core keeps every ground-truth pose; the node publishes its own at each step.
  s.ground_truth_rate_hz = 1.0;
  const int seed = param<int>(nh, "seed", static_cast<int>(s.seed));
  if (seed < 0) fail(nh, "seed", "must not be negative");
  s.seed = static_cast<std::uint64_t>(seed);
  s.events.events.noise_rate_hz_per_pixel =
      param<double>(nh, "noise_rate", s.events.events.noise_rate_hz_per_pixel);
  s.robot.radius_m = param<double>(nh, "robot_radius", s.robot.radius_m);
  s.robot.max_speed_mps = param<double>(nh, "max_speed", s.robot.max_speed_mps);
  s.robot.max_turn_rate_rps = param<double>(nh, "max_turn_rate", s.robot.max_turn_rate_rps);
  s.robot.bump_segments = param<int>(nh, "bump_segments", s.robot.bump_segments);
  if (s.robot.bump_segments < 1 || s.robot.bump_segments > 32) {
    fail(nh, "bump_segments", "must be in 1..32");
  }
  validateCore(nh, s);
  c.step_s = param<double>(nh, "step", c.step_s);
  requirePositive(c.step_s, nh, "step");
  if (c.step_s > 1.0) fail(nh, "step", "must be at most 1 s");
  c.speed = param<double>(nh, "speed", c.speed);
  requirePositive(c.speed, nh, "speed");
  c.cmd_timeout_s = param<double>(nh, "cmd_timeout", c.cmd_timeout_s);
  requirePositive(c.cmd_timeout_s, nh, "cmd_timeout");
  c.publish_clock = param<bool>(nh, "publish_clock", c.publish_clock);
  c.clock_start_s = param<double>(nh, "clock_start", c.clock_start_s);
  requirePositive(c.clock_start_s, nh, "clock_start");
  c.wait_for_subscribers = param<bool>(nh, "wait_for_subscribers", c.wait_for_subscribers);
  c.lockstep = param<bool>(nh, "lockstep", c.lockstep);
  if (c.lockstep && !c.publish_clock) fail(nh, "lockstep", "needs publish_clock");
  c.lockstep_timeout_s = param<double>(nh, "lockstep_timeout", c.lockstep_timeout_s);
  requirePositive(c.lockstep_timeout_s, nh, "lockstep_timeout");
  c.frame_id = param<std::string>(nh, "frame_id", c.frame_id);
  c.base_frame = param<std::string>(nh, "base_frame", c.base_frame);
  c.map_frame = param<std::string>(nh, "map_frame", c.map_frame);
  c.ground_truth_frame = param<std::string>(nh, "ground_truth_frame", c.ground_truth_frame);
  requireFrame(nh, "frame_id", c.frame_id);
  requireFrame(nh, "base_frame", c.base_frame);
  requireFrame(nh, "map_frame", c.map_frame);
  requireFrame(nh, "ground_truth_frame", c.ground_truth_frame);
  c.path_length = param<int>(nh, "path_length", c.path_length);
  if (c.path_length < 1) fail(nh, "path_length", "must be at least 1");
  return c;
}

}  // namespace ebslam_ros
