// DASP / ASP against synthetic ground truth, determinism, counts and connectivity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dasp/connectivity.h"
#include "dasp/dasp.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/metrics.h"
#include "dasp_synthetic.h"

namespace dasp {
namespace {

// Fraction of superpixels (with at least `min_pixels` pixels) that have pixels on both sides
// of `mask`, ignoring a `tolerance` share of stray pixels.
double straddlingFraction(const Superpixels& result, const cv::Mat& mask, double tolerance) {
  std::vector<int> inside(result.superpixels.size(), 0), total(result.superpixels.size(), 0);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      const int label = result.labels.at<int>(y, x);
      if (label < 0) continue;
      ++total[static_cast<std::size_t>(label)];
      if (mask.at<std::uint8_t>(y, x)) ++inside[static_cast<std::size_t>(label)];
    }
  }
  int straddling = 0, counted = 0;
  for (std::size_t k = 0; k < total.size(); ++k) {
    if (total[k] == 0) continue;
    ++counted;
    const double share = static_cast<double>(inside[k]) / total[k];
    if (share > tolerance && share < 1.0 - tolerance) ++straddling;
  }
  return counted > 0 ? static_cast<double>(straddling) / counted : 0.0;
}

// Number of labels >= 0 that have more than one 4-connected component.
int disconnectedLabels(const cv::Mat& labels) {
  cv::Mat visited = cv::Mat::zeros(labels.size(), CV_8UC1);
  std::map<int, int> components;
  std::vector<cv::Point> stack;
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const int label = labels.at<int>(y, x);
      if (label < 0 || visited.at<std::uint8_t>(y, x)) continue;
      ++components[label];
      stack.assign(1, cv::Point(x, y));
      visited.at<std::uint8_t>(y, x) = 1;
      while (!stack.empty()) {
        const cv::Point p = stack.back();
        stack.pop_back();
        const cv::Point next[4] = {{p.x - 1, p.y}, {p.x + 1, p.y}, {p.x, p.y - 1}, {p.x, p.y + 1}};
        for (const cv::Point& q : next) {
          if (q.x < 0 || q.y < 0 || q.x >= labels.cols || q.y >= labels.rows) continue;
          if (visited.at<std::uint8_t>(q) || labels.at<int>(q) != label) continue;
          visited.at<std::uint8_t>(q) = 1;
          stack.push_back(q);
        }
      }
    }
  }
  int disconnected = 0;
  for (const auto& entry : components) disconnected += entry.second > 1 ? 1 : 0;
  return disconnected;
}

TEST(DaspFeatures, FrontoParallelPlaneHasCameraFacingNormalsAndPixelArea) {
  const RgbdFrame frame = test::twoPlanes(64, 48, 1.5f, 1.5f, nullptr);
  const PixelFeatures f = computeFeatures(frame);
  ASSERT_EQ(f.valid_count, 64 * 48);
  const std::size_t i = 20 * 64 + 10;
  EXPECT_NEAR(f.z[i], 1.5f, 1e-6f);
  EXPECT_NEAR(f.x[i], 1.5f * (10 - frame.intrinsics.cx) / frame.intrinsics.fx, 1e-6f);  // eq. 3.4
  EXPECT_NEAR(f.y[i], 1.5f * (20 - frame.intrinsics.cy) / frame.intrinsics.fy, 1e-6f);
  EXPECT_NEAR(f.nz[i], -1.0f, 1e-5f);
  EXPECT_NEAR(f.area[i], 1.5f * 1.5f / (200.0f * 200.0f), 1e-9f);
}

