#include "ebslam/events/trajectory_evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace ebslam {
namespace {

// Ground truth: a 3-D wandering path with changing orientation, sampled at 100 Hz. Its
// piecewise-linear/slerp interpolation is the true continuous trajectory.
Trajectory syntheticGroundTruth() {
  Trajectory gt;
  for (int i = 0; i <= 2000; ++i) {
    const double t = 1000.0 + 0.01 * i;
    StampedPose p;
    p.t_s = t;
    p.position = Eigen::Vector3d(2.0 * std::sin(0.3 * (t - 1000.0)), std::cos(0.5 * (t - 1000.0)),
                                 0.3 * std::sin(1.1 * (t - 1000.0)));
    p.orientation = Eigen::AngleAxisd(0.4 * (t - 1000.0), Eigen::Vector3d::UnitZ()) *
                    Eigen::AngleAxisd(0.3 * std::sin(t), Eigen::Vector3d::UnitX());
    gt.push_back(p);
  }
  return gt;
}

struct KnownTransform {
  double offset = 0.137;  // estimate clock + offset = ground-truth clock
  Eigen::Quaterniond rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  Eigen::Vector3d translation = Eigen::Vector3d(0.7, -2.5, 1.3);
  double scale = 1.0;
  Eigen::Quaterniond body = Eigen::Quaterniond::Identity();
};

// The estimate expressed in its own world frame and clock: A(estimate) = ground truth.
Trajectory syntheticEstimate(const Trajectory& gt, const KnownTransform& k) {
  Trajectory estimate;
  for (double t = 1001.0; t < 1018.0; t += 0.0333) {
    const StampedPose truth = interpolatePose(gt, t + k.offset);
    StampedPose e;
    e.t_s = t;
    e.position = k.rotation.conjugate() * (truth.position - k.translation) / k.scale;
    e.orientation = (k.rotation.conjugate() * truth.orientation * k.body.conjugate()).normalized();
    estimate.push_back(e);
  }
  return estimate;
}

TEST(TrajectoryEvaluation, RecoversKnownRigidTransformAndTimeOffsetExactly) {
  const Trajectory gt = syntheticGroundTruth();
  const KnownTransform known;
  const Trajectory estimate = syntheticEstimate(gt, known);
  const TrajectoryEvaluation r = evaluateTrajectory(estimate, gt);
  EXPECT_NEAR(r.alignment.time_offset_s, known.offset, 1e-7);
  EXPECT_NEAR(r.alignment.rotation.angularDistance(known.rotation), 0.0, 1e-8);
  EXPECT_LT((r.alignment.translation - known.translation).norm(), 1e-7);
  EXPECT_DOUBLE_EQ(r.alignment.scale, 1.0);
  EXPECT_LT(r.position_rmse_m, 1e-7);
  EXPECT_LT(r.rotation_rmse_deg, 1e-5);
  EXPECT_EQ(r.errors.size(), estimate.size());
  EXPECT_EQ(r.estimated_poses, estimate.size());

  // The offset search on a subset of the poses finds the same optimum.
  TrajectoryEvaluationConfig subset;
  subset.max_search_poses = 100;
  ASSERT_GT(estimate.size(), 400u);
  const TrajectoryEvaluation s = evaluateTrajectory(estimate, gt, subset);
  EXPECT_NEAR(s.alignment.time_offset_s, known.offset, 1e-7);
  EXPECT_LT(s.position_rmse_m, 1e-7);
  EXPECT_EQ(s.errors.size(), estimate.size());
}

TEST(TrajectoryEvaluation, WithoutOffsetSearchTheErrorIsLarge) {
  const Trajectory gt = syntheticGroundTruth();
  const Trajectory estimate = syntheticEstimate(gt, KnownTransform{});
  TrajectoryEvaluationConfig config;
  config.estimate_time_offset = false;
  const TrajectoryEvaluation r = evaluateTrajectory(estimate, gt, config);
  EXPECT_EQ(r.alignment.time_offset_s, 0.0);
  EXPECT_GT(r.position_rmse_m, 0.01);  // 0.137 s at up to ~0.6 m/s
}

TEST(TrajectoryEvaluation, RecoversScaleAndBodyRotationWhenAsked) {
  const Trajectory gt = syntheticGroundTruth();
  KnownTransform known;
  known.offset = -0.2531;
  known.scale = 2.5;
  known.body = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized()));
  const Trajectory estimate = syntheticEstimate(gt, known);

  const TrajectoryEvaluation rigid = evaluateTrajectory(estimate, gt);
  EXPECT_GT(rigid.position_rmse_m, 0.1);  // wrong scale cannot be fitted rigidly

  TrajectoryEvaluationConfig config;
  config.estimate_scale = true;
  config.estimate_body_rotation = true;
  const TrajectoryEvaluation r = evaluateTrajectory(estimate, gt, config);
  EXPECT_NEAR(r.alignment.time_offset_s, known.offset, 1e-7);
  EXPECT_NEAR(r.alignment.scale, known.scale, 1e-7);
  EXPECT_NEAR(r.alignment.body_rotation.angularDistance(known.body), 0.0, 1e-6);
  EXPECT_LT(r.position_rmse_m, 1e-6);
  EXPECT_LT(r.rotation_rmse_deg, 1e-4);
}

