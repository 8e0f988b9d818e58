#include "ebslam/simulation/dedvs_scene.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace ebslam {
namespace {

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// A rectangle with corner `origin`, spanned by the unit vectors axis_u, axis_v (normal
// axis_u x axis_v), shaded by a fixed light from above.
void addRectangle(Scene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& axis_u,
                  const Eigen::Vector3d& axis_v, double size_u, double size_v,
                  const cv::Mat& texture, double metres_per_texel, const Eigen::Vector3f& colour,
                  const Eigen::Vector3d& outward_normal) {
  TexturedPlane plane;
  Eigen::Matrix3d rotation;
  rotation.col(0) = axis_u;
  rotation.col(1) = axis_v;
  rotation.col(2) = axis_u.cross(axis_v);
  plane.pose.linear() = rotation;
  plane.pose.translation() = origin;
  plane.size_m = Eigen::Vector2d(size_u, size_v);
  // Ambient plus a diffuse light from above and one side: faces of different orientation
  // differ in brightness, as in a lit room (box edges are edges in intensity too).
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  const double shade = 0.55 + 0.45 * std::max(0.0, outward_normal.normalized().dot(light));
  plane.texture = texture * shade;
  plane.metres_per_texel = metres_per_texel;
  plane.repeat = true;
  plane.colour = colour;
  scene.planes.push_back(std::move(plane));
}

}  // namespace

void DeadLeavesConfig::validate() const {
  require(size_px >= 8 && size_px <= 8192, "DeadLeavesConfig: size_px must lie in [8, 8192]");
  require(std::isfinite(min_radius_px) && min_radius_px >= 0.5,
          "DeadLeavesConfig: min_radius_px must be >= 0.5");
  require(std::isfinite(max_radius_px) && max_radius_px >= min_radius_px,
          "DeadLeavesConfig: max_radius_px must be >= min_radius_px");
  require(std::isfinite(mean_intensity) && mean_intensity > 0.0 && mean_intensity <= 1.0,
          "DeadLeavesConfig: mean_intensity must lie in (0, 1]");
  require(std::isfinite(contrast) && contrast >= 0.0 && contrast <= 2.0,
          "DeadLeavesConfig: contrast must lie in [0, 2]");
}

cv::Mat makeDeadLeavesTexture(const DeadLeavesConfig& config) {
  config.validate();
  const int n = config.size_px;
  cv::Mat texture(n, n, CV_32FC1, cv::Scalar(-1.0f));
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Radii with density ~ r^-3 on [r0, r1] by inversion: r = (r0^-2 - u (r0^-2 - r1^-2))^-1/2.
  const double a = 1.0 / (config.min_radius_px * config.min_radius_px);
  const double b = 1.0 / (config.max_radius_px * config.max_radius_px);
  std::size_t uncovered = static_cast<std::size_t>(n) * n;
  const std::size_t stop = uncovered / 2000;  // 99.95 % covered
  // Front to back: each new disc only fills texels no nearer disc has covered.
  for (std::size_t disc = 0; uncovered > stop && disc < 50'000'000; ++disc) {
    const double r = 1.0 / std::sqrt(a - uniform(rng) * (a - b));
    const double cx = uniform(rng) * n;
    const double cy = uniform(rng) * n;
    const float value = static_cast<float>(
        std::clamp(config.mean_intensity + config.contrast * (uniform(rng) - 0.5), 0.02, 1.0));
    const int x0 = static_cast<int>(std::floor(cx - r));
    const int x1 = static_cast<int>(std::ceil(cx + r));
    const int y0 = static_cast<int>(std::floor(cy - r));
    const int y1 = static_cast<int>(std::ceil(cy + r));
    const double r2 = r * r;
    for (int y = y0; y <= y1; ++y) {
      const double dy = y + 0.5 - cy;
      if (dy * dy > r2) continue;
      float* row = texture.ptr<float>(((y % n) + n) % n);  // wraps: the texture tiles
      // Chord of the disc on this row, then wrapped columns.
      const double half = std::sqrt(r2 - dy * dy);
      const int from = std::max(x0, static_cast<int>(std::ceil(cx - half - 0.5)));
      const int to = std::min(x1, static_cast<int>(std::floor(cx + half - 0.5)));
      for (int x = from; x <= to; ++x) {
        float& texel = row[x >= 0 && x < n ? x : ((x % n) + n) % n];
        if (texel < 0.0f) {
          texel = value;
          --uncovered;
        }
      }
    }
  }
  const float mean = static_cast<float>(config.mean_intensity);
  texture.forEach<float>([mean](float& value, const int*) {
    if (value < 0.0f) value = mean;
  });
  // Anti-aliasing of the disc edges (wrapping border keeps the tiling seamless).
  cv::Mat padded;
  cv::copyMakeBorder(texture, padded, 4, 4, 4, 4, cv::BORDER_WRAP);
  cv::GaussianBlur(padded, padded, cv::Size(), 0.5, 0.5);
  return padded(cv::Rect(4, 4, n, n)).clone();
}

