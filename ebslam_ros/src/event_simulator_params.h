#pragma once
// Parameters of the EventSimulator nodelet (and its scenario files).

#include <ros/node_handle.h>

#include <ebslam/simulation/simulator.h>
#include <ebslam/simulation/simulator_scenes.h>

#include <string>
#include <vector>

namespace ebslam_ros {

/// The floor-robot event simulator (thesis 6.5.3, as ebslam_simulate_events).
///
/// Scenario file (~scenario): the scene and the motion as flat yaml `key: value` lines whose keys
/// are the parameter names below (kScenarioKeys); a ~parameter that is set wins over the file,
/// the file over the built-in default; `trajectory` and a `texture` image are relative to the
/// file. Default: the demo's scenario in the repository
/// (test/data/sample_session/pioneer_360_excerpt.yaml).
struct EventSimulatorNodeConfig {
  std::string scenario;  ///< ~scenario: the scenario file read ("" = none)
  /// ~trajectory: TUM file of the robot's camera poses (required, from ~scenario or set).
  std::string trajectory;
  bool raw_camera_poses = false;          ///< ~raw_camera_poses: the file holds eDVS poses (z up)
  double smoothing_half_window_s = 0.05;  ///< ~smoothing [s] (makeFloorRobotTrajectory)
  std::string texture = "lines";          ///< ~texture: image file or "lines"
  double metres_per_texel = 0.01;         ///< ~texture_resolution [m]
  ebslam::LinesAndCirclesConfig lines;    ///< ~texture_seed, ~line_intensity
  double ceiling_height_m = 2.59;         ///< ~ceiling_distance [m] (as the filters' parameter)
  ebslam::SimulatorConfig simulator;      ///< ~camera/*, ~seed, ~contrast, ~noise_rate, ...
  double t_begin_s = 0.0;                 ///< ~t_begin: start, seconds after the trajectory start
  double t_end_s = -1.0;  ///< ~t_end: end, seconds after the start (< 0: the trajectory end)
  double speed = 1.0;     ///< ~speed: simulated seconds per wall second
  /// ~loop: drive ~t_begin..~t_end forth and back endlessly (pass k backwards when k is odd,
  /// event seed ~seed + k), the time running on; false: one pass, then stop.
  bool loop = false;
  double publish_rate_hz = 100.0;     ///< ~publish_rate: EventArray per simulated second [Hz]
  bool publish_clock = false;         ///< ~publish_clock: publish /clock (use_sim_time)
  double clock_start_s = 1000.0;      ///< ~clock_start: ROS time of the run's start with /clock [s]
  bool wait_for_subscribers = false;  ///< ~wait_for_subscribers: start on the first subscriber
  /// ~start_when_subscribed: topics (space-separated, relative ones resolved in the node's
  /// namespace) that must each have a subscriber before the start, e.g. the SLAM's input; "" = none
  std::vector<std::string> start_when_subscribed;
  std::string frame_id = "edvs_optical_frame";      ///< ~frame_id
  std::string map_frame = "map";                    ///< ~map_frame
  std::string ground_truth_frame = "ground_truth";  ///< ~ground_truth_frame
  /// ~align_frame: when set, published once as a static child of map_frame at the ground truth's
  /// start pose (planar: x, y, yaw), so an estimator whose map is this frame and which starts at
  /// its origin (initial_pose 0 0 0) draws its path over the ground truth's. "" = none.
  std::string align_frame;
  int path_length = 10000;  ///< ~path_length
};
/// The parameters a scenario file may hold.
extern const std::vector<std::string> kScenarioKeys;
/// Reads ~scenario (default_scenario when unset; a missing default file is skipped, a missing
/// ~scenario is an error) and the parameters; throws std::invalid_argument naming the parameter
/// or the scenario file and key.
EventSimulatorNodeConfig loadEventSimulatorNodeConfig(const ros::NodeHandle& private_nh,
                                                      const std::string& default_scenario);

}  // namespace ebslam_ros
