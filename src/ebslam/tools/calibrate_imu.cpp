// Calibrates the rotation of an IMU on an event sensor (GyroPrior's sensor_from_imu) from one
// recording: the gyro's rates against the sensor's angular velocity from a pose trajectory of the
// sensor (e.g. EB-SLAM-3D's estimate of the same recording, run without the IMU), fitted by
// Kabsch with the gyro bias (calibrateSensorFromImu, gyro_prior.h). Needs turns about at least
// two axes.
// Inputs: --imu, one reading per line, `t gx gy gz [...]` separated by spaces or commas (t in
// seconds, or in nanoseconds when above 1e12 as `rostopic echo -b bag -p /imu/angular_velocity`
// writes it; rates [rad/s] in the IMU frame; lines starting with '#' or '%' skipped: the run
// files' imu.txt reads as is); --trajectory, TUM (sensor optical frame -> map), on the same
// clock.
//   ebslam_calibrate_imu --imu run/imu.txt --trajectory estimate.txt
// Prints one JSON object: the rotation (quaternion w x y z and roll pitch yaw [rad]), the bias
// [rad/s], the RMS residual [rad/s] and the pairs used. Exit status: 0 success, 1 input error,
// 2 not enough rotation to calibrate.

#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/slam/gyro_prior.h"

namespace {

std::vector<ebslam::GyroSample> readRates(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<ebslam::GyroSample> samples;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#' || line[0] == '%') continue;
    for (char& c : line) {
      if (c == ',') c = ' ';
    }
    std::istringstream fields(line);
    double t = 0.0;
    Eigen::Vector3d w;
    if (!(fields >> t >> w.x() >> w.y() >> w.z()) || !std::isfinite(t) || !w.allFinite()) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": not 't gx gy gz'");
    }
    const double t_s = t > 1e12 ? 1e-9 * t : t;
    const auto t_us = static_cast<std::int64_t>(std::llround(t_s * 1e6));
    if (!samples.empty() && t_us <= samples.back().t_us) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": time not increasing");
    }
    samples.push_back({t_us, w});
  }
  return samples;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"IMU -> event sensor rotation from gyro rates and a pose trajectory"};
  std::string imu_path, trajectory_path;
  ebslam::GyroCalibrationConfig config;
  app.add_option("--imu", imu_path, "gyro rates: t gx gy gz per line")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--trajectory", trajectory_path, "TUM trajectory of the sensor")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--window", config.window_s, "[s] window of one rate pair")->capture_default_str();
  app.add_option("--min-rate", config.min_rate, "[rad/s] slower windows are left out")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<ebslam::GyroSample> samples = readRates(imu_path);
    const ebslam::Trajectory poses = ebslam::readTumTrajectory(trajectory_path);
    const auto calibration = ebslam::calibrateSensorFromImu(samples, poses, config);
    if (!calibration) {
      std::fprintf(stderr,
                   "error: fewer than %zu windows turning faster than %g rad/s about two axes "
                   "(%zu readings, %zu poses)\n",
                   config.min_pairs, config.min_rate, samples.size(), poses.size());
      return 2;
    }
    const Eigen::Quaterniond& q = calibration->sensor_from_imu;
    const Eigen::Vector3d rpy = q.toRotationMatrix().eulerAngles(2, 1, 0).reverse();
    const Eigen::Vector3d& b = calibration->bias;
    std::printf(
        "{\"sensor_from_imu_wxyz\": [%.9f, %.9f, %.9f, %.9f], \"sensor_from_imu_rpy\": [%.9f, "
        "%.9f, %.9f], \"gyro_bias_rad_s\": [%.6f, %.6f, %.6f], \"rms_residual_rad_s\": %.6f, "
        "\"pairs\": %zu}\n",
        q.w(), q.x(), q.y(), q.z(), rpy.x(), rpy.y(), rpy.z(), b.x(), b.y(), b.z(),
        calibration->rms_residual, calibration->pairs);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
