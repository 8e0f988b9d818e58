#include "ebslam/calibration/dedvs_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Dense>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// Eq. 8.4 residual: depth-frame point -> eDVS pixel (eq. 8.1-8.2) minus the observed pixel.
// Parameters: edvs_from_depth rotation (angle-axis) and translation [m]; eDVS intrinsics
// (f, cx, cy, kappa1, kappa2).
struct ReprojectionResidual {
  Eigen::Vector3d point;  // depth optical frame [m] (eq. 8.3 of u, D)
  Eigen::Vector2d observed;

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* intrinsics, T* residual) const {
    using std::sqrt;
    const T p[3] = {T(point.x()), T(point.y()), T(point.z())};
    T q[3];
    ceres::AngleAxisRotatePoint(rotation, p, q);
    for (int k = 0; k < 3; ++k) q[k] += translation[k];
    if (!(q[2] > T(1e-6))) return false;
    const T sx = intrinsics[0] * q[0] / q[2];
    const T sy = intrinsics[0] * q[1] / q[2];
    const T r2 = sx * sx + sy * sy;
    const T r = r2 > T(0.0) ? T(sqrt(r2)) : T(0.0);
    const T factor = T(1.0) + intrinsics[3] * r + intrinsics[4] * r2;
    residual[0] = intrinsics[1] + sx / factor - T(observed.x());
    residual[1] = intrinsics[2] + sy / factor - T(observed.y());
    return true;
  }
};

Eigen::Vector3d depthPoint(const PinholeCamera& depth, const Eigen::Vector2d& pixel,
                           double depth_m) {
  return depth_m *
         Eigen::Vector3d((pixel.x() - depth.cx) / depth.fx, (pixel.y() - depth.cy) / depth.fy, 1.0);
}

}  // namespace

void LedExtractionConfig::validate() const {
  require(std::isfinite(led_frequency_hz) && led_frequency_hz > 0.0,
          "LedExtractionConfig: led_frequency_hz must be positive");
  require(window_periods >= 2 && window_periods <= 64,
          "LedExtractionConfig: window_periods must lie in [2, 64]");
  require(min_cycle_fraction > 0.0 && min_cycle_fraction <= 1.0,
          "LedExtractionConfig: min_cycle_fraction must lie in (0, 1]");
  require(min_phase_coherence >= 0.0 && min_phase_coherence <= 1.0,
          "LedExtractionConfig: min_phase_coherence must lie in [0, 1]");
  require(std::isfinite(centroid_radius_px) && centroid_radius_px >= 0.0,
          "LedExtractionConfig: centroid_radius_px must be >= 0");
  require(min_spot_pixels >= 1, "LedExtractionConfig: min_spot_pixels must be >= 1");
  require(std::isfinite(max_motion_px) && max_motion_px >= 0.0,
          "LedExtractionConfig: max_motion_px must be >= 0");
  require(min_weight_fraction >= 0.0 && min_weight_fraction <= 1.0,
          "LedExtractionConfig: min_weight_fraction must lie in [0, 1]");
  require(width > 0 && height > 0 && width <= 4096 && height <= 4096,
          "LedExtractionConfig: width and height must lie in [1, 4096]");
}

