#include "ebslam/events/trajectory_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace ebslam {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// Estimated poses paired with the ground truth at t_i + offset.
struct Association {
  std::vector<std::size_t> estimated_index;
  Eigen::Matrix3Xd estimated_positions;
  Eigen::Matrix3Xd ground_truth_positions;
  std::vector<Eigen::Quaterniond> ground_truth_orientations;
};

Association associate(const Trajectory& estimated, const Trajectory& ground_truth, double offset,
                      const TrajectoryEvaluationConfig& config, bool with_orientations) {
  Association a;
  std::vector<Eigen::Vector3d> est;
  std::vector<Eigen::Vector3d> gt;
  est.reserve(estimated.size());
  gt.reserve(estimated.size());
  const auto time_less = [](double t, const StampedPose& p) { return t < p.t_s; };
  for (std::size_t i = 0; i < estimated.size(); ++i) {
    const double t = estimated[i].t_s + offset;
    // First ground-truth pose later than t.
    const auto upper = std::upper_bound(ground_truth.begin(), ground_truth.end(), t, time_less);
    StampedPose match;
    if (config.association == TimeAssociation::kInterpolate) {
      if (t < ground_truth.front().t_s || t > ground_truth.back().t_s) continue;
      if (upper != ground_truth.end() && upper != ground_truth.begin() &&
          upper->t_s - (upper - 1)->t_s > config.max_association_gap_s) {
        continue;  // no ground truth near t: do not invent poses across a gap
      }
      match = interpolatePose(ground_truth, t);
    } else {
      auto best = upper == ground_truth.end() ? upper - 1 : upper;
      if (upper != ground_truth.begin() &&
          std::abs((upper - 1)->t_s - t) <= std::abs(best->t_s - t)) {
        best = upper - 1;
      }
      if (std::abs(best->t_s - t) > config.max_association_gap_s) continue;
      match = *best;
    }
    a.estimated_index.push_back(i);
    est.push_back(estimated[i].position);
    gt.push_back(match.position);
    if (with_orientations) a.ground_truth_orientations.push_back(match.orientation);
  }
  a.estimated_positions.resize(3, static_cast<Eigen::Index>(est.size()));
  a.ground_truth_positions.resize(3, static_cast<Eigen::Index>(gt.size()));
  for (std::size_t k = 0; k < est.size(); ++k) {
    a.estimated_positions.col(static_cast<Eigen::Index>(k)) = est[k];
    a.ground_truth_positions.col(static_cast<Eigen::Index>(k)) = gt[k];
  }
  return a;
}

// Closed-form least-squares similarity/rigid transform dst ~ s R src + t (Umeyama 1991, which
// for s = 1 is Horn's / Arun's solution with the reflection fix). Returns false when the
// problem is degenerate (no spread in the source points while a scale is asked for).
bool umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale,
             Eigen::Matrix3d& rotation, Eigen::Vector3d& translation, double& scale) {
  const auto n = static_cast<double>(src.cols());
  const Eigen::Vector3d src_mean = src.rowwise().mean();
  const Eigen::Vector3d dst_mean = dst.rowwise().mean();
  const Eigen::Matrix3Xd src_c = src.colwise() - src_mean;
  const Eigen::Matrix3Xd dst_c = dst.colwise() - dst_mean;
  const Eigen::Matrix3d covariance = dst_c * src_c.transpose() / n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d d = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) d(2) = -1.0;
  rotation = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
  scale = 1.0;
  if (with_scale) {
    const double src_variance = src_c.squaredNorm() / n;
    if (!(src_variance > 0.0)) return false;
    scale = svd.singularValues().dot(d) / src_variance;
  }
  translation = dst_mean - scale * rotation * src_mean;
  return rotation.allFinite() && translation.allFinite() && std::isfinite(scale);
}

struct Fit {
  double mean_squared_error = std::numeric_limits<double>::infinity();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;
};

Fit fitAtOffset(const Trajectory& estimated, const Trajectory& ground_truth, double offset,
                const TrajectoryEvaluationConfig& config) {
  Fit fit;
  const Association a = associate(estimated, ground_truth, offset, config, false);
  if (a.estimated_index.size() < std::max<std::size_t>(config.min_pairs, 1)) return fit;
  if (!umeyama(a.estimated_positions, a.ground_truth_positions, config.estimate_scale, fit.rotation,
               fit.translation, fit.scale)) {
    return fit;
  }
  const Eigen::Matrix3Xd aligned =
      (fit.scale * fit.rotation * a.estimated_positions).colwise() + fit.translation;
  fit.mean_squared_error = (aligned - a.ground_truth_positions).colwise().squaredNorm().mean();
  return fit;
}

