#include <cmath>
#include <filesystem>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/camera_model.h"

namespace ebslam {
namespace {

// A wall facing the rig: the plane z = distance in the world, the rig at the origin looking
// along +z (rig frame = world frame at identity).
Scene wallScene(double distance_m, double contrast, std::uint64_t seed = 3) {
  DeadLeavesConfig leaves;
  leaves.size_px = 256;
  leaves.contrast = contrast;
  leaves.seed = seed;
  TexturedPlane wall;
  wall.pose.translation() = Eigen::Vector3d(-4.0, -4.0, distance_m);
  wall.size_m = Eigen::Vector2d(8.0, 8.0);
  wall.texture = makeDeadLeavesTexture(leaves);
  wall.metres_per_texel = 0.005;
  Scene scene;
  scene.planes.push_back(wall);
  return scene;
}

// Rig turning about its y axis at `rate` rad/s from t = 0 to duration.
Trajectory panning(double rate_rad_s, double duration_s) {
  Trajectory trajectory;
  for (int i = 0; i <= 10; ++i) {
    StampedPose pose;
    pose.t_s = duration_s * i / 10.0;
    pose.orientation =
        Eigen::Quaterniond(Eigen::AngleAxisd(rate_rad_s * pose.t_s, Eigen::Vector3d::UnitY()));
    trajectory.push_back(pose);
  }
  return trajectory;
}

DedvsSimulatorConfig quietConfig() {
  DedvsSimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 0.0;
  return config;
}

TEST(DedvsCamera, Eq81DistortionRoundTripsAndIsBarrel) {
  const CameraModel camera = DedvsSimulatorConfig::defaultEdvsCamera();
  ASSERT_NO_THROW(camera.validate());
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0.3, -0.2, 1.0), Eigen::Vector3d(-0.4, 0.35, 1.0),
        Eigen::Vector3d(0.0, 0.0, 2.0)}) {
    const std::optional<Eigen::Vector2d> pixel = camera.project(p);
    ASSERT_TRUE(pixel);
    const std::optional<Eigen::Vector3d> ray = camera.backprojectRay(*pixel);
    ASSERT_TRUE(ray);
    EXPECT_NEAR((*ray * p.z() - p).norm(), 0.0, 1e-9);
    // Eq. 8.1: e = c + s / L(|s|), s the undistorted offset.
    const Eigen::Vector2d s = camera.focal_px * p.head<2>() / p.z();
    const double l = 1.0 + camera.kappa1 * s.norm() + camera.kappa2 * s.squaredNorm();
    EXPECT_NEAR((*pixel - (camera.principal_point + s / l)).norm(), 0.0, 1e-9);
    EXPECT_LE((*pixel - camera.principal_point).norm(), s.norm() + 1e-12);  // barrel
  }
}

TEST(DedvsScene, DeadLeavesIsSeededTileableAndFollowsContrast) {
  DeadLeavesConfig config;
  config.size_px = 128;
  const cv::Mat a = makeDeadLeavesTexture(config);
  const cv::Mat b = makeDeadLeavesTexture(config);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  config.seed = 2;
  EXPECT_GT(cv::norm(a, makeDeadLeavesTexture(config), cv::NORM_INF), 0.1);
  cv::Scalar mean, sd_high, sd_low;
  cv::meanStdDev(a, mean, sd_high);
  config.contrast = 0.1;
  cv::meanStdDev(makeDeadLeavesTexture(config), mean, sd_low);
  EXPECT_GT(sd_high[0], 3.0 * sd_low[0]);
  EXPECT_NEAR(mean[0], config.mean_intensity, 0.05);
  // Seamless tiling: the jump across the wrap is no larger than inside the texture.
  double wrap = 0.0, inside = 0.0;
  for (int r = 0; r < a.rows; ++r) {
    wrap += std::abs(a.at<float>(r, 0) - a.at<float>(r, a.cols - 1));
    inside += std::abs(a.at<float>(r, a.cols / 2) - a.at<float>(r, a.cols / 2 - 1));
  }
  EXPECT_LT(wrap, 2.0 * inside + 1.0);
  config.contrast = -1.0;
  EXPECT_THROW(makeDeadLeavesTexture(config), std::invalid_argument);
}