std::optional<LedObservation> extractLed(const std::vector<Event>& events, double t_s,
                                         const LedExtractionConfig& config) {
  config.validate();
  require(std::isfinite(t_s), "extractLed: t_s must be finite");
  const double period_us = 1e6 / config.led_frequency_hz;
  const double begin_us = t_s * 1e6 - 0.5 * config.window_periods * period_us;
  const double end_us = begin_us + config.window_periods * period_us;
  const auto first =
      std::lower_bound(events.begin(), events.end(), begin_us,
                       [](const Event& e, double t) { return static_cast<double>(e.t_us) < t; });

  struct Cell {
    std::uint64_t on = 0, off = 0;  // periods with an ON / OFF event (bit per period)
    double re[2] = {0.0, 0.0};      // sum of p_k exp(-2 pi i f t_k), per half window
    double im[2] = {0.0, 0.0};
    int count = 0;
  };
  std::vector<Cell> cells(static_cast<std::size_t>(config.width) * config.height);
  std::vector<std::size_t> touched;
  const double omega = 2.0 * kPi / period_us;
  for (auto it = first; it != events.end() && static_cast<double>(it->t_us) < end_us; ++it) {
    if (it->x >= config.width || it->y >= config.height) continue;
    const std::size_t i = static_cast<std::size_t>(it->y) * config.width + it->x;
    Cell& cell = cells[i];
    if (cell.count == 0) touched.push_back(i);
    const double dt = static_cast<double>(it->t_us) - begin_us;
    const int bin = std::min(config.window_periods - 1, static_cast<int>(dt / period_us));
    const double sign = it->polarity ? 1.0 : -1.0;
    (it->polarity ? cell.on : cell.off) |= std::uint64_t{1} << bin;
    const int h = bin < config.window_periods / 2 ? 0 : 1;
    cell.re[h] += sign * std::cos(omega * dt);
    cell.im[h] -= sign * std::sin(omega * dt);
    ++cell.count;
  }
  // Cycles are counted per half window: a pixel the LED leaves or reaches halfway through the
  // window (the plate starts or stops moving) does not qualify.
  const int half = config.window_periods / 2;
  const std::uint64_t first_half = (std::uint64_t{1} << half) - 1u;
  const int min_cycles_first = static_cast<int>(std::ceil(config.min_cycle_fraction * half - 1e-9));
  const int min_cycles_second = static_cast<int>(
      std::ceil(config.min_cycle_fraction * (config.window_periods - half) - 1e-9));
  auto popcount = [](std::uint64_t bits) {
    int n = 0;
    for (; bits != 0; bits &= bits - 1) ++n;
    return n;
  };
  struct Weight {
    std::size_t pixel;
    double all, first, second;  // coherent event count: whole window, first and second half
  };
  std::vector<Weight> weights;
  double best = 0.0;
  std::size_t best_pixel = 0;
  for (std::size_t i : touched) {
    const Cell& cell = cells[i];
    const std::uint64_t both = cell.on & cell.off;
    if (popcount(both & first_half) < min_cycles_first ||
        popcount(both & ~first_half) < min_cycles_second) {
      continue;
    }
    const double magnitude = std::hypot(cell.re[0] + cell.re[1], cell.im[0] + cell.im[1]);
    if (magnitude < config.min_phase_coherence * cell.count) continue;
    weights.push_back(
        {i, magnitude, std::hypot(cell.re[0], cell.im[0]), std::hypot(cell.re[1], cell.im[1])});
    if (magnitude > best) {
      best = magnitude;
      best_pixel = i;
    }
  }
  if (weights.empty()) return std::nullopt;
  // Weighted centroid of the LED pixels near the strongest one, then again around that
  // centroid (the strongest pixel need not be the spot's centre when the response saturates).
  LedObservation observation;
  Eigen::Vector2d centre(static_cast<double>(best_pixel % config.width),
                         static_cast<double>(best_pixel / config.width));
  Eigen::Vector2d half_sum[2] = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  double half_total[2] = {0.0, 0.0};
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double total = 0.0;
    observation.pixels = 0;
    for (const Weight& w : weights) {
      const Eigen::Vector2d pixel(static_cast<double>(w.pixel % config.width),
                                  static_cast<double>(w.pixel / config.width));
      if ((pixel - centre).norm() > config.centroid_radius_px ||
          w.all < config.min_weight_fraction * best) {
        continue;
      }
      sum += w.all * pixel;
      total += w.all;
      ++observation.pixels;
      if (pass == 1) {
        // A spot cut by the sensor's border has a biased centroid.
        if (pixel.x() == 0.0 || pixel.y() == 0.0 || pixel.x() == config.width - 1 ||
            pixel.y() == config.height - 1) {
          return std::nullopt;
        }
        half_sum[0] += w.first * pixel;
        half_total[0] += w.first;
        half_sum[1] += w.second * pixel;
        half_total[1] += w.second;
      }
    }
    centre = sum / total;
  }
  if (observation.pixels < config.min_spot_pixels) return std::nullopt;
  // The LED must rest during the window: the centroids of its two halves agree.
  if (!(half_total[0] > 0.0 && half_total[1] > 0.0) ||
      (half_sum[0] / half_total[0] - half_sum[1] / half_total[1]).norm() > config.max_motion_px) {
    return std::nullopt;
  }
  observation.t_s = t_s;
  observation.pixel = centre;
  observation.score = best;
  return observation;
}