// Golden-section search for the minimum of f on [lo, hi] down to `tolerance`.
template <typename Function>
double goldenSection(Function f, double lo, double hi, double tolerance) {
  const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;  // 0.618...
  double a = lo;
  double b = hi;
  double c = b - inv_phi * (b - a);
  double d = a + inv_phi * (b - a);
  double fc = f(c);
  double fd = f(d);
  for (int iteration = 0; iteration < 200 && (b - a) > tolerance; ++iteration) {
    if (fc <= fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - inv_phi * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + inv_phi * (b - a);
      fd = f(d);
    }
  }
  return fc <= fd ? c : d;
}

// Rotation angle of a unit quaternion [rad], sign-invariant: |2 acos(|w|)| (eq. 8.20).
double rotationAngle(const Eigen::Quaterniond& q) {
  return 2.0 * std::acos(std::min(1.0, std::abs(q.w())));
}

// Average of unit quaternions (Markley et al. 2007): the eigenvector of sum q q^T with the
// largest eigenvalue; sign-invariant.
Eigen::Quaterniond averageQuaternion(const std::vector<Eigen::Quaterniond>& quaternions) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  for (const Eigen::Quaterniond& q : quaternions) m += q.coeffs() * q.coeffs().transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> solver(m);
  Eigen::Quaterniond average;
  average.coeffs() = solver.eigenvectors().col(3);
  return average.normalized();
}

void validateConfig(const TrajectoryEvaluationConfig& c) {
  const auto bad = [](const std::string& what) {
    throw std::invalid_argument("evaluateTrajectory: " + what);
  };
  if (!(c.max_time_offset_s >= 0.0) || !std::isfinite(c.max_time_offset_s)) {
    bad("max_time_offset_s must be finite and >= 0");
  }
  if (!(c.coarse_step_s > 0.0) || !std::isfinite(c.coarse_step_s)) bad("coarse_step_s must be > 0");
  if (c.max_time_offset_s / c.coarse_step_s > 1e6) bad("time offset grid larger than 10^6 points");
  if (!(c.time_offset_tolerance_s > 0.0)) bad("time_offset_tolerance_s must be > 0");
  if (!(c.max_association_gap_s > 0.0)) bad("max_association_gap_s must be > 0");
}

}  // namespace

StampedPose TrajectoryAlignment::apply(const StampedPose& estimated) const {
  StampedPose aligned;
  aligned.t_s = estimated.t_s + time_offset_s;
  aligned.position = scale * (rotation * estimated.position) + translation;
  aligned.orientation = (rotation * estimated.orientation * body_rotation).normalized();
  return aligned;
}

