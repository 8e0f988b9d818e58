// Metrics against synthetic label images with hand-computed answers.
#include "dasp/metrics.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace dasp {
namespace metrics {
namespace {

// Label image whose label is 0 left of column `split` and 1 from it on.
cv::Mat splitAt(int rows, int cols, int split, int left = 0, int right = 1) {
  cv::Mat labels(rows, cols, CV_32SC1, cv::Scalar(left));
  labels.colRange(split, cols).setTo(right);
  return labels;
}

TEST(MetricsBoundary, IdenticalPartitionsScorePerfect) {
  const cv::Mat gt = splitAt(10, 20, 10);
  const BoundaryScores s = boundaryScores(gt, gt, cv::Mat(), 0);
  EXPECT_DOUBLE_EQ(s.recall, 1.0);
  EXPECT_DOUBLE_EQ(s.precision, 1.0);
  EXPECT_DOUBLE_EQ(s.f1, 1.0);
  // Both sides of the edge: columns 9 and 10, 10 rows.
  EXPECT_EQ(s.reference_boundary_pixels, 20u);
}

TEST(MetricsBoundary, ToleranceIsChebyshevPixels) {
  const cv::Mat gt = splitAt(10, 20, 10);      // boundary columns 9, 10
  const cv::Mat labels = splitAt(10, 20, 13);  // boundary columns 12, 13
  // Column 10 is 2 px from column 12, column 9 is 3 px away.
  EXPECT_DOUBLE_EQ(boundaryScores(labels, gt, cv::Mat(), 1).recall, 0.0);
  EXPECT_DOUBLE_EQ(boundaryScores(labels, gt, cv::Mat(), 2).recall, 0.5);
  EXPECT_DOUBLE_EQ(boundaryScores(labels, gt, cv::Mat(), 3).recall, 1.0);
  EXPECT_DOUBLE_EQ(boundaryScores(labels, gt, cv::Mat(), 2).precision, 0.5);
}

TEST(MetricsBoundary, ExtraBoundariesLowerPrecisionNotRecall) {
  const cv::Mat gt = splitAt(10, 20, 10);
  cv::Mat labels = gt.clone();
  labels.colRange(15, 20).setTo(2);  // extra edge at columns 14/15, far from the reference edge
  const BoundaryScores s = boundaryScores(labels, gt, cv::Mat(), 2);
  EXPECT_DOUBLE_EQ(s.recall, 1.0);
  EXPECT_DOUBLE_EQ(s.precision, 0.5);
  EXPECT_NEAR(s.f1, 2.0 * 0.5 / 1.5, 1e-12);
}

TEST(MetricsBoundary, NoPartitionBoundaryRecallsNothing) {
  const cv::Mat gt = splitAt(10, 20, 10);
  const cv::Mat labels(10, 20, CV_32SC1, cv::Scalar(7));
  const BoundaryScores s = boundaryScores(labels, gt, cv::Mat(), 2);
  EXPECT_DOUBLE_EQ(s.recall, 0.0);
  EXPECT_EQ(s.partition_boundary_pixels, 0u);
  EXPECT_DOUBLE_EQ(s.f1, 0.0);
}

TEST(MetricsBoundary, MaskEdgeIsNoBoundary) {
  const cv::Mat gt = splitAt(10, 20, 10);
  cv::Mat mask(10, 20, CV_8UC1, cv::Scalar(255));
  mask.colRange(8, 12).setTo(0);  // the reference edge lies in the invalid band
  const BoundaryScores s = boundaryScores(gt, gt, mask, 2);
  EXPECT_EQ(s.reference_boundary_pixels, 0u);
  EXPECT_DOUBLE_EQ(s.recall, 1.0);
  const cv::Mat map = boundaryMap(gt, mask);
  EXPECT_EQ(cv::countNonZero(map), 0);
}

TEST(MetricsBoundary, AcceptsSixteenBitGroundTruth) {
  cv::Mat gt16;
  splitAt(10, 20, 10).convertTo(gt16, CV_16U);
  EXPECT_DOUBLE_EQ(boundaryScores(splitAt(10, 20, 10), gt16, cv::Mat()).recall, 1.0);
}

// 10x10 image, reference: columns 0-4 vs 5-9. Superpixels: columns 0-6 (70 px) vs 7-9 (30 px).
struct Straddle : ::testing::Test {
  cv::Mat gt = splitAt(10, 10, 5);
  cv::Mat labels = splitAt(10, 10, 7, 3, 8);
};

TEST_F(Straddle, NeubertProtzelUndersegmentation) {
  // Left: min(50, 20) = 20; right: min(20, 50) = 20 and min(30, 0) = 0.
  EXPECT_NEAR(undersegmentationErrorNp(labels, gt, cv::Mat()), 0.4, 1e-12);
}

TEST_F(Straddle, ThesisUndersegmentationWithGamma) {
  // gamma 0.05: left counts 70, right counts 70 + 30 -> 170 / 100 - 1.
  EXPECT_NEAR(undersegmentationErrorThesis(labels, gt, cv::Mat(), 0.05), 0.7, 1e-12);
  // The 70 px superpixel covers the right half only to 20/70 = 0.286 < 0.3: 70 + 30 -> 0.
  EXPECT_NEAR(undersegmentationErrorThesis(labels, gt, cv::Mat(), 0.3), 0.0, 1e-12);
}

TEST_F(Straddle, AchievableSegmentationAccuracy) {
  EXPECT_NEAR(achievableSegmentationAccuracy(labels, gt, cv::Mat()), 0.8, 1e-12);
}

TEST_F(Straddle, MaskRemovesTheStraddlingPart) {
  cv::Mat mask(10, 10, CV_8UC1, cv::Scalar(255));
  mask.colRange(5, 7).setTo(0);
  EXPECT_DOUBLE_EQ(undersegmentationErrorNp(labels, gt, mask), 0.0);
  EXPECT_DOUBLE_EQ(undersegmentationErrorThesis(labels, gt, mask), 0.0);
  EXPECT_DOUBLE_EQ(achievableSegmentationAccuracy(labels, gt, mask), 1.0);
}

TEST_F(Straddle, UnlabelledPixelsFormOneSegment) {
  // Leaving the straddling columns unlabelled does not help: they count as one segment.
  cv::Mat partial = labels.clone();
  partial.colRange(4, 7).setTo(-1);
  // Unlabelled columns 4-6 (10 px left, 20 px right): left min(10, 20), right min(20, 10) -> 0.2.
  EXPECT_NEAR(undersegmentationErrorNp(partial, gt, cv::Mat()), 0.2, 1e-12);
  EXPECT_NEAR(achievableSegmentationAccuracy(partial, gt, cv::Mat()), 0.9, 1e-12);
}

TEST_F(Straddle, PerfectPartitionHasNoError) {
  EXPECT_DOUBLE_EQ(undersegmentationErrorNp(gt, gt, cv::Mat()), 0.0);
  EXPECT_DOUBLE_EQ(undersegmentationErrorThesis(gt, gt, cv::Mat()), 0.0);
  EXPECT_DOUBLE_EQ(achievableSegmentationAccuracy(gt, gt, cv::Mat()), 1.0);
}

TEST(MetricsConnectivity, SplitSegmentIsCounted) {
  cv::Mat labels(10, 10, CV_32SC1, cv::Scalar(1));
  labels(cv::Rect(0, 0, 3, 2)).setTo(0);  // 6 px
  labels(cv::Rect(6, 8, 2, 2)).setTo(0);  // 4 px, not touching the first part
  const ConnectivityScores s = connectivity(labels, cv::Mat());
  EXPECT_EQ(s.segments, 2u);
  EXPECT_EQ(s.disconnected_segments, 1u);
  EXPECT_NEAR(s.quotient, 4.0 / 100.0, 1e-12);  // eq. A.5: |S| (1 - 6/10) / N
}

TEST(MetricsConnectivity, DiagonalContactIsNotConnected) {
  cv::Mat labels(4, 4, CV_32SC1, cv::Scalar(1));
  labels.at<int>(0, 0) = 0;
  labels.at<int>(1, 1) = 0;
  const ConnectivityScores s = connectivity(labels, cv::Mat());
  EXPECT_EQ(s.disconnected_segments, 1u);
  EXPECT_NEAR(s.quotient, 1.0 / 16.0, 1e-12);
}

TEST(MetricsConnectivity, MaskHolesAndUnlabelledPixels) {
  cv::Mat labels = splitAt(6, 6, 3);
  labels.at<int>(0, 5) = -1;  // unlabelled pixels are no segment
  EXPECT_EQ(countSegments(labels, cv::Mat()), 2u);
  EXPECT_EQ(connectivity(labels, cv::Mat()).disconnected_segments, 0u);
  cv::Mat mask(6, 6, CV_8UC1, cv::Scalar(255));
  mask.row(3).setTo(0);  // cuts both segments in two inside the mask
  EXPECT_EQ(connectivity(labels, mask).disconnected_segments, 2u);
}

TEST(MetricsIsoperimetric, SquareAndRectangles) {
  const cv::Mat one(10, 10, CV_32SC1, cv::Scalar(0));
  // 100 px with 36 boundary pixels.
  EXPECT_NEAR(isoperimetricQuotient(one, cv::Mat()), 4.0 * M_PI * 100.0 / (36.0 * 36.0), 1e-12);
  // Two 10x5 halves: 50 px, 26 boundary pixels each.
  EXPECT_NEAR(isoperimetricQuotient(splitAt(10, 10, 5), cv::Mat()),
              4.0 * M_PI * 50.0 / (26.0 * 26.0), 1e-12);
}

TEST(MetricsIsoperimetric, DiscIsMoreCompactThanStrip) {
  cv::Mat disc(61, 61, CV_32SC1, cv::Scalar(0));
  cv::Mat mask(61, 61, CV_8UC1, cv::Scalar(0));
  cv::circle(mask, cv::Point(30, 30), 25, cv::Scalar(255), cv::FILLED);
  cv::Mat strip(61, 61, CV_32SC1, cv::Scalar(0));
  cv::Mat strip_mask(61, 61, CV_8UC1, cv::Scalar(0));
  strip_mask(cv::Rect(0, 28, 61, 4)).setTo(255);
  const double disc_ipq = isoperimetricQuotient(disc, mask);
  EXPECT_GT(disc_ipq, 0.9);
  EXPECT_LT(isoperimetricQuotient(strip, strip_mask), 0.5 * disc_ipq);
}

TEST(MetricsIsoperimetric, ThreeDFrontoParallelEqualsTwoD) {
  const cv::Mat labels = splitAt(12, 16, 7);
  const cv::Mat depth(12, 16, CV_32FC1, cv::Scalar(1.5f));
  const cv::Mat normals(12, 16, CV_32FC3, cv::Scalar(0.0f, 0.0f, -1.0f));
  EXPECT_NEAR(isoperimetricQuotient3d(labels, cv::Mat(), depth, normals, 525.0),
              isoperimetricQuotient(labels, cv::Mat()), 1e-9);
}

TEST(MetricsIsoperimetric, ThreeDSlantStretchesArea) {
  // n_z = 0.5 doubles area and perimeter per pixel: IPQ3D = 4 pi 2A / (2P)^2 = IPQ / 2.
  const cv::Mat labels(10, 10, CV_32SC1, cv::Scalar(0));
  const cv::Mat depth(10, 10, CV_32FC1, cv::Scalar(2.0f));
  const float s = std::sqrt(0.75f);
  const cv::Mat normals(10, 10, CV_32FC3, cv::Scalar(s, 0.0f, 0.5f));
  EXPECT_NEAR(isoperimetricQuotient3d(labels, cv::Mat(), depth, normals, 500.0),
              0.5 * isoperimetricQuotient(labels, cv::Mat()), 1e-6);
  // Clamp: a grazing normal counts as n_z = min_normal_z.
  const cv::Mat grazing(10, 10, CV_32FC3, cv::Scalar(1.0f, 0.0f, 0.0f));
  EXPECT_NEAR(isoperimetricQuotient3d(labels, cv::Mat(), depth, grazing, 500.0, 0.25),
              0.25 * isoperimetricQuotient(labels, cv::Mat()), 1e-6);
}

TEST(MetricsCompression, PiecewiseConstantFeatureIsExplained) {
  const cv::Mat labels = splitAt(10, 10, 5);
  cv::Mat depth(10, 10, CV_32FC1, cv::Scalar(800.0f));
  depth.colRange(5, 10).setTo(1200.0f);
  const CompressionScores s = compressionScores(labels, cv::Mat(), depth);
  EXPECT_NEAR(s.compression_error, 0.0, 1e-9);
  EXPECT_NEAR(s.explained_variation, 1.0, 1e-12);
  EXPECT_EQ(s.pixels, 100u);
}

TEST(MetricsCompression, KnownResidual) {
  // Left segment alternates 0 / 2 (mean 1, residual 1 per pixel), right segment is 1.
  const cv::Mat labels = splitAt(10, 10, 5);
  cv::Mat f(10, 10, CV_32FC1, cv::Scalar(1.0f));
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 5; ++x) f.at<float>(y, x) = (x + y) % 2 == 0 ? 0.0f : 2.0f;
  }
  const CompressionScores s = compressionScores(labels, cv::Mat(), f);
  EXPECT_NEAR(s.compression_error, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.explained_variation, 0.0, 1e-12);  // both segment means equal the global mean
}

