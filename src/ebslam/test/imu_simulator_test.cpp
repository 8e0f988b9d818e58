// IMU simulator (imu_simulator.h): noise density and bias random walk within tolerance of their
// configuration, exact noise-free rates, gravity in the accelerometer, seeded reproducibility.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/simulation/imu_simulator.h"

namespace ebslam {
namespace {

Trajectory stillPath(double duration_s) {
  Trajectory path;
  for (int k = 0; k <= 10; ++k) {
    StampedPose p;
    p.t_s = duration_s * k / 10.0;
    path.push_back(p);
  }
  return path;
}

// A turn at a constant rate about a fixed axis (body frame).
Trajectory turningPath(double duration_s, const Eigen::Vector3d& rate_body) {
  Trajectory path;
  for (int k = 0; k <= 1000; ++k) {
    StampedPose p;
    p.t_s = duration_s * k / 1000.0;
    const Eigen::Vector3d v = rate_body * p.t_s;
    p.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(v.norm(), v.normalized()));
    p.position = Eigen::Vector3d(0.1 * p.t_s, 0.0, 0.0);
    path.push_back(p);
  }
  return path;
}

TEST(ImuSimulator, GyroNoiseDensityAndBiasRandomWalk) {
  ImuSimulatorConfig config;
  config.gyro_initial_bias_std = 0.0;
  config.gyro_bias_random_walk = 0.0;
  config.rate_hz = 200.0;
  const std::vector<ImuReading> readings = simulateImu(stillPath(100.0), 0.0, 100.0, config);
  ASSERT_EQ(readings.size(), 20001u);
  // Per-reading std. dev. = density sqrt(rate): 0.0707 rad/s; 60k values: within 3 %.
  double sum_sq = 0.0;
  for (const ImuReading& r : readings) sum_sq += r.gyro.squaredNorm();
  const double sigma = std::sqrt(sum_sq / (3.0 * readings.size()));
  EXPECT_NEAR(sigma / (config.gyro_noise_density * std::sqrt(config.rate_hz)), 1.0, 0.03);
  // Noise density measured as an angle random walk: the integral over 1 s windows has std. dev.
  // density * sqrt(1 s) (independent of the rate).
  double walk_sq = 0.0;
  int windows = 0;
  for (std::size_t k = 1; k + 200 <= readings.size(); k += 200, ++windows) {
    Eigen::Vector3d angle = Eigen::Vector3d::Zero();
    for (std::size_t j = k; j < k + 200; ++j) angle += readings[j].gyro / 200.0;
    walk_sq += angle.squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(walk_sq / (3.0 * windows)) / config.gyro_noise_density, 1.0, 0.15);

  // Bias random walk: increments over 1 s have std. dev. 0.01 rad/s.
  config = {};
  config.gyro_initial_bias_std = 0.0;
  const std::vector<ImuReading> drifting = simulateImu(stillPath(200.0), 0.0, 200.0, config);
  double inc_sq = 0.0;
  int increments = 0;
  for (std::size_t k = 200; k < drifting.size(); k += 200, ++increments) {
    inc_sq += (drifting[k].gyro_bias - drifting[k - 200].gyro_bias).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(inc_sq / (3.0 * increments)) / config.gyro_bias_random_walk, 1.0, 0.12);
  EXPECT_EQ(drifting.front().gyro_bias, Eigen::Vector3d::Zero());
}

TEST(ImuSimulator, NoiseFreeRatesGravityAndMounting) {
  ImuSimulatorConfig config;
  config.gyro_noise_density = config.gyro_bias_random_walk = config.gyro_initial_bias_std = 0.0;
  config.accel_noise_density = config.accel_bias_std = 0.0;
  const Eigen::Vector3d rate_body(0.2, -0.5, 1.0);
  const std::vector<ImuReading> readings =
      simulateImu(turningPath(5.0, rate_body), 0.5, 4.5, config);
  const Eigen::Vector3d rate_imu = config.body_from_imu.conjugate() * rate_body;
  for (const ImuReading& r : readings) {
    ASSERT_LT((r.gyro - rate_imu).norm(), 1e-6) << r.t_s;
    EXPECT_EQ(r.gyro, r.true_rate);
    // Constant velocity: the specific force is gravity's reaction, |f| = 9.81.
    EXPECT_NEAR(r.accel.norm(), 9.81, 1e-3);
  }
  // At rest with the body at identity: f = -g = 9.81 along world z = body z, seen in the IMU
  // frame through the mounting.
  const std::vector<ImuReading> still = simulateImu(stillPath(1.0), 0.0, 1.0, config);
  const Eigen::Vector3d expected = config.body_from_imu.conjugate() * Eigen::Vector3d(0, 0, 9.81);
  EXPECT_LT((still[10].accel - expected).norm(), 1e-9);
  EXPECT_THROW(simulateImu(stillPath(1.0), 0.0, 2.0, config), std::invalid_argument);
  config.rate_hz = 0.0;
  EXPECT_THROW(simulateImu(stillPath(1.0), 0.0, 1.0, config), std::invalid_argument);
}

TEST(ImuSimulator, SeededAndReproducible) {
  ImuSimulatorConfig config;
  const Trajectory path = turningPath(2.0, Eigen::Vector3d(0.0, 1.0, 0.0));
  const auto a = simulateImu(path, 0.0, 2.0, config);
  const auto b = simulateImu(path, 0.0, 2.0, config);
  config.seed = 2;
  const auto c = simulateImu(path, 0.0, 2.0, config);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].gyro, b[i].gyro);
    ASSERT_EQ(a[i].accel, b[i].accel);
    differs = differs || a[i].gyro != c[i].gyro;
  }
  EXPECT_TRUE(differs);
}

TEST(ImuSimulator, DedvsRigImuFrame) {
  // The eDVS sees the rig's rotation conjugated by depth_from_edvs: a rate about the rig's y axis
  // reaches the eDVS through edvsFromImu.
  DedvsSimulatorConfig config;
  const Eigen::Quaterniond edvs_from_imu = edvsFromImu(config);
  const Eigen::Quaterniond depth_from_edvs(config.depth_from_edvs.linear());
  const Eigen::Vector3d rate_imu(0.1, 0.2, 0.3);
  const Eigen::Vector3d rate_rig = config.imu.body_from_imu * rate_imu;
  EXPECT_LT((edvs_from_imu * rate_imu - depth_from_edvs.conjugate() * rate_rig).norm(), 1e-12);
}

TEST(ImuSimulator, RunFilesKeepTheReadings) {
  DedvsSimulatorConfig config;
  DedvsRun run;
  run.imu = simulateImu(turningPath(1.0, Eigen::Vector3d(0.3, 0.0, 0.1)), 0.0, 1.0, config.imu);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("ebslam_imu_run_" + std::to_string(::getpid()));
  writeDedvsRun(dir.string(), run, sensorsOf(config));
  const DedvsRun back = readDedvsRun(dir.string());
  ASSERT_EQ(back.imu.size(), run.imu.size());
  for (std::size_t i = 0; i < run.imu.size(); ++i) {
    EXPECT_NEAR(back.imu[i].t_s, run.imu[i].t_s, 1e-9);
    EXPECT_LT((back.imu[i].gyro - run.imu[i].gyro).norm(), 1e-7);
    EXPECT_LT((back.imu[i].accel - run.imu[i].accel).norm(), 1e-6);
  }
  // A corrupt line is an error naming the file, not a silently shorter run.
  std::ofstream(dir / "imu.txt", std::ios::app) << "0.5 1 2 nan 4 5 6\n";
  EXPECT_THROW(readDedvsRun(dir.string()), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ebslam
