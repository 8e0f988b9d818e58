// Seed sampling: SPDS point counts match the density integral and follow the density.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dasp/density.h"
#include "dasp/sampling.h"

namespace dasp {
namespace {

cv::Mat rampDensity(int width, int height, double integral) {
  cv::Mat density(height, width, CV_32FC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) density.at<float>(y, x) = 1.0f + 3.0f * x / (width - 1);
  }
  density *= integral / cv::sum(density)[0];
  return density;
}

cv::Mat blobDensity(int width, int height, double integral) {
  cv::Mat density(height, width, CV_32FC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double dx = x - 0.3 * width, dy = y - 0.6 * height;
      density.at<float>(y, x) =
          static_cast<float>(0.05 + std::exp(-(dx * dx + dy * dy) / (0.02 * width * width)));
    }
  }
  density *= integral / cv::sum(density)[0];
  return density;
}

TEST(DensityPyramid, LevelsSumChildrenAndTopIsIntegral) {
  const cv::Mat density = rampDensity(37, 23, 55.0);  // not a power of two
  const DensityPyramid pyramid(density);
  EXPECT_EQ(pyramid.level(pyramid.levels() - 1).total(), 1u);
  EXPECT_NEAR(pyramid.mass(pyramid.levels() - 1, 0, 0), 55.0, 1e-3);
  EXPECT_NEAR(
      pyramid.mass(1, 3, 2),
      pyramid.mass(0, 6, 4) + pyramid.mass(0, 7, 4) + pyramid.mass(0, 6, 5) + pyramid.mass(0, 7, 5),
      1e-9);
  EXPECT_EQ(pyramid.mass(0, 40, 0), 0.0);
}

class SpdsCount : public ::testing::TestWithParam<bool> {};

TEST_P(SpdsCount, PointCountMatchesDensityIntegral) {
  const bool improved = GetParam();
  for (const cv::Mat& density : {rampDensity(256, 256, 500.0), blobDensity(200, 150, 300.0)}) {
    const double integral = densityIntegral(density);
    double mean = 0.0;
    const int runs = 20;
    for (int seed = 0; seed < runs; ++seed) {
      const std::vector<Seed> seeds =
          sampleSpds(density, improved, static_cast<std::uint64_t>(seed));
      EXPECT_NEAR(static_cast<double>(seeds.size()), integral, 5.0 * std::sqrt(integral));
      for (const Seed& s : seeds) {
        ASSERT_GE(s.u, 0.0f);
        ASSERT_LT(s.u, static_cast<float>(density.cols));
        ASSERT_GE(s.v, 0.0f);
        ASSERT_LT(s.v, static_cast<float>(density.rows));
      }
      mean += static_cast<double>(seeds.size()) / runs;
    }
    EXPECT_NEAR(mean, integral, 0.02 * integral);
  }
}

TEST_P(SpdsCount, PointsFollowTheDensity) {
  const cv::Mat density = rampDensity(256, 256, 800.0);
  // Mass of the right half relative to the left half.
  const double left = cv::sum(density(cv::Rect(0, 0, 128, 256)))[0];
  const double right = cv::sum(density(cv::Rect(128, 0, 128, 256)))[0];
  const std::vector<Seed> seeds = sampleSpds(density, GetParam(), 3);
  int left_count = 0, right_count = 0;
  for (const Seed& s : seeds) (s.u < 128.0f ? left_count : right_count)++;
  EXPECT_NEAR(static_cast<double>(right_count) / left_count, right / left, 0.15 * right / left);
}

INSTANTIATE_TEST_SUITE_P(Alg1AndAlg2, SpdsCount, ::testing::Values(false, true));

TEST(SpdsImproved, CountsPerRegionMuchMoreRegularThanWhiteNoise) {
  // SPDS reproduces the low frequencies of the density: the number of points in 16x16 blocks
  // deviates far less from the block's mass than for white noise (Poisson variance = mass).
  const cv::Mat density = rampDensity(256, 256, 800.0);
  const auto block_error = [&density](const std::vector<Seed>& seeds) {
    cv::Mat counts = cv::Mat::zeros(16, 16, CV_64FC1);
    for (const Seed& s : seeds)
      counts.at<double>(static_cast<int>(s.v) / 16, static_cast<int>(s.u) / 16) += 1.0;
    double error = 0.0;
    for (int by = 0; by < 16; ++by) {
      for (int bx = 0; bx < 16; ++bx) {
        const double mass = cv::sum(density(cv::Rect(bx * 16, by * 16, 16, 16)))[0];
        error += (counts.at<double>(by, bx) - mass) * (counts.at<double>(by, bx) - mass);
      }
    }
    return error;
  };
  for (std::uint64_t seed = 0; seed < 3; ++seed) {
    EXPECT_LT(block_error(sampleSpds(density, true, seed)),
              0.3 * block_error(sampleRandom(density, seed)));
  }
}

TEST(RandomAndGridSampling, CountsMatchIntegral) {
  const cv::Mat density = blobDensity(200, 150, 300.0);
  EXPECT_EQ(sampleRandom(density, 5).size(), 300u);
  const std::size_t grid =
      sampleGrid(cv::Mat(150, 200, CV_32FC1, cv::Scalar(300.0 / 30000.0))).size();
  EXPECT_NEAR(static_cast<double>(grid), 300.0, 30.0);
}

TEST(Sampling, SameSeedSamePoints) {
  const cv::Mat density = blobDensity(100, 80, 60.0);
  const std::vector<Seed> a = sampleSpds(density, true, 11);
  const std::vector<Seed> b = sampleSpds(density, true, 11);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].u, b[i].u);
    EXPECT_EQ(a[i].v, b[i].v);
  }
}

}  // namespace
}  // namespace dasp
