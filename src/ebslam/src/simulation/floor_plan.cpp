#include "ebslam/simulation/floor_plan.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace ebslam {
namespace {

Eigen::Vector2d closestOnSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

double signedArea(const Polygon2& polygon) {
  double area = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    area += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * area;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Proper intersection of segments ab and cd (touching at shared endpoints does not count).
bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& d) {
  const double d1 = cross(b - a, c - a);
  const double d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c);
  const double d4 = cross(d - c, b - c);
  return ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) &&
         ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0));
}

void validatePolygon(const Polygon2& polygon, const std::string& what) {
  if (polygon.size() < 3) {
    throw std::invalid_argument(what + ": needs at least three vertices");
  }
  for (const Eigen::Vector2d& v : polygon) {
    if (!v.allFinite()) throw std::invalid_argument(what + ": non-finite vertex");
  }
  if (!(std::abs(signedArea(polygon)) > 1e-9)) {
    throw std::invalid_argument(what + ": zero area");
  }
}

template <typename Visit>
void forEachEdge(const FloorPlan& plan, Visit&& visit) {
  const auto edges = [&visit](const Polygon2& polygon) {
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      visit(polygon[i], polygon[(i + 1) % polygon.size()]);
    }
  };
  edges(plan.walls);
  for (const Polygon2& obstacle : plan.obstacles) edges(obstacle);
}

}  // namespace

bool insidePolygon(const Polygon2& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

void FloorPlan::validate() const {
  validatePolygon(walls, "floor plan walls");
  for (std::size_t i = 0; i < walls.size(); ++i) {
    for (std::size_t j = i + 2; j < walls.size(); ++j) {
      if (i == 0 && j == walls.size() - 1) continue;  // adjacent through the closing edge
      if (segmentsCross(walls[i], walls[i + 1], walls[j], walls[(j + 1) % walls.size()])) {
        throw std::invalid_argument("floor plan walls: the polygon intersects itself at edges " +
                                    std::to_string(i) + " and " + std::to_string(j));
      }
    }
  }
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    validatePolygon(obstacles[k], "floor plan obstacle " + std::to_string(k));
  }
  if (!std::isfinite(start.x) || !std::isfinite(start.y) || !std::isfinite(start.theta))
    throw std::invalid_argument("floor plan: start pose is not finite");
}

double FloorPlan::clearance(const Eigen::Vector2d& p) const {
  return (nearestBoundaryPoint(p) - p).norm();
}

Eigen::Vector2d FloorPlan::nearestBoundaryPoint(const Eigen::Vector2d& p) const {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d nearest = p;
  forEachEdge(*this, [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d q = closestOnSegment(a, b, p);
    const double d2 = (q - p).squaredNorm();
    if (d2 < best) {
      best = d2;
      nearest = q;
    }
  });
  return nearest;
}

std::vector<Eigen::Vector2d> FloorPlan::boundaryPointsWithin(const Eigen::Vector2d& p,
                                                             double radius) const {
  std::vector<Eigen::Vector2d> points;
  forEachEdge(*this, [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d q = closestOnSegment(a, b, p);
    if ((q - p).norm() < radius) points.push_back(q);
  });
  return points;
}

bool FloorPlan::isFloor(const Eigen::Vector2d& p) const {
  if (!insidePolygon(walls, p)) return false;
  for (const Polygon2& obstacle : obstacles) {
    if (insidePolygon(obstacle, p)) return false;
  }
  return true;
}

bool FloorPlan::discFits(const Eigen::Vector2d& p, double radius) const {
  return isFloor(p) && clearance(p) >= radius;
}

Eigen::Vector2d FloorPlan::boundsMin() const {
  Eigen::Vector2d m = walls.front();
  for (const Eigen::Vector2d& v : walls) m = m.cwiseMin(v);
  return m;
}

Eigen::Vector2d FloorPlan::boundsMax() const {
  Eigen::Vector2d m = walls.front();
  for (const Eigen::Vector2d& v : walls) m = m.cwiseMax(v);
  return m;
}

FloorPlan parseFloorPlan(const std::string& text, const std::string& source,
                         double robot_radius_m) {
  FloorPlan plan;
  bool have_walls = false;
  bool have_start = false;
  // The polygon being read: its vertices, its keyword and the line it started on.
  Polygon2 current;
  std::string current_kind;
  int current_line = 0;
  const auto fail = [&source](int line, const std::string& message) {
    throw std::invalid_argument(source + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                                message);
  };
  const auto finish = [&]() {
    if (current_kind.empty()) return;
    if (current.size() < 4) {
      fail(current_line, "the " + current_kind +
                             " polygon needs at least three vertices plus the closing vertex");
    }
    if ((current.front() - current.back()).norm() > 1e-9) {
      std::ostringstream message;
      message << "the " << current_kind << " polygon is not closed: its last vertex ("
              << current.back().x() << ", " << current.back().y() << ") must repeat its first ("
              << current.front().x() << ", " << current.front().y() << ")";
      fail(current_line, message.str());
    }
    current.pop_back();
    if (current_kind == "walls") {
      if (have_walls) fail(current_line, "a second walls polygon (only one is allowed)");
      plan.walls = current;
      have_walls = true;
    } else {
      plan.obstacles.push_back(current);
    }
    current.clear();
    current_kind.clear();
  };

  std::istringstream input(text);
  std::string raw;
  int line_number = 0;
  while (std::getline(input, raw)) {
    ++line_number;
    const std::string line = raw.substr(0, raw.find('#'));
    std::istringstream fields(line);
    std::string first;
    if (!(fields >> first)) continue;
    if (first == "walls" || first == "obstacle") {
      finish();
      current_kind = first;
      current_line = line_number;
      continue;
    }
    if (first == "name") {
      if (!(fields >> plan.name)) fail(line_number, "name needs a word");
      continue;
    }
    if (first == "start") {
      double x = 0.0, y = 0.0, theta = 0.0;
      if (!(fields >> x >> y >> theta)) fail(line_number, "start needs x y theta");
      plan.start = Pose2{x, y, theta};
      have_start = true;
      continue;
    }
    // A vertex line.
    std::istringstream numbers(line);
    double x = 0.0, y = 0.0;
    std::string rest;
    if (!(numbers >> x >> y) || (numbers >> rest)) {
      fail(
          line_number,
          "expected a keyword (name, start, walls, obstacle) or a vertex 'x y', got '" + raw + "'");
    }
    if (current_kind.empty()) fail(line_number, "a vertex outside a walls or obstacle polygon");
    if (!std::isfinite(x) || !std::isfinite(y)) fail(line_number, "non-finite vertex");
    current.emplace_back(x, y);
  }
  finish();
  if (!have_walls) fail(0, "empty floor plan: no walls polygon");
  if (!have_start) fail(0, "no start pose ('start x y theta')");
  try {
    plan.validate();
  } catch (const std::invalid_argument& error) {
    fail(0, error.what());
  }
  const Eigen::Vector2d start(plan.start.x, plan.start.y);
  if (!plan.isFloor(start) || (robot_radius_m > 0.0 && !plan.discFits(start, robot_radius_m))) {
    fail(0,
         "the start pose leaves no room for the robot (outside the walls, inside an "
         "obstacle or closer than the robot radius to an edge)");
  }
  return plan;
}

FloorPlan readFloorPlan(const std::string& path, double robot_radius_m) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("readFloorPlan: cannot open " + path);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return parseFloorPlan(buffer.str(), path, robot_radius_m);
}

}  // namespace ebslam
