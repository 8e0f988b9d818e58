#pragma once

// Trajectory evaluation (thesis 8.4, eq. 8.16-8.20): the estimated path is mapped into the
// ground-truth frame by the alignment a = (t_a, p_a, q_a) of eq. 8.18,
//   A((t, p, q), a) = (t + t_a, s * q_a p + p_a, q_a q),
// that minimises the position RMSE [m] (eq. 8.16, 8.17, 8.19): closed-form Horn / Umeyama for a
// fixed t_a, a 1-D search over t_a. Ground truth interpolated at t_i + t_a by default (kNearest:
// the thesis' nearest pose). Rotation error (eq. 8.20) in degrees.
// Details: docs/trajectory_evaluation.md#what-is-computed-thesis-84

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/trajectory.h"

namespace ebslam {

enum class TimeAssociation {
  kInterpolate,  ///< ground truth interpolated at t + t_a (default, continuous in t_a)
  kNearest,      ///< temporally nearest ground-truth pose (thesis eq. 8.16)
};

struct TrajectoryEvaluationConfig {
  bool estimate_scale = false;            ///< also fit a scale s (Umeyama); rigid by default
  bool estimate_time_offset = true;       ///< search t_a; otherwise t_a = 0
  double max_time_offset_s = 1.0;         ///< search range [-max, +max] for t_a [s]
  double coarse_step_s = 0.01;            ///< grid step of the coarse search [s]
  double time_offset_tolerance_s = 1e-9;  ///< golden-section stops at this bracket width [s]
  TimeAssociation association = TimeAssociation::kInterpolate;
  /// kInterpolate: largest ground-truth sampling gap to interpolate across; kNearest: largest
  /// |t_i + t_a - t'_j| accepted [s].
  double max_association_gap_s = 0.1;
  /// Also fit a constant rotation between the estimated and the ground-truth body frames
  /// (q' = q_a q q_b), e.g. a camera frame versus a motion-capture marker frame. Affects the
  /// rotation error only; the position alignment does not depend on it.
  bool estimate_body_rotation = false;
  std::size_t min_pairs = 3;  ///< fewer associated poses => no alignment at that offset
  /// The time-offset search evaluates an evenly spaced subset of at most this many estimated
  /// poses (0 = all; values below 100 count as 100), so estimates with a pose per event stay
  /// fast; the final alignment and all reported errors use every pose.
  std::size_t max_search_poses = 5000;
};

/// The alignment of eq. 8.18 (plus the optional scale and body rotation).
struct TrajectoryAlignment {
  double time_offset_s = 0.0;  ///< t_a: estimate time + t_a = ground-truth time [s]
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();       ///< q_a: estimate -> gt world
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();              ///< p_a [m]
  double scale = 1.0;                                                 ///< s (1 unless estimated)
  Eigen::Quaterniond body_rotation = Eigen::Quaterniond::Identity();  ///< q_b (identity unless
                                                                      ///< estimated)

  /// Applies the alignment to an estimated pose (time, position, orientation).
  StampedPose apply(const StampedPose& estimated) const;
};

/// Error of one associated pose.
struct PoseError {
  double t_s = 0.0;                 ///< estimated pose's own timestamp [s]
  double position_error_m = 0.0;    ///< eq. 8.17 after alignment [m]
  double rotation_error_deg = 0.0;  ///< eq. 8.20 after alignment [deg]
  Eigen::Vector3d aligned_position = Eigen::Vector3d::Zero();       ///< in gt world [m]
  Eigen::Vector3d ground_truth_position = Eigen::Vector3d::Zero();  ///< [m]
};

struct TrajectoryEvaluation {
  TrajectoryAlignment alignment;
  double position_rmse_m = 0.0;    ///< eq. 8.16 [m]
  double rotation_rmse_deg = 0.0;  ///< RMS of eq. 8.20 [deg]
  double position_max_m = 0.0;
  double rotation_max_deg = 0.0;
  std::size_t estimated_poses = 0;  ///< poses in the estimate
  std::vector<PoseError> errors;    ///< one per associated estimated pose, in time order
};

/// Finds the best alignment of `estimated` onto `ground_truth` and reports the errors.
/// Throws std::invalid_argument for an empty trajectory, invalid poses (NaN, non-increasing
/// time, non-unit quaternion; see validateTrajectory), an invalid config, or when no offset in
/// the search range associates at least config.min_pairs poses.
TrajectoryEvaluation evaluateTrajectory(const Trajectory& estimated, const Trajectory& ground_truth,
                                        const TrajectoryEvaluationConfig& config = {});

/// Writes the per-pose errors as CSV: header
/// `t_s,position_error_m,rotation_error_deg,est_x,est_y,est_z,gt_x,gt_y,gt_z` (est = aligned).
/// Throws std::runtime_error on I/O failure.
void writeTrajectoryErrorsCsv(const std::string& path, const TrajectoryEvaluation& evaluation);

}  // namespace ebslam
