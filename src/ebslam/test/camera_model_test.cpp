// Event-camera lenses of any size: the CameraInfo lenses (plumb_bob, equidistant) against
// OpenCV's own implementation, the per-pixel undistortion table, and the sensor presets.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "ebslam/slam/camera_model.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/undistortion_table.h"

namespace ebslam {
namespace {

CameraModel plumbBob346() {
  CameraModel c;
  c.width = 346;
  c.height = 260;
  c.focal_px = 255.0;
  c.focal_y_px = 253.5;
  c.principal_point = Eigen::Vector2d(171.2, 131.9);
  c.distortion_model = DistortionModel::kPlumbBob;
  c.lens_coefficients = {-0.36, 0.14, 0.0012, -0.0008, -0.02};
  return c;
}

CameraModel equidistant640() {
  CameraModel c;
  c.width = 640;
  c.height = 480;
  c.focal_px = 300.0;
  c.focal_y_px = 300.0;
  c.principal_point = Eigen::Vector2d(322.0, 236.5);
  c.distortion_model = DistortionModel::kEquidistant;
  c.lens_coefficients = {-0.02, 0.004, -0.0015, 0.0002, 0.0};
  return c;
}

cv::Matx33d intrinsics(const CameraModel& c) {
  return {c.fx(), 0.0, c.principal_point.x(), 0.0, c.fy(), c.principal_point.y(), 0, 0, 1};
}

std::vector<cv::Point2d> gridPixels(const CameraModel& c, int step) {
  std::vector<cv::Point2d> pixels;
  for (int y = 0; y < c.height; y += step) {
    for (int x = 0; x < c.width; x += step) pixels.emplace_back(x, y);
  }
  pixels.emplace_back(c.width - 1, c.height - 1);
  return pixels;
}

TEST(CameraModel, PlumbBobProjectsAsOpenCv) {
  const CameraModel c = plumbBob346();
  ASSERT_NO_THROW(c.validate());
  std::vector<cv::Point3d> points;
  for (double x = -0.6; x <= 0.6; x += 0.15) {
    for (double y = -0.45; y <= 0.45; y += 0.15) points.emplace_back(x, y, 1.3);
  }
  std::vector<cv::Point2d> expected;
  const std::vector<double> d(c.lens_coefficients.begin(), c.lens_coefficients.end());
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), intrinsics(c), d, expected);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto pixel = c.project(Eigen::Vector3d(points[i].x, points[i].y, points[i].z));
    ASSERT_TRUE(pixel);
    EXPECT_NEAR(pixel->x(), expected[i].x, 1e-9);
    EXPECT_NEAR(pixel->y(), expected[i].y, 1e-9);
  }
}

TEST(CameraModel, PlumbBobUndistortsEverySensorPixelAsOpenCvIterated) {
  const CameraModel c = plumbBob346();
  const std::vector<cv::Point2d> pixels = gridPixels(c, 7);
  std::vector<cv::Point2d> normalised;
  const std::vector<double> d(c.lens_coefficients.begin(), c.lens_coefficients.end());
  cv::undistortPoints(
      pixels, normalised, intrinsics(c), d, cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-14));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const auto ray = c.backprojectRay(Eigen::Vector2d(pixels[i].x, pixels[i].y));
    ASSERT_TRUE(ray) << pixels[i];
    EXPECT_NEAR(ray->x(), normalised[i].x, 1e-6) << pixels[i];
    EXPECT_NEAR(ray->y(), normalised[i].y, 1e-6) << pixels[i];
    // And back: the ray projects onto the pixel.
    const auto back = c.project(*ray);
    EXPECT_NEAR(back->x(), pixels[i].x, 1e-7);
    EXPECT_NEAR(back->y(), pixels[i].y, 1e-7);
  }
}

TEST(CameraModel, EquidistantMatchesOpenCvFisheyeBothWays) {
  const CameraModel c = equidistant640();
  ASSERT_NO_THROW(c.validate());
  const std::vector<cv::Point2d> pixels = gridPixels(c, 13);
  const cv::Vec4d d(c.lens_coefficients[0], c.lens_coefficients[1], c.lens_coefficients[2],
                    c.lens_coefficients[3]);
  std::vector<cv::Point2d> normalised;
  cv::fisheye::undistortPoints(pixels, normalised, intrinsics(c), d);
  std::vector<cv::Point2d> reprojected;
  cv::fisheye::distortPoints(normalised, reprojected, intrinsics(c), d);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const auto ray = c.backprojectRay(Eigen::Vector2d(pixels[i].x, pixels[i].y));
    ASSERT_TRUE(ray) << pixels[i];
    // OpenCV's fisheye inverse stops at its own tolerance: compare through its forward model,
    // which is exact.
    std::vector<cv::Point2d> mine{{ray->x(), ray->y()}}, mine_distorted;
    cv::fisheye::distortPoints(mine, mine_distorted, intrinsics(c), d);
    EXPECT_NEAR(mine_distorted[0].x, pixels[i].x, 1e-6);
    EXPECT_NEAR(mine_distorted[0].y, pixels[i].y, 1e-6);
    EXPECT_NEAR(ray->x(), normalised[i].x, 1e-4);
    EXPECT_NEAR(ray->y(), normalised[i].y, 1e-4);
    const auto back = c.project(*ray);
    EXPECT_NEAR(back->x(), pixels[i].x, 1e-7);
    EXPECT_NEAR(back->y(), pixels[i].y, 1e-7);
  }
}

