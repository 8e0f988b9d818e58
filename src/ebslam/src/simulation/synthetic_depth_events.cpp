#include "ebslam/simulation/synthetic_depth_events.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace ebslam {

std::vector<Eigen::Vector3f> makeSyntheticRoom(const Trajectory& path,
                                               const SyntheticRoomConfig& config) {
  if (path.empty()) throw std::invalid_argument("makeSyntheticRoom: empty path");
  if (!(config.point_spacing_m > 0.0) || !(config.margin_m > 0.0) ||
      config.edges_per_square_m < 0) {
    throw std::invalid_argument("makeSyntheticRoom: spacing and margin must be positive");
  }
  Eigen::Vector3d lo = path.front().position, hi = path.front().position;
  for (const StampedPose& p : path) {
    lo = lo.cwiseMin(p.position);
    hi = hi.cwiseMax(p.position);
  }
  lo.array() -= config.margin_m;
  hi.array() += config.margin_m;
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3f> points;
  const auto addSegment = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double length = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(length / config.point_spacing_m)));
    for (int k = 0; k <= n; ++k) {
      points.push_back((a + (b - a) * (static_cast<double>(k) / n)).cast<float>());
    }
  };
  // The room's own twelve edges.
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int corner = 0; corner < 4; ++corner) {
      Eigen::Vector3d a, b;
      a[u] = b[u] = (corner & 1) ? hi[u] : lo[u];
      a[v] = b[v] = (corner & 2) ? hi[v] : lo[v];
      a[axis] = lo[axis];
      b[axis] = hi[axis];
      addSegment(a, b);
    }
  }
  // Texture on each face: axis-aligned rectangles (posters) and free lines.
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double area = (hi[u] - lo[u]) * (hi[v] - lo[v]);
    for (int side = 0; side < 2; ++side) {
      const double plane = side ? hi[axis] : lo[axis];
      const int count = static_cast<int>(std::lround(area * config.edges_per_square_m));
      for (int k = 0; k < count; ++k) {
        const auto onFace = [&](double su, double sv) {
          Eigen::Vector3d p;
          p[axis] = plane;
          p[u] = lo[u] + su * (hi[u] - lo[u]);
          p[v] = lo[v] + sv * (hi[v] - lo[v]);
          return p;
        };
        const double su = unit(rng), sv = unit(rng);
        if (unit(rng) < 0.5) {
          // Rectangle of 0.1-0.6 m sides (four edges, counted as one texture item).
          const double du = (0.1 + 0.5 * unit(rng)) / (hi[u] - lo[u]);
          const double dv = (0.1 + 0.5 * unit(rng)) / (hi[v] - lo[v]);
          const double u1 = std::min(1.0, su + du), v1 = std::min(1.0, sv + dv);
          addSegment(onFace(su, sv), onFace(u1, sv));
          addSegment(onFace(u1, sv), onFace(u1, v1));
          addSegment(onFace(u1, v1), onFace(su, v1));
          addSegment(onFace(su, v1), onFace(su, sv));
        } else {
          const double angle = unit(rng) * M_PI;
          const double len = 0.2 + 0.8 * unit(rng);
          const double su1 = std::clamp(su + len * std::cos(angle) / (hi[u] - lo[u]), 0.0, 1.0);
          const double sv1 = std::clamp(sv + len * std::sin(angle) / (hi[v] - lo[v]), 0.0, 1.0);
          addSegment(onFace(su, sv), onFace(su1, sv1));
        }
      }
    }
  }
  return points;
}

PointEventVector simulateDepthEvents(const std::vector<Eigen::Vector3f>& scene,
                                     const SyntheticDepthSensor& sensor, const Trajectory& path,
                                     double t0_s, double t1_s, const SyntheticEventConfig& config) {
  if (!(t1_s > t0_s) || !(config.step_s > 0.0) || !(config.noise_share >= 0.0) ||
      sensor.width < 1 || sensor.height < 1 || !(sensor.focal_px > 0.0)) {
    throw std::invalid_argument("simulateDepthEvents: invalid time range, step or sensor");
  }
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto f = static_cast<float>(sensor.focal_px);
  const auto cx = static_cast<float>(sensor.cx), cy = static_cast<float>(sensor.cy);
  const auto zmin = static_cast<float>(sensor.min_depth_m);
  const auto zmax = static_cast<float>(sensor.max_depth_m);
  constexpr std::int32_t kNotVisible = -1;
  std::vector<std::int32_t> previous(scene.size(), kNotVisible);
  PointEventVector events;
  const auto emit = [&](std::int64_t t_us, int u, int v, float z) {
    const float zn = z + static_cast<float>(sensor.depth_noise_per_m2) * z * z * normal(rng);
    PointEvent e;
    e.t_us = t_us;
    e.point = Eigen::Vector3f((static_cast<float>(u) + 0.5f - cx) / f * zn,
                              (static_cast<float>(v) + 0.5f - cy) / f * zn, zn);
    events.push_back(e);
  };
  const auto steps = static_cast<std::int64_t>(std::floor((t1_s - t0_s) / config.step_s));
  double noise_debt = 0.0;
  for (std::int64_t s = 0; s <= steps; ++s) {
    const double t = t0_s + static_cast<double>(s) * config.step_s;
    const StampedPose pose = interpolatePose(path, t);
    const Eigen::Matrix3f r_t = pose.orientation.toRotationMatrix().transpose().cast<float>();
    const Eigen::Vector3f c = pose.position.cast<float>();
    const auto t_us = static_cast<std::int64_t>(std::llround(t * 1e6));
    const std::size_t before = events.size();
    for (std::size_t k = 0; k < scene.size(); ++k) {
      const Eigen::Vector3f p = r_t * (scene[k] - c);
      std::int32_t pixel = kNotVisible;
      int u = 0, v = 0;
      if (p.z() >= zmin && p.z() <= zmax) {
        const float fu = f * p.x() / p.z() + cx, fv = f * p.y() / p.z() + cy;
        if (fu >= 0.0f && fv >= 0.0f && fu < sensor.width && fv < sensor.height) {
          u = static_cast<int>(fu);
          v = static_cast<int>(fv);
          pixel = v * sensor.width + u;
        }
      }
      if (pixel != kNotVisible && previous[k] != kNotVisible && pixel != previous[k]) {
        emit(t_us, u, v, p.z());
      }
      previous[k] = pixel;
    }
    noise_debt += config.noise_share * static_cast<double>(events.size() - before);
    while (noise_debt >= 1.0) {
      noise_debt -= 1.0;
      const int u = static_cast<int>(unit(rng) * sensor.width);
      const int v = static_cast<int>(unit(rng) * sensor.height);
      emit(t_us, std::min(u, sensor.width - 1), std::min(v, sensor.height - 1),
           static_cast<float>(sensor.min_depth_m +
                              unit(rng) * (sensor.max_depth_m - sensor.min_depth_m)));
    }
  }
  return events;
}

}  // namespace ebslam