std::vector<LedCorrespondence> collectLedCorrespondences(
    const std::vector<Event>& events, const std::vector<DepthLedObservation>& depth_observations,
    const LedExtractionConfig& config) {
  config.validate();
  std::vector<LedCorrespondence> result;
  for (const DepthLedObservation& depth : depth_observations) {
    const std::optional<LedObservation> led = extractLed(events, depth.t_s, config);
    if (!led) continue;
    LedCorrespondence c;
    c.depth_pixel = depth.pixel;
    c.depth_m = depth.depth_m;
    c.edvs_pixel = led->pixel;
    result.push_back(c);
  }
  return result;
}

CameraModel DedvsCalibrationConfig::defaultInitialEdvs() {
  CameraModel camera;
  camera.width = 128;
  camera.height = 128;
  camera.focal_px = 160.0;
  camera.principal_point =
      Eigen::Vector2d(63.5, 63.5);  // eq. 8.6's (64, 64), pixel centres at integers
  camera.kappa1 = 0.0;
  camera.kappa2 = 0.0;
  camera.distortion_model = DistortionModel::kDivideEq81;
  return camera;
}

void DedvsCalibrationConfig::validate() const {
  initial_edvs.validate();
  require(initial_edvs.distortion_model == DistortionModel::kDivideEq81,
          "DedvsCalibrationConfig: the initial eDVS camera must use the eq. 8.1 model");
  const Eigen::Matrix3d r = initial_depth_from_edvs.linear();
  require(initial_depth_from_edvs.matrix().allFinite() &&
              (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6,
          "DedvsCalibrationConfig: initial_depth_from_edvs must be a finite rigid transform");
  require(std::isfinite(coarse_loss_scale_px) && coarse_loss_scale_px > 0.0 &&
              std::isfinite(loss_scale_px) && loss_scale_px > 0.0,
          "DedvsCalibrationConfig: loss scales must be positive");
  require(std::isfinite(outlier_sigmas) && outlier_sigmas >= 0.0,
          "DedvsCalibrationConfig: outlier_sigmas must be >= 0");
  require(std::isfinite(inlier_threshold_px) && inlier_threshold_px > 0.0,
          "DedvsCalibrationConfig: inlier_threshold_px must be positive");
  require(max_iterations >= 1, "DedvsCalibrationConfig: max_iterations must be >= 1");
  require(min_correspondences >= 6, "DedvsCalibrationConfig: min_correspondences must be >= 6");
  require(min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0,
          "DedvsCalibrationConfig: min_inlier_fraction must lie in [0, 1]");
  require(std::isfinite(max_rmse_px) && max_rmse_px > 0.0,
          "DedvsCalibrationConfig: max_rmse_px must be positive");
}

const char* toString(CalibrationStatus status) {
  switch (status) {
    case CalibrationStatus::kOk:
      return "ok";
    case CalibrationStatus::kNotConverged:
      return "not converged";
    case CalibrationStatus::kTooFewInliers:
      return "too few inliers";
    case CalibrationStatus::kHighError:
      return "reprojection error too high";
    case CalibrationStatus::kInvalidCamera:
      return "fitted distortion not invertible";
  }
  return "unknown";
}

namespace {

// Eq. 8.4 parameters as Ceres blocks: edvs_from_depth (rotation vector, translation) and the
// eDVS intrinsics (f, cx, cy, kappa1, kappa2).
struct CalibrationParameters {
  double rotation[3];
  double translation[3];
  double intrinsics[5];

  // Initial values (eq. 8.6) from the configuration.
  explicit CalibrationParameters(const DedvsCalibrationConfig& config) {
    const Eigen::Isometry3d initial = config.initial_depth_from_edvs.inverse();
    const Eigen::AngleAxisd initial_rotation(initial.linear());
    const Eigen::Vector3d rotation_vector = initial_rotation.angle() * initial_rotation.axis();
    const CameraModel& edvs = config.initial_edvs;
    const double values[11] = {rotation_vector.x(),
                               rotation_vector.y(),
                               rotation_vector.z(),
                               initial.translation().x(),
                               initial.translation().y(),
                               initial.translation().z(),
                               edvs.focal_px,
                               edvs.principal_point.x(),
                               edvs.principal_point.y(),
                               edvs.kappa1,
                               edvs.kappa2};
    std::copy(values, values + 3, rotation);
    std::copy(values + 3, values + 6, translation);
    std::copy(values + 6, values + 11, intrinsics);
  }

  // Reprojection error [px] of one correspondence (infinite if it does not project).
  double error(const ReprojectionResidual& residual) const {
    double r[2] = {0.0, 0.0};
    return residual(rotation, translation, intrinsics, r) ? std::hypot(r[0], r[1])
                                                          : std::numeric_limits<double>::infinity();
  }
};

// One Levenberg-Marquardt solve over the used correspondences: Huber loss in stage 0, Cauchy
// after it.
ceres::Solver::Summary solveStage(CalibrationParameters& p,
                                  const std::vector<ReprojectionResidual>& residuals,
                                  const std::vector<bool>& used, int stage,
                                  const DedvsCalibrationConfig& config) {
  ceres::Problem problem;
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    if (!used[i]) continue;
    // The problem takes ownership of the cost and loss functions.
    std::unique_ptr<ceres::LossFunction> loss;
    if (stage == 0) {
      loss = std::make_unique<ceres::HuberLoss>(config.coarse_loss_scale_px);
    } else {
      loss = std::make_unique<ceres::CauchyLoss>(config.loss_scale_px);
    }
    auto cost = std::make_unique<ceres::AutoDiffCostFunction<ReprojectionResidual, 2, 3, 3, 5>>(
        std::make_unique<ReprojectionResidual>(residuals[i]).release());
    problem.AddResidualBlock(cost.release(), loss.release(), p.rotation, p.translation,
                             p.intrinsics);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = config.max_iterations;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary;
}

// Trim: marks as used the correspondences within outlier_sigmas robust standard deviations
// (1.4826 x the median residual, capped at inlier_threshold_px) and returns that threshold;
// nullopt (`used` unchanged or partly set, not to be solved on) if too few would remain.
std::optional<double> trimOutliers(const CalibrationParameters& p,
                                   const std::vector<ReprojectionResidual>& residuals,
                                   const DedvsCalibrationConfig& config, std::vector<bool>& used) {
  std::vector<double> errors;
  for (const ReprojectionResidual& residual : residuals) errors.push_back(p.error(residual));
  std::vector<double> sorted = errors;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double sigma = 1.4826 * sorted[sorted.size() / 2];
  const double threshold = std::min(config.inlier_threshold_px, config.outlier_sigmas * sigma);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < errors.size(); ++i) {
    used[i] = errors[i] < threshold;
    kept += used[i] ? 1 : 0;
  }
  if (kept < config.min_correspondences) return std::nullopt;
  return threshold;
}

// The fitted sensors, residuals and RMSEs (inliers: error below inlier_threshold) and status.
void fillResult(const CalibrationParameters& p, const std::vector<ReprojectionResidual>& residuals,
                const DedvsSensors& base, const DedvsCalibrationConfig& config,
                double inlier_threshold, bool converged, DedvsCalibrationResult& result) {
  const Eigen::Vector3d fitted_rotation(p.rotation[0], p.rotation[1], p.rotation[2]);
  Eigen::Isometry3d edvs_from_depth = Eigen::Isometry3d::Identity();
  if (fitted_rotation.norm() > 0.0) {
    edvs_from_depth.linear() =
        Eigen::AngleAxisd(fitted_rotation.norm(), fitted_rotation.normalized()).toRotationMatrix();
  }
  edvs_from_depth.translation() =
      Eigen::Vector3d(p.translation[0], p.translation[1], p.translation[2]);
  result.sensors = base;
  result.sensors.depth_from_edvs = edvs_from_depth.inverse();
  CameraModel& edvs = result.sensors.edvs;
  edvs = config.initial_edvs;
  edvs.width = base.edvs.width;
  edvs.height = base.edvs.height;
  edvs.focal_px = p.intrinsics[0];
  edvs.principal_point = Eigen::Vector2d(p.intrinsics[1], p.intrinsics[2]);
  edvs.kappa1 = p.intrinsics[3];
  edvs.kappa2 = p.intrinsics[4];

  double sum_all = 0.0, sum_inliers = 0.0;
  for (const ReprojectionResidual& residual : residuals) {
    const double error = p.error(residual);
    result.residuals_px.push_back(error);
    sum_all += error * error;
    if (error < inlier_threshold) {
      sum_inliers += error * error;
      ++result.inliers;
    }
  }
  result.rmse_all_px = std::sqrt(sum_all / static_cast<double>(residuals.size()));
  result.rmse_px = result.inliers > 0 ? std::sqrt(sum_inliers / static_cast<double>(result.inliers))
                                      : std::numeric_limits<double>::infinity();

  bool valid_camera = true;
  try {
    edvs.validate();
  } catch (const std::invalid_argument&) {
    valid_camera = false;
  }
  if (!converged) {
    result.status = CalibrationStatus::kNotConverged;
  } else if (!valid_camera) {
    result.status = CalibrationStatus::kInvalidCamera;
  } else if (static_cast<double>(result.inliers) <
             config.min_inlier_fraction * static_cast<double>(residuals.size())) {
    result.status = CalibrationStatus::kTooFewInliers;
  } else if (!(result.rmse_px <= config.max_rmse_px)) {
    result.status = CalibrationStatus::kHighError;
  }
}

// Standard deviations of the parameters at the solution from the covariance of a plain least
// squares problem over the used correspondences, scaled by their residual variance; nullopt when
// the covariance is singular (the poses do not determine every parameter).
std::optional<CalibrationUncertainty> estimateUncertainty(
    CalibrationParameters p, const std::vector<ReprojectionResidual>& residuals,
    const std::vector<bool>& used) {
  constexpr int kParameters = 11;
  ceres::Problem problem;
  double sum_squares = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    if (!used[i]) continue;
    const double error = p.error(residuals[i]);
    if (!std::isfinite(error)) continue;
    sum_squares += error * error;
    ++count;
    auto cost = std::make_unique<ceres::AutoDiffCostFunction<ReprojectionResidual, 2, 3, 3, 5>>(
        std::make_unique<ReprojectionResidual>(residuals[i]).release());
    problem.AddResidualBlock(cost.release(), nullptr, p.rotation, p.translation, p.intrinsics);
  }
  if (2 * count <= kParameters) return std::nullopt;
  // The Jacobian Ceres evaluates at the solution; its columns differ by orders of magnitude
  // (radians, metres, pixels, kappa2 per square pixel), so (J^T J)^-1 is formed on columns scaled
  // to unit norm and scaled back (Ceres' own covariance would call it rank deficient).
  ceres::CRSMatrix crs;
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = {p.rotation, p.translation, p.intrinsics};
  if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &crs)) return std::nullopt;
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) {
      jacobian(row, crs.cols[k]) = crs.values[k];
    }
  }
  const Eigen::VectorXd norms = jacobian.colwise().norm();
  if (!(norms.minCoeff() > 0.0) || !norms.allFinite()) return std::nullopt;
  const Eigen::VectorXd inverse_norms = norms.cwiseInverse();
  const Eigen::MatrixXd scaled = jacobian * inverse_norms.asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinV);
  const Eigen::VectorXd singular = svd.singularValues();
  if (!(singular.minCoeff() > 1e-9 * singular.maxCoeff())) return std::nullopt;
  const Eigen::MatrixXd v = svd.matrixV();
  const Eigen::VectorXd inverse_variances = singular.array().square().inverse().matrix();
  const Eigen::MatrixXd scaled_covariance = v * inverse_variances.asDiagonal() * v.transpose();
  Eigen::Matrix<double, kParameters, kParameters> c =
      inverse_norms.asDiagonal() * scaled_covariance * inverse_norms.asDiagonal();
  // Residuals in pixels, two per correspondence: variance of one residual component.
  c *= sum_squares / static_cast<double>(2 * count - kParameters);
  if (!c.allFinite()) return std::nullopt;
  constexpr double kDeg = 180.0 / kPi;
  CalibrationUncertainty u;
  const Eigen::Matrix3d rotation = c.topLeftCorner<3, 3>();
  for (int k = 0; k < 3; ++k) {
    u.rotation_axes_std_deg[k] = kDeg * std::sqrt(std::max(0.0, rotation(k, k)));
    u.translation_std_mm[k] = 1000.0 * std::sqrt(std::max(0.0, c(3 + k, 3 + k)));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(rotation);
  u.rotation_std_deg = kDeg * std::sqrt(std::max(0.0, eigen.eigenvalues().maxCoeff()));
  u.focal_std_px = std::sqrt(std::max(0.0, c(6, 6)));
  u.principal_point_std_px =
      Eigen::Vector2d(std::sqrt(std::max(0.0, c(7, 7))), std::sqrt(std::max(0.0, c(8, 8))));
  for (int r = 0; r < 3; ++r) {
    for (int q = 7; q < 9; ++q) {
      const double norm = std::sqrt(c(r, r) * c(q, q));
      if (norm > 0.0) {
        u.rotation_principal_point_correlation =
            std::max(u.rotation_principal_point_correlation, std::abs(c(r, q)) / norm);
      }
    }
  }
  return u;
}

}  // namespace

