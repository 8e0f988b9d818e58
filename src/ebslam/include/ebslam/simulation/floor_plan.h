#pragma once

// Floor plan of a room for the closed-loop exploration simulator (thesis 7.4, fig. 7.10): walls as
// one closed polygon, obstacles as further closed polygons, in the floor-robot world frame
// (simulator_scenes.h: x, y on the floor [m], z up). Text file: `name`, `start x y theta`
// (required), one `walls` and any number of `obstacle` keywords, each followed by one "x y" vertex
// per line, the last vertex repeating the first; '#' comments.
// Format: docs/ebslam_core.md#floor-plans

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ebslam/events/pose.h"

namespace ebslam {

/// A closed polygon; vertices in order, the closing vertex not repeated [m].
using Polygon2 = std::vector<Eigen::Vector2d>;

struct FloorPlan {
  std::string name;
  Polygon2 walls;                   ///< room boundary; the floor is its inside
  std::vector<Polygon2> obstacles;  ///< solid obstacles inside the room
  Pose2 start;                      ///< robot start pose

  /// Throws std::invalid_argument with the reason if the plan is unusable: fewer than three
  /// vertices or zero area in a polygon, non-finite coordinates, a self-intersecting wall
  /// polygon.
  void validate() const;

  /// Distance from point p to the nearest wall or obstacle edge [m].
  double clearance(const Eigen::Vector2d& p) const;
  /// Nearest point on any wall or obstacle edge to p.
  Eigen::Vector2d nearestBoundaryPoint(const Eigen::Vector2d& p) const;
  /// For every edge closer to p than `radius` [m], its point nearest to p.
  std::vector<Eigen::Vector2d> boundaryPointsWithin(const Eigen::Vector2d& p, double radius) const;
  /// p lies on the floor: inside the walls and outside every obstacle.
  bool isFloor(const Eigen::Vector2d& p) const;
  /// A disc of `radius` centred at p fits on the floor (isFloor and clearance >= radius).
  bool discFits(const Eigen::Vector2d& p, double radius) const;
  /// Axis-aligned bounding box of the walls: (min x, min y), (max x, max y).
  Eigen::Vector2d boundsMin() const;
  Eigen::Vector2d boundsMax() const;
};

/// Parses a floor plan (format in the file comment). `source` names the text in messages.
/// Throws std::invalid_argument naming the source and line for an empty plan (no walls), an
/// unclosed polygon, a malformed line, a missing start pose or a plan validate() rejects, and
/// if the start pose does not leave room for a robot of `robot_radius_m` (pass 0 to skip).
FloorPlan parseFloorPlan(const std::string& text, const std::string& source = "floor plan",
                         double robot_radius_m = 0.0);
/// Reads and parses a floor-plan file; throws std::runtime_error if it cannot be read and
/// std::invalid_argument as parseFloorPlan.
FloorPlan readFloorPlan(const std::string& path, double robot_radius_m = 0.0);

/// Point-in-polygon test (even-odd rule).
bool insidePolygon(const Polygon2& polygon, const Eigen::Vector2d& p);

}  // namespace ebslam