TrajectoryEvaluation evaluateTrajectory(const Trajectory& estimated, const Trajectory& ground_truth,
                                        const TrajectoryEvaluationConfig& config) {
  if (estimated.empty())
    throw std::invalid_argument("evaluateTrajectory: empty estimated trajectory");
  if (ground_truth.empty()) {
    throw std::invalid_argument("evaluateTrajectory: empty ground-truth trajectory");
  }
  validateTrajectory(estimated, "estimated trajectory");
  validateTrajectory(ground_truth, "ground-truth trajectory");
  validateConfig(config);

  // Evenly spaced subset for the offset search (at least 100 poses, see the config).
  Trajectory search_subset;
  const std::size_t search_poses = std::max<std::size_t>(config.max_search_poses, 100);
  const bool subsample = config.max_search_poses > 0 && estimated.size() > search_poses;
  if (subsample) {
    search_subset.reserve(search_poses);
    const double stride =
        static_cast<double>(estimated.size() - 1) / static_cast<double>(search_poses - 1);
    for (std::size_t k = 0; k < search_poses; ++k) {
      const std::size_t index =
          std::min(static_cast<std::size_t>(std::llround(stride * static_cast<double>(k))),
                   estimated.size() - 1);
      if (search_subset.empty() || estimated[index].t_s > search_subset.back().t_s) {
        search_subset.push_back(estimated[index]);
      }
    }
  }
  const Trajectory& search_estimate = subsample ? search_subset : estimated;
  const auto objective = [&](double offset) {
    return fitAtOffset(search_estimate, ground_truth, offset, config).mean_squared_error;
  };

  double best_offset = 0.0;
  if (config.estimate_time_offset && config.max_time_offset_s > 0.0) {
    // Coarse grid containing 0 and both ends of the range.
    const double step = config.coarse_step_s;
    const auto half = static_cast<long>(std::floor(config.max_time_offset_s / step));
    std::vector<double> grid;
    grid.push_back(-config.max_time_offset_s);
    for (long k = -half; k <= half; ++k) grid.push_back(static_cast<double>(k) * step);
    grid.push_back(config.max_time_offset_s);
    std::sort(grid.begin(), grid.end());
    grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
    double best_error = std::numeric_limits<double>::infinity();
    std::size_t best_index = 0;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double error = objective(grid[k]);
      if (error < best_error) {
        best_error = error;
        best_index = k;
      }
    }
    if (!std::isfinite(best_error)) {
      throw std::invalid_argument(
          "evaluateTrajectory: the trajectories do not overlap in time: fewer than " +
          std::to_string(config.min_pairs) + " associated poses for every time offset in +-" +
          std::to_string(config.max_time_offset_s) + " s");
    }
    const double lo = grid[best_index == 0 ? 0 : best_index - 1];
    const double hi = grid[std::min(best_index + 1, grid.size() - 1)];
    best_offset = grid[best_index];
    if (hi > lo) {
      const double refined = goldenSection(objective, lo, hi, config.time_offset_tolerance_s);
      if (objective(refined) <= best_error) best_offset = refined;
    }
  }

  const Fit fit = fitAtOffset(estimated, ground_truth, best_offset, config);
  if (!std::isfinite(fit.mean_squared_error)) {
    throw std::invalid_argument("evaluateTrajectory: fewer than " +
                                std::to_string(config.min_pairs) +
                                " poses associated in time (do the trajectories overlap?)");
  }
  TrajectoryEvaluation result;
  result.estimated_poses = estimated.size();
  result.alignment.time_offset_s = best_offset;
  result.alignment.rotation = Eigen::Quaterniond(fit.rotation).normalized();
  result.alignment.translation = fit.translation;
  result.alignment.scale = fit.scale;

  const Association a = associate(estimated, ground_truth, best_offset, config, true);
  if (config.estimate_body_rotation) {
    std::vector<Eigen::Quaterniond> offsets;
    offsets.reserve(a.estimated_index.size());
    for (std::size_t k = 0; k < a.estimated_index.size(); ++k) {
      const Eigen::Quaterniond world =
          result.alignment.rotation * estimated[a.estimated_index[k]].orientation;
      offsets.push_back(world.conjugate() * a.ground_truth_orientations[k]);
    }
    result.alignment.body_rotation = averageQuaternion(offsets);
  }

  double position_sum = 0.0;
  double rotation_sum = 0.0;
  result.errors.reserve(a.estimated_index.size());
  for (std::size_t k = 0; k < a.estimated_index.size(); ++k) {
    const StampedPose aligned = result.alignment.apply(estimated[a.estimated_index[k]]);
    PoseError e;
    e.t_s = estimated[a.estimated_index[k]].t_s;
    e.aligned_position = aligned.position;
    e.ground_truth_position = a.ground_truth_positions.col(static_cast<Eigen::Index>(k));
    e.position_error_m = (e.aligned_position - e.ground_truth_position).norm();
    e.rotation_error_deg =
        rotationAngle(aligned.orientation.conjugate() * a.ground_truth_orientations[k]) * kRadToDeg;
    position_sum += e.position_error_m * e.position_error_m;
    rotation_sum += e.rotation_error_deg * e.rotation_error_deg;
    result.position_max_m = std::max(result.position_max_m, e.position_error_m);
    result.rotation_max_deg = std::max(result.rotation_max_deg, e.rotation_error_deg);
    result.errors.push_back(e);
  }
  const auto n = static_cast<double>(result.errors.size());
  result.position_rmse_m = std::sqrt(position_sum / n);
  result.rotation_rmse_deg = std::sqrt(rotation_sum / n);
  return result;
}

void writeTrajectoryErrorsCsv(const std::string& path, const TrajectoryEvaluation& evaluation) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("cannot create CSV file '" + path + "'");
  bool ok = std::fprintf(file,
                         "t_s,position_error_m,rotation_error_deg,est_x,est_y,est_z,gt_x,gt_y,"
                         "gt_z\n") > 0;
  for (const PoseError& e : evaluation.errors) {
    if (!ok) break;
    ok = std::fprintf(file, "%.9f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", e.t_s,
                      e.position_error_m, e.rotation_error_deg, e.aligned_position.x(),
                      e.aligned_position.y(), e.aligned_position.z(), e.ground_truth_position.x(),
                      e.ground_truth_position.y(), e.ground_truth_position.z()) > 0;
  }
  ok = (std::fclose(file) == 0) && ok;
  if (!ok) throw std::runtime_error("error writing CSV file '" + path + "'");
}

}  // namespace ebslam
