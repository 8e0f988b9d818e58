#pragma once

// Internal to the D-eDVS simulator (dedvs_simulator.cpp): the ray-casting renderer of a Scene of
// textured planes for the eDVS and the depth camera (depth, colour and intensity per pixel).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ebslam/simulation/dedvs_simulator.h"

namespace ebslam {
namespace dedvs_render {

constexpr float kNoHit = std::numeric_limits<float>::infinity();

// The viewing rays of a camera (z = 1 in its frame) in tiles of 16 x 16 pixels, each tile with
// the bounding box of its rays' (x, y): planes are only tested against tiles whose box meets
// the plane's image.
struct RayGrid {
  int width = 0;
  int height = 0;
  double focal_px = 1.0;          // for the pixel footprint
  std::vector<float> x, y, norm;  // per pixel, row-major; norm = |(x, y, 1)|
  struct Tile {
    int x0, y0, x1, y1;  // pixel range [x0, x1) x [y0, y1)
    float min_x, max_x, min_y, max_y;
  };
  std::vector<Tile> tiles;

  template <typename RayOf>
  void build(int w, int h, double focal, RayOf ray_of) {
    width = w;
    height = h;
    focal_px = focal;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    x.resize(n);
    y.resize(n);
    norm.resize(n);
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const Eigen::Vector2d xy = ray_of(col, row);
        const std::size_t i = static_cast<std::size_t>(row) * w + col;
        x[i] = static_cast<float>(xy.x());
        y[i] = static_cast<float>(xy.y());
        norm[i] = static_cast<float>(std::sqrt(xy.squaredNorm() + 1.0));
      }
    }
    constexpr int kTile = 16;
    for (int ty = 0; ty < h; ty += kTile) {
      for (int tx = 0; tx < w; tx += kTile) {
        Tile tile{tx,
                  ty,
                  std::min(w, tx + kTile),
                  std::min(h, ty + kTile),
                  std::numeric_limits<float>::max(),
                  -std::numeric_limits<float>::max(),
                  std::numeric_limits<float>::max(),
                  -std::numeric_limits<float>::max()};
        for (int row = tile.y0; row < tile.y1; ++row) {
          for (int col = tile.x0; col < tile.x1; ++col) {
            const std::size_t i = static_cast<std::size_t>(row) * w + col;
            tile.min_x = std::min(tile.min_x, x[i]);
            tile.max_x = std::max(tile.max_x, x[i]);
            tile.min_y = std::min(tile.min_y, y[i]);
            tile.max_y = std::max(tile.max_y, y[i]);
          }
        }
        tiles.push_back(tile);
      }
    }
  }
};

// A plane with its texture pyramid; geometry in the world (updated for moving planes).
struct PreparedPlane {
  std::vector<cv::Mat> pyramid;   // CV_32FC1; level k has 2^-k the resolution
  double texels_per_metre = 1.0;  // at level 0
  Eigen::Vector3d origin, axis_u, axis_v, normal;
  double size_u = 0.0, size_v = 0.0;
  Eigen::Vector3f colour = Eigen::Vector3f::Ones();
  bool repeat = true;

  void setPose(const Eigen::Isometry3d& pose) {
    origin = pose.translation();
    axis_u = pose.linear().col(0).normalized();
    axis_v = pose.linear().col(1).normalized();
    normal = pose.linear().col(2).normalized();
  }
};

// Per-pixel hits of one render: ray parameter lambda (= z in the camera frame, rays have
// z = 1), plane index and plane coordinates [m].
struct Hits {
  std::vector<float> z;
  std::vector<int> plane;
  std::vector<float> u, v;
  void reset(std::size_t n) {
    z.assign(n, kNoHit);
    plane.assign(n, -1);
    u.resize(n);
    v.resize(n);
  }
};

class RoomRenderer {
 public:
  explicit RoomRenderer(const Scene& scene) {
    for (const TexturedPlane& plane : scene.planes) {
      PreparedPlane prepared;
      prepared.setPose(plane.pose);
      prepared.size_u = plane.size_m.x();
      prepared.size_v = plane.size_m.y();
      prepared.colour = plane.colour;
      prepared.repeat = plane.repeat;
      prepared.texels_per_metre = 1.0 / plane.metres_per_texel;
      cv::Mat level = textureFromImage(plane.texture);
      prepared.pyramid.push_back(level);
      while (level.cols >= 8 && level.rows >= 8 && prepared.pyramid.size() < 12) {
        cv::Mat next;
        cv::pyrDown(level, next);
        prepared.pyramid.push_back(next);
        level = next;
      }
      planes_.push_back(std::move(prepared));
    }
    background_ = static_cast<float>(scene.background_intensity);
  }