TEST(MetricsCompression, NonFiniteAndMaskedPixelsAreSkipped) {
  const cv::Mat labels(4, 4, CV_32SC1, cv::Scalar(0));
  cv::Mat f(4, 4, CV_32FC3, cv::Scalar(1.0f, 2.0f, 3.0f));
  f.at<cv::Vec3f>(0, 0) = cv::Vec3f(NAN, 0.0f, 0.0f);
  f.at<cv::Vec3f>(3, 3) = cv::Vec3f(100.0f, 0.0f, 0.0f);
  cv::Mat mask(4, 4, CV_8UC1, cv::Scalar(255));
  mask.at<std::uint8_t>(3, 3) = 0;
  const CompressionScores s = compressionScores(labels, mask, f);
  EXPECT_EQ(s.pixels, 14u);
  EXPECT_NEAR(s.compression_error, 0.0, 1e-12);
}

TEST(MetricsCompression, UnitVectorMean) {
  // Half the pixels (1,0,0), half (0,1,0): unit mean (1,1,0)/sqrt2, residual^2 = 2 - sqrt2 each.
  const cv::Mat labels(2, 2, CV_32SC1, cv::Scalar(0));
  cv::Mat n(2, 2, CV_32FC3, cv::Scalar(1.0f, 0.0f, 0.0f));
  n.row(1).setTo(cv::Scalar(0.0f, 1.0f, 0.0f));
  const CompressionScores s = compressionScores(labels, cv::Mat(), n, FeatureMean::kUnitVector);
  EXPECT_NEAR(s.compression_error, std::sqrt(2.0 - std::sqrt(2.0)), 1e-6);
  const CompressionScores a = compressionScores(labels, cv::Mat(), n, FeatureMean::kArithmetic);
  EXPECT_NEAR(a.compression_error, std::sqrt(0.5), 1e-6);
}

