#include "peers/lccp.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include "peers/peers.h"

namespace dasp {
namespace peers {

cv::Mat computeLccp(const RgbdFrame& frame, const LccpConfig& config, int* supervoxel_count) {
  if (frame.color.type() != CV_8UC3 || frame.depth.type() != CV_16UC1 ||
      frame.depth.size() != frame.color.size()) {
    throw std::invalid_argument(
        "computeLccp: colour CV_8UC3 and depth CV_16UC1 (mm) of the same size required");
  }
  const Intrinsics& k = frame.intrinsics;
  if (!(k.fx > 0.0f && k.fy > 0.0f) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    throw std::invalid_argument("computeLccp: intrinsics must have positive focal lengths");
  }
  if (!(config.voxel_resolution_m > 0.0f && config.seed_resolution_m > 0.0f)) {
    throw std::invalid_argument("computeLccp: voxel and seed resolution must be > 0");
  }
  // Organized cloud, NaN where depth is missing, so that point index = pixel index.
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
  pcl::SupervoxelClustering<pcl::PointXYZRGBA> vccs(config.voxel_resolution_m,
                                                    config.seed_resolution_m);
  vccs.setUseSingleCameraTransform(config.single_camera_transform);
  vccs.setInputCloud(cloud);
  vccs.setColorImportance(config.color_importance);
  vccs.setSpatialImportance(config.spatial_importance);
  vccs.setNormalImportance(config.normal_importance);
  std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> clusters;
  vccs.extract(clusters);
  if (config.supervoxel_refinement) vccs.refineSupervoxels(2, clusters);
  if (supervoxel_count != nullptr) *supervoxel_count = static_cast<int>(clusters.size());
  std::multimap<std::uint32_t, std::uint32_t> adjacency;
  vccs.getSupervoxelAdjacency(adjacency);

  pcl::LCCPSegmentation<pcl::PointXYZRGBA> lccp;
  lccp.setConcavityToleranceThreshold(config.concavity_tolerance_deg);
  lccp.setSanityCheck(config.sanity_criterion);
  lccp.setSmoothnessCheck(true, config.voxel_resolution_m, config.seed_resolution_m,
                          config.smoothness_threshold);
  lccp.setKFactor(config.extended_convexity ? 1 : 0);
  lccp.setInputSupervoxels(clusters, adjacency);
  lccp.setMinSegmentSize(config.min_segment_size);
  lccp.segment();
  pcl::PointCloud<pcl::PointXYZL>::Ptr labelled = vccs.getLabeledCloud();
  if (labelled->size() != cloud->size()) {
    throw std::runtime_error("computeLccp: PCL returned a labelled cloud of a different size");
  }
  lccp.relabelCloud(*labelled);
  cv::Mat labels(frame.color.size(), CV_32SC1, cv::Scalar(-1));
  for (int y = 0; y < labels.rows; ++y) {
    int* row = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const std::uint32_t label = (*labelled)[static_cast<std::size_t>(y) * labels.cols + x].label;
      row[x] = label == 0 ? -1 : static_cast<int>(label);  // PCL: 0 = unlabelled
    }
  }
  compactLabels(labels);
  return labels;
}

}  // namespace peers
}  // namespace dasp