TEST(TrajectoryEvaluation, NearestAssociationIsTheThesisDefinition) {
  const Trajectory gt = syntheticGroundTruth();
  KnownTransform known;
  known.offset = 0.05;  // a multiple of the 10 ms ground-truth period
  Trajectory estimate;
  for (std::size_t i = 100; i < 1900; i += 3) {  // estimate sampled at ground-truth times
    StampedPose e = gt[i];
    e.t_s = gt[i].t_s - known.offset;
    e.position = known.rotation.conjugate() * (gt[i].position - known.translation);
    e.orientation = known.rotation.conjugate() * gt[i].orientation;
    estimate.push_back(e);
  }
  TrajectoryEvaluationConfig config;
  config.association = TimeAssociation::kNearest;
  config.max_association_gap_s = 0.004;
  const TrajectoryEvaluation r = evaluateTrajectory(estimate, gt, config);
  EXPECT_NEAR(r.alignment.time_offset_s, known.offset, 0.005);
  EXPECT_LT(r.position_rmse_m, 1e-9);
  EXPECT_LT(r.rotation_rmse_deg, 1e-5);
  EXPECT_EQ(r.errors.size(), estimate.size());
}

TEST(TrajectoryEvaluation, PerPoseErrorsMatchAKnownPerturbation) {
  const Trajectory gt = syntheticGroundTruth();
  Trajectory estimate;
  for (std::size_t i = 0; i < gt.size(); i += 10) estimate.push_back(gt[i]);
  // Alternating +-1 cm along z: a rigid alignment can remove almost none of it (zero mean,
  // uncorrelated with the path), so the RMSE is just below 1 cm and the rotation nearly zero.
  for (std::size_t i = 0; i < estimate.size(); ++i)
    estimate[i].position.z() += (i % 2 ? 0.01 : -0.01);
  if (estimate.size() % 2 == 1) estimate.pop_back();
  TrajectoryEvaluationConfig config;
  config.estimate_time_offset = false;
  const TrajectoryEvaluation r = evaluateTrajectory(estimate, gt, config);
  EXPECT_LE(r.position_rmse_m, 0.01 + 1e-12);
  EXPECT_GT(r.position_rmse_m, 0.0099);
  EXPECT_LT(r.rotation_rmse_deg, 0.02);
  ASSERT_EQ(r.errors.size(), estimate.size());
  EXPECT_NEAR(r.errors[7].position_error_m, 0.01, 5e-4);
  EXPECT_NEAR(r.errors[7].t_s, estimate[7].t_s, 0.0);
}

TEST(TrajectoryEvaluation, BadInputIsRejectedClearly) {
  const Trajectory gt = syntheticGroundTruth();
  const Trajectory estimate = syntheticEstimate(gt, KnownTransform{});
  EXPECT_THROW(evaluateTrajectory(Trajectory{}, gt), std::invalid_argument);
  EXPECT_THROW(evaluateTrajectory(estimate, Trajectory{}), std::invalid_argument);
  Trajectory with_nan = gt;
  with_nan[5].position.x() = std::numeric_limits<double>::quiet_NaN();
  try {
    evaluateTrajectory(estimate, with_nan);
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ground-truth trajectory: pose 5"), std::string::npos)
        << e.what();
  }
  Trajectory backwards = estimate;
  std::swap(backwards[3], backwards[4]);
  EXPECT_THROW(evaluateTrajectory(backwards, gt), std::invalid_argument);
  // No temporal overlap within the search range.
  Trajectory later = estimate;
  for (auto& p : later) p.t_s += 1000.0;
  EXPECT_THROW(evaluateTrajectory(later, gt), std::invalid_argument);
  TrajectoryEvaluationConfig bad;
  bad.coarse_step_s = 0.0;
  EXPECT_THROW(evaluateTrajectory(estimate, gt, bad), std::invalid_argument);

  // NaN in a ground-truth file: the reader names file and line.
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("ebslam_gt_nan_" + std::to_string(::getpid()) + ".txt"))
                               .string();
  {
    std::ofstream out(path);
    out << "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 0 NaN 0 0 0 0 1\n";
  }
  try {
    readTumTrajectory(path);
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":3: non-finite"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace ebslam