void RoomSceneConfig::validate() const {
  require(std::isfinite(wall_margin_m) && wall_margin_m >= 0.3,
          "RoomSceneConfig: wall_margin_m must be >= 0.3 m");
  require(std::isfinite(ceiling_height_m) && ceiling_height_m > 1.0,
          "RoomSceneConfig: ceiling_height_m must be > 1 m");
  require(std::isfinite(texture_contrast) && texture_contrast >= 0.0 && texture_contrast <= 2.0,
          "RoomSceneConfig: texture_contrast must lie in [0, 2]");
  require(std::isfinite(metres_per_texel) && metres_per_texel > 0.0,
          "RoomSceneConfig: metres_per_texel must be positive");
  require(box_count >= 0 && box_count <= 100, "RoomSceneConfig: box_count must lie in [0, 100]");
}

void addBox(Scene& scene, const Eigen::Vector3d& min, const Eigen::Vector3d& max,
            const cv::Mat& texture, double metres_per_texel, const Eigen::Vector3f& colour) {
  require(min.allFinite() && max.allFinite() && (max - min).minCoeff() > 0.0,
          "addBox: max must exceed min on every axis");
  const Eigen::Vector3d size = max - min;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d ey = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  // Top (z = max), and the four sides; axes chosen right-handed, normals outward.
  addRectangle(scene, Eigen::Vector3d(min.x(), min.y(), max.z()), ex, ey, size.x(), size.y(),
               texture, metres_per_texel, colour, ez);
  addRectangle(scene, min, ez, ex, size.z(), size.x(), texture, metres_per_texel, colour, -ey);
  addRectangle(scene, Eigen::Vector3d(min.x(), max.y(), min.z()), ex, ez, size.x(), size.z(),
               texture, metres_per_texel, colour, ey);
  addRectangle(scene, min, ey, ez, size.y(), size.z(), texture, metres_per_texel, colour, -ex);
  addRectangle(scene, Eigen::Vector3d(max.x(), min.y(), min.z()), ez, ey, size.z(), size.y(),
               texture, metres_per_texel, colour, ex);
}

namespace {

struct Footprint {
  Eigen::Vector2d min, max;
};

// Whether f comes closer than `gap` metres to any of `others`.
bool clashes(const Footprint& f, const std::vector<Footprint>& others, double gap) {
  for (const Footprint& o : others) {
    if (f.min.x() < o.max.x() + gap && o.min.x() < f.max.x() + gap && f.min.y() < o.max.y() + gap &&
        o.min.y() < f.max.y() + gap) {
      return true;
    }
  }
  return false;
}

// Where the optical axes meet the table height at 0.3-3 m from the camera: median x and y
// (the centre of the path's box if they never do).
Eigen::Vector2d lookedAtPoint(const Trajectory& trajectory, double height,
                              const Eigen::Vector2d& fallback) {
  std::vector<double> xs, ys;
  for (std::size_t i = 0; i < trajectory.size();
       i += std::max<std::size_t>(1, trajectory.size() / 400)) {
    const Eigen::Vector3d axis = trajectory[i].orientation.normalized() * Eigen::Vector3d::UnitZ();
    if (axis.z() > -0.2) continue;
    const double s = (height - trajectory[i].position.z()) / axis.z();
    if (s < 0.3 || s > 3.0) continue;
    const Eigen::Vector3d hit = trajectory[i].position + s * axis;
    xs.push_back(hit.x());
    ys.push_back(hit.y());
  }
  if (xs.empty()) return fallback;
  std::nth_element(xs.begin(), xs.begin() + xs.size() / 2, xs.end());
  std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
  return {xs[xs.size() / 2], ys[ys.size() / 2]};
}

// makeRoomScene in its steps. The order of the texture() calls and of the random draws is
// part of the scene a seed gives.
class RoomBuilder {
 public:
  RoomBuilder(const Eigen::Vector3d& room_min, const Eigen::Vector3d& room_max,
              const RoomSceneConfig& config)
      : config_(config),
        room_min_(room_min),
        room_max_(room_max),
        room_size_(room_max - room_min),
        mpt_(config.metres_per_texel),
        texture_seed_(config.seed * 1000),
        rng_(config.seed) {
    scene_.background_intensity = 0.3;
  }