  std::vector<PreparedPlane>& planes() { return planes_; }

  // Nearest hit per pixel of `grid` seen from `camera` (camera -> world).
  void trace(const Eigen::Isometry3d& camera, const RayGrid& grid, Hits& hits) const {
    const std::size_t n = grid.x.size();
    hits.reset(n);
    const Eigen::Matrix3d rt = camera.linear().transpose();
    const Eigen::Vector3d t = camera.translation();
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      const PreparedPlane& p = planes_[k];
      // Image of the plane's rectangle: corners into the camera frame, clipped at z = 0.01 m,
      // bounding box of x / z, y / z.
      const Eigen::Vector3d corners[4] = {p.origin, p.origin + p.size_u * p.axis_u,
                                          p.origin + p.size_u * p.axis_u + p.size_v * p.axis_v,
                                          p.origin + p.size_v * p.axis_v};
      Eigen::Vector3d in_camera[4];
      for (int c = 0; c < 4; ++c) in_camera[c] = rt * (corners[c] - t);
      constexpr double kNear = 0.01;
      double min_x = std::numeric_limits<double>::max(), max_x = -min_x;
      double min_y = min_x, max_y = -min_x;
      bool any = false;
      auto include = [&](const Eigen::Vector3d& q) {
        min_x = std::min(min_x, q.x() / q.z());
        max_x = std::max(max_x, q.x() / q.z());
        min_y = std::min(min_y, q.y() / q.z());
        max_y = std::max(max_y, q.y() / q.z());
        any = true;
      };
      for (int c = 0; c < 4; ++c) {
        const Eigen::Vector3d& a = in_camera[c];
        const Eigen::Vector3d& b = in_camera[(c + 1) % 4];
        if (a.z() >= kNear) include(a);
        if ((a.z() >= kNear) != (b.z() >= kNear)) {
          const double s = (kNear - a.z()) / (b.z() - a.z());
          include(a + s * (b - a));
        }
      }
      if (!any) continue;
      const Eigen::Vector3d n_c = rt * p.normal;
      const double h = p.normal.dot(p.origin - t);
      if (std::abs(h) < 1e-9) continue;  // camera in the plane: sees it edge-on
      const Eigen::Vector3d au_c = rt * p.axis_u;
      const Eigen::Vector3d av_c = rt * p.axis_v;
      const double cu = p.axis_u.dot(t - p.origin);
      const double cv_ = p.axis_v.dot(t - p.origin);
      const float nx = static_cast<float>(n_c.x()), ny = static_cast<float>(n_c.y()),
                  nz = static_cast<float>(n_c.z());
      const float ux = static_cast<float>(au_c.x()), uy = static_cast<float>(au_c.y()),
                  uz = static_cast<float>(au_c.z());
      const float vx = static_cast<float>(av_c.x()), vy = static_cast<float>(av_c.y()),
                  vz = static_cast<float>(av_c.z());
      const float hf = static_cast<float>(h), cuf = static_cast<float>(cu),
                  cvf = static_cast<float>(cv_);
      const float su = static_cast<float>(p.size_u), sv = static_cast<float>(p.size_v);
      const int plane_index = static_cast<int>(k);
      for (const RayGrid::Tile& tile : grid.tiles) {
        if (tile.max_x < min_x || tile.min_x > max_x || tile.max_y < min_y || tile.min_y > max_y) {
          continue;
        }
        for (int row = tile.y0; row < tile.y1; ++row) {
          const std::size_t base = static_cast<std::size_t>(row) * grid.width;
          for (std::size_t i = base + tile.x0; i < base + tile.x1; ++i) {
            const float x = grid.x[i], y = grid.y[i];
            const float den = nx * x + ny * y + nz;
            const float lambda = hf / den;
            if (!(lambda > 0.0f && lambda < hits.z[i])) continue;
            const float u = cuf + lambda * (ux * x + uy * y + uz);
            const float v = cvf + lambda * (vx * x + vy * y + vz);
            if (u < 0.0f || v < 0.0f || u > su || v > sv) continue;
            hits.z[i] = lambda;
            hits.plane[i] = plane_index;
            hits.u[i] = u;
            hits.v[i] = v;
          }
        }
      }
    }
  }

  // Intensity per pixel from the hits (texture at the footprint's mip level, trilinear).
  void shade(const Eigen::Isometry3d& camera, const RayGrid& grid, const Hits& hits,
             std::vector<float>& intensity) const {
    const std::size_t n = grid.x.size();
    intensity.resize(n);
    const Eigen::Matrix3d rt = camera.linear().transpose();
    normals_.resize(planes_.size());
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      normals_[k] = (rt * planes_[k].normal).cast<float>();
    }
    const float inv_focal = static_cast<float>(1.0 / grid.focal_px);
    for (std::size_t i = 0; i < n; ++i) {
      const int k = hits.plane[i];
      if (k < 0) {
        intensity[i] = background_;
        continue;
      }
      const PreparedPlane& p = planes_[static_cast<std::size_t>(k)];
      const Eigen::Vector3f& n_c = normals_[static_cast<std::size_t>(k)];
      const float cos_incidence = std::max(
          0.05f, std::abs(n_c.x() * grid.x[i] + n_c.y() * grid.y[i] + n_c.z()) / grid.norm[i]);
      // Footprint [texels at level 0]: distance / f across the ray, stretched by the
      // incidence along the slant (geometric mean of the two axes).
      const float footprint = hits.z[i] * grid.norm[i] * inv_focal / std::sqrt(cos_incidence) *
                              static_cast<float>(p.texels_per_metre);
      const float level = std::clamp(std::log2(std::max(footprint, 1e-6f)), 0.0f,
                                     static_cast<float>(p.pyramid.size() - 1));
      const int l0 = static_cast<int>(level);
      const int l1 = std::min<int>(l0 + 1, static_cast<int>(p.pyramid.size()) - 1);
      const float a = level - static_cast<float>(l0);
      const float s0 = sample(p, l0, hits.u[i], hits.v[i]);
      const float s1 = a > 0.0f ? sample(p, l1, hits.u[i], hits.v[i]) : s0;
      intensity[i] = s0 + a * (s1 - s0);
    }
  }

  // Plane index and plane coordinates -> texture value at a mip level (bilinear, tiled).
  float sample(const PreparedPlane& p, int level, float u_m, float v_m) const {
    const cv::Mat& texture = p.pyramid[static_cast<std::size_t>(level)];
    const float scale = static_cast<float>(p.texels_per_metre) / static_cast<float>(1 << level);
    const float x = u_m * scale - 0.5f;
    const float y = v_m * scale - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    int x1 = x0 + 1, y1 = y0 + 1;
    const int cols = texture.cols, rows = texture.rows;
    if (p.repeat && (cols & (cols - 1)) == 0 && (rows & (rows - 1)) == 0) {
      x0 &= cols - 1;  // power-of-two sizes (two's complement: also for negative x0)
      y0 &= rows - 1;
      x1 = (x0 + 1) & (cols - 1);
      y1 = (y0 + 1) & (rows - 1);
    } else if (p.repeat) {
      x0 = ((x0 % cols) + cols) % cols;
      y0 = ((y0 % rows) + rows) % rows;
      x1 = x0 + 1 == cols ? 0 : x0 + 1;
      y1 = y0 + 1 == rows ? 0 : y0 + 1;
    } else {
      x0 = std::clamp(x0, 0, cols - 1);
      x1 = std::clamp(x1, 0, cols - 1);
      y0 = std::clamp(y0, 0, rows - 1);
      y1 = std::clamp(y1, 0, rows - 1);
    }
    const float* r0 = texture.ptr<float>(y0);
    const float* r1 = texture.ptr<float>(y1);
    const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
    const float bottom = r1[x0] + ax * (r1[x1] - r1[x0]);
    return top + ay * (bottom - top);
  }

  float background() const { return background_; }

 private:
  std::vector<PreparedPlane> planes_;
  float background_ = 0.5f;
  mutable std::vector<Eigen::Vector3f> normals_;
};

}  // namespace dedvs_render
}  // namespace ebslam
