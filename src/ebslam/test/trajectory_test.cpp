#include "ebslam/events/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace ebslam {
namespace {

namespace fs = std::filesystem;

std::string tempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("ebslam_traj_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

TEST(Trajectory, TumRoundTrip) {
  Trajectory trajectory;
  for (int i = 0; i < 50; ++i) {
    StampedPose p;
    p.t_s = 1311876799.7716 + 0.01 * i;
    p.position = Eigen::Vector3d(std::sin(0.1 * i), std::cos(0.1 * i), 0.01 * i);
    p.orientation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    trajectory.push_back(p);
  }
  const std::string path = tempPath("roundtrip.txt");
  writeTumTrajectory(path, trajectory);
  const Trajectory read = readTumTrajectory(path);
  ASSERT_EQ(read.size(), trajectory.size());
  for (std::size_t i = 0; i < read.size(); ++i) {
    EXPECT_NEAR(read[i].t_s, trajectory[i].t_s, 1e-6);
    EXPECT_LT((read[i].position - trajectory[i].position).norm(), 1e-8);
    EXPECT_NEAR(std::abs(read[i].orientation.dot(trajectory[i].orientation)), 1.0, 1e-12);
  }
  fs::remove(path);
}

TEST(Pose3, IsometryRoundTripNormalisesTheQuaternion) {
  Pose3 pose;
  pose.position = Eigen::Vector3d(0.5, -1.25, 2.0);
  pose.orientation = Eigen::Quaterniond(2.0, 0.2, -0.4, 0.6);  // not unit: isometry() normalises
  const Eigen::Isometry3d t = pose.isometry();
  EXPECT_NEAR((t.linear() * t.linear().transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0,
              1e-12);
  EXPECT_NEAR((t * Eigen::Vector3d::Zero() - pose.position).norm(), 0.0, 1e-12);
  const Pose3 back = Pose3::fromIsometry(t);
  EXPECT_NEAR((back.position - pose.position).norm(), 0.0, 1e-12);
  EXPECT_NEAR(back.orientation.angularDistance(pose.orientation.normalized()), 0.0, 1e-9);
  EXPECT_NEAR(back.orientation.norm(), 1.0, 1e-12);
}

TEST(Trajectory, MalformedLinesNameFileAndLine) {
  const std::string path = tempPath("bad.txt");
  const std::string good = "# comment\n1.0 0 0 0 0 0 0 1\n";
  const std::vector<std::string> bad_lines = {"2.0 nan 0 0 0 0 0 1\n", "2.0 0 0 0 0 0 0\n",
                                              "2.0 0 0 0 0 0 0 1 9\n", "0.5 0 0 0 0 0 0 1\n",
                                              "2.0 0 0 0 0 0 0 0\n",   "2.0 0 0 0 0 0 0 2\n",
                                              "2.0 inf 0 0 0 0 0 1\n", "two 0 0 0 0 0 0 1\n"};
  for (const std::string& bad : bad_lines) {
    writeText(path, good + bad);
    try {
      readTumTrajectory(path);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":3:"), std::string::npos) << e.what();
    }
  }
  // Repeated timestamps: kept once by default, an error on request.
  writeText(path, good + "1.0 5 5 5 0 0 0 1\n2.0 1 1 1 0 0 0 1\n");
  const Trajectory kept = readTumTrajectory(path);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept[0].position, Eigen::Vector3d::Zero());
  EXPECT_THROW(readTumTrajectory(path, DuplicateTimestampPolicy::kThrow), std::runtime_error);
  EXPECT_THROW(readTumTrajectory(tempPath("missing.txt")), std::runtime_error);
  fs::remove(path);
}

