// The organized PCL point cloud of an RGB-D frame, shared by the PCL peers (VCCS, LCCP). Internal
// to dasp_peers: only its sources include PCL.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <memory>

#include "dasp/dasp.h"

namespace dasp {
namespace peers {

/// Organized cloud (point index = pixel index), metres in the camera optical frame, NaN where the
/// depth is 0. Throws std::invalid_argument (prefixed with `what`) unless colour is CV_8UC3,
/// depth CV_16UC1 millimetres of the same size and the focal lengths positive.
std::shared_ptr<pcl::PointCloud<pcl::PointXYZRGBA>> organizedCloud(const RgbdFrame& frame,
                                                                   const char* what);

/// Gives VCCS its input cloud and the weights of a peer config (VccsConfig, LccpConfig: fields
/// single_camera_transform, color_importance, spatial_importance, normal_importance).
template <typename Config>
void configureSupervoxels(pcl::SupervoxelClustering<pcl::PointXYZRGBA>& vccs,
                          const std::shared_ptr<pcl::PointCloud<pcl::PointXYZRGBA>>& cloud,
                          const Config& config) {
  vccs.setUseSingleCameraTransform(config.single_camera_transform);
  vccs.setInputCloud(cloud);
  vccs.setColorImportance(config.color_importance);
  vccs.setSpatialImportance(config.spatial_importance);
  vccs.setNormalImportance(config.normal_importance);
}

}  // namespace peers
}  // namespace dasp