TEST(DaspFeatures, SlantedPlaneNormalMatchesGeometry) {
  const float angle = 0.8f;  // about 46 degrees
  const RgbdFrame frame = test::slantedPlane(80, 60, 2.0f, angle);
  const PixelFeatures f = computeFeatures(frame);
  const Eigen::Vector3f expected(std::sin(angle), 0.0f, -std::cos(angle));  // towards camera
  int checked = 0;
  for (int y = 5; y < 55; y += 7) {
    for (int x = 5; x < 75; x += 7) {
      const std::size_t i = static_cast<std::size_t>(y) * 80 + x;
      const Eigen::Vector3f n(f.nx[i], f.ny[i], f.nz[i]);
      EXPECT_GT(n.dot(expected), std::cos(1.0f * 3.14159f / 180.0f)) << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 50);
}

TEST(DaspDensity, CountModeDensityIntegratesToK) {
  const RgbdFrame frame = test::slantedPlane(80, 60, 2.0f, 0.6f);
  const PixelFeatures f = computeFeatures(frame);
  const float radius = radiusForCount(f, 37);
  EXPECT_NEAR(densityIntegral(computeDepthDensity(f, radius)), 37.0, 1e-3);  // eq. 3.17
}

TEST(DaspDensity, DaspRadiusFollowsTheSizeModeAndExponent) {
  const RgbdFrame frame = test::twoPlanes(64, 48, 1.0f, 2.0f, nullptr);
  const PixelFeatures f = computeFeatures(frame);
  DaspConfig config;
  config.superpixel_count = 37;
  config.experimental.depth_exponent = 1.0f;
  EXPECT_FLOAT_EQ(daspRadius(f, config), radiusForCount(f, 37, 1.0f));
  EXPECT_NE(daspRadius(f, config), radiusForCount(f, 37));  // the exponent is passed on
  config.size_mode = SizeMode::kRadius;
  config.radius_m = 0.03f;
  EXPECT_FLOAT_EQ(daspRadius(f, config), 0.03f);
}

TEST(DaspDensity, FartherSurfaceGetsQuadraticallyHigherDensity) {
  const RgbdFrame frame = test::twoPlanes(64, 48, 1.0f, 2.0f, nullptr);
  const PixelFeatures f = computeFeatures(frame);
  const cv::Mat density = computeDepthDensity(f, 0.05f);
  // eq. 3.15: rho ~ D^2 for fronto-parallel surfaces.
  EXPECT_NEAR(density.at<float>(2, 2) / density.at<float>(24, 32), 4.0f, 1e-3f);
}

TEST(DaspDensity, DepthExponentSetsHowDensityGrowsWithDepth) {
  const RgbdFrame frame = test::twoPlanes(64, 48, 1.0f, 2.0f, nullptr);
  const PixelFeatures f = computeFeatures(frame);
  // rho ~ D^a: far (2 m) against near (1 m), fronto-parallel.
  for (const float exponent : {0.0f, 0.5f, 1.0f, 1.5f, 2.0f}) {
    const cv::Mat density = computeDepthDensity(f, 0.05f, exponent);
    EXPECT_NEAR(density.at<float>(2, 2) / density.at<float>(24, 32), std::pow(2.0f, exponent),
                1e-3f)
        << "a = " << exponent;
    const float radius = radiusForCount(f, 37, exponent);
    EXPECT_NEAR(densityIntegral(computeDepthDensity(f, radius, exponent)), 37.0, 1e-3);
    // R is the radius at 1 m; at 2 m it is R 2^((2 - a) / 2).
    EXPECT_FLOAT_EQ(radiusAtDepth(0.05f, 1.0f, exponent), 0.05f);
    EXPECT_NEAR(radiusAtDepth(0.05f, 2.0f, exponent),
                0.05f * std::pow(2.0f, 1.0f - 0.5f * exponent), 1e-6f);
  }
  EXPECT_FLOAT_EQ(radiusAtDepth(0.05f, 3.7f, 2.0f), 0.05f);
  for (const float bad : {-0.5f, 0.7f, 2.5f, std::numeric_limits<float>::quiet_NaN()}) {
    EXPECT_THROW(computeDepthDensity(f, 0.05f, bad), std::invalid_argument) << bad;
    EXPECT_THROW(radiusForCount(f, 10, bad), std::invalid_argument) << bad;
    DaspConfig config;
    config.experimental.depth_exponent = bad;
    EXPECT_THROW(computeDasp(frame, config), std::invalid_argument) << bad;
  }
}

// With depth exponent 1 the far plane's superpixels are larger on the surface (radius x sqrt 2
// at twice the depth) and cover half the pixels of the near plane's, not a quarter (a = 2).
TEST(Dasp, DepthExponentOneGivesFarSurfacesLargerSuperpixels) {
  cv::Mat near_mask;
  const RgbdFrame frame = test::twoPlanes(240, 180, 1.0f, 2.0f, &near_mask);
  for (const float exponent : {2.0f, 1.0f}) {
    DaspConfig config;
    config.superpixel_count = 150;
    config.experimental.depth_exponent = exponent;
    const Superpixels s = computeDasp(frame, config);
    double near_pixels = 0.0, far_pixels = 0.0, near_radius = 0.0, far_radius = 0.0;
    int near_count = 0, far_count = 0;
    for (const Superpixel& sp : s.superpixels) {
      if (sp.pixel_count == 0) continue;
      const bool near = sp.position.z() < 1.5f;
      (near ? near_pixels : far_pixels) += sp.pixel_count;
      (near ? near_radius : far_radius) += sp.radius_m;
      ++(near ? near_count : far_count);
    }
    ASSERT_GT(near_count, 5);
    ASSERT_GT(far_count, 5);
    const double pixel_ratio = (near_pixels / near_count) / (far_pixels / far_count);
    EXPECT_NEAR(pixel_ratio, std::pow(2.0, exponent), 0.2 * std::pow(2.0, exponent))
        << "a = " << exponent;
    EXPECT_NEAR((far_radius / far_count) / (near_radius / near_count),
                std::pow(2.0, 1.0 - 0.5 * exponent), 1e-3)
        << "a = " << exponent;
  }
}

TEST(Dasp, SeparatesSameColourPlanesThatColourOnlyCannot) {
  cv::Mat near_mask;
  const RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.6f, &near_mask);
  DaspConfig config;
  config.superpixel_count = 80;
  const Superpixels dasp = computeDasp(frame, config);
  AspConfig asp;
  asp.superpixel_count = 80;
  const Superpixels rgb = computeAspRgb(frame.color, asp);
  const double dasp_straddling = straddlingFraction(dasp, near_mask, 0.02);
  const double rgb_straddling = straddlingFraction(rgb, near_mask, 0.02);
  EXPECT_EQ(dasp_straddling, 0.0);
  EXPECT_GT(rgb_straddling, 0.15);
}