// Square tiles of `size` px as labels.
cv::Mat grid(int rows, int cols, int size) {
  cv::Mat labels(rows, cols, CV_32SC1);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) labels.at<int>(y, x) = (y / size) * (cols / size) + x / size;
  }
  return labels;
}

TEST(MetricsUniformDistribution, SigmaAndGridBeatsClump) {
  const cv::Mat tiles = grid(100, 100, 10);
  const UniformDistributionScores g = uniformDistributionError(tiles, cv::Mat());
  // 100 centres on 10^4 px: rho0 = 0.01, sigma* = sqrt(1 / (2 pi 0.01)).
  EXPECT_NEAR(g.sigma_px, std::sqrt(1.0 / (2.0 * M_PI * 0.01)), 1e-9);
  EXPECT_EQ(segmentCentroids(tiles, cv::Mat()).size(), 100u);
  EXPECT_NEAR(segmentCentroids(tiles, cv::Mat())[0].x, 4.5, 1e-12);
  // Same number of segments, but 99 tiny ones in one corner and one large rest.
  cv::Mat clumped(100, 100, CV_32SC1, cv::Scalar(0));
  for (int i = 1; i < 100; ++i) clumped.at<int>(i / 10, i % 10) = i;
  const UniformDistributionScores c = uniformDistributionError(clumped, cv::Mat());
  EXPECT_LT(g.relative_rms, 0.5);
  EXPECT_GT(c.relative_rms, 3.0 * g.relative_rms);
  EXPECT_NEAR(g.error, g.relative_rms * 0.01 * std::sqrt(1e4), 1e-9);
}

