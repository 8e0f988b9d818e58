// PCL's Locally Convex Connected Patches segmentation (LCCP, Stein et al. 2014) on VCCS
// supervoxels, the depth-based peer of s-DASP. Part of dasp_peers (tools only).
#pragma once

#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp {
namespace peers {

/// Parameters; defaults are those of PCL's example_lccp_segmentation.cpp.
struct LccpConfig {
  float voxel_resolution_m = 0.0075f;  ///< VCCS voxel size.
  float seed_resolution_m = 0.03f;     ///< VCCS seed spacing (the supervoxel size).
  float color_importance = 0.0f;       ///< VCCS weights.
  float spatial_importance = 1.0f;
  float normal_importance = 4.0f;
  bool single_camera_transform = false;   ///< Depth-dependent voxel grid.
  bool supervoxel_refinement = false;     ///< VCCS refineSupervoxels(2, ...).
  float concavity_tolerance_deg = 10.0f;  ///< Concave edges flatter than this count as convex.
  float smoothness_threshold = 0.1f;      ///< Smoothness check, 0 strictest .. 1 off.
  bool extended_convexity = false;        ///< k factor 1 instead of 0.
  bool sanity_criterion = false;
  unsigned min_segment_size = 0;  ///< Segments with fewer supervoxels are merged.
};

/// LCCP segments of a frame (depth CV_16UC1 mm): CV_32SC1 labels 0..n-1, -1 for pixels without
/// depth or supervoxel. `supervoxel_count` (optional) receives the number of supervoxels.
cv::Mat computeLccp(const RgbdFrame& frame, const LccpConfig& config,
                    int* supervoxel_count = nullptr);

}  // namespace peers
}  // namespace dasp
