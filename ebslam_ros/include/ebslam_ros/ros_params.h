#pragma once
// The one place where private ROS parameters of ebslam_ros nodelets become configuration structs.
// Loaders validate and throw std::invalid_argument naming the parameter.

#include <ros/node_handle.h>

#include <optional>
#include <string>

#include <array>
#include <cmath>
#include <vector>

#include <ebslam/events/event.h>
#include <ebslam/events/event_denoiser.h>
#include <ebslam/events/event_io.h>
#include <ebslam/simulation/closed_loop_simulator.h>
#include <ebslam/simulation/dedvs_scene.h>
#include <ebslam/simulation/dedvs_simulator.h>
#include <ebslam/simulation/simulator.h>
#include <ebslam/simulation/simulator_scenes.h>
#include <ebslam/slam/camera_model.h>
#include <ebslam/slam/dedvs_fusion.h>
#include <ebslam/slam/ebpf.h>
#include <ebslam/slam/ebslam2d.h>
#include <ebslam/slam/ebslam3d.h>
#include <ebslam/slam/exploration.h>
#include <ebslam/slam/particle_set2d.h>

namespace ebslam_ros {

/// Configuration of the event file player.
struct EventFilePlayerConfig {
  std::string file;                               ///< ~file: event file to play
  std::optional<ebslam::EventFileFormat> format;  ///< ~format: binary|text|rpg, "" = detect
  std::optional<ebslam::SensorSize> sensor;       ///< ~width, ~height [px]; 0 = from the file
  std::string frame_id = "edvs_optical_frame";    ///< ~frame_id: optical frame of the sensor
  double publish_rate_hz = 100.0;  ///< ~publish_rate: EventArray messages per second [Hz]
  double speed = 1.0;              ///< ~speed: playback speed factor (2 = twice real time)
  bool loop = false;               ///< ~loop: start again at the end of the file
  /// ~max_gap: longest step of the file's clock between two events that is played as it is [s of
  /// stream time]; a longer one is a gap to skip when the next event confirms it, else damage
  double max_gap_s = 10.0;
  bool wait_for_subscribers =
      false;  ///< ~wait_for_subscribers: start playing on the first subscriber
};

EventFilePlayerConfig loadEventFilePlayerConfig(const ros::NodeHandle& private_nh);

/// The upward-looking eDVS (thesis 6.5.1): lens and ceiling distance.
struct CeilingSensorConfig {
  ebslam::CameraModel camera;        ///< ~camera/{width, height, focal_px, cx, cy, kappa1, kappa2}
  double ceiling_distance_m = 2.59;  ///< ~ceiling_distance: sensor to ceiling D [m]
};

/// ROS side of EventParticleFilter and EventSlam2d (frames, mounting, output, input checks).
struct PoseFilterNodeConfig {
  CeilingSensorConfig sensor;
  ebslam::Pose2 initial_pose;                       ///< ~initial_pose: base_link in map [m, m, rad]
  std::string map_frame = "map";                    ///< ~map_frame
  std::string odom_frame = "odom";                  ///< ~odom_frame
  std::string base_frame = "base_link";             ///< ~base_frame
  std::string sensor_frame = "edvs_optical_frame";  ///< ~sensor_frame: the events' frame
  /// ~odom_from_tf: map -> odom = pose * (odom -> base_link from tf, e.g. wheel odometry);
  /// false: the node publishes odom -> base_link as identity.
  bool odom_from_tf = false;
  /// ~mount_from_tf: base_link -> sensor_frame from tf; false: from ~mount_xyz, ~mount_rpy,
  /// published by the node as a static transform.
  bool mount_from_tf = false;
  std::array<double, 3> mount_xyz{0.0, 0.0, 0.0};  ///< ~mount_xyz [m]
  std::array<double, 3> mount_rpy{0.0, 0.0, 0.0};  ///< ~mount_rpy [rad]
  bool publish_tf = true;                          ///< ~publish_tf: map -> odom (-> base_link)
  int path_length = 10000;                         ///< ~path_length: poses kept on `path`
  int queue_size = 1000;                           ///< ~queue_size: EventArray messages queued
  double max_backward_s = 0.001;  ///< ~max_backward: earlier events are clamped up to this [s]
  double gap_warning_s = 1.0;     ///< ~gap_warning: warn about pauses in the stream longer [s]
  /// ~max_events_per_update: events per filter call and pose (a huge message gives several).
  int max_events_per_update = 200000;
  /// ~denoise: run the background-activity filter on the events before the pose filter (no
  /// topic hop); its parameters under ~denoiser/ (loadBackgroundActivityFilterConfig).
  bool denoise = false;
  ebslam::BackgroundActivityFilterConfig denoiser;
};

/// Common filter knobs (~num_particles, ~batch_size, ~resample_every, ~beta, ~g0, ~initial_spread,
/// ~initial_spread_rad, ~estimate (mean|best), ~latency_compensation, ~seed; into `experimental`:
/// ~diffusion_scale, ~reset_scores_on_resample, ~adapt_g0) over `defaults`.
ebslam::EventFilterConfig loadEventFilterConfig(const ros::NodeHandle& private_nh,
                                                const ebslam::EventFilterConfig& defaults);
PoseFilterNodeConfig loadPoseFilterNodeConfig(const ros::NodeHandle& private_nh);
CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& private_nh);