// A 3 % depth step (1.00 m against 1.03 m, same colour) is a discontinuity for the default
// depth_jump_ratio (0.02): no superpixel spans it. With the former 0.05, connectivity joins
// pixels across it and some superpixels do.
TEST(Dasp, SmallDepthStepIsADiscontinuity) {
  cv::Mat near_mask;
  const RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.03f, &near_mask);
  DaspConfig config;
  config.superpixel_count = 80;
  EXPECT_EQ(straddlingFraction(computeDasp(frame, config), near_mask, 0.0), 0.0);
  config.depth_jump_ratio = 0.05f;
  EXPECT_GT(straddlingFraction(computeDasp(frame, config), near_mask, 0.0), 0.0);
}

TEST(Dasp, SlantedPlaneSuperpixelsHaveEqualSurfaceAreaButDifferentPixelArea) {
  const RgbdFrame frame = test::slantedPlane(240, 180, 2.0f, 0.6f);  // about 34 degrees
  DaspConfig config;
  config.superpixel_count = 120;
  config.iterations = 10;
  const Superpixels result = computeDasp(frame, config);
  const PixelFeatures f = computeFeatures(frame, config);
  std::vector<double> area(result.superpixels.size(), 0.0);
  std::vector<bool> border(result.superpixels.size(), false);
  for (int y = 0; y < 180; ++y) {
    for (int x = 0; x < 240; ++x) {
      const int label = result.labels.at<int>(y, x);
      ASSERT_GE(label, 0);
      area[static_cast<std::size_t>(label)] += f.area[static_cast<std::size_t>(y) * 240 + x];
      if (x == 0 || y == 0 || x == 239 || y == 179) border[static_cast<std::size_t>(label)] = true;
    }
  }
  // Interior superpixels: 3D areas agree within a tolerance; pixel counts follow the depth.
  std::vector<std::pair<float, const Superpixel*>> by_depth;
  std::vector<double> interior_area;
  for (const Superpixel& sp : result.superpixels) {
    if (border[static_cast<std::size_t>(sp.id)]) continue;
    by_depth.push_back({sp.position.z(), &sp});
    interior_area.push_back(area[static_cast<std::size_t>(sp.id)]);
  }
  ASSERT_GT(by_depth.size(), 30u);
  const double mean = std::accumulate(interior_area.begin(), interior_area.end(), 0.0) /
                      static_cast<double>(interior_area.size());
  double variance = 0.0;
  for (double a : interior_area) variance += (a - mean) * (a - mean);
  const double cv_area = std::sqrt(variance / static_cast<double>(interior_area.size())) / mean;
  EXPECT_LT(cv_area, 0.25);
  std::sort(by_depth.begin(), by_depth.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  const std::size_t fifth = by_depth.size() / 5;
  double near_pixels = 0.0, far_pixels = 0.0, near_area = 0.0, far_area = 0.0;
  for (std::size_t i = 0; i < fifth; ++i) {
    const Superpixel* n = by_depth[i].second;
    const Superpixel* r = by_depth[by_depth.size() - 1 - i].second;
    near_pixels += n->pixel_count;
    far_pixels += r->pixel_count;
    near_area += area[static_cast<std::size_t>(n->id)];
    far_area += area[static_cast<std::size_t>(r->id)];
  }
  EXPECT_GT(near_pixels / far_pixels, 2.0);      // pixel areas differ a lot ...
  EXPECT_NEAR(near_area / far_area, 1.0, 0.25);  // ... 3D areas do not
  // Eigenvalue area of eq. 3.22 agrees with the summed pixel area for flat discs.
  for (const auto& entry : by_depth) {
    EXPECT_NEAR(entry.second->area_m2 / area[static_cast<std::size_t>(entry.second->id)], 1.0,
                0.35);
    EXPECT_LT(entry.second->thickness, 0.01f);  // plane: no thickness
    EXPECT_GT(entry.second->normal.dot(Eigen::Vector3f(std::sin(0.6f), 0, -std::cos(0.6f))),
              0.999f);
  }
}

// weight_depth > 0 penalises depth differences more than lateral ones: on a plane whose depth
// grows along x, superpixels stretch along y (lines of equal depth), so the depth compression
// error falls and the count stays.
TEST(Dasp, DepthWeightStretchesSuperpixelsAlongEqualDepth) {
  const RgbdFrame frame = test::slantedPlane(240, 180, 2.0f, 0.9f);  // about 52 degrees
  const cv::Mat mask(180, 240, CV_8UC1, cv::Scalar(255));
  DaspConfig config;
  config.superpixel_count = 150;
  const Superpixels isotropic = computeDasp(frame, config);
  config.experimental.weight_depth = 4.0f;
  const Superpixels weighted = computeDasp(frame, config);
  EXPECT_NEAR(static_cast<double>(weighted.superpixels.size()), 150.0, 3.0);
  // Pixel-weighted ratio of the superpixels' spread along x (the depth gradient) to along y.
  const auto spreadRatio = [](const Superpixels& s) {
    std::vector<double> n(s.superpixels.size(), 0.0), sx(n), sy(n), sxx(n), syy(n);
    for (int y = 0; y < s.labels.rows; ++y) {
      for (int x = 0; x < s.labels.cols; ++x) {
        const int label = s.labels.at<int>(y, x);
        if (label < 0) continue;
        const auto l = static_cast<std::size_t>(label);
        n[l] += 1.0;
        sx[l] += x;
        sy[l] += y;
        sxx[l] += static_cast<double>(x) * x;
        syy[l] += static_cast<double>(y) * y;
      }
    }
    double var_x = 0.0, var_y = 0.0;
    for (std::size_t l = 0; l < n.size(); ++l) {
      var_x += sxx[l] - sx[l] * sx[l] / n[l];
      var_y += syy[l] - sy[l] * sy[l] / n[l];
    }
    return std::sqrt(var_x / var_y);
  };
  const double ratio_isotropic = spreadRatio(isotropic), ratio_weighted = spreadRatio(weighted);
  EXPECT_LT(ratio_weighted, 0.75 * ratio_isotropic);
  const double ce_isotropic =
      metrics::compressionScores(isotropic.labels, mask, frame.depth).compression_error;
  const double ce_weighted =
      metrics::compressionScores(weighted.labels, mask, frame.depth).compression_error;
  EXPECT_LT(ce_weighted, 0.85 * ce_isotropic);
}

TEST(Dasp, SameSeedSameOutputAndThreadsAgree) {
  cv::Mat near_mask;
  const RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.6f, &near_mask);
  cv::Mat color = frame.color.clone();
  cv::randu(color, cv::Scalar::all(0), cv::Scalar::all(255));
  RgbdFrame noisy = frame;
  noisy.color = color;
  DaspConfig config;
  config.superpixel_count = 150;
  config.seed = 7;
  const Superpixels a = computeDasp(noisy, config);
  const Superpixels b = computeDasp(noisy, config);
  EXPECT_EQ(cv::countNonZero(a.labels != b.labels), 0);
  config.threads = 0;
  const Superpixels c = computeDasp(noisy, config);
  EXPECT_EQ(cv::countNonZero(a.labels != c.labels), 0);
  config.threads = 1;
  config.seed = 8;
  const Superpixels d = computeDasp(noisy, config);
  EXPECT_GT(cv::countNonZero(a.labels != d.labels), 0);  // the seed matters
}

