#pragma once
// Parameters of the ClosedLoopSimulator nodelet.

#include <ros/node_handle.h>

#include <ebslam/simulation/closed_loop_simulator.h>

#include <string>

namespace ebslam_ros {

/// The closed-loop floor-robot simulator (ClosedLoopSimulator nodelet, thesis 7.4).
struct ClosedLoopSimulatorNodeConfig {
  std::string floor_plan;  ///< ~floor_plan: floor-plan file (ebslam/simulation/floor_plan.h)
  /// The eDVS (~camera/*, ~ceiling_distance as the filters'), ~seed (event model and ceiling),
  /// ~noise_rate [Hz per pixel], robot limits ~robot_radius [m], ~max_speed [m/s],
  /// ~max_turn_rate [rad/s], ~bump_segments.
  ebslam::ClosedLoopSimulatorConfig simulator;
  double step_s = 0.02;               ///< ~step: simulated time per step (events, bump, pose) [s]
  double speed = 1.0;                 ///< ~speed: simulated seconds per wall second
  double cmd_timeout_s = 0.5;         ///< ~cmd_timeout: stop when cmd_vel is older [s, simulated]
  bool publish_clock = false;         ///< ~publish_clock: publish /clock (use_sim_time)
  double clock_start_s = 1000.0;      ///< ~clock_start: ROS time of the start with /clock [s]
  bool wait_for_subscribers = false;  ///< ~wait_for_subscribers: start on the first subscriber
  /// ~lockstep (needs ~publish_clock): each step waits for the localisation's pose of its events
  /// and the controller's cmd_vel on its clock tick (the offline tool's loop; file comment of
  /// closed_loop_simulator_nodelet.cpp).
  bool lockstep = false;
  double lockstep_timeout_s = 2.0;  ///< ~lockstep_timeout: longest wait of a step [s, wall]
  std::string frame_id = "edvs_optical_frame";      ///< ~frame_id: the events' frame
  std::string base_frame = "base_link";             ///< ~base_frame: the bump readings' frame
  std::string map_frame = "map";                    ///< ~map_frame: origin at the start pose
  std::string ground_truth_frame = "ground_truth";  ///< ~ground_truth_frame
  int path_length = 10000;                          ///< ~path_length: poses on ground_truth/path
};
ClosedLoopSimulatorNodeConfig loadClosedLoopSimulatorNodeConfig(
    const ros::NodeHandle& private_nh, const std::string& default_floor_plan);

}  // namespace ebslam_ros