struct EventParticleFilterNodeConfig {
  PoseFilterNodeConfig node;
  ebslam::EbpfConfig filter;  ///< plus ~gamma (sensor model sigma [W_trig])
  std::string map_yaml;       ///< ~map: ceiling map yaml (map_server style or simulator's)
};
EventParticleFilterNodeConfig loadEventParticleFilterNodeConfig(const ros::NodeHandle& private_nh);

struct EventSlam2dNodeConfig {
  PoseFilterNodeConfig node;
  /// plus ~cell_size, ~map_size, ~splat_sigma, ~splat (expected_pose|all_particles),
  /// ~normalisation_step, ~normalisation_prior
  ebslam::Ebslam2dConfig slam;
  double map_publish_period_s = 1.0;  ///< ~map_publish_period: `map` at most this often [s]
  /// ~map_period_on_stamps: count ~map_publish_period in event time (the stamps) instead of
  /// wall time: maps at the same points of the data at any pace (exploration in lockstep).
  bool map_period_on_stamps = false;
};
EventSlam2dNodeConfig loadEventSlam2dNodeConfig(const ros::NodeHandle& private_nh);

/// EB-SLAM-3D core (ebslam/slam/ebslam3d.h) over `defaults`: ~num_particles, ~batch_size,
/// ~resample_every, ~event_share, ~sigma_position [m], ~sigma_rotation [rad], ~score_alpha,
/// ~voxel_size [m], ~splat_lambda, ~focal_px [px], ~min_range [m], ~max_range [m],
/// ~max_map_mb [MiB, 0 = unbounded], ~splat (expected_pose|all_particles), ~seed.
ebslam::Ebslam3dConfig loadEbslam3dConfig(const ros::NodeHandle& private_nh,
                                          const ebslam::Ebslam3dConfig& defaults);