  // Floor, ceiling, four walls; normals point into the room.
  void addShell() {
    const Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d ey = Eigen::Vector3d::UnitY();
    const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
    const Eigen::Vector3f wall_colour(0.95f, 0.92f, 0.85f);
    const Eigen::Vector3d& lo = room_min_;
    const Eigen::Vector3d& size = room_size_;
    addRectangle(scene_, lo, ex, ey, size.x(), size.y(), texture(1024, 0.35, 1.0), mpt_,
                 Eigen::Vector3f(0.75f, 0.7f, 0.65f), ez);
    addRectangle(scene_, Eigen::Vector3d(lo.x(), lo.y(), room_max_.z()), ey, ex, size.y(), size.x(),
                 texture(512, 0.7, 0.4), 2.0 * mpt_, Eigen::Vector3f::Ones(), -ez);
    addRectangle(scene_, lo, ez, ey, size.z(), size.y(), texture(1024, 0.6, 1.0), mpt_, wall_colour,
                 ex);
    addRectangle(scene_, Eigen::Vector3d(room_max_.x(), lo.y(), 0.0), ey, ez, size.y(), size.z(),
                 texture(1024, 0.6, 1.0), mpt_, wall_colour, -ex);
    addRectangle(scene_, lo, ex, ez, size.x(), size.z(), texture(1024, 0.55, 1.0), mpt_,
                 Eigen::Vector3f(0.85f, 0.9f, 0.95f), ey);
    addRectangle(scene_, Eigen::Vector3d(lo.x(), room_max_.y(), 0.0), ez, ex, size.z(), size.x(),
                 texture(1024, 0.55, 1.0), mpt_, Eigen::Vector3f(0.85f, 0.9f, 0.95f), -ey);
  }

  // Shelf against the +y wall, centred in x.
  void addShelf() {
    const double width = std::min(1.2, 0.5 * room_size_.x());
    const Eigen::Vector3d min(room_min_.x() + 0.5 * (room_size_.x() - width), room_max_.y() - 0.35,
                              0.0);
    const Eigen::Vector3d max(min.x() + width, room_max_.y() - 0.01, 1.8);
    addBox(scene_, min, max, texture(256, 0.5, 1.2), mpt_, Eigen::Vector3f(0.6f, 0.45f, 0.3f));
    occupied_.push_back({min.head<2>(), max.head<2>()});
  }

  // A 1.6 x 0.8 m table where the camera looks, kept off the walls.
  void addTable(const Eigen::Vector2d& looked_at) {
    const Eigen::Vector2d half(0.8, 0.4);
    const Eigen::Vector2d centre =
        looked_at.cwiseMax(room_min_.head<2>() + half + Eigen::Vector2d(0.3, 0.3))
            .cwiseMin(room_max_.head<2>() - half - Eigen::Vector2d(0.5, 0.5));
    table_ = {centre - half, centre + half};
    const cv::Mat top = texture(256, 0.55, 0.6);
    addBox(scene_, Eigen::Vector3d(table_.min.x(), table_.min.y(), kTableHeight - 0.03),
           Eigen::Vector3d(table_.max.x(), table_.max.y(), kTableHeight), top, mpt_,
           Eigen::Vector3f(0.8f, 0.6f, 0.4f));
    const cv::Mat leg = texture(64, 0.3, 0.5);
    for (int i = 0; i < 4; ++i) {
      const double x = (i & 1) ? table_.max.x() - 0.08 : table_.min.x() + 0.03;
      const double y = (i & 2) ? table_.max.y() - 0.08 : table_.min.y() + 0.03;
      addBox(scene_, Eigen::Vector3d(x, y, 0.0),
             Eigen::Vector3d(x + 0.05, y + 0.05, kTableHeight - 0.03), leg, mpt_,
             Eigen::Vector3f(0.4f, 0.4f, 0.4f));
    }
    occupied_.push_back(table_);
  }