TEST(Dasp, DeliversRequestedCountAndConnectedSuperpixels) {
  const RgbdFrame frame = test::slantedPlane(200, 150, 2.0f, 0.9f);
  cv::Mat near_mask;
  const RgbdFrame planes = test::twoPlanes(200, 150, 1.0f, 1.7f, &near_mask);
  for (const RgbdFrame* f : {&frame, &planes}) {
    for (int k : {50, 200, 600}) {
      DaspConfig config;
      config.superpixel_count = k;
      const Superpixels result = computeDasp(*f, config);
      EXPECT_NEAR(static_cast<double>(result.superpixels.size()), k, 0.02 * k) << k;
      EXPECT_EQ(disconnectedLabels(result.labels), 0) << k;
      for (const Superpixel& sp : result.superpixels) EXPECT_GT(sp.pixel_count, 0);
    }
  }
}

TEST(Dasp, InvalidDepthIsMinusOne) {
  RgbdFrame frame = test::twoPlanes(120, 90, 1.0f, 1.6f, nullptr);
  frame.depth(cv::Rect(0, 0, 40, 90)).setTo(0);
  DaspConfig config;
  config.superpixel_count = 60;
  const Superpixels result = computeDasp(frame, config);
  for (int y = 0; y < 90; ++y) {
    for (int x = 0; x < 120; ++x) {
      if (x < 40) {
        ASSERT_EQ(result.labels.at<int>(y, x), -1);
      } else {
        ASSERT_GE(result.labels.at<int>(y, x), 0);
      }
    }
  }
}

