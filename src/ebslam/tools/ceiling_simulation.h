#pragma once

// The simulated floor-robot runs of the EB-PF / EB-SLAM-2D experiments (not a tool itself): an
// eDVS 2.59 m under a ceiling of random lines and circles (thesis 6.5.3) driven along a planar
// robot path, its events, ground truth and the ceiling's Canny edge map, cached in a folder.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ebslam/events/event_io.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/ebpf.h"
#include "ebslam/slam/grid_map2f.h"

namespace ebslam::tools {

/// One simulated run.
struct Simulated {
  EventVector events;
  std::vector<std::uint8_t> noise_labels;  // 1 = background noise; empty if not known
  Trajectory ground_truth;
  CeilingMap map;
};

/// Simulates the floor-robot camera path `floor` (camera poses, z up; e.g.
/// makeFloorRobotTrajectory of a motion-capture run) for its first duration_s [s] (0 = all), or
/// reads the cached simulation from `dir`. `camera`: the upward camera (any size and lens).
/// contrast_threshold > 0 replaces the simulator's ON and OFF contrast thresholds (a lower one
/// gives a denser stream).
inline Simulated simulateFloorRun(const Trajectory& floor, const std::filesystem::path& dir,
                                  double duration_s, std::uint64_t seed, double noise_rate_hz,
                                  const CameraModel& camera = CameraModel{},
                                  double contrast_threshold = 0.0) {
  namespace fs = std::filesystem;
  Simulated s;
  const fs::path events_path = dir / "events.ebe";
  const fs::path labels_path = dir / "noise_labels.bin";
  const fs::path gt_path = dir / "ground_truth.tum";
  const fs::path edges_path = dir / "ceiling_edges.png";
  const fs::path meta_path = dir / "ceiling_map.txt";
  SimulatorConfig sim;
  sim.camera = camera;
  sim.events.seed = seed;
  sim.events.noise_rate_hz_per_pixel = noise_rate_hz;
  if (contrast_threshold > 0.0) {
    sim.events.contrast_threshold_on = contrast_threshold;
    sim.events.contrast_threshold_off = contrast_threshold;
  }
  if (fs::exists(events_path) && fs::exists(gt_path) && fs::exists(edges_path) &&
      fs::exists(meta_path)) {
    s.events = readEventFile(events_path.string()).events;
    if (fs::exists(labels_path)) {
      std::ifstream in(labels_path, std::ios::binary);
      s.noise_labels.resize(s.events.size());
      in.read(reinterpret_cast<char*>(s.noise_labels.data()),
              static_cast<std::streamsize>(s.noise_labels.size()));
      if (!in) s.noise_labels.clear();
    }
    s.ground_truth = readTumTrajectory(gt_path.string());
    s.map.edges = cv::imread(edges_path.string(), cv::IMREAD_GRAYSCALE);
    std::ifstream meta(meta_path);
    meta >> s.map.metres_per_pixel >> s.map.origin_m.x() >> s.map.origin_m.y();
    return s;
  }
  fs::create_directories(dir);
  const double t0 = floor.front().t_s;
  const double t1 =
      duration_s > 0.0 ? std::min(floor.back().t_s, t0 + duration_s) : floor.back().t_s;
  Trajectory used;
  for (const StampedPose& p : floor) {
    if (p.t_s <= t1 + 0.1) used.push_back(p);
  }
  const FloorRegion region = visibleCeilingRegion(used, sim.camera);
  LinesAndCirclesConfig texture_config;  // thesis 6.5.3: random lines and circles
  texture_config.seed = seed;
  const double metres_per_texel = 0.01;
  texture_config.width_px = static_cast<int>((region.max.x() - region.min.x()) / 0.01) + 1;
  texture_config.height_px = static_cast<int>((region.max.y() - region.min.y()) / 0.01) + 1;
  // Keep the density of the default texture (40 lines, 25 circles per 10.24 m x 10.24 m).
  const double area_factor =
      (texture_config.width_px * texture_config.height_px) / (1024.0 * 1024.0);
  texture_config.line_count = static_cast<int>(std::lround(40 * area_factor));
  texture_config.circle_count = static_cast<int>(std::lround(25 * area_factor));
  const cv::Mat texture = makeLinesAndCirclesTexture(texture_config);
  const Scene scene = makeCeilingScene(texture, region, metres_per_texel);
  const EventSimulator simulator(sim);
  SimulationResult result = simulator.simulate(scene, used, t0, t1);
  s.events = std::move(result.events);
  s.noise_labels = std::move(result.noise_labels);
  s.ground_truth = std::move(result.ground_truth);
  // Known ceiling map for EB-PF as in fig. 6.8: Canny edges of the ceiling image (here the
  // texture itself, blurred to about half a sensor pixel on the ceiling like CeilingMapConfig).
  // Canny puts an edge on one of the two pixels straddling it, a bias of up to half a pixel; at
  // twice the texture resolution that bias is 2.5 mm. Pixel (col, row) of the edge image covers
  // region.min + [col, col + 1) * metres_per_texel / 2 (cv::resize keeps pixel centres).
  cv::Mat texture8, upsampled, blurred;
  texture.convertTo(texture8, CV_8U, 255.0);
  cv::resize(texture8, upsampled, cv::Size(), 2.0, 2.0, cv::INTER_LINEAR);
  const double edge_pixel_m = 0.5 * metres_per_texel;
  cv::GaussianBlur(upsampled, blurred, cv::Size(), 0.015 / edge_pixel_m);
  cv::Canny(blurred, s.map.edges, 20, 50);
  s.map.intensity = texture;
  s.map.metres_per_pixel = edge_pixel_m;
  s.map.origin_m = region.min + Eigen::Vector2d::Constant(0.5 * edge_pixel_m);
  writeEventFile(events_path.string(), s.events,
                 SensorSize{static_cast<std::uint32_t>(camera.width),
                            static_cast<std::uint32_t>(camera.height)});
  {
    std::ofstream out(labels_path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(s.noise_labels.data()),
              static_cast<std::streamsize>(s.noise_labels.size()));
  }
  writeTumTrajectory(gt_path.string(), s.ground_truth);
  cv::imwrite(edges_path.string(), s.map.edges);
  cv::Mat intensity8;
  s.map.intensity.convertTo(intensity8, CV_8U, 255.0);
  cv::imwrite((dir / "ceiling.png").string(), intensity8);
  std::ofstream meta(meta_path);
  meta.precision(12);
  meta << s.map.metres_per_pixel << ' ' << s.map.origin_m.x() << ' ' << s.map.origin_m.y() << '\n';
  return s;
}

/// EB-PF's sensor model cached on a 1 cm grid (2 x 2 means of the 5 mm one, which keeps cell
/// centres): a quarter of the memory, so the per-event lookups stay in cache.
inline GridMap2f coarseLikelihood(const CeilingMap& map, const CeilingCamera& camera) {
  const GridMap2f fine = makeEdgeLikelihoodMap(map.edges, map.metres_per_pixel, map.origin_m,
                                               EbpfConfig{}.gamma * camera.wTrig());
  GridMap2f coarse(fine.width / 2, fine.height / 2, 2.0 * fine.resolution_m, fine.origin_x_m,
                   fine.origin_y_m);
  for (int r = 0; r < coarse.height; ++r) {
    for (int c = 0; c < coarse.width; ++c) {
      coarse.at(c, r) = 0.25f * (fine.at(2 * c, 2 * r) + fine.at(2 * c + 1, 2 * r) +
                                 fine.at(2 * c, 2 * r + 1) + fine.at(2 * c + 1, 2 * r + 1));
    }
  }
  return coarse;
}

}  // namespace ebslam::tools
