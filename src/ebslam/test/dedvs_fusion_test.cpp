#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/dedvs_fusion.h"

namespace ebslam {
namespace {

Scene frontalWall(double distance_m) {
  DeadLeavesConfig leaves;
  leaves.size_px = 128;
  TexturedPlane wall;
  wall.pose.translation() = Eigen::Vector3d(-4.0, -4.0, distance_m);
  wall.size_m = Eigen::Vector2d(8.0, 8.0);
  wall.texture = makeDeadLeavesTexture(leaves);
  wall.metres_per_texel = 0.005;
  Scene scene;
  scene.planes.push_back(wall);
  return scene;
}

Trajectory turning(double rate, double duration) {
  Trajectory trajectory;
  for (int i = 0; i <= 10; ++i) {
    StampedPose pose;
    pose.t_s = duration * i / 10.0;
    pose.orientation =
        Eigen::Quaterniond(Eigen::AngleAxisd(rate * pose.t_s, Eigen::Vector3d::UnitY()));
    trajectory.push_back(pose);
  }
  return trajectory;
}

TEST(DepthEventFusion, RecoversTheTrueDepthOfSimulatedEvents) {
  DedvsSimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 0.0;
  Scene scene = frontalWall(2.0);
  DeadLeavesConfig leaves;
  leaves.size_px = 64;
  addBox(scene, Eigen::Vector3d(-0.3, -0.3, 1.0), Eigen::Vector3d(0.1, 0.3, 1.2),
         makeDeadLeavesTexture(leaves), 0.005);
  const DedvsRun run = DedvsSimulator(config).simulate(scene, turning(0.3, 0.1), 0.0, 0.1);
  DepthEventFusion fusion(sensorsOf(config));
  EXPECT_GT(fusion.tableBytes(), 16384u * 8u);
  EXPECT_LT(fusion.tableBytes(), 8u << 20);  // a few MB
  std::size_t next = 0, fused = 0, close = 0, total = 0;
  for (const TrueDepthEvent& e : run.events) {
    while (next < run.depth_frames.size() &&
           run.depth_frames[next].t_s <= e.event.t_us * 1e-6 + 0.017) {
      fusion.addDepthFrame(run.depth_frames[next].depth_mm, run.depth_frames[next].stamp_s);
      ++next;
    }
    ++total;
    const FusedEvent f = fusion.fuse(e.event);
    if (f.status != FusionStatus::kOk) {
      EXPECT_TRUE(std::isnan(f.depth_m));
      continue;
    }
    ++fused;
    EXPECT_NEAR(f.point.z(), f.depth_m, 1e-6);
    close += std::abs(f.depth_m - e.depth_m) < 0.03f * e.depth_m;
  }
  ASSERT_GT(total, 1000u);
  EXPECT_GT(fused, total * 8 / 10);
  EXPECT_GT(close, fused * 9 / 10);
}

TEST(DepthEventFusion, BadInputGetsNoDepthAndAReason) {
  const DedvsSimulatorConfig config;
  DepthEventFusion fusion(sensorsOf(config));
  Event event;
  event.t_us = 1'000'000;
  event.x = 64;
  event.y = 64;
  EXPECT_EQ(fusion.fuse(event).status, FusionStatus::kNoDepthFrame);
  // Wrong size and encoding: rejected, nothing kept.
  EXPECT_THROW(fusion.addDepthFrame(cv::Mat(240, 321, CV_16UC1, cv::Scalar(1000)), 1.0),
               std::invalid_argument);
  EXPECT_THROW(fusion.addDepthFrame(cv::Mat(240, 320, CV_8UC1, cv::Scalar(10)), 1.0),
               std::invalid_argument);
  EXPECT_EQ(fusion.frameCount(), 0u);
  // A frame at 1 s (event clock) of a wall at 1.5 m: the event at 1 s gets about 1.5 m.
  const double stamp = 1.0 + config.depth.clock_offset_s;
  ASSERT_TRUE(fusion.addDepthFrame(cv::Mat(240, 320, CV_16UC1, cv::Scalar(1500)), stamp));
  FusedEvent fused = fusion.fuse(event);
  ASSERT_EQ(fused.status, FusionStatus::kOk);
  // Wall at depth-camera z = 1.5: eDVS z differs by the mount's offset and tilt.
  EXPECT_NEAR(fused.depth_m, 1.5, 0.05);
  EXPECT_FALSE(fusion.addDepthFrame(cv::Mat(240, 320, CV_16UC1, cv::Scalar(1500)), stamp - 0.1));
  // Events older than every frame, or beyond the frames (clock disagreement): no depth.
  event.t_us = 500'000;
  EXPECT_EQ(fusion.fuse(event).status, FusionStatus::kOlderThanFrames);
  event.t_us = 1'200'000;
  EXPECT_EQ(fusion.fuse(event).status, FusionStatus::kNewerThanFrames);
  EXPECT_TRUE(std::isnan(fusion.fuse(event).depth_m));
  // Holes and out-of-range surfaces give no intersection.
  ASSERT_TRUE(fusion.addDepthFrame(cv::Mat(240, 320, CV_16UC1, cv::Scalar(0)), stamp + 0.2));
  EXPECT_EQ(fusion.fuse(event).status, FusionStatus::kNoIntersection);
  event.x = 200;
  EXPECT_EQ(fusion.fuse(event).status, FusionStatus::kOutsideSensor);
  // Float depth in metres with NaN holes is accepted too.
  cv::Mat metres(240, 320, CV_32FC1, cv::Scalar(2.0f));
  metres.at<float>(0, 0) = std::nanf("");
  EXPECT_TRUE(fusion.addDepthFrame(metres, stamp + 0.3));
  DepthFusionConfig bad;
  bad.max_depth_m = 0.1;
  EXPECT_THROW(DepthEventFusion(sensorsOf(config), bad), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam
