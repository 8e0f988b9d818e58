// The command-line options of peers::MethodOptions that dasp_segment and dasp_evaluate share:
// one definition, so that both tools take the same DASP options under the same names.
#pragma once

#include <CLI/CLI.hpp>

#include "peers/methods.h"

namespace dasp::peers {

/// Adds --iterations, --seed, the DASP options (DaspConfig members, see dasp.h) and
/// --vccs-seed-scale to `app`, bound to `options`.
inline void addMethodOptions(CLI::App& app, MethodOptions& options) {
  app.add_option("--iterations", options.iterations, "DALIC iterations (DASP family)")
      ->capture_default_str();
  app.add_option("--seed", options.seed, "random seed (DASP family)")->capture_default_str();
  app.add_option("--max-slant-factor", options.experimental.max_slant_factor,
                 "DASP density clamp of the slant factor (DaspExperimental::max_slant_factor)")
      ->capture_default_str();
  app.add_option("--dasp-weight-depth", options.experimental.weight_depth,
                 "DASP extra weight of the depth component (DaspExperimental::weight_depth)")
      ->capture_default_str();
  app.add_option("--depth-jump-ratio", options.depth_jump_ratio,
                 "DASP/ASP_RGBD relative depth jump of a discontinuity "
                 "(DaspConfig::depth_jump_ratio)")
      ->capture_default_str();
  app.add_option("--depth-exponent", options.experimental.depth_exponent,
                 "DASP depth exponent of the density, one of 0, 0.5, 1, 1.5, 2 "
                 "(DaspExperimental::depth_exponent)")
      ->capture_default_str();
  app.add_option("--vccs-seed-scale", options.vccs_seed_scale,
                 "VCCS seed resolution scale (see peers.h)")
      ->capture_default_str();
}

}  // namespace dasp::peers
