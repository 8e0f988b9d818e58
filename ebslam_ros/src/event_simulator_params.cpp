#include "event_simulator_params.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include <ebslam_ros_common/ros_param_helpers.h>
#include "ceiling_sensor_params.h"
#include "ebslam_ros/flat_yaml.h"

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

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

}  // namespace ebslam_ros