TEST(MetricsDensityError, SingleKernelReproducesItsOwnDensity) {
  // rho(u) = c exp(-pi c |u - p|^2) is exactly the kernel of a point at p (eq. 2.5).
  const double c = 0.01;
  cv::Mat density(101, 101, CV_64FC1);
  for (int y = 0; y < 101; ++y) {
    for (int x = 0; x < 101; ++x) {
      density.at<double>(y, x) =
          c * std::exp(-M_PI * c * ((x - 50.0) * (x - 50.0) + (y - 50.0) * (y - 50.0)));
    }
  }
  EXPECT_NEAR(relativeDensityError(density, {cv::Point2d(50, 50)}), 0.0, 1e-4);
  // No point at all: the whole density is missing.
  EXPECT_NEAR(relativeDensityError(density, {}), 1.0, 1e-12);
  // A point off-centre has a wider, lower kernel that misses much of the density.
  EXPECT_GT(relativeDensityError(density, {cv::Point2d(40, 50)}), 0.5);
}

TEST(MetricsDensityError, GridSamplesConstantDensity) {
  const cv::Mat density(200, 200, CV_32FC1, cv::Scalar(0.01f));
  std::vector<cv::Point2d> grid_points;
  std::vector<cv::Point2d> clumped_points;
  for (int y = 5; y < 200; y += 10) {
    for (int x = 5; x < 200; x += 10) {
      grid_points.emplace_back(x, y);
      clumped_points.emplace_back(x / 2.0, y / 2.0);  // all in the top-left quarter
    }
  }
  const double grid_error = relativeDensityError(density, grid_points);
  EXPECT_LT(grid_error, 0.2);
  EXPECT_GT(relativeDensityError(density, clumped_points), 1.0);
}