/// The EventSlam3d nodelet: a depth-event sensor (D-eDVS) anywhere on the robot, full 6-DoF.
struct EventSlam3dNodeConfig {
  ebslam::Ebslam3dConfig slam;
  /// ~initial_pose: base_link in map [x, y, z m, roll, pitch, yaw rad] at the (re)start.
  std::array<double, 6> initial_pose{0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  std::string map_frame = "map";                    ///< ~map_frame
  std::string odom_frame = "odom";                  ///< ~odom_frame
  std::string base_frame = "base_link";             ///< ~base_frame
  std::string sensor_frame = "edvs_optical_frame";  ///< ~sensor_frame: the events' frame
  bool odom_from_tf = false;                        ///< ~odom_from_tf: as PoseFilterNodeConfig
  bool mount_from_tf = false;                       ///< ~mount_from_tf: as PoseFilterNodeConfig
  std::array<double, 3> mount_xyz{0.0, 0.0, 0.0};   ///< ~mount_xyz [m]
  /// ~mount_rpy [rad]: default the optical frame of a sensor looking along base_link's x (REP 103:
  /// optical z forward, x right, y down).
  std::array<double, 3> mount_rpy{-M_PI / 2, 0.0, -M_PI / 2};
  bool publish_tf = true;         ///< ~publish_tf: map -> odom (-> base_link)
  int path_length = 10000;        ///< ~path_length: poses kept on `path`
  int queue_size = 100;           ///< ~queue_size: DepthEventArray messages queued
  double max_backward_s = 0.001;  ///< ~max_backward: earlier events are clamped up to this [s]
  double gap_warning_s = 1.0;     ///< ~gap_warning: warn about pauses in the stream longer [s]
  /// ~max_events_per_update: events per filter call and pose (a huge message gives several).
  int max_events_per_update = 200000;
  double map_threshold = 1.0;         ///< ~map_threshold: voxels above this value go to `map`
  double map_publish_period_s = 1.0;  ///< ~map_publish_period: `map` at most this often [s]
  std::string map_file = "ebslam3d_map.ply";  ///< ~map_file: save_map's file (.ply or .pcd)
};
EventSlam3dNodeConfig loadEventSlam3dNodeConfig(const ros::NodeHandle& private_nh);

/// Background-activity filter (ebslam/events/event_denoiser.h) from `nh`: ~window [s] 0.1,
/// ~min_support 3, ~polarity_match true, ~refractory_filter false, ~refractory_period [s] 0.001
/// (the core defaults). Times are rounded to microseconds.
ebslam::BackgroundActivityFilterConfig loadBackgroundActivityFilterConfig(
    const ros::NodeHandle& nh);

/// The EventDenoiser nodelet.
struct EventDenoiserNodeConfig {
  ebslam::BackgroundActivityFilterConfig filter;
  int queue_size = 1000;  ///< ~queue_size: EventArray messages queued
  /// ~max_backward: events earlier than their predecessor by up to this are filtered at the
  /// predecessor's time (jitter); earlier by more, the stream restarted: the filter forgets [s]
  double max_backward_s = 0.001;
};
EventDenoiserNodeConfig loadEventDenoiserNodeConfig(const ros::NodeHandle& private_nh);

/// Event image renderer (EventRenderer).
struct EventRendererConfig {
  double publish_rate_hz = 30.0;         ///< ~publish_rate: images per second of wall time [Hz]
  double accumulation_time_s = 0.033;    ///< ~accumulation_time: events of this much event time [s]
  std::array<int, 3> on_rgb{0, 0, 255};  ///< ~on_colour [r, g, b] 0..255 (rpg_dvs_ros: blue)
  std::array<int, 3> off_rgb{255, 0, 0};  ///< ~off_colour [r, g, b] 0..255 (red)
};
EventRendererConfig loadEventRendererConfig(const ros::NodeHandle& private_nh);

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

/// Configuration of the DepthEventFusion nodelet (D-eDVS depth for every event, thesis 8.2).
struct DepthEventFusionNodeConfig {
  /// ~calibration (required): sensors yaml (ebslam/simulation/dedvs_io.h readDedvsSensors format:
  /// eDVS intrinsics and distortion, depth intrinsics, depth_from_edvs, depth clock offset, frame
  /// rate)
  std::string calibration;
  ebslam::DedvsSensors sensors;      ///< read from ~calibration
  ebslam::DepthFusionConfig fusion;  ///< ~min_depth, ~max_depth [m], ~max_frame_age [s],
                                     ///< ~max_surface_jump_ratio, ~frames_kept
  bool edvs_camera_info = false;     ///< ~edvs_camera_info: eDVS size, focal, centre from
                                     ///< `camera_info` (kappas stay the calibration's)
  std::string edvs_frame = "edvs_optical_frame";           ///< ~edvs_frame
  std::string depth_frame = "camera_depth_optical_frame";  ///< ~depth_frame
  bool publish_tf = true;  ///< ~publish_tf: static tf of the calibration's depth_from_edvs
  /// ~tf_parent: "depth" (~depth_frame -> ~edvs_frame) or "edvs" (~edvs_frame -> ~depth_frame,
  /// when the eDVS frame has a parent already, e.g. EventSlam3d's base_link)
  std::string tf_parent = "depth";
  /// ~max_wait: longest wall time an EventArray newer than the latest depth frame waits for the
  /// next (nearer) frame [s]
  double max_wait_s = 0.2;
  int queue_size = 100;  ///< ~queue_size: subscriber queues [messages]
};

DepthEventFusionNodeConfig loadDepthEventFusionNodeConfig(const ros::NodeHandle& private_nh);

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
  /// ~seed (events, depth noise), ~depth_width (320 or 640), ~noise_rate [Hz per pixel],
  /// ~depth_rate [Hz], ~depth_clock_offset [s]; the rest the core's defaults
  ebslam::DedvsSimulatorConfig simulator;
  ebslam::RoomSceneConfig room;  ///< ~seed (furniture, textures), ~texture_contrast
  std::string edvs_frame = "edvs_optical_frame";           ///< ~edvs_frame
  std::string depth_frame = "camera_depth_optical_frame";  ///< ~depth_frame (colour registered)
  std::string map_frame = "map";                           ///< ~map_frame
  std::string ground_truth_frame = "ground_truth";         ///< ~ground_truth_frame: the rig
  int path_length = 10000;                                 ///< ~path_length
  std::string write_calibration;  ///< ~write_calibration: write the rig's sensors yaml there
};

