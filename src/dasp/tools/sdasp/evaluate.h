#pragma once

// dasp_sdasp evaluate: boundary precision/recall curves, ODS and OIS F1 and time per frame of
// s-DASP, s-SLIC and PCL's LCCP over a folder of labelled frames, as JSON (see ../sdasp.cpp).

#include <cstdint>
#include <string>

#include "dasp/sdasp.h"

namespace sdasp_tool {

// `evaluate`: the folder, the methods and the parameter grids (comma lists).
struct EvaluateOptions {
  std::string folder, json_path, methods_text = "sDASP,sSLIC,LCCP";
  int threshold_count = 201;
  int max_frames = 0;
  std::string color_weights, position_weights, normal_weights, eigen_counts, thetas;
  std::string lccp_seeds = "0.015,0.02,0.03";
  std::string adaptive_scales, adaptive_quantiles, adaptive_caps;
  bool per_frame = false;
  bool lccp_single_camera = false;

  explicit EvaluateOptions(const dasp::SdaspConfig& config)
      : color_weights(std::to_string(config.graph.weight_color)),
        position_weights(std::to_string(config.graph.weight_position)),
        normal_weights(std::to_string(config.graph.weight_normal)),
        eigen_counts(std::to_string(config.spectral.eigenvector_count)),
        thetas(std::to_string(config.graph.min_border_pairs)),
        adaptive_scales(std::to_string(config.adaptive_scale)),
        adaptive_quantiles(std::to_string(config.adaptive_quantile)),
        adaptive_caps(std::to_string(config.adaptive_max_threshold)) {}
};

/// Runs the evaluation and writes o.json_path; returns the exit status. Throws
/// std::invalid_argument for a bad list or folder, std::runtime_error if the JSON cannot be
/// written.
int runEvaluate(const EvaluateOptions& o, const dasp::SdaspConfig& config, int count,
                std::uint64_t seed);

}  // namespace sdasp_tool
