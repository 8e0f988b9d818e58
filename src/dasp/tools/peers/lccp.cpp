#include "peers/lccp.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include "peers/pcl_cloud.h"
#include "peers/peers.h"

namespace dasp {
namespace peers {

cv::Mat computeLccp(const RgbdFrame& frame, const LccpConfig& config, int* supervoxel_count) {
  const auto cloud = organizedCloud(frame, "computeLccp");
  if (!(config.voxel_resolution_m > 0.0f && config.seed_resolution_m > 0.0f)) {
    throw std::invalid_argument("computeLccp: voxel and seed resolution must be > 0");
  }
  pcl::SupervoxelClustering<pcl::PointXYZRGBA> vccs(config.voxel_resolution_m,
                                                    config.seed_resolution_m);
  configureSupervoxels(vccs, cloud, config);
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