TEST(Dasp, RadiusModeGivesExpectedCount) {
  const RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.0f, nullptr);
  // Plane at 1 m, 200 px focal length: 0.8 m x 0.6 m = 0.48 m^2; R = 0.04 m -> 0.48 / (pi R^2).
  DaspConfig config;
  config.size_mode = SizeMode::kRadius;
  config.radius_m = 0.04f;
  const Superpixels result = computeDasp(frame, config);
  const double expected = 0.48 / (3.14159 * 0.04 * 0.04);
  EXPECT_NEAR(static_cast<double>(result.superpixels.size()), expected, 0.2 * expected);
}

TEST(AspRgb, FollowsAUserDensity) {
  const cv::Mat color = test::flatColor(160, 120);
  cv::Mat density(120, 160, CV_32FC1);
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) density.at<float>(y, x) = x < 80 ? 1.0f : 4.0f;
  }
  AspConfig config;
  config.superpixel_count = 100;
  config.density = density;
  const Superpixels result = computeAspRgb(color, config);
  EXPECT_NEAR(static_cast<double>(result.superpixels.size()), 100.0, 2.0);
  int left = 0, right = 0;
  for (const Superpixel& sp : result.superpixels) (sp.u < 79.5f ? left : right)++;
  EXPECT_NEAR(static_cast<double>(right) / left, 4.0, 1.2);
  EXPECT_EQ(disconnectedLabels(result.labels), 0);
}

