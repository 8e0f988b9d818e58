#pragma once

// Rooms for the D-eDVS simulator (thesis 8.2): walls, floor, ceiling, a table and boxes, each
// face a TexturedPlane of the shared Scene type with a procedural dead-leaves texture (Lee, Mumford
// and Huang, IJCV 2001). World frame: z up, metres (the TUM RGB-D freiburg1 motion-capture frame);
// the room is an axis-aligned box, floor at z = 0, built around a trajectory's positions.
// Details: docs/dedvs_core.md#rooms-and-textures

#include <cstdint>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"

namespace ebslam {

/// Dead-leaves texture parameters.
struct DeadLeavesConfig {
  int size_px = 512;             ///< square texture [texels]; tiles seamlessly (discs wrap)
  double min_radius_px = 2.0;    ///< smallest disc radius [texels]
  double max_radius_px = 120.0;  ///< largest disc radius [texels]
  double mean_intensity = 0.45;  ///< mean grey level (linear intensity, [0, 1])
  /// Grey levels are uniform in mean +- contrast / 2 (clamped to [0.02, 1]); 0 gives a
  /// uniform texture, 0.8 a strongly textured one.
  double contrast = 0.6;
  std::uint64_t seed = 1;

  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

/// A tileable dead-leaves texture, CV_32FC1 in [0, 1], anti-aliased (discs rendered at the
/// texel grid with a 0.5 texel Gaussian).
cv::Mat makeDeadLeavesTexture(const DeadLeavesConfig& config = {});

/// Parameters of makeRoomScene.
struct RoomSceneConfig {
  /// Horizontal distance from the trajectory's bounding box to each wall [m].
  double wall_margin_m = 1.6;
  double ceiling_height_m = 2.8;  ///< [m], floor at z = 0
  /// Texture contrast of every surface (DeadLeavesConfig::contrast).
  double texture_contrast = 0.35;
  double metres_per_texel = 0.005;  ///< texel size on the walls and furniture [m]
  int box_count = 6;                ///< boxes on the floor and on the table
  bool with_table = true;           ///< a 1.6 x 0.8 m table, 0.75 m high, with four legs
  std::uint64_t seed = 1;           ///< textures and furniture placement

  void validate() const;
};

/// A room around the positions of `trajectory` (see the file comment), furnished: the table
/// stands where the trajectory's optical axes (camera z, TUM convention) meet the table height
/// most often (so a desk run looks at the desk), boxes stand on the floor and on the table,
/// a shelf (a tall box) stands at a wall. Faces carry per-face shading (a fixed light from
/// above) in their texture and a colour in TexturedPlane::colour. Throws std::invalid_argument
/// for an empty trajectory or an invalid config.
Scene makeRoomScene(const Trajectory& trajectory, const RoomSceneConfig& config = {});

/// Appends the five visible faces (no bottom) of an axis-aligned box standing on z = min.z(),
/// textured with `texture` at `metres_per_texel`, to `scene`.
void addBox(Scene& scene, const Eigen::Vector3d& min, const Eigen::Vector3d& max,
            const cv::Mat& texture, double metres_per_texel,
            const Eigen::Vector3f& colour = Eigen::Vector3f::Ones());

}  // namespace ebslam
