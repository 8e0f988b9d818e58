// rostest of the exploration closed loop through ROS (exploration_loop.test includes
// launch/exploration.launch): ClosedLoopSimulator -> EventSlam2d -> Exploration -> cmd_vel for
// ~duration simulated seconds, measured as the offline tool ebslam_explore measures a run
// (ebslam/simulation/exploration_run.h): the covered fraction of the reachable free area swept by
// the robot's true disc (CoverageRaster, 2 cm cells) and EB-SLAM's position error, aligned RMSE
// (evaluateTrajectory, no time offset, 0.1 s association gap) and raw RMSE, associated by
// header.stamp (estimate = /ebslam/pose in map, ground truth = /ground_truth/pose in map).
// Asserts both within the range of the offline runs (parameters ~min_covered, ~max_rmse) and, with
// ~expect_done 0 or 1, the explorer's latched /exploration/done at the end. With
// ~output set, also writes the figures as one CSV line there (used for docs/results).
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/events/trajectory_evaluation.h>
#include <ebslam/simulation/exploration_run.h>
#include <ebslam/simulation/floor_plan.h>
#include <ebslam/simulation/simulator_scenes.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace {

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

TEST(ExplorationLoop, CoverageAndLocalisationAsOffline) {
  ros::NodeHandle nh, pnh("~");
  std::string plan_path, output;
  double duration_s = 120.0, min_covered = 0.0, max_rmse_m = 1.0, robot_radius_m = 0.15;
  double wall_limit_s = 600.0;
  int expect_done = -1;
  ASSERT_TRUE(pnh.getParam("floor_plan", plan_path));
  pnh.getParam("duration", duration_s);
  pnh.getParam("min_covered", min_covered);
  pnh.getParam("max_rmse", max_rmse_m);
  pnh.getParam("robot_radius", robot_radius_m);
  pnh.getParam("wall_limit", wall_limit_s);
  pnh.getParam("output", output);
  pnh.getParam("expect_done", expect_done);
  const ebslam::FloorPlan plan = ebslam::readFloorPlan(plan_path, robot_radius_m);
  ebslam::CoverageRaster coverage(plan, robot_radius_m, 0.02);
  // ~map_frame of the simulator lies at plan.start: map -> room.
  const double c = std::cos(plan.start.theta), s = std::sin(plan.start.theta);
  const auto toRoom = [&](double x, double y) {
    return Eigen::Vector2d(plan.start.x + c * x - s * y, plan.start.y + s * x + c * y);
  };
  ebslam::Trajectory truth, estimate;
  const auto push = [](ebslam::Trajectory& t, const ebslam::StampedPose& p) {
    if (t.empty() || p.t_s > t.back().t_s) t.push_back(p);
  };
  ros::Subscriber truth_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/ground_truth/pose", 10000, [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        ebslam::StampedPose p;
        p.t_s = m->header.stamp.toSec();
        p.position = {m->pose.position.x, m->pose.position.y, m->pose.position.z};
        const auto& q = m->pose.orientation;
        p.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized();
        push(truth, p);
        coverage.cover(toRoom(p.position.x(), p.position.y()));
      });
  ros::Subscriber estimate_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "/ebslam/pose", 10000, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
        const auto& p = m->pose.pose;
        push(estimate, ebslam::se2ToFloorPose(m->header.stamp.toSec(), p.position.x, p.position.y,
                                              yawOf(p.orientation)));
      });
  int done = -1;  // nothing received yet
  ros::Subscriber done_sub = nh.subscribe<std_msgs::Bool>(
      "/exploration/done", 10, [&](const std_msgs::Bool::ConstPtr& m) { done = m->data ? 1 : 0; });
  const ros::WallTime wall_start = ros::WallTime::now();
  const ros::WallTime wall_end = wall_start + ros::WallDuration(wall_limit_s);
  while (ros::ok() && ros::WallTime::now() < wall_end &&
         (truth.empty() || truth.back().t_s - truth.front().t_s < duration_s)) {
    ros::spinOnce();
    ros::WallDuration(0.002).sleep();
  }
  const double wall_s = (ros::WallTime::now() - wall_start).toSec();
  ASSERT_FALSE(truth.empty());
  const double simulated_s = truth.back().t_s - truth.front().t_s;
  ASSERT_GE(simulated_s, duration_s) << "the loop did not run " << duration_s
                                     << " simulated seconds in " << wall_limit_s << " s wall";
  ASSERT_GT(estimate.size(), 100u);
  // Only the poses of the measured span.
  const double end_t = truth.front().t_s + duration_s;
  while (!estimate.empty() && estimate.back().t_s > end_t) estimate.pop_back();
  ebslam::TrajectoryEvaluationConfig eval;
  eval.estimate_time_offset = false;  // one clock: the simulator's
  eval.max_association_gap_s = 0.1;
  const double rmse_aligned = ebslam::evaluateTrajectory(estimate, truth, eval).position_rmse_m;
  double sum2 = 0.0;
  std::vector<double> errors;
  for (const ebslam::StampedPose& e : estimate) {
    if (e.t_s < truth.front().t_s || e.t_s > truth.back().t_s) continue;
    const ebslam::StampedPose g = ebslam::interpolatePose(truth, e.t_s);
    const double d = (e.position - g.position).head<2>().norm();
    errors.push_back(d);
    sum2 += d * d;
  }
  ASSERT_FALSE(errors.empty());
  const double rmse_raw = std::sqrt(sum2 / static_cast<double>(errors.size()));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  const double median = errors[errors.size() / 2];
  const double covered = coverage.coveredFraction();
  std::printf(
      "exploration loop: %.1f simulated s in %.1f s wall, covered %.4f, RMSE aligned %.2f cm, "
      "raw %.2f cm, median error %.2f cm\n",
      simulated_s, wall_s, covered, 100 * rmse_aligned, 100 * rmse_raw, 100 * median);
  if (!output.empty()) {
    std::ofstream out(output, std::ios::app);
    out << duration_s << ',' << covered << ',' << rmse_aligned << ',' << rmse_raw << ',' << median
        << ',' << wall_s << '\n';
    ebslam::writeTumTrajectory(output + ".gt.tum", truth);
    ebslam::writeTumTrajectory(output + ".est.tum", estimate);
  }
  EXPECT_GE(covered, min_covered);
  EXPECT_LE(rmse_aligned, max_rmse_m);
  if (expect_done >= 0) {
    EXPECT_EQ(done, expect_done) << "latched /exploration/done (-1: none)";
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "exploration_loop_rostest");
  return RUN_ALL_TESTS();
}
