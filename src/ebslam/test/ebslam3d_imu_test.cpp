// EB-SLAM-3D's gyro rotation prior (Ebslam3dImuConfig): a fast turn that the filter loses
// without the IMU and follows with it; samples ignored when disabled; deterministic per seed.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ebslam/simulation/imu_simulator.h"
#include "ebslam/simulation/synthetic_depth_events.h"
#include "ebslam/slam/ebslam3d.h"

namespace ebslam {
namespace {

// At rest for 1 s (the map forms), a whip turn of `angle` rad about the optical y axis (a pan)
// and x (a tilt, a third of it) in `turn_s` with a smooth speed profile, at rest again for 1 s.
Trajectory whipPath(double angle, double turn_s) {
  Trajectory path;
  const double total = 2.0 + turn_s;
  for (int k = 0; k <= 2000; ++k) {
    StampedPose p;
    p.t_s = total * k / 2000.0;
    const double s = std::min(1.0, std::max(0.0, (p.t_s - 1.0) / turn_s));
    const double u = s - std::sin(2.0 * M_PI * s) / (2.0 * M_PI);  // 0 -> 1, zero speed at ends
    p.position = Eigen::Vector3d(0.05 * u, 0.0, 0.0);
    p.orientation = Eigen::AngleAxisd(angle * u, Eigen::Vector3d::UnitY()) *
                    Eigen::AngleAxisd(angle / 3.0 * u, Eigen::Vector3d::UnitX());
    path.push_back(p);
  }
  return path;
}

struct Outcome {
  double final_rotation_error_deg = 0.0;
  double final_position_error_m = 0.0;
  std::uint64_t predicted = 0;
};

// Runs the filter over the path's events in 10 ms chunks, gyro readings (if any) up to one past
// each chunk's end given first (or all of them at the start).
Outcome run(const Trajectory& truth, const PointEventVector& events,
            const std::vector<ImuReading>* imu, Ebslam3dConfig config, bool imu_first = false) {
  EventSlam3d slam(config);
  if (imu && imu_first) {
    for (const ImuReading& r : *imu) slam.addGyro(std::llround(r.t_s * 1e6), r.gyro);
  }
  std::size_t next = 0, i = 0;
  while (i < events.size()) {
    std::size_t j = i;
    while (j < events.size() && events[j].t_us < events[i].t_us + 10000) ++j;
    if (imu) {
      while (next < imu->size()) {
        const auto t_us = static_cast<std::int64_t>(std::llround((*imu)[next].t_s * 1e6));
        slam.addGyro(t_us, (*imu)[next].gyro);
        ++next;
        if (t_us >= events[j - 1].t_us) break;
      }
    }
    slam.process(events.data() + i, j - i);
    i = j;
  }
  const StampedPose end = truth.back();
  Outcome o;
  o.final_rotation_error_deg =
      slam.estimate().orientation.angularDistance(end.orientation) * 180.0 / M_PI;
  o.final_position_error_m = (slam.estimate().position - end.position).norm();
  o.predicted = slam.gyroPredictedBatches();
  return o;
}

class WhipTurn : public ::testing::Test {
 protected:
  void SetUp() override {
    truth_ = whipPath(1.6, 0.25);  // 92 deg in 0.25 s: mean 6.4 rad/s, peak 12.8 rad/s
    SyntheticRoomConfig room;
    room.margin_m = 1.0;
    room.edges_per_square_m = 6;
    const auto scene = makeSyntheticRoom(truth_, room);
    events_ = simulateDepthEvents(scene, SyntheticDepthSensor{}, truth_, truth_.front().t_s,
                                  truth_.back().t_s);
    ImuSimulatorConfig imu;  // consumer MEMS defaults, IMU mounted with REP 103 body axes
    imu.seed = 3;
    imu_ = simulateImu(truth_, truth_.front().t_s, truth_.back().t_s, imu);
    config_ = Ebslam3dConfig::defaults();
    config_.imu.gyro.sensor_from_imu = imu.body_from_imu;
  }
  Trajectory truth_;
  PointEventVector events_;
  std::vector<ImuReading> imu_;
  Ebslam3dConfig config_;
};

TEST_F(WhipTurn, FollowedWithTheGyroLostWithout) {
  ASSERT_GT(events_.size(), 20000u);
  const Outcome without = run(truth_, events_, nullptr, config_);
  const Outcome with = run(truth_, events_, &imu_, config_);
  std::printf("without IMU: %.2f deg, %.3f m; with: %.2f deg, %.3f m (%llu batches predicted)\n",
              without.final_rotation_error_deg, without.final_position_error_m,
              with.final_rotation_error_deg, with.final_position_error_m,
              static_cast<unsigned long long>(with.predicted));
  EXPECT_GT(without.final_rotation_error_deg, 20.0);
  EXPECT_LT(with.final_rotation_error_deg, 3.0);
  EXPECT_LT(with.final_position_error_m, 0.08);  // measured 4.1 cm
  EXPECT_GT(with.predicted, 1000u);
}

TEST_F(WhipTurn, DisabledIgnoresSamplesAndSeedsReproduce) {
  const PointEventVector head(events_.begin(), events_.begin() + 30000);
  Ebslam3dConfig disabled = config_;
  disabled.imu.enabled = false;
  const Outcome plain = run(truth_, head, nullptr, config_);
  const Outcome ignored = run(truth_, head, &imu_, disabled);
  EXPECT_EQ(plain.final_rotation_error_deg, ignored.final_rotation_error_deg);
  EXPECT_EQ(plain.final_position_error_m, ignored.final_position_error_m);
  EXPECT_EQ(ignored.predicted, 0u);
  const Outcome a = run(truth_, head, &imu_, config_);
  const Outcome b = run(truth_, head, &imu_, config_);
  EXPECT_EQ(a.final_rotation_error_deg, b.final_rotation_error_deg);
  EXPECT_EQ(a.final_position_error_m, b.final_position_error_m);
  // How far ahead of the events the samples arrive does not matter once they cover them (what
  // a ROS node holding events for the IMU relies on).
  const Outcome ahead = run(truth_, head, &imu_, config_, true);
  EXPECT_EQ(a.final_rotation_error_deg, ahead.final_rotation_error_deg);
  EXPECT_EQ(a.final_position_error_m, ahead.final_position_error_m);
  EXPECT_GT(a.predicted, 0u);
  Ebslam3dConfig bad = config_;
  bad.imu.bias_window_s = 0.0;
  EXPECT_THROW(EventSlam3d{bad}, std::invalid_argument);
  bad = config_;
  bad.imu.gyro.max_sample_gap_s = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam
