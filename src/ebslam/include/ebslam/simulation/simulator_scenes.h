#pragma once

// The floor-robot scenario of thesis 6.5 / 7.3: an eDVS on a floor robot looks straight up at a
// textured ceiling D = 2.59 m above. World: z up, the sensor in the plane z = 0; robot pose
// (x, y, theta) -> camera -> world = ((x, y, 0), R_z(theta)), camera x = robot forward (T_p of
// eq. 6.33). Ceiling map pixel (col, row) has its centre at origin_m + (col, row) *
// metres_per_pixel (makeEdgeLikelihoodMap's origin_centre_m).
// Details: docs/event_simulator.md#floor-robot-scenario-65

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"

namespace ebslam {

/// Ceiling height above the sensor in the thesis' experiments (6.5.3) [m].
inline constexpr double kThesisCeilingHeightM = 2.59;

/// How a hand-held or robot-mounted 6-DoF motion-capture trajectory becomes a planar robot
/// trajectory under the ceiling.
struct FloorRobotTrajectoryConfig {
  /// Half-width of the centred moving-average window applied to x, y and the unwrapped yaw
  /// [s]; removes the motion-capture jitter (about 1 mm / 0.2 deg at 300 Hz in the TUM
  /// pioneer files) which would otherwise make edge pixels flicker. 0 disables smoothing.
  double smoothing_half_window_s = 0.05;
  /// Resampling interval of the output [s]; 0 keeps the input timestamps.
  double resample_interval_s = 0.005;
  /// Shift time so that the output starts at t = 0.
  bool start_at_zero = true;
  /// Shift x, y so that the output starts at the origin with the heading unchanged.
  bool start_at_origin = false;
};

/// Projects a motion-capture trajectory into the floor plane and returns the eDVS camera poses
/// looking up (see the file comment): floor normal = the world axis of least position variance;
/// x, y = the position in the floor plane (height, roll and pitch dropped); theta = the heading
/// of the body's optical axis (body z). Details: docs/event_simulator.md#floor-robot-scenario-65
/// Throws std::invalid_argument for fewer than two poses or invalid poses, and if the optical
/// axis is nearly vertical (not a floor robot).
Trajectory makeFloorRobotTrajectory(const Trajectory& mocap_trajectory,
                                    const FloorRobotTrajectoryConfig& config = {});

/// SE(2) pose (x, y, theta) of a floor-robot camera pose (camera -> world with camera z up).
Pose2 floorPoseToSe2(const StampedPose& pose);
/// Camera pose (camera -> world, z up) of an SE(2) robot pose at time t_s.
StampedPose se2ToFloorPose(double t_s, double x, double y, double theta);

/// Axis-aligned rectangle in the floor plane [m].
struct FloorRegion {
  Eigen::Vector2d min{0.0, 0.0};
  Eigen::Vector2d max{0.0, 0.0};
};

/// The region of the ceiling the sensor can see along a floor-robot trajectory: the bounding
/// box of the positions grown by the radius of the sensor's footprint on the ceiling (its
/// half-diagonal, any heading) plus `margin_m`.
FloorRegion visibleCeilingRegion(const Trajectory& floor_trajectory, const CameraModel& camera,
                                 double ceiling_height_m = kThesisCeilingHeightM,
                                 double margin_m = 0.2);

/// A horizontal ceiling at height ceiling_height_m covering `region`, texture tiled from the
/// region's minimum corner (texel (0, 0) at region.min) at `metres_per_texel`.
/// Throws std::invalid_argument for an empty texture, an empty region or non-positive sizes.
Scene makeCeilingScene(const cv::Mat& texture, const FloorRegion& region, double metres_per_texel,
                       double ceiling_height_m = kThesisCeilingHeightM);

/// Procedural ceiling texture as in the thesis' simulation (6.5.3): a bright background with
/// randomly placed dark lines and circles (anti-aliased), CV_32FC1 in [0, 1].
struct LinesAndCirclesConfig {
  int width_px = 1024;  ///< texture size [texels]
  int height_px = 1024;
  int line_count = 40;
  int circle_count = 25;
  double stroke_width_px = 3.0;  ///< line/circle stroke width [texels]
  double max_line_length_px = 400.0;
  double min_circle_radius_px = 10.0;
  double max_circle_radius_px = 80.0;
  double background = 0.85;  ///< intensity of the ceiling
  /// Intensity of the strokes. 0.45 (log contrast 0.62, about four thresholds) gives about
  /// 40k events/s on the TUM pioneer runs, the thesis' typical eDVS rate ("normally less than
  /// 40000 events per second", 6.5.3); black tape (0.1) gives about 150k events/s.
  double foreground = 0.45;
  std::uint64_t seed = 1;
};
cv::Mat makeLinesAndCirclesTexture(const LinesAndCirclesConfig& config = {});

/// The procedural ceiling over `region` (ebslam_simulate_events --texture lines): the texture
/// is sized to the region at `metres_per_texel` and the line and circle counts of `lines` are
/// scaled with its area relative to the default 1024 x 1024 texels (same feature density).
/// Throws std::invalid_argument for an empty region or a non-positive texel size.
Scene makeLinesCeilingScene(const FloorRegion& region, double metres_per_texel,
                            LinesAndCirclesConfig lines = {},
                            double ceiling_height_m = kThesisCeilingHeightM);

/// A known ceiling map for EB-PF (thesis fig. 6.8): the ceiling as seen from below, rendered
/// orthographically at metres_per_pixel, and its Canny edge image.
struct CeilingMap {
  cv::Mat intensity;  ///< CV_32FC1 in [0, 1], blurred like the sensor sees it
  cv::Mat edges;      ///< CV_8UC1, 255 on edges, 0 elsewhere
  double metres_per_pixel = 0.0;
  Eigen::Vector2d origin_m{0.0, 0.0};  ///< world (x, y) of the centre of map pixel (0, 0)
};

struct CeilingMapConfig {
  double metres_per_pixel = 0.01;  ///< map resolution [m]
  /// Gaussian blur before Canny [m]; default: about half a sensor pixel on the ceiling
  /// (W_trig / 2 = 1.5 cm at D = 2.59 m, f = 86.3), so only edges the eDVS resolves remain.
  double blur_sigma_m = 0.015;
  double canny_low = 20.0;  ///< Canny hysteresis thresholds on the 8-bit image
  double canny_high = 50.0;
};

/// Renders the ceiling plane of `scene` (the first plane whose normal is vertical) over
/// `region` and computes its edge map. Throws std::invalid_argument if the scene has no
/// horizontal plane or the region is empty.
CeilingMap renderCeilingMap(const Scene& scene, const FloorRegion& region,
                            const CeilingMapConfig& config = {});

}  // namespace ebslam
