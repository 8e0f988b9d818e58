// The organized PCL point cloud of an RGB-D frame, shared by the PCL peers (VCCS, LCCP). Internal
// to dasp_peers: only its sources include PCL.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <memory>

#include "dasp/dasp.h"

namespace dasp {
namespace peers {

/// Organized cloud (point index = pixel index), metres in the camera optical frame, NaN where the
/// depth is 0. Throws std::invalid_argument (prefixed with `what`) unless colour is CV_8UC3,
/// depth CV_16UC1 millimetres of the same size and the focal lengths positive.
std::shared_ptr<pcl::PointCloud<pcl::PointXYZRGBA>> organizedCloud(const RgbdFrame& frame,
                                                                   const char* what);

}  // namespace peers
}  // namespace dasp