DedvsCalibrationResult calibrateDedvs(const std::vector<LedCorrespondence>& correspondences,
                                      const DedvsSensors& base,
                                      const DedvsCalibrationConfig& config) {
  config.validate();
  base.depth.validate();
  require(correspondences.size() >= config.min_correspondences,
          "calibrateDedvs: " + std::to_string(correspondences.size()) +
              " correspondences, fewer than min_correspondences = " +
              std::to_string(config.min_correspondences));
  for (const LedCorrespondence& c : correspondences) {
    require(c.depth_pixel.allFinite() && c.edvs_pixel.allFinite() && std::isfinite(c.depth_m) &&
                c.depth_m > 0.0,
            "calibrateDedvs: a correspondence is not finite or has depth <= 0");
  }
  CalibrationParameters parameters(config);
  std::vector<ReprojectionResidual> residuals;
  residuals.reserve(correspondences.size());
  for (const LedCorrespondence& c : correspondences) {
    residuals.push_back({depthPoint(base.depth, c.depth_pixel, c.depth_m), c.edvs_pixel});
  }

  // Three stages: coarse (Huber), fine (Cauchy), fine again on the trimmed correspondences.
  DedvsCalibrationResult result;
  bool converged = true;
  std::vector<bool> used(residuals.size(), true);
  double inlier_threshold = config.inlier_threshold_px;
  for (int stage = 0; stage < 3; ++stage) {
    if (stage == 2) {
      if (config.outlier_sigmas <= 0.0) break;
      const std::optional<double> trimmed = trimOutliers(parameters, residuals, config, used);
      if (!trimmed) break;
      inlier_threshold = *trimmed;
    }
    const ceres::Solver::Summary summary = solveStage(parameters, residuals, used, stage, config);
    result.iterations += static_cast<int>(summary.iterations.size());
    if (stage >= 1) converged = summary.termination_type == ceres::CONVERGENCE;
    if (summary.termination_type == ceres::FAILURE) converged = false;
  }
  fillResult(parameters, residuals, base, config, inlier_threshold, converged, result);
  // The uncertainty of the final solve's correspondences (the trimmed ones when trimmed).
  result.uncertainty = estimateUncertainty(parameters, residuals, used);
  return result;
}