TEST(AspRgbd, RunsAndDeliversCount) {
  cv::Mat near_mask;
  const RgbdFrame frame = test::twoPlanes(160, 120, 1.0f, 1.6f, &near_mask);
  DaspConfig config;
  config.superpixel_count = 80;
  const Superpixels result = computeAspRgbd(frame, config);
  EXPECT_NEAR(static_cast<double>(result.superpixels.size()), 80.0, 2.0);
  EXPECT_LT(straddlingFraction(result, near_mask, 0.02), 0.05);  // depth term separates too
}

TEST(Connectivity, StrayPiecesJoinTheirLongestBorderNeighbour) {
  // Label 0 left, 1 right, with a stray 2x2 piece of label 0 inside label 1 and an island of
  // label 2 too small to keep.
  cv::Mat labels(8, 8, CV_32SC1, cv::Scalar(0));
  labels(cv::Rect(4, 0, 4, 8)).setTo(1);
  labels(cv::Rect(5, 2, 2, 2)).setTo(0);
  labels.at<int>(6, 1) = 2;
  const int count = enforceConnectivity(labels, cv::Mat(), cv::Mat(), 2.0);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(labels.at<int>(2, 5), labels.at<int>(0, 7));
  EXPECT_EQ(labels.at<int>(6, 1), labels.at<int>(0, 0));
  EXPECT_EQ(disconnectedLabels(labels), 0);
}

TEST(Dasp, RealFrameDeliversCountConnected) {
  const std::filesystem::path folder = std::filesystem::path(DASP_SHARED_DATA_DIR) / "osd/learn";
  if (!std::filesystem::exists(folder / "learn0_rgb.png")) {
    GTEST_SKIP() << "shared data not found at " << folder;
  }
  RgbdFrame frame;
  frame.color = cv::imread((folder / "learn0_rgb.png").string(), cv::IMREAD_COLOR);
  frame.depth = cv::imread((folder / "learn0_depth_mm.png").string(), cv::IMREAD_UNCHANGED);
  frame.intrinsics = {525.0f, 525.0f, 319.5f, 239.5f};
  const Superpixels result = computeDasp(frame);
  EXPECT_NEAR(static_cast<double>(result.superpixels.size()), 1000.0, 20.0);
  EXPECT_EQ(disconnectedLabels(result.labels), 0);
  for (int y = 0; y < frame.depth.rows; ++y) {
    for (int x = 0; x < frame.depth.cols; ++x) {
      if (frame.depth.at<std::uint16_t>(y, x) == 0) {
        ASSERT_EQ(result.labels.at<int>(y, x), -1);
      }
    }
  }
}

}  // namespace
}  // namespace dasp