TEST(DedvsDepthCamera, NoiseGrowsWithDepthSquaredAndRangeLimitsHold) {
  DedvsSimulatorConfig config = quietConfig();
  const DedvsSimulator simulator(config);
  const Trajectory still = panning(0.0, 0.05);
  for (double distance : {1.0, 2.0, 3.0}) {
    const DedvsRun run = simulator.simulate(wallScene(distance, 0.3), still, 0.0, 0.04);
    ASSERT_GE(run.depth_frames.size(), 1u);
    const cv::Mat& depth = run.depth_frames[0].depth_mm;
    double sum = 0.0, sum2 = 0.0;
    int count = 0;
    for (int r = 0; r < depth.rows; ++r) {
      for (int c = 0; c < depth.cols; ++c) {
        const double z = depth.at<std::uint16_t>(r, c) * 1e-3;
        if (z == 0.0) continue;
        sum += z - distance;
        sum2 += (z - distance) * (z - distance);
        ++count;
      }
    }
    ASSERT_GT(count, depth.total() * 9 / 10) << "holes on a frontal wall at " << distance;
    const double bias = sum / count;
    const double sd = std::sqrt(sum2 / count - bias * bias);
    const double expected = depthNoiseSigma(config.depth, distance);
    EXPECT_NEAR(sd, expected, 0.35 * expected + 0.0006) << distance;
    EXPECT_LT(std::abs(bias), 0.5 * expected + 0.001) << distance;
    EXPECT_NEAR(run.depth_frames[0].stamp_s - run.depth_frames[0].t_s, config.depth.clock_offset_s,
                1e-12);
  }
  // Beyond the range: no depth at all.
  const DedvsRun far = simulator.simulate(wallScene(4.6, 0.3), still, 0.0, 0.02);
  EXPECT_EQ(cv::countNonZero(far.depth_frames[0].depth_mm), 0);
}

TEST(DedvsDepthCamera, ProjectorShadowsAndEdgesLeaveHoles) {
  DedvsSimulatorConfig config = quietConfig();
  config.depth.edge_hole_probability = 0.0;
  Scene scene = wallScene(2.5, 0.3);
  DeadLeavesConfig leaves;
  leaves.size_px = 64;
  addBox(scene, Eigen::Vector3d(-0.2, -0.2, 1.0), Eigen::Vector3d(0.2, 0.2, 1.3),
         makeDeadLeavesTexture(leaves), 0.005);
  // addBox stands boxes on z = min.z (world z up); here z is the viewing axis, which only
  // orients the box differently. The box occludes the wall's centre.
  const DedvsSimulator simulator(config);
  const DedvsRun run = simulator.simulate(scene, panning(0.0, 0.05), 0.0, 0.02);
  const cv::Mat& depth = run.depth_frames[0].depth_mm;
  const cv::Mat& truth = run.depth_frames[0].true_depth_m;
  int shadow = 0;
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      if (truth.at<float>(r, c) > 2.4f && depth.at<std::uint16_t>(r, c) == 0) ++shadow;
    }
  }
  // Wall pixels hidden from the projector beside the box: a band of about
  // f b (1/z_box - 1/z_wall) = 260 * 0.075 * (1/1.3 - 1/2.5) = 7 px wide along the box's side.
  EXPECT_GT(shadow, 100);
  EXPECT_LT(shadow, 4000);
  config.depth.edge_hole_probability = 1.0;
  const DedvsRun with_edges = DedvsSimulator(config).simulate(scene, panning(0.0, 0.05), 0.0, 0.02);
  EXPECT_GT(cv::countNonZero(depth) - cv::countNonZero(with_edges.depth_frames[0].depth_mm), 100);
}

TEST(DedvsSimulator, EventRateRisesWithSpeedAndContrast) {
  const DedvsSimulator simulator(quietConfig());
  auto rate = [&](double speed, double contrast) {
    const DedvsRun run =
        simulator.simulate(wallScene(1.5, contrast), panning(speed, 0.1), 0.0, 0.1);
    return static_cast<double>(run.events.size()) / 0.1;
  };
  const double slow = rate(0.3, 0.4);
  const double fast = rate(0.9, 0.4);
  const double flat = rate(0.3, 0.1);
  EXPECT_GT(slow, 1000.0);
  EXPECT_GT(fast, 2.0 * slow);
  EXPECT_GT(slow, 2.0 * flat);
}

TEST(DedvsSimulator, EventsCarryTheTrueDepthAndAreDeterministic) {
  DedvsSimulatorConfig config;  // with noise events
  const DedvsSimulator simulator(config);
  const Scene scene = wallScene(1.5, 0.4);
  const DedvsRun a = simulator.simulate(scene, panning(0.5, 0.06), 0.0, 0.06);
  const DedvsRun b = simulator.simulate(scene, panning(0.5, 0.06), 0.0, 0.06);
  ASSERT_EQ(a.events.size(), b.events.size());
  ASSERT_GT(a.events.size(), 500u);
  const Eigen::Isometry3d edvs_in_depth = config.depth_from_edvs;
  std::size_t noise = 0;
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    ASSERT_EQ(a.events[i].event, b.events[i].event);
    ASSERT_EQ(a.events[i].depth_m, b.events[i].depth_m);
    if (i > 0) {
      ASSERT_LE(a.events[i - 1].event.t_us, a.events[i].event.t_us);
    }
    noise += a.events[i].is_noise;
    // Ray of the event's pixel in the world at the event time hits the wall z = 1.5.
    const TrueDepthEvent& e = a.events[i];
    const Eigen::Isometry3d rig(
        Eigen::AngleAxisd(0.5 * e.event.t_us * 1e-6, Eigen::Vector3d::UnitY()));
    const Eigen::Isometry3d edvs = rig * edvs_in_depth;
    const Eigen::Vector3d ray = *config.edvs.backprojectRay(Eigen::Vector2d(e.event.x, e.event.y));
    const Eigen::Vector3d point = edvs * (static_cast<double>(e.depth_m) * ray);
    ASSERT_NEAR(point.z(), 1.5, 2e-4) << i;
  }
  EXPECT_EQ(noise, a.noise_events);
  EXPECT_EQ(a.edvs_ground_truth.size(), a.rig_ground_truth.size());
  EXPECT_EQ(a.depth_frames.size(), 2u);  // t = 0 and 1/30 s
}