std::optional<Eigen::Vector2d> depthToEdvsPixel(const DedvsSensors& sensors,
                                                const Eigen::Vector2d& depth_pixel,
                                                double depth_m) {
  const Eigen::Vector3d point = depthPoint(sensors.depth, depth_pixel, depth_m);
  return sensors.edvs.project(sensors.depth_from_edvs.inverse() * point);
}

LedPoseCoverage ledPoseCoverage(const std::vector<LedCorrespondence>& correspondences, int width,
                                int height, double corner_size_fraction) {
  require(width > 0 && height > 0, "ledPoseCoverage: width and height must be positive");
  require(corner_size_fraction > 0.0 && corner_size_fraction <= 0.5,
          "ledPoseCoverage: corner_size_fraction must lie in (0, 0.5]");
  LedPoseCoverage coverage;
  coverage.poses = correspondences.size();
  const double corner_w = corner_size_fraction * width, corner_h = corner_size_fraction * height;
  for (const LedCorrespondence& c : correspondences) {
    const double x = c.edvs_pixel.x(), y = c.edvs_pixel.y();
    const bool left = x<corner_w - 0.5, right = x> width - 0.5 - corner_w;
    const bool top = y<corner_h - 0.5, bottom = y> height - 0.5 - corner_h;
    if ((left || right) && (top || bottom)) ++coverage.corners[(top ? 0 : 2) + (left ? 0 : 1)];
    if (coverage.min_depth_m == 0.0 || c.depth_m < coverage.min_depth_m) {
      coverage.min_depth_m = c.depth_m;
    }
    coverage.max_depth_m = std::max(coverage.max_depth_m, c.depth_m);
  }
  return coverage;
}

