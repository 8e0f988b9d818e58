#pragma once
// Parameters of the RgbdEventSimulator nodelet.

#include <ros/node_handle.h>

#include <ebslam/simulation/dedvs_scene.h>
#include <ebslam/simulation/dedvs_simulator.h>

#include <string>
#include <vector>

namespace ebslam_ros {

/// Configuration of the RgbdEventSimulator nodelet (D-eDVS simulator, thesis 8.2).
struct RgbdEventSimulatorNodeConfig {
  /// ~trajectory: TUM file of the rig (depth optical frame -> world); default the repository's
  /// test/data/sample_session/pioneer_360_excerpt.txt
  std::string trajectory;
  double t_begin_s = 0.0;  ///< ~t_begin: start, seconds after the trajectory start
  double t_end_s = -1.0;   ///< ~t_end: end, seconds after the start (< 0: the trajectory end)
  double speed = 1.0;      ///< ~speed: simulated seconds per wall second
  double publish_rate_hz = 100.0;     ///< ~publish_rate: EventArray per simulated second [Hz]
  bool publish_clock = false;         ///< ~publish_clock: publish /clock (use_sim_time)
  double clock_start_s = 1000.0;      ///< ~clock_start: ROS time of the run's start with /clock [s]
  bool wait_for_subscribers = false;  ///< ~wait_for_subscribers: start on the first subscriber
  /// ~start_when_subscribed: topics (space-separated, relative ones resolved in the node's
  /// namespace) that must each have a subscriber before the start, e.g. the SLAM's input; "" = none
  std::vector<std::string> start_when_subscribed;
  /// ~loop: drive ~t_begin..~t_end forth and back endlessly (pass k backwards when k is odd, event
  /// and depth-noise seeds ~seed + k, the same room), the time running on; false: one pass.
  bool loop = false;
  /// ~seed (events, depth noise), ~depth_width (320 or 640), ~edvs_preset (edvs128, davis240,
  /// davis346, vga, hd720: the eDVS lens scaled to that size), ~noise_rate [Hz per pixel],
  /// ~depth_rate [Hz], ~depth_clock_offset [s]; the rest the core's defaults
  ebslam::DedvsSimulatorConfig simulator;
  ebslam::RoomSceneConfig room;  ///< ~seed (furniture, textures), ~texture_contrast
  std::string edvs_frame = "edvs_optical_frame";           ///< ~edvs_frame
  std::string depth_frame = "camera_depth_optical_frame";  ///< ~depth_frame (colour registered)
  std::string map_frame = "map";                           ///< ~map_frame
  std::string ground_truth_frame = "ground_truth";         ///< ~ground_truth_frame: the rig
  int path_length = 10000;                                 ///< ~path_length
  std::string write_calibration;  ///< ~write_calibration: write the rig's sensors yaml there
  /// ~publish_imu: publish the rig IMU's readings on `imu` (sensor_msgs/Imu in ~imu_frame) and
  /// the static tf ~edvs_frame -> ~imu_frame. The IMU (simulator.imu, imu_simulator.h):
  /// ~imu_rate [Hz], ~gyro_noise_density [rad/s/sqrt(Hz)], ~gyro_bias_random_walk
  /// [rad/s/sqrt(s)], ~gyro_initial_bias [rad/s], ~accel_noise_density [m/s^2/sqrt(Hz)]; mounted
  /// with REP 103 body axes on the depth camera; seeded by ~seed (+ the pass).
  bool publish_imu = true;
  std::string imu_frame = "imu_link";  ///< ~imu_frame
};

RgbdEventSimulatorNodeConfig loadRgbdEventSimulatorNodeConfig(
    const ros::NodeHandle& private_nh, const std::string& default_trajectory);

}  // namespace ebslam_ros