TEST(DedvsSimulator, RejectsBadInput) {
  DedvsSimulatorConfig config;
  config.depth.min_range_m = 5.0;
  EXPECT_THROW(DedvsSimulator{config}, std::invalid_argument);
  const DedvsSimulator simulator;
  EXPECT_THROW(simulator.simulate(wallScene(1.0, 0.3), panning(0.1, 0.1), 0.0, 0.2),
               std::invalid_argument);
  EXPECT_THROW(simulator.simulate(wallScene(1.0, 0.3), Trajectory(1), 0.0, 0.1),
               std::invalid_argument);
}

TEST(DedvsIo, RunRoundTripsThroughFiles) {
  const DedvsSimulatorConfig config;
  const DedvsRun run =
      DedvsSimulator(config).simulate(wallScene(1.5, 0.4), panning(0.4, 0.04), 0.0, 0.04);
  const std::string directory =
      (std::filesystem::temp_directory_path() / ("dedvs_io_test_" + std::to_string(::getpid())))
          .string();
  writeDedvsRun(directory, run, sensorsOf(config));
  DedvsSensors sensors;
  const DedvsRun back = readDedvsRun(directory, &sensors);
  std::filesystem::remove_all(directory);
  ASSERT_EQ(back.events.size(), run.events.size());
  for (std::size_t i = 0; i < run.events.size(); ++i) {
    ASSERT_EQ(back.events[i].event, run.events[i].event);
    ASSERT_EQ(back.events[i].is_noise, run.events[i].is_noise);
    ASSERT_EQ(back.events[i].at_depth_edge, run.events[i].at_depth_edge);
    ASSERT_TRUE(back.events[i].depth_m == run.events[i].depth_m ||
                (std::isnan(back.events[i].depth_m) && std::isnan(run.events[i].depth_m)));
  }
  ASSERT_EQ(back.depth_frames.size(), run.depth_frames.size());
  EXPECT_EQ(cv::norm(back.depth_frames[0].depth_mm, run.depth_frames[0].depth_mm, cv::NORM_INF),
            0.0);
  EXPECT_NEAR(back.depth_frames[1].stamp_s, run.depth_frames[1].stamp_s, 1e-9);
  EXPECT_NEAR((sensors.depth_from_edvs.matrix() - config.depth_from_edvs.matrix()).norm(), 0.0,
              1e-9);
  EXPECT_DOUBLE_EQ(sensors.edvs.kappa1, config.edvs.kappa1);
  EXPECT_THROW(readDedvsSensors("/nonexistent/sensors.yaml"), std::runtime_error);
}

// The repository's freiburg1_xyz excerpt (4.5 s, hand-held) always, freiburg1_desk too when
// ../shared has it.
TEST(DedvsSimulator, TumHandHeldRunInAFurnishedRoom) {
  std::vector<std::string> paths{std::string(EBSLAM_SAMPLE_SESSION_DIR) +
                                 "/freiburg1_xyz_excerpt.txt"};
  const std::string desk = std::string(EBSLAM_SHARED_DATA_DIR) +
                           "/tum-groundtruth/rgbd_dataset_freiburg1_desk-groundtruth.txt";
  if (std::filesystem::exists(desk)) paths.push_back(desk);
  for (const std::string& path : paths) {
    SCOPED_TRACE(path);
    const Trajectory trajectory = readTumTrajectory(path);
    RoomSceneConfig room;
    room.box_count = 3;
    const Scene scene = makeRoomScene(trajectory, room);
    EXPECT_GE(scene.planes.size(), 6u + 5u + 25u + 15u);
    const double t0 = trajectory.front().t_s + 3.0;
    const DedvsRun run = DedvsSimulator().simulate(scene, trajectory, t0, t0 + 0.1);
    EXPECT_GT(run.events.size(), 1000u);
    EXPECT_GE(run.depth_frames.size(), 3u);  // at t0 + k / 30 s, the last one at the end or not
    EXPECT_LE(run.depth_frames.size(), 4u);
    std::size_t with_depth = 0;
    for (const TrueDepthEvent& e : run.events) with_depth += std::isfinite(e.depth_m);
    EXPECT_EQ(with_depth, run.events.size());  // a closed room: every ray hits a surface
    EXPECT_GT(cv::countNonZero(run.depth_frames[0].depth_mm), 320 * 240 / 2);
  }
}

}  // namespace
}  // namespace ebslam
