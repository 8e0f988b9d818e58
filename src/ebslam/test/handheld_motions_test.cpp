#include "ebslam/simulation/handheld_motions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace ebslam {
namespace {

// Heading of the optical axis about world z [rad].
double heading(const StampedPose& p) {
  const Eigen::Vector3d axis = p.orientation * Eigen::Vector3d::UnitZ();
  return std::atan2(axis.y(), axis.x());
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

TEST(HandheldMotions, YawTurnTurnsOnceAroundFast) {
  const Trajectory path = makeHandheldMotion(HandheldMotion::kYawTurn, 15.0, 1);
  ASSERT_EQ(path.size(), 1501u);
  double turned = 0.0, peak = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    const double d = wrap(heading(path[k]) - heading(path[k - 1]));
    turned += d;
    peak = std::max(peak, std::abs(d) / (path[k].t_s - path[k - 1].t_s));
  }
  EXPECT_NEAR(turned, 2.0 * M_PI, 0.3);  // the pans return to their start
  EXPECT_GT(peak * 180.0 / M_PI, 150.0);
  EXPECT_LT(peak * 180.0 / M_PI, 260.0);
  for (const StampedPose& p : path) EXPECT_NEAR(p.position.z(), 1.4, 0.05);
}

TEST(HandheldMotions, FloorSweepStaysLowLookingDown) {
  const Trajectory path = makeHandheldMotion(HandheldMotion::kFloorSweep, 10.0, 2);
  double min_x = 1e9, max_x = -1e9;
  for (const StampedPose& p : path) {
    EXPECT_GT(p.position.z(), 0.45);
    EXPECT_LT(p.position.z(), 0.65);
    const Eigen::Vector3d axis = p.orientation * Eigen::Vector3d::UnitZ();
    EXPECT_LT(axis.z(), -0.8);  // about 60 deg down
    min_x = std::min(min_x, p.position.x());
    max_x = std::max(max_x, p.position.x());
  }
  EXPECT_GT(max_x - min_x, 0.9);
}

TEST(HandheldMotions, ShakeIsFastAndSmall) {
  const Trajectory path = makeHandheldMotion(HandheldMotion::kShake, 5.0, 3);
  double sum_speed2 = 0.0, sum_rate2 = 0.0, max_offset = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    const double dt = path[k].t_s - path[k - 1].t_s;
    sum_speed2 += (path[k].position - path[k - 1].position).squaredNorm() / (dt * dt);
    const double a = path[k].orientation.angularDistance(path[k - 1].orientation) / dt;
    sum_rate2 += a * a;
    max_offset = std::max(max_offset, (path[k].position - path[0].position).norm());
  }
  const auto n = static_cast<double>(path.size() - 1);
  EXPECT_GT(std::sqrt(sum_speed2 / n), 0.4);                 // [m/s]
  EXPECT_GT(std::sqrt(sum_rate2 / n) * 180.0 / M_PI, 40.0);  // [deg/s]
  EXPECT_LT(max_offset, 0.5);
}

TEST(HandheldMotions, OrbitCirclesTheObjectAtCloseRange) {
  const Trajectory path = makeHandheldMotion(HandheldMotion::kOrbit, 12.0, 2);
  const Eigen::Vector3d target(0.0, 0.0, 0.85);
  double min_d = 1e9, max_d = 0.0, turned = 0.0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const StampedPose& p = path[k];
    const Eigen::Vector3d to_target = target - p.position;
    min_d = std::min(min_d, to_target.norm());
    max_d = std::max(max_d, to_target.norm());
    const Eigen::Vector3d axis = p.orientation * Eigen::Vector3d::UnitZ();
    EXPECT_GT(axis.dot(to_target.normalized()), 0.98);  // looks at the object (tremor aside)
    if (k > 0) {
      const Eigen::Vector3d a = path[k - 1].position - target, b = p.position - target;
      turned += std::atan2(a.x() * b.y() - a.y() * b.x(), a.head<2>().dot(b.head<2>()));
    }
  }
  EXPECT_GT(min_d, 0.38);
  EXPECT_LT(min_d, 0.5);
  EXPECT_GT(max_d, 0.7);
  EXPECT_LT(max_d, 0.82);
  EXPECT_NEAR(turned, 2.0 * M_PI, 0.1);  // one revolution in 12 s
}

TEST(HandheldMotions, SeededAndValidated) {
  const Trajectory a = makeHandheldMotion(HandheldMotion::kShake, 2.0, 5);
  const Trajectory b = makeHandheldMotion(HandheldMotion::kShake, 2.0, 5);
  const Trajectory c = makeHandheldMotion(HandheldMotion::kShake, 2.0, 6);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a[100].position, b[100].position);
  EXPECT_NE(a[100].position, c[100].position);
  EXPECT_THROW(makeHandheldMotion(HandheldMotion::kShake, 0.0, 1), std::invalid_argument);
  EXPECT_THROW(handheldMotionFromString("spin"), std::invalid_argument);
  for (const char* name : {"yaw_turn", "floor_sweep", "shake", "orbit"}) {
    EXPECT_STREQ(toString(handheldMotionFromString(name)), name);
  }
}

}  // namespace
}  // namespace ebslam
