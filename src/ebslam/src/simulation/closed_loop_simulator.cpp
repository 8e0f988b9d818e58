#include "ebslam/simulation/closed_loop_simulator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ebslam/events/pose.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kContactGapM = 1e-4;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

double approach(double current, double target, double max_change) {
  return current + std::clamp(target - current, -max_change, max_change);
}

Eigen::Isometry3d cameraPose(const Pose2& pose) {
  Eigen::Isometry3d camera = Eigen::Isometry3d::Identity();
  camera.linear() = Eigen::AngleAxisd(pose.theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  camera.translation() = Eigen::Vector3d(pose.x, pose.y, 0.0);
  return camera;
}

}  // namespace

void DiffDriveConfig::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(positive(radius_m), "DiffDriveConfig: radius_m must be positive");
  require(positive(max_speed_mps), "DiffDriveConfig: max_speed_mps must be positive");
  require(positive(max_turn_rate_rps), "DiffDriveConfig: max_turn_rate_rps must be positive");
  require(positive(max_acceleration_mps2),
          "DiffDriveConfig: max_acceleration_mps2 must be positive");
  require(positive(max_angular_acceleration_rps2),
          "DiffDriveConfig: max_angular_acceleration_rps2 must be positive");
  require(positive(integration_step_s) && integration_step_s <= 0.1,
          "DiffDriveConfig: integration_step_s must be in (0, 0.1]");
  require(bump_segments >= 1 && bump_segments <= 32,
          "DiffDriveConfig: bump_segments must be in [1, 32]");
  require(std::isfinite(contact_tolerance_m) && contact_tolerance_m >= 0.0,
          "DiffDriveConfig: contact_tolerance_m must be >= 0");
}

void ClosedLoopSimulatorConfig::validate() const {
  events.validate();
  robot.validate();
  require(std::isfinite(ceiling_height_m) && ceiling_height_m > 0.0,
          "ClosedLoopSimulatorConfig: ceiling_height_m must be positive");
  require(std::isfinite(ceiling_metres_per_texel) && ceiling_metres_per_texel > 0.0,
          "ClosedLoopSimulatorConfig: ceiling_metres_per_texel must be positive");
  require(std::isfinite(ground_truth_rate_hz) && ground_truth_rate_hz > 0.0,
          "ClosedLoopSimulatorConfig: ground_truth_rate_hz must be positive");
}

Scene makeRoomCeilingScene(const FloorPlan& plan, const ClosedLoopSimulatorConfig& config) {
  plan.validate();
  // The region the sensor can see from anywhere in the room: the room's bounding box grown by
  // the footprint (visibleCeilingRegion of a path through two opposite corners).
  const Eigen::Vector2d lo = plan.boundsMin();
  const Eigen::Vector2d hi = plan.boundsMax();
  const Trajectory corners = {se2ToFloorPose(0.0, lo.x(), lo.y(), 0.0),
                              se2ToFloorPose(1.0, hi.x(), hi.y(), 0.0)};
  const FloorRegion region =
      visibleCeilingRegion(corners, config.events.camera, config.ceiling_height_m);
  LinesAndCirclesConfig texture = config.ceiling;
  texture.seed = config.seed;
  const double texel = config.ceiling_metres_per_texel;
  texture.width_px = static_cast<int>((region.max.x() - region.min.x()) / texel) + 1;
  texture.height_px = static_cast<int>((region.max.y() - region.min.y()) / texel) + 1;
  const double area_factor =
      (static_cast<double>(texture.width_px) * texture.height_px) /
      (static_cast<double>(config.ceiling.width_px) * config.ceiling.height_px);
  texture.line_count = static_cast<int>(std::lround(config.ceiling.line_count * area_factor));
  texture.circle_count = static_cast<int>(std::lround(config.ceiling.circle_count * area_factor));
  return makeCeilingScene(makeLinesAndCirclesTexture(texture), region, texel,
                          config.ceiling_height_m);
}

namespace {
ClosedLoopSimulatorConfig seeded(ClosedLoopSimulatorConfig config) {
  config.validate();
  config.events.events.seed = config.seed;
  config.ceiling.seed = config.seed;
  return config;
}
}  // namespace

ClosedLoopSimulator::ClosedLoopSimulator(const FloorPlan& plan,
                                         const ClosedLoopSimulatorConfig& config)
    : plan_(plan),
      config_(seeded(config)),
      scene_(makeRoomCeilingScene(plan_, config_)),
      stream_(config_.events, scene_, cameraPose(plan_.start), 0.0),
      pose_(plan_.start) {
  require(fits(Eigen::Vector2d(pose_.x, pose_.y)),
          "ClosedLoopSimulator: the robot does not fit at the floor plan's start pose");
  pose_.theta = wrapAngle(pose_.theta);
  ground_truth_.push_back(se2ToFloorPose(0.0, pose_.x, pose_.y, pose_.theta));
  next_ground_truth_s_ = 1.0 / config_.ground_truth_rate_hz;
}

bool ClosedLoopSimulator::fits(const Eigen::Vector2d& p) const {
  return plan_.discFits(p, config_.robot.radius_m);
}

