#pragma once

// D-eDVS simulator (thesis 8.2): a hand-held rig with an eDVS (128 x 128, eq. 8.1-8.2) and a
// PrimeSense-like depth camera with registered colour moves along a trajectory through a Scene of
// textured planes (dedvs_scene.h builds rooms). Frames: REP 103 optical frames, metres; rig frame
// = depth optical frame (trajectory: rig -> world); p_depth = depth_from_edvs * p_edvs (R, t of
// eq. 8.4). Time: trajectory clock [s], events round(t * 1e6) [us]; depth frames stamped on the
// camera clock (true time + clock_offset_s). Depth CV_16UC1 [mm], 0 = no depth; colour CV_8UC3
// BGR. Deterministic per seed; single-threaded. Details: docs/dedvs_core.md#simulator

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/event_model.h"
#include "ebslam/simulation/imu_simulator.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/slam/camera_model.h"
#include "ebslam/slam/dedvs_sensors.h"

namespace ebslam {

/// The PrimeSense-like depth camera with registered colour.
struct DepthCameraConfig {
  PinholeCamera camera;
  double frame_rate_hz = 30.0;
  double min_range_m = 0.5;  ///< nearer: no depth
  double max_range_m = 4.0;  ///< farther: no depth
  /// Disparity model (Khoshelham and Oude Elberink 2012; Kinect/Xtion values): baseline
  /// between IR camera and projector [m] and the IR camera's focal length at its native
  /// 640 x 480 resolution [px]. z = f_ir b / d.
  double baseline_m = 0.075;
  double ir_focal_px = 580.0;
  int subpixel_steps = 8;  ///< disparity quantisation: 1/8 pixel (PrimeSense)
  /// Disparity noise [IR pixels], sigma. 0.0625 gives sigma_z = 5.7 mm at 2 m and 2.3 cm at
  /// 4 m (plus quantisation), as measured for the Kinect (Khoshelham 2012; Nguyen et al. 2012).
  double disparity_noise_px = 0.0625;
  /// Direction from the IR camera to the projector in the depth frame (unit * baseline).
  Eigen::Vector3d projector_direction{1.0, 0.0, 0.0};
  /// Incidence angle (between ray and surface normal) beyond which there is no depth [deg].
  double max_incidence_deg = 78.0;
  /// A pixel whose 4-neighbour's depth differs by more than this fraction is on a depth edge;
  /// edge pixels have no depth with edge_hole_probability (the correlation window straddles
  /// the edge).
  double edge_jump_ratio = 0.05;
  double edge_hole_probability = 0.5;
  /// Offset of the camera's clock: stamp = true exposure time + clock_offset_s [s].
  double clock_offset_s = 0.012;
  /// Colour image noise, sigma in 8-bit grey levels.
  double colour_noise_sigma = 2.0;
  /// Exposure time of the colour image, centred on the frame's time [s]: a blinking LED's
  /// brightness is its on-time fraction during the exposure (a calibration run sets the camera
  /// to a short fixed exposure so that the LED blinks from frame to frame).
  double colour_exposure_s = 0.002;

  void validate() const;
};

/// Configuration of the D-eDVS simulator.
struct DedvsSimulatorConfig {
  /// The eDVS: 128 x 128, eq. 8.1 distortion. Focal length chosen so that its vertical field
  /// of view matches the depth camera's (thesis 8.2: 2 * atan(64 / 154) = 45 deg) before
  /// distortion; kappa1 > 0 is barrel distortion.
  CameraModel edvs = defaultEdvsCamera();
  EventModelConfig events;
  /// eDVS optical frame -> depth optical frame: mounted on top (-y), 4 cm above the depth
  /// camera, slightly rotated (mount tolerance).
  Eigen::Isometry3d depth_from_edvs = defaultDepthFromEdvs();
  DepthCameraConfig depth;
  double render_rate_hz = 500.0;    ///< minimum eDVS render rate [Hz]
  double max_step_motion_px = 0.5;  ///< finer steps when the image moves faster [px]
  double ground_truth_rate_hz = 200.0;
  /// eDVS irradiance scale: intensity = texture * illumination (and the LED's).
  double illumination = 1.0;
  /// The rig's IMU (imu_simulator.h): its body is the rig (depth optical frame), body_from_imu
  /// its mounting; readings on the trajectory clock (= the event clock), seeded by imu.seed.
  ImuSimulatorConfig imu;
  bool simulate_imu = true;  ///< false: DedvsRun::imu stays empty
  std::uint64_t seed = 1;    ///< depth noise and holes; events use events.seed

