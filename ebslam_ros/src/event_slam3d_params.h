#pragma once
// Parameters of the EventSlam3d nodelet (EB-SLAM-3D, thesis 8.3).

#include <ros/node_handle.h>

#include <ebslam/slam/ebslam3d.h>

#include <array>
#include <cmath>
#include <string>

#include "pose_node_params.h"

namespace ebslam_ros {

/// EB-SLAM-3D core (ebslam/slam/ebslam3d.h) over `defaults`: ~num_particles, ~batch_size,
/// ~resample_every, ~event_share, ~sigma_position [m], ~sigma_rotation [rad], ~score_alpha,
/// ~voxel_size [m], ~splat_lambda, ~focal_px [px], ~min_range [m], ~max_range [m],
/// ~max_map_mb [MiB, 0 = unbounded], ~splat (expected_pose|all_particles), ~seed; the gyro prior
/// (Ebslam3dImuConfig, used with ~use_imu): ~gyro_noise_density [rad/s/sqrt(Hz)],
/// ~gyro_bias_random_walk [rad/s/sqrt(s)], ~gyro_initial_bias [rad/s], ~imu_sigma_rotation_time
/// [rad/sqrt(s)], ~imu_bias_window [s], ~imu_estimate_bias.
ebslam::Ebslam3dConfig loadEbslam3dConfig(const ros::NodeHandle& private_nh,
                                          const ebslam::Ebslam3dConfig& defaults);

/// The EventSlam3d nodelet: a depth-event sensor (D-eDVS) anywhere on the robot, full 6-DoF.
/// Frames, mounting, outputs and input checks in PoseNodeConfig, with two other defaults:
/// ~queue_size 100 (DepthEventArray messages) and ~mount_rpy the optical frame of a sensor
/// looking along base_link's x (REP 103: optical z forward, x right, y down).
struct EventSlam3dNodeConfig : PoseNodeConfig {
  EventSlam3dNodeConfig() {
    queue_size = 100;
    mount_rpy = {-M_PI / 2, 0.0, -M_PI / 2};
  }
  ebslam::Ebslam3dConfig slam;
  /// ~initial_pose: base_link in map [x, y, z m, roll, pitch, yaw rad] at the (re)start.
  std::array<double, 6> initial_pose{0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double map_threshold = 1.0;         ///< ~map_threshold: voxels above this value go to `map`
  double map_publish_period_s = 1.0;  ///< ~map_publish_period: `map` at most this often [s]
  std::string map_file = "ebslam3d_map.ply";  ///< ~map_file: save_map's file (.ply or .pcd)
  /// ~use_imu: subscribe `imu` (sensor_msgs/Imu, stamps on the events' clock) for the gyro
  /// rotation prior; events wait for the IMU to cover them (at most ~imu_max_wait).
  bool use_imu = false;
  /// ~imu_rotation_from_tf: the IMU -> sensor rotation from tf (the Imu message's frame_id ->
  /// ~sensor_frame); false: ~imu_rpy.
  bool imu_rotation_from_tf = true;
  /// ~imu_rpy: sensor_from_imu as [roll, pitch, yaw] [rad] (fixed axes x, y, z).
  std::array<double, 3> imu_rpy{0.0, 0.0, 0.0};
  /// ~imu_max_wait: events wait at most this long [s of event time] for IMU samples covering
  /// them, then go in without (the batches fall back to the usual diffusion).
  double imu_max_wait_s = 0.1;
};
EventSlam3dNodeConfig loadEventSlam3dNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