RgbdEventSimulatorNodeConfig loadRgbdEventSimulatorNodeConfig(
    const ros::NodeHandle& private_nh, const std::string& default_trajectory);
/// The Exploration nodelet (thesis 7.4): the explorer's parameters under their core names
/// (ebslam::ExplorationConfig, units in its comments: ~hex_spacing [m], ~grid_extent [m],
/// ~robot_radius [m], ~bump_cone_depth [m], ~bump_cone_half_angle [rad], ~weight_z, ~weight_e,
/// ~alpha, ~planner_max_nodes, ~planner_time_budget [s], ~near_blocked_cost, ~oscillation_window,
/// ~oscillation_max_cells, ~commit_min_cells, ~escape_blocked_cost,
/// ~min_path_cells, ~max_path_cells, ~waypoint_tolerance [m], ~lookahead [m], ~turn_in_place
/// [rad], ~heading_gain [1/s], ~max_speed [m/s], ~max_turn_rate [rad/s], ~backout_time [s],
/// ~backout_speed [m/s], ~max_bumps_in_a_row, ~pose_timeout [s], ~pose_jump [m],
/// ~pose_jump_rad [rad]) and the node's own.
struct ExplorationNodeConfig {
  ebslam::ExplorationConfig exploration;
  double control_rate_hz = 20.0;  ///< ~control_rate: control steps and cmd_vel per second [Hz]
  std::string map_frame = "map";  ///< ~map_frame: frame of pose, Z map, plan and markers
  /// ~use_localisation_map: subscribe EB-SLAM's normalisation map (`map/normalisation`) for Z;
  /// false: Z stays 0 (only E and the bumps guide the robot).
  bool use_localisation_map = true;
  double markers_period_s = 1.0;  ///< ~markers_period: grid_markers while subscribed [s]
  /// ~initial_pose [x [m], y [m], yaw [rad]] in ~map_frame: the localisation's start pose (e.g.
  /// EventSlam2d's ~initial_pose), used from the first control step until the first `pose`
  /// arrives, as ebslam_explore starts from EB-SLAM's estimate before any event. Unset: the
  /// explorer stands still until the first pose.
  std::optional<ebslam::Pose2> initial_pose;
};
ExplorationNodeConfig loadExplorationNodeConfig(const ros::NodeHandle& private_nh);

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