  // Boxes: every second one on the table (if any), the others on the floor; each placed at the
  // first of 100 random spots where it clashes with nothing.
  void addBoxes() {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int i = 0; i < config_.box_count; ++i) {
      const bool table_box = config_.with_table && (i % 2 == 0);
      const Eigen::Vector3f colour(static_cast<float>(0.5 + 0.5 * uniform(rng_)),
                                   static_cast<float>(0.5 + 0.5 * uniform(rng_)),
                                   static_cast<float>(0.5 + 0.5 * uniform(rng_)));
      const cv::Mat box_texture =
          texture(256, 0.35 + 0.35 * uniform(rng_), 1.0 + 0.4 * uniform(rng_));
      for (int attempt = 0; attempt < 100; ++attempt) {
        Eigen::Vector3d size;
        Eigen::Vector2d lo_xy, hi_xy;
        double base = 0.0;
        if (table_box) {
          size = Eigen::Vector3d(0.1 + 0.25 * uniform(rng_), 0.1 + 0.2 * uniform(rng_),
                                 0.08 + 0.25 * uniform(rng_));
          lo_xy = table_.min + Eigen::Vector2d(0.05, 0.05);
          hi_xy = table_.max - Eigen::Vector2d(0.05, 0.05) - size.head<2>();
          base = kTableHeight;
        } else {
          size = Eigen::Vector3d(0.25 + 0.4 * uniform(rng_), 0.25 + 0.4 * uniform(rng_),
                                 0.2 + 0.5 * uniform(rng_));
          lo_xy = room_min_.head<2>() + Eigen::Vector2d(0.2, 0.2);
          hi_xy = room_max_.head<2>() - Eigen::Vector2d(0.2, 0.2) - size.head<2>();
        }
        if ((hi_xy - lo_xy).minCoeff() <= 0.0) break;
        const Eigen::Vector2d corner(lo_xy.x() + uniform(rng_) * (hi_xy.x() - lo_xy.x()),
                                     lo_xy.y() + uniform(rng_) * (hi_xy.y() - lo_xy.y()));
        const Footprint footprint{corner, corner + size.head<2>()};
        std::vector<Footprint>& group = table_box ? on_table_ : occupied_;
        if (clashes(footprint, group, 0.05) || (!table_box && clashes(footprint, occupied_, 0.1))) {
          continue;
        }
        group.push_back(footprint);
        addBox(scene_, Eigen::Vector3d(corner.x(), corner.y(), base),
               Eigen::Vector3d(corner.x() + size.x(), corner.y() + size.y(), base + size.z()),
               box_texture, mpt_, colour);
        break;
      }
    }
  }

  Scene take() { return std::move(scene_); }

  static constexpr double kTableHeight = 0.75;  // [m]

 private:
  cv::Mat texture(int size, double mean, double contrast_scale) {
    DeadLeavesConfig leaves;
    leaves.size_px = size;
    leaves.mean_intensity = mean;
    leaves.contrast = std::min(2.0, config_.texture_contrast * contrast_scale);
    leaves.max_radius_px = size / 6.0;
    leaves.seed = ++texture_seed_;
    return makeDeadLeavesTexture(leaves);
  }

  const RoomSceneConfig& config_;
  const Eigen::Vector3d room_min_, room_max_, room_size_;
  const double mpt_;
  std::uint64_t texture_seed_;
  std::mt19937_64 rng_;
  Scene scene_;
  std::vector<Footprint> occupied_, on_table_;
  Footprint table_{};
};

}  // namespace

Scene makeRoomScene(const Trajectory& trajectory, const RoomSceneConfig& config) {
  config.validate();
  require(!trajectory.empty(), "makeRoomScene: the trajectory is empty");
  Eigen::Vector3d lo = trajectory.front().position;
  Eigen::Vector3d hi = lo;
  for (const StampedPose& pose : trajectory) {
    require(pose.position.allFinite(), "makeRoomScene: trajectory position is not finite");
    lo = lo.cwiseMin(pose.position);
    hi = hi.cwiseMax(pose.position);
  }
  const double margin = config.wall_margin_m;
  RoomBuilder room(Eigen::Vector3d(lo.x() - margin, lo.y() - margin, 0.0),
                   Eigen::Vector3d(hi.x() + margin, hi.y() + margin, config.ceiling_height_m),
                   config);
  room.addShell();
  room.addShelf();
  if (config.with_table) {
    room.addTable(lookedAtPoint(trajectory, RoomBuilder::kTableHeight, 0.5 * (lo + hi).head<2>()));
  }
  room.addBoxes();
  return room.take();
}

}  // namespace ebslam
