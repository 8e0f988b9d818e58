#include "peers/peers.h"

#include "peers/pcl_cloud.h"

#include "dasp/features.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/seeds.hpp>
#include <opencv2/ximgproc/slic.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace dasp {
namespace peers {
namespace {

void checkColor(const cv::Mat& bgr, int count, const char* what) {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw std::invalid_argument(std::string(what) + ": colour image must be CV_8UC3 (BGR)");
  }
  if (count < 1 || static_cast<std::size_t>(count) > bgr.total()) {
    throw std::invalid_argument(std::string(what) +
                                ": superpixel count must be in [1, number of pixels]");
  }
}

cv::Mat toLab(const cv::Mat& bgr) {
  cv::Mat lab;
  cv::cvtColor(bgr, lab, cv::COLOR_BGR2Lab);
  return lab;
}

}  // namespace

int compactLabels(cv::Mat& labels) {
  if (labels.type() != CV_32SC1) {
    throw std::invalid_argument("compactLabels: labels must be CV_32SC1");
  }
  std::unordered_map<int, int> map;
  for (int y = 0; y < labels.rows; ++y) {
    int* row = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] < 0) {
        row[x] = -1;
        continue;
      }
      auto [it, inserted] = map.try_emplace(row[x], static_cast<int>(map.size()));
      row[x] = it->second;
    }
  }
  return static_cast<int>(map.size());
}

cv::Mat computeOpenCvSlic(const cv::Mat& bgr, const SlicConfig& config) {
  checkColor(bgr, config.superpixel_count, "computeOpenCvSlic");
  if (config.iterations < 1 || !(config.ruler > 0.0f)) {
    throw std::invalid_argument("computeOpenCvSlic: iterations >= 1 and ruler > 0 required");
  }
  const int region_size = std::max(
      1, static_cast<int>(
             std::lround(std::sqrt(static_cast<double>(bgr.total()) / config.superpixel_count))));
  cv::Ptr<cv::ximgproc::SuperpixelSLIC> slic = cv::ximgproc::createSuperpixelSLIC(
      toLab(bgr), config.zero_parameter ? cv::ximgproc::SLICO : cv::ximgproc::SLIC, region_size,
      config.ruler);
  slic->iterate(config.iterations);
  slic->enforceLabelConnectivity(config.min_element_percent);
  cv::Mat labels;
  slic->getLabels(labels);
  compactLabels(labels);
  return labels;
}

cv::Mat computeOpenCvSeeds(const cv::Mat& bgr, const SeedsConfig& config) {
  checkColor(bgr, config.superpixel_count, "computeOpenCvSeeds");
  if (config.levels < 1 || config.iterations < 1 || config.histogram_bins < 1) {
    throw std::invalid_argument("computeOpenCvSeeds: levels, iterations and bins must be >= 1");
  }
  cv::Ptr<cv::ximgproc::SuperpixelSEEDS> seeds = cv::ximgproc::createSuperpixelSEEDS(
      bgr.cols, bgr.rows, 3, config.superpixel_count, config.levels, config.prior,
      config.histogram_bins, false);
  seeds->iterate(toLab(bgr), config.iterations);
  cv::Mat labels;
  seeds->getLabels(labels);
  compactLabels(labels);
  return labels;
}

std::shared_ptr<pcl::PointCloud<pcl::PointXYZRGBA>> organizedCloud(const RgbdFrame& frame,
                                                                   const char* what) {
  if (frame.color.type() != CV_8UC3 || frame.depth.type() != CV_16UC1 ||
      frame.depth.size() != frame.color.size()) {
    throw std::invalid_argument(
        std::string(what) + ": colour CV_8UC3 and depth CV_16UC1 (mm) of the same size required");
  }
  const Intrinsics& k = frame.intrinsics;
  if (!(k.fx > 0.0f && k.fy > 0.0f) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    throw std::invalid_argument(std::string(what) +
                                ": intrinsics must have positive focal lengths");
  }
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZRGBA>>(
      static_cast<std::uint32_t>(frame.color.cols), static_cast<std::uint32_t>(frame.color.rows));
  cloud->is_dense = false;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < frame.color.rows; ++y) {
    const std::uint16_t* depth = frame.depth.ptr<std::uint16_t>(y);
    const cv::Vec3b* color = frame.color.ptr<cv::Vec3b>(y);
    for (int x = 0; x < frame.color.cols; ++x) {
      pcl::PointXYZRGBA& p = cloud->at(x, y);
      p.b = color[x][0];
      p.g = color[x][1];
      p.r = color[x][2];
      p.a = 255;
      if (depth[x] == 0) {
        p.x = p.y = p.z = nan;
        continue;
      }
      const float z = 0.001f * depth[x];
      p.x = (x - k.cx) * z / k.fx;
      p.y = (y - k.cy) * z / k.fy;
      p.z = z;
    }
  }
  return cloud;
}

