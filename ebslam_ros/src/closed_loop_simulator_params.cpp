#include "closed_loop_simulator_params.h"

#include <cstdint>

#include <ebslam_ros_common/ros_param_helpers.h>
#include "ceiling_sensor_params.h"

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

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