std::string advisePoseDiversity(const DedvsCalibrationResult& result,
                                const LedPoseCoverage& coverage, double max_rotation_std_deg) {
  require(std::isfinite(max_rotation_std_deg) && max_rotation_std_deg > 0.0,
          "advisePoseDiversity: max_rotation_std_deg must be positive");
  const std::array<std::size_t, 4>& k = coverage.corners;
  const std::size_t in_corners = k[0] + k[1] + k[2] + k[3];
  char where[256];
  std::snprintf(where, sizeof(where),
                "%zu of the %zu poses had the LED in a corner of the eDVS image (top-left %zu, "
                "top-right %zu, bottom-left %zu, bottom-right %zu)",
                in_corners, coverage.poses, k[0], k[1], k[2], k[3]);
  if (!result.uncertainty) {
    return std::string("the poses do not determine the calibration (singular covariance): ") +
           where +
           ". Rest the LED at many places over the whole eDVS image, half of them in its four "
           "corners, near and far.";
  }
  const double std_deg = result.uncertainty->rotation_std_deg;
  if (std_deg <= max_rotation_std_deg) return {};
  // The information grows with the poses: this many more poses of the same kind reach the
  // target; poses in the corners count several times as much.
  const double ratio = std_deg / max_rotation_std_deg;
  const auto more = static_cast<std::size_t>(
      std::ceil(static_cast<double>(coverage.poses) * (ratio * ratio - 1.0)));
  char text[768];
  std::snprintf(text, sizeof(text),
                "the rotation is uncertain (standard deviation %.3f deg, above %.3f deg): a small "
                "rotation of the eDVS and a shift of its principal point (std %.2f, %.2f px, "
                "correlation %.2f) move the LED almost alike, and only LED positions in the "
                "corners of the eDVS image tell them apart. %s. Record about %zu more rests "
                "(fewer when they are in the corners): about half of the rests with the LED in "
                "the four corners, as close to them as the whole spot stays in view, near and far.",
                std_deg, max_rotation_std_deg, result.uncertainty->principal_point_std_px.x(),
                result.uncertainty->principal_point_std_px.y(),
                result.uncertainty->rotation_principal_point_correlation, where, more);
  return text;
}

ExtrinsicError extrinsicError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  ExtrinsicError error;
  error.translation_mm = 1000.0 * (estimate.translation() - truth.translation()).norm();
  const Eigen::Matrix3d difference = estimate.linear().transpose() * truth.linear();
  error.rotation_deg = Eigen::AngleAxisd(difference).angle() * 180.0 / kPi;
  return error;
}

}  // namespace ebslam
