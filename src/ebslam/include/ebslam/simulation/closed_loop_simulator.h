#pragma once

// Closed-loop floor-robot simulator for autonomous exploration (thesis 7.4): a differential-drive
// robot in a FloorPlan room, driven by velocity commands, with a 360-degree bump ring and the
// upward eDVS of simulator_scenes.h (an EventStream moved along the actual motion); seeded,
// deterministic. Frames: world = the floor plan's (z up); robot pose = the sensor's pose; bump
// directions in the robot frame, 0 = forward, counter-clockwise positive [rad].
// Details: docs/ebslam_core.md#closed-loop-simulator

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ebslam/events/event.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/floor_plan.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/floor_robot.h"

namespace ebslam {

/// Differential-drive robot: a disc with speed, turn-rate and acceleration limits.
struct DiffDriveConfig {
  double radius_m = 0.15;                      ///< body and bump-ring radius [m]
  double max_speed_mps = 0.3;                  ///< |v| limit [m/s] (the TUM pioneer runs' speed)
  double max_turn_rate_rps = 1.5;              ///< |omega| limit [rad/s]
  double max_acceleration_mps2 = 1.0;          ///< |dv/dt| limit [m/s^2]
  double max_angular_acceleration_rps2 = 6.0;  ///< |domega/dt| limit [rad/s^2]
  double integration_step_s = 0.005;           ///< kinematics sub-step [s]
  /// Number of contact segments of the bump ring, centred at k * 2 pi / n (robot frame).
  int bump_segments = 8;
  /// A segment reports contact while an edge is closer than radius + this [m] and the robot
  /// pushes towards it.
  double contact_tolerance_m = 0.002;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

struct ClosedLoopSimulatorConfig {
  SimulatorConfig events;  ///< camera (the eDVS of 6.5), event model and render rate
  DiffDriveConfig robot;
  double ceiling_height_m = kThesisCeilingHeightM;
  /// Ceiling texture (thesis 6.5.3); its size is set from the room and its line and circle
  /// counts scaled to keep the default density (40 lines, 25 circles per 10.24 m x 10.24 m).
  LinesAndCirclesConfig ceiling;
  double ceiling_metres_per_texel = 0.01;
  /// Render the eDVS and emit events; off for controllers that use no events (the random
  /// baseline), which makes the simulation about ten times faster.
  bool simulate_events = true;
  /// Render the eDVS once per kinematics sub-step (integration_step_s, i.e. at >= 200 Hz
  /// whatever events.render_rate_hz says) as before, instead of along the whole step's
  /// sub-step path at events.render_rate_hz (finer where the image moves more than
  /// events.max_step_motion_px). The path is the same; only the render times differ. For
  /// comparing with runs made before; about half the rendering at 100 Hz.
  bool render_per_substep = false;
  /// Ground-truth poses are recorded at this rate [Hz].
  double ground_truth_rate_hz = 100.0;
  /// Seeds the event model and the ceiling texture (overrides events.events.seed and
  /// ceiling.seed).
  std::uint64_t seed = 1;

  void validate() const;
};

class ClosedLoopSimulator {
 public:
  /// Builds the ceiling over the room (its bounding box grown by the sensor's footprint on the
  /// ceiling) and places the robot at plan.start at time t = 0. Throws std::invalid_argument for
  /// an invalid config or plan, or a start pose where the robot does not fit.
  ClosedLoopSimulator(const FloorPlan& plan, const ClosedLoopSimulatorConfig& config = {});

  /// Applies `command` (clamped to the robot's limits) for dt_s [s]: moves the robot (stopping
  /// at contact; turning in place is always possible for a disc), appends the eDVS events of the
  /// motion to `events` and returns the bump ring's reading at the end of the step. Throws
  /// std::invalid_argument for a non-positive or non-finite dt_s or a non-finite command.
  BumpReading step(const VelocityCommand& command, double dt_s, EventVector& events);

  double time() const { return t_s_; }
  /// True robot pose (x, y, theta) in the world frame.
  Pose2 pose() const { return pose_; }
  /// Current velocity after limits (v [m/s], omega [rad/s]).
  VelocityCommand velocity() const { return velocity_; }
  /// Ground truth (camera -> world, as simulator_scenes.h) at ground_truth_rate_hz.
  const Trajectory& groundTruth() const { return ground_truth_; }
  const FloorPlan& plan() const { return plan_; }
  const ClosedLoopSimulatorConfig& config() const { return config_; }
  const Scene& scene() const { return scene_; }
  /// Number of steps that ended with a contact.
  std::size_t bumpSteps() const { return bump_steps_; }

 private:
  bool fits(const Eigen::Vector2d& p) const;
  BumpReading readBumpRing(const Eigen::Vector2d& push_direction_world) const;

  FloorPlan plan_;
  ClosedLoopSimulatorConfig config_;
  Scene scene_;
  EventStream stream_;
  double t_s_ = 0.0;
  Pose2 pose_;
  VelocityCommand velocity_;
  Trajectory ground_truth_;
  double next_ground_truth_s_ = 0.0;
  std::size_t bump_steps_ = 0;
  std::vector<std::pair<double, Pose2>> substeps_;  // (time, pose) of the step's sub-steps
};

/// The ceiling scene over a floor plan as ClosedLoopSimulator builds it.
Scene makeRoomCeilingScene(const FloorPlan& plan, const ClosedLoopSimulatorConfig& config);

}  // namespace ebslam
