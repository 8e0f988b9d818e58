#pragma once

// dasp_sdasp: what its `segment` and `evaluate` commands share.

#include <cstdint>
#include <string>

#include "dasp/dasp.h"
#include "dasp/rgbd_io.h"

namespace sdasp_tool {

/// CPU time of the calling thread [ms], for the per-stage times.
double threadCpuMilliseconds();

/// Superpixels for the segmentation: DASP (s-DASP) or colour-only ASP_RGB (s-SLIC) over the whole
/// image, or ASP_RGB_VALID: ASP_RGB with the pixels without depth unlabelled, so that the graph
/// covers the same pixels as DASP's (the depth values themselves are still not used). Throws
/// std::invalid_argument for another kind.
dasp::Superpixels computeSuperpixels(const std::string& kind, const dasp::RgbdFrame& frame,
                                     int count, std::uint64_t seed);

}  // namespace sdasp_tool