TEST(MetricsBadInput, ClearExceptions) {
  const cv::Mat labels = splitAt(10, 10, 5);
  cv::Mat float_labels;
  labels.convertTo(float_labels, CV_32F);
  EXPECT_THROW(boundaryScores(float_labels, labels, cv::Mat()), std::invalid_argument);
  EXPECT_THROW(boundaryScores(labels, splitAt(10, 11, 5), cv::Mat()), std::invalid_argument);
  EXPECT_THROW(boundaryScores(labels, labels, cv::Mat(), -1), std::invalid_argument);
  EXPECT_THROW(undersegmentationErrorNp(labels, labels, cv::Mat(10, 10, CV_8UC1, cv::Scalar(0))),
               std::invalid_argument);
  EXPECT_THROW(undersegmentationErrorThesis(labels, labels, cv::Mat(), 1.5), std::invalid_argument);
  EXPECT_THROW(connectivity(labels, cv::Mat(10, 10, CV_32FC1)), std::invalid_argument);
  EXPECT_THROW(compressionScores(labels, cv::Mat(), cv::Mat(10, 10, CV_64FC2)),
               std::invalid_argument);
  EXPECT_THROW(isoperimetricQuotient3d(labels, cv::Mat(), cv::Mat(10, 10, CV_32FC1),
                                       cv::Mat(10, 10, CV_32FC3), 0.0),
               std::invalid_argument);
  EXPECT_THROW(relativeDensityError(cv::Mat(10, 10, CV_32FC1, cv::Scalar(-1.0f)), {}),
               std::invalid_argument);
  EXPECT_THROW(
      relativeDensityError(cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0f)), {cv::Point2d(20, 3)}),
      std::invalid_argument);
  EXPECT_THROW(boundaryScores(cv::Mat(), labels, cv::Mat()), std::invalid_argument);
}

TEST(MetricsRealData, GroundTruthScoresItselfPerfectly) {
  const std::filesystem::path dir = std::filesystem::path(DASP_SHARED_DATA_DIR) / "osd" / "learn";
  const std::filesystem::path file = dir / "learn0_label_object.png";
  if (!std::filesystem::exists(file)) {
    GTEST_SKIP() << "shared data not found at " << dir << " (optional real-data test)";
  }
  const cv::Mat gt16 = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(gt16.type(), CV_16UC1);
  cv::Mat gt;
  gt16.convertTo(gt, CV_32S);
  const cv::Mat mask = gt16 > 0;
  EXPECT_DOUBLE_EQ(boundaryScores(gt, gt16, mask).recall, 1.0);
  EXPECT_DOUBLE_EQ(undersegmentationErrorNp(gt, gt16, mask), 0.0);
  EXPECT_DOUBLE_EQ(achievableSegmentationAccuracy(gt, gt16, mask), 1.0);
  // A 20 px grid over the same frame leaks across object edges.
  const cv::Mat tiles = grid(gt.rows, gt.cols, 20);
  EXPECT_GT(undersegmentationErrorNp(tiles, gt16, mask), 0.0);
  EXPECT_LT(achievableSegmentationAccuracy(tiles, gt16, mask), 1.0);
}

}  // namespace
}  // namespace metrics
}  // namespace dasp