BumpReading ClosedLoopSimulator::readBumpRing(const Eigen::Vector2d& push_direction_world) const {
  BumpReading reading;
  reading.t_s = t_s_;
  reading.segment_count = config_.robot.bump_segments;
  if (push_direction_world.squaredNorm() == 0.0) return reading;
  const DiffDriveConfig& robot = config_.robot;
  const Eigen::Vector2d centre(pose_.x, pose_.y);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& q :
       plan_.boundaryPointsWithin(centre, robot.radius_m + robot.contact_tolerance_m)) {
    const Eigen::Vector2d to_contact = q - centre;
    if (to_contact.squaredNorm() == 0.0) continue;
    const Eigen::Vector2d unit = to_contact.normalized();
    if (unit.dot(push_direction_world) <= 0.0) continue;  // not pushed against this contact
    const double direction = wrapAngle(std::atan2(unit.y(), unit.x()) - pose_.theta);
    const double sector = 2.0 * kPi / robot.bump_segments;
    const int k = static_cast<int>(std::lround(direction / sector) + robot.bump_segments) %
                  robot.bump_segments;
    reading.segments |= std::uint32_t{1} << k;
    sum += Eigen::Vector2d(std::cos(direction), std::sin(direction));
  }
  if (reading.contact()) reading.direction_rad = std::atan2(sum.y(), sum.x());
  return reading;
}

BumpReading ClosedLoopSimulator::step(const VelocityCommand& command, double dt_s,
                                      EventVector& events) {
  require(std::isfinite(dt_s) && dt_s > 0.0, "ClosedLoopSimulator::step: dt_s must be positive");
  require(std::isfinite(command.v_mps) && std::isfinite(command.omega_rps),
          "ClosedLoopSimulator::step: the command is not finite");
  const DiffDriveConfig& robot = config_.robot;
  const double target_v = std::clamp(command.v_mps, -robot.max_speed_mps, robot.max_speed_mps);
  const double target_omega =
      std::clamp(command.omega_rps, -robot.max_turn_rate_rps, robot.max_turn_rate_rps);
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt_s / robot.integration_step_s)));
  const double h = dt_s / substeps;
  const double t_end = t_s_ + dt_s;
  const bool render_per_substep = config_.render_per_substep;
  substeps_.clear();
  substeps_.emplace_back(t_s_, pose_);
  for (int i = 0; i < substeps; ++i) {
    velocity_.v_mps = approach(velocity_.v_mps, target_v, robot.max_acceleration_mps2 * h);
    velocity_.omega_rps =
        approach(velocity_.omega_rps, target_omega, robot.max_angular_acceleration_rps2 * h);
    const double theta_mid = pose_.theta + 0.5 * velocity_.omega_rps * h;
    const Eigen::Vector2d delta =
        velocity_.v_mps * h * Eigen::Vector2d(std::cos(theta_mid), std::sin(theta_mid));
    Eigen::Vector2d position(pose_.x, pose_.y);
    if (fits(position + delta)) {
      position += delta;
    } else {
      // Move up to the contact (bisection on the fraction of the sub-step), then stop. The
      // robot stops kContactGapM short of the edge so that it can drive along a wall it
      // touches (at exactly the radius, rounding would block every tangential move).
      double lo = 0.0, hi = 1.0;
      for (int k = 0; k < 12; ++k) {
        const double mid = 0.5 * (lo + hi);
        (plan_.discFits(position + mid * delta, robot.radius_m + kContactGapM) ? lo : hi) = mid;
      }
      position += lo * delta;
      velocity_.v_mps = 0.0;
    }
    pose_ = Pose2{position.x(), position.y(), wrapAngle(pose_.theta + velocity_.omega_rps * h)};
    const double t1 = i + 1 == substeps ? t_end : t_s_ + h;
    if (config_.simulate_events) {
      if (render_per_substep) {
        stream_.moveTo(cameraPose(pose_), t1, events);
      } else {
        substeps_.emplace_back(t1, pose_);
      }
    }
    t_s_ = t1;
    while (next_ground_truth_s_ <= t_s_ + 1e-12) {
      // Record the pose at the sub-step end that reaches the ground-truth time (sub-steps are
      // much shorter than the recording period).
      ground_truth_.push_back(se2ToFloorPose(t_s_, pose_.x, pose_.y, pose_.theta));
      next_ground_truth_s_ += 1.0 / config_.ground_truth_rate_hz;
    }
  }
  if (config_.simulate_events && !render_per_substep) {
    // The camera along the sub-steps' path, linear in position and heading between sub-step
    // ends (as moveTo per sub-step), rendered at the event simulator's own rate.
    const auto pose_at = [this](double t) {
      const auto after = std::lower_bound(
          substeps_.begin() + 1, substeps_.end(), t,
          [](const std::pair<double, Pose2>& s, double time) { return s.first < time; });
      const auto& b = after == substeps_.end() ? substeps_.back() : *after;
      const auto& a = after == substeps_.end() ? substeps_.back() : *(after - 1);
      const double span = b.first - a.first;
      const double f = span > 0.0 ? std::clamp((t - a.first) / span, 0.0, 1.0) : 1.0;
      const Pose2 p{a.second.x + f * (b.second.x - a.second.x),
                    a.second.y + f * (b.second.y - a.second.y),
                    a.second.theta + f * wrapAngle(b.second.theta - a.second.theta)};
      return cameraPose(p);
    };
    stream_.advance(
        t_end, pose_at,
        [&events](const EventVector& step, const std::vector<std::uint8_t>&, double) {
          events.insert(events.end(), step.begin(), step.end());
        },
        false);
  }
  Eigen::Vector2d push = Eigen::Vector2d::Zero();
  if (target_v != 0.0) {
    push = Eigen::Vector2d(std::cos(pose_.theta), std::sin(pose_.theta)) *
           (target_v > 0.0 ? 1.0 : -1.0);
  }
  const BumpReading reading = readBumpRing(push);
  if (reading.contact()) ++bump_steps_;
  return reading;
}

}  // namespace ebslam
