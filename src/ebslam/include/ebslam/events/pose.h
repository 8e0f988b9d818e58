#pragma once

// The pose types of the core: Pose2 on the plane (floor robots, ceiling-facing sensors) and Pose3
// in space (hand-held D-eDVS, trajectories), with the SE(2) operations the filters and their
// users share. A pose maps body coordinates into its parent frame: p_parent = R p_body + t.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ebslam {

/// Planar pose: position [m], heading [rad] (eq. 6.31).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

/// Rigid pose in space: body frame -> parent frame.
struct Pose3 {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< unit

  /// The pose as a transform, p_parent = T p_body (orientation normalised).
  Eigen::Isometry3d isometry() const {
    Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
    transform.linear() = orientation.normalized().toRotationMatrix();
    transform.translation() = position;
    return transform;
  }
  /// The pose of a rigid transform (orientation normalised).
  static Pose3 fromIsometry(const Eigen::Isometry3d& transform) {
    Pose3 pose;
    pose.position = transform.translation();
    pose.orientation = Eigen::Quaterniond(transform.linear()).normalized();
    return pose;
  }
};

/// The angle a [rad] mapped into [-pi, pi] (as atan2 of its sine and cosine).
inline double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

/// a * b: the pose b (given in a's body frame) in a's parent frame. The heading is reduced into
/// [-pi, pi] with std::remainder.
inline Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y,
          std::remainder(a.theta + b.theta, 2.0 * M_PI)};
}

/// The inverse pose: compose(p, inverse(p)) is the identity.
inline Pose2 inverse(const Pose2& p) {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  return {-c * p.x - s * p.y, s * p.x - c * p.y, -p.theta};
}

}  // namespace ebslam
