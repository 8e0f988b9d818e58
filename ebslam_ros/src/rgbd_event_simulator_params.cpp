#include "rgbd_event_simulator_params.h"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <ebslam_ros_common/ros_param_helpers.h>

#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

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
  // The event camera: the D-eDVS' eDVS lens scaled to a sensor size (same horizontal field of
  // view), e.g. davis346.
  const std::string edvs_preset = param<std::string>(nh, "edvs_preset", "edvs128");
  try {
    c.simulator.edvs = ebslam::CameraModel::preset(edvs_preset, c.simulator.edvs);
  } catch (const std::invalid_argument& e) {
    fail(nh, "edvs_preset", e.what());
  }
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
  c.publish_imu = param<bool>(nh, "publish_imu", c.publish_imu);
  c.imu_frame = param<std::string>(nh, "imu_frame", c.imu_frame);
  requireFrame(nh, "imu_frame", c.imu_frame);
  ebslam::ImuSimulatorConfig& imu = c.simulator.imu;
  imu.rate_hz = param<double>(nh, "imu_rate", imu.rate_hz);
  requirePositive(imu.rate_hz, nh, "imu_rate");
  imu.gyro_noise_density = param<double>(nh, "gyro_noise_density", imu.gyro_noise_density);
  imu.gyro_bias_random_walk = param<double>(nh, "gyro_bias_random_walk", imu.gyro_bias_random_walk);
  imu.gyro_initial_bias_std = param<double>(nh, "gyro_initial_bias", imu.gyro_initial_bias_std);
  imu.accel_noise_density = param<double>(nh, "accel_noise_density", imu.accel_noise_density);
  imu.seed = c.simulator.seed;
  c.simulator.simulate_imu = false;  // the nodelet simulates the IMU per pass itself
  validateCore(nh, c.room);
  validateCore(nh, c.simulator);
  return c;
}

}  // namespace ebslam_ros