TEST(CameraModel, ALensThatFoldsInsideTheSensorIsRejected) {
  CameraModel c = plumbBob346();
  c.lens_coefficients = {-2.5, 0.0, 0.0, 0.0, 0.0};  // r (1 - 2.5 r^2) turns back at r = 0.37
  EXPECT_THROW(c.validate(), std::invalid_argument);
  EXPECT_THROW(UndistortionTable{c}, std::invalid_argument);
  c = plumbBob346();
  c.lens_coefficients[1] = std::nan("");
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = plumbBob346();
  c.focal_y_px = -1.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
}

TEST(UndistortionTable, HoldsEveryPixelsRay) {
  for (const CameraModel& c : {plumbBob346(), equidistant640(), CameraModel{}}) {
    const UndistortionTable table(c);
    ASSERT_EQ(table.width(), c.width);
    ASSERT_EQ(table.height(), c.height);
    double max_radius = 0.0;
    for (int y = 0; y < c.height; y += 3) {
      for (int x = 0; x < c.width; x += 3) {
        const Eigen::Vector3d ray = *c.backprojectRay(Eigen::Vector2d(x, y));
        EXPECT_NEAR(table.ray(x, y).x(), ray.x(), 1e-6);
        EXPECT_NEAR(table.ray(x, y).y(), ray.y(), 1e-6);
        max_radius = std::max(max_radius, ray.head<2>().norm());
      }
    }
    EXPECT_GE(table.maxRadius(), max_radius - 1e-6);
  }
}

TEST(CameraModel, PresetsKeepTheLensFieldOfView) {
  const CameraModel thesis;
  const double fov = std::atan2(thesis.width * 0.5, thesis.focal_px);
  for (const auto& [name, w, h] : {std::tuple<const char*, int, int>{"edvs128", 128, 128},
                                   {"davis240", 240, 180},
                                   {"davis346", 346, 260},
                                   {"vga", 640, 480},
                                   {"hd720", 1280, 720}}) {
    const CameraModel c = CameraModel::preset(name);
    EXPECT_EQ(c.width, w) << name;
    EXPECT_EQ(c.height, h) << name;
    EXPECT_NEAR(std::atan2(c.width * 0.5, c.focal_px), fov, 1e-12) << name;
    EXPECT_NEAR(c.principal_point.x(), 0.5 * (w - 1), 1e-12);
    EXPECT_NEAR(c.principal_point.y(), 0.5 * (h - 1), 1e-12);
    EXPECT_NO_THROW(c.validate());
  }
  EXPECT_THROW(CameraModel::preset("kinect"), std::invalid_argument);
  // Pixel-unit distortion scales with the pixels: the sensor corner's ray stays the same.
  CameraModel eq63;
  eq63.kappa1 = -1e-3;
  eq63.kappa2 = 2e-6;
  const CameraModel big = eq63.scaledTo(512, 512);
  const Eigen::Vector3d small_corner = *eq63.backprojectRay(Eigen::Vector2d(-0.5, -0.5));
  const Eigen::Vector3d big_corner = *big.backprojectRay(Eigen::Vector2d(-0.5, -0.5));
  EXPECT_NEAR(small_corner.x(), big_corner.x(), 1e-9);
  EXPECT_NEAR(small_corner.y(), big_corner.y(), 1e-9);
}

TEST(CeilingCamera, AnyLensProjectsItsPixelOffsetsBackOntoThePixels) {
  for (const CameraModel& c : {plumbBob346(), equidistant640()}) {
    const CeilingCamera camera(c, 2.59);
    for (int y = 0; y < c.height; y += 17) {
      for (int x = 0; x < c.width; x += 17) {
        const std::size_t i = static_cast<std::size_t>(y) * c.width + x;
        const Eigen::Vector2d p(camera.offsetX()[i], camera.offsetY()[i]);
        const Eigen::Vector2d pixel = camera.project(p);
        EXPECT_NEAR(pixel.x(), x, 1e-3);
        EXPECT_NEAR(pixel.y(), y, 1e-3);
      }
    }
  }
}

}  // namespace
}  // namespace ebslam