  static CameraModel defaultEdvsCamera();
  static Eigen::Isometry3d defaultDepthFromEdvs();
  void validate() const;
};

/// An eDVS event with the simulator's ground truth.
struct TrueDepthEvent {
  Event event;
  /// z of the surface point the pixel's ray (through its centre) hits at the event time, in
  /// the eDVS optical frame [m]; NaN if the ray hits nothing.
  float depth_m = 0.0f;
  bool is_noise = false;  ///< background-activity event (not caused by the scene)
  /// The pixel sees a depth edge at the event time: a 4-neighbour's ray hits a surface whose
  /// depth differs by more than 10 %.
  bool at_depth_edge = false;
  /// Nearest and farthest z [m] the rays of the pixel and its 8 neighbours hit at the event
  /// time (the surfaces the pixel's footprint may cover); NaN where none hits. Not stored in
  /// event files.
  float neighbourhood_min_depth_m = 0.0f;
  float neighbourhood_max_depth_m = 0.0f;
};

/// A simulated run.
struct DedvsRun {
  std::vector<TrueDepthEvent> events;  ///< sorted by time
  std::vector<DepthFrame> depth_frames;
  Trajectory rig_ground_truth;   ///< depth optical frame -> world at ground_truth_rate_hz
  Trajectory edvs_ground_truth;  ///< eDVS optical frame -> world, same times
  /// IMU readings over [t_begin, t_end] (config.imu; empty unless simulate_imu).
  std::vector<ImuReading> imu;
  std::size_t signal_events = 0;
  std::size_t noise_events = 0;
  std::size_t render_steps = 0;
};

/// A light source on a plane of the scene whose emitted intensity follows a square wave (the
/// pulsed calibration diode of thesis 8.2). Seen by the eDVS and the colour camera as a small
/// disc (the colour camera integrates it over its exposure), by the depth camera not at all.
struct BlinkingLed {
  /// Position [m] in the frame of the plane it is fixed to (plane index, see Scene), or in the
  /// world when plane_index < 0.
  Eigen::Vector3d position{0.0, 0.0, 0.0};
  int plane_index = -1;
  double frequency_hz = 500.0;  ///< square-wave frequency
  double radius_m = 0.004;      ///< disc radius [m]
  double on_intensity = 4.0;    ///< added intensity while on (texture units)
  double phase_s = 0.0;
};

/// Moves planes over time (e.g. a calibration target waved in front of the rig): maps a time
/// [s] to a plane -> world pose for the plane index given; planes not listed stay put.
struct MovingPlane {
  int plane_index = 0;
  Trajectory pose;  ///< plane -> world over time (must cover the simulated time range)
};

/// Simulates the D-eDVS.
class DedvsSimulator {
 public:
  /// Throws std::invalid_argument for an invalid configuration.
  explicit DedvsSimulator(const DedvsSimulatorConfig& config = {});
  const DedvsSimulatorConfig& config() const { return config_; }

  using EventSink = std::function<void(const std::vector<TrueDepthEvent>& events)>;
  using DepthSink = std::function<void(const DepthFrame& frame)>;

  /// Simulates the rig moving along `rig_trajectory` (depth optical frame -> world) from
  /// t_begin_s to t_end_s; streams event batches and depth frames in time order (a depth
  /// frame is delivered once all events up to its exposure time are). Either sink may be
  /// empty. Returns statistics and the ground truth (events and frames left empty).
  /// Throws std::invalid_argument for an invalid scene, trajectory or time range.
  DedvsRun simulate(const Scene& scene, const Trajectory& rig_trajectory, double t_begin_s,
                    double t_end_s, const EventSink& event_sink, const DepthSink& depth_sink,
                    const std::vector<BlinkingLed>& leds = {},
                    const std::vector<MovingPlane>& moving_planes = {}) const;

  /// As above, collecting everything in the result.
  DedvsRun simulate(const Scene& scene, const Trajectory& rig_trajectory, double t_begin_s,
                    double t_end_s, const std::vector<BlinkingLed>& leds = {},
                    const std::vector<MovingPlane>& moving_planes = {}) const;

  /// The eDVS intensity image (CV_32FC1) and its true depth (CV_32FC1, NaN = no hit) at a rig
  /// pose; for pictures and tests.
  void renderEdvs(const Scene& scene, const Eigen::Isometry3d& rig_pose, cv::Mat& intensity,
                  cv::Mat& depth_m) const;

 private:
  DedvsSimulatorConfig config_;
};

/// The rig IMU's frame -> the eDVS optical frame (the rotation EB-SLAM-3D's gyro prior needs):
/// depth_from_edvs^-1 * imu.body_from_imu.
Eigen::Quaterniond edvsFromImu(const DedvsSimulatorConfig& config);

/// Standard deviation of the depth camera's depth [m] at depth z from the disparity model
/// (noise and quantisation): sqrt(sigma_d^2 + q^2 / 12) z^2 / (f_ir b), q = 1 / subpixel_steps.
double depthNoiseSigma(const DepthCameraConfig& config, double z_m);

}  // namespace ebslam