TEST(Trajectory, InterpolationIsLinearAndSlerp) {
  Trajectory trajectory(2);
  trajectory[0].t_s = 10.0;
  trajectory[0].position = Eigen::Vector3d(0, 0, 0);
  trajectory[1].t_s = 12.0;
  trajectory[1].position = Eigen::Vector3d(2, 4, -6);
  trajectory[1].orientation = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  const StampedPose mid = interpolatePose(trajectory, 10.5);
  EXPECT_LT((mid.position - Eigen::Vector3d(0.5, 1.0, -1.5)).norm(), 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.orientation).angle(), 0.25, 1e-12);
  const StampedPose end = interpolatePose(trajectory, 12.0);
  EXPECT_LT((end.position - trajectory[1].position).norm(), 1e-15);
  // Shortest arc: a sign-flipped quaternion is the same rotation.
  trajectory[1].orientation.coeffs() *= -1.0;
  EXPECT_NEAR(Eigen::AngleAxisd(interpolatePose(trajectory, 11.0).orientation).angle(), 0.5, 1e-12);
  EXPECT_THROW(interpolatePose(trajectory, 9.999), std::out_of_range);
  EXPECT_THROW(interpolatePose(trajectory, 12.001), std::out_of_range);
  EXPECT_THROW(interpolatePose(trajectory, std::nan("")), std::out_of_range);
  EXPECT_THROW(interpolatePose(Trajectory{}, 0.0), std::invalid_argument);
}

// The repository's excerpt of freiburg2_pioneer_360 always, the whole file when ../shared has it.
TEST(Trajectory, ReadsRealTumGroundTruth) {
  // 3600 poses in the excerpt, 1 of them repeats the previous timestamp.
  const Trajectory excerpt =
      readTumTrajectory(std::string(EBSLAM_SAMPLE_SESSION_DIR) + "/pioneer_360_excerpt.txt");
  EXPECT_EQ(excerpt.size(), 3599u);
  EXPECT_NO_THROW(validateTrajectory(excerpt));
  const fs::path file = fs::path(EBSLAM_SHARED_DATA_DIR) / "tum-groundtruth" /
                        "rgbd_dataset_freiburg2_pioneer_360-groundtruth.txt";
  if (!fs::is_regular_file(file)) return;  // ../shared absent: the excerpt only
  const Trajectory trajectory = readTumTrajectory(file.string());
  // 21823 poses in the file, 3 of them repeat the previous timestamp.
  EXPECT_EQ(trajectory.size(), 21820u);
  EXPECT_NO_THROW(validateTrajectory(trajectory));
}

// The shipped TUM excerpts and, when ../shared has them, all six TUM ground-truth files read
// cleanly (repeated timestamps dropped) and validate.
TEST(Trajectory, ReadsAllRealTumFiles) {
  for (const auto& [name, poses] :
       {std::pair<const char*, std::size_t>{"pioneer_360", 3599}, {"freiburg1_xyz", 450}}) {
    const std::string file = std::string(EBSLAM_SAMPLE_SESSION_DIR) + "/" + name + "_excerpt.txt";
    Trajectory trajectory;
    EXPECT_NO_THROW(trajectory = readTumTrajectory(file)) << file;
    EXPECT_EQ(trajectory.size(), poses) << file;
    EXPECT_NO_THROW(validateTrajectory(trajectory)) << file;
  }
  const fs::path dir = fs::path(EBSLAM_SHARED_DATA_DIR) / "tum-groundtruth";
  if (!fs::is_directory(dir)) return;  // ../shared absent: the excerpts only
  for (const char* name : {"freiburg1_desk", "freiburg1_room", "freiburg1_xyz", "freiburg2_xyz",
                           "freiburg2_pioneer_360", "freiburg2_pioneer_slam"}) {
    const fs::path file = dir / ("rgbd_dataset_" + std::string(name) + "-groundtruth.txt");
    Trajectory trajectory;
    EXPECT_NO_THROW(trajectory = readTumTrajectory(file.string())) << file;
    EXPECT_GT(trajectory.size(), 2000u) << file;
    EXPECT_NO_THROW(validateTrajectory(trajectory)) << file;
  }
}

}  // namespace
}  // namespace ebslam