cv::Mat computeVccs(const RgbdFrame& frame, const VccsConfig& config, int* runs_used) {
  const char* what = "computeVccs";
  checkColor(frame.color, config.superpixel_count, what);
  const auto cloud = organizedCloud(frame, what);
  if (!(config.seed_scale > 0.0f && config.voxel_resolution_m > 0.0f)) {
    throw std::invalid_argument("computeVccs: seed_scale and voxel_resolution_m must be > 0");
  }
  // VCCS seeds one supervoxel per occupied cell of a cubic grid of the seed resolution s. A
  // surface patch of area A with unit normal n cuts about A (|n_x| + |n_y| + |n_z|) / s^2 cells,
  // so s = sqrt(sum_u area(u) |n(u)|_1 / K) asks for about K supervoxels.
  const PixelFeatures features = computeFeatures(frame);  // throws if no pixel has depth
  double seed_cells_m2 = 0.0;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.valid[i]) continue;
    const double l1 =
        std::abs(features.nx[i]) + std::abs(features.ny[i]) + std::abs(features.nz[i]);
    seed_cells_m2 += features.area[i] * (l1 > 0.0 ? l1 : 1.0);
  }
  const auto run = [&](float seed_resolution) {
    const float voxel_resolution = std::min(config.voxel_resolution_m, seed_resolution / 3.0f);
    pcl::SupervoxelClustering<pcl::PointXYZRGBA> vccs(voxel_resolution, seed_resolution);
    configureSupervoxels(vccs, cloud, config);
    std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> clusters;
    vccs.extract(clusters);
    const pcl::PointCloud<pcl::PointXYZL>::Ptr labelled = vccs.getLabeledCloud();
    if (labelled->size() != cloud->size()) {
      throw std::runtime_error("computeVccs: PCL returned a labelled cloud of a different size");
    }
    cv::Mat labels(frame.color.size(), CV_32SC1, cv::Scalar(-1));
    for (int y = 0; y < labels.rows; ++y) {
      int* row = labels.ptr<int>(y);
      for (int x = 0; x < labels.cols; ++x) {
        const std::uint32_t label =
            (*labelled)[static_cast<std::size_t>(y) * labels.cols + x].label;
        row[x] = label == 0 ? -1 : static_cast<int>(label);  // PCL: 0 = unlabelled
      }
    }
    const int count = compactLabels(labels);
    return std::make_pair(labels, count);
  };
  float seed_resolution =
      config.seed_scale * static_cast<float>(std::sqrt(seed_cells_m2 / config.superpixel_count));
  auto best = run(seed_resolution);
  const int wanted = config.superpixel_count;
  const auto error = [wanted](int count) { return std::abs(count - wanted); };
  // Count matching: the supervoxel count goes about as 1 / s^2, so rescale s by
  // sqrt(count / K) until the count is within count_tolerance of K (or the runs are used up).
  auto current = best;
  int attempt = 1;
  for (; attempt < config.count_matching_runs &&
         error(best.second) > config.count_tolerance * wanted && current.second > 0;
       ++attempt) {
    seed_resolution *= static_cast<float>(std::sqrt(static_cast<double>(current.second) / wanted));
    current = run(seed_resolution);
    if (error(current.second) < error(best.second)) best = current;
  }
  if (runs_used != nullptr) *runs_used = attempt;
  return best.first;
}

}  // namespace peers
}  // namespace dasp
