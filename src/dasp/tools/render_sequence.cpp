// dasp_render_sequence: a labelled RGB-D test video made from one real RGB-D frame. The frame's
// depth map is turned into a triangle mesh (neighbouring pixels joined unless a depth jump lies
// between them) and re-rendered with a z-buffer from camera poses along an excerpt of a real
// camera trajectory (TUM format), scaled to small motion and taken relative to its first pose.
// Colour and the human object labels are carried by the mesh, so every frame's ground-truth
// labels are known; surfaces the source camera did not see stay holes (depth 0), as disoccluded
// regions are in a real sensor. Optional Kinect-like depth noise and colour noise (seeded).
//
// Output folder (the OSD layout that dasp::listRgbdFolder reads): frame<k>_rgb.png,
// frame<k>_depth_mm.png, frame<k>_label_object.png (uint16, 0 = no label), and poses.txt with one
// line "k tx ty tz qx qy qz qw" per frame: the pose of camera k in the optical frame of camera 0
// (x right, y down, z forward, metres), i.e. T_0k with p_0 = T_0k p_k.
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dasp/rgbd_io.h"

namespace {

struct StampedPose {
  double time = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera in world
};

std::vector<StampedPose> readTumTrajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read trajectory " + path);
  std::vector<StampedPose> poses;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double t, tx, ty, tz, qx, qy, qz, qw;
    if (!(fields >> t >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) continue;
    StampedPose p;
    p.time = t;
    p.pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    p.pose.translation() = Eigen::Vector3d(tx, ty, tz);
    poses.push_back(p);
  }
  if (poses.size() < 2) throw std::runtime_error("trajectory " + path + " has < 2 poses");
  return poses;
}

// Pose at time t by linear interpolation of translation and slerp of rotation.
Eigen::Isometry3d poseAt(const std::vector<StampedPose>& poses, double t) {
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const StampedPose& p, double time) { return p.time < time; });
  if (it == poses.begin()) return it->pose;
  if (it == poses.end()) return poses.back().pose;
  const StampedPose& b = *it;
  const StampedPose& a = *(it - 1);
  const double s = (t - a.time) / std::max(1e-9, b.time - a.time);
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond qa(a.pose.linear()), qb(b.pose.linear());
  p.linear() = qa.slerp(s, qb).toRotationMatrix();
  p.translation() = (1.0 - s) * a.pose.translation() + s * b.pose.translation();
  return p;
}

// Relative motion scaled down: translation times s, rotation angle times s.
Eigen::Isometry3d scaleMotion(const Eigen::Isometry3d& relative, double s) {
  Eigen::AngleAxisd aa(relative.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() * s, aa.axis()).toRotationMatrix();
  out.translation() = relative.translation() * s;
  return out;
}

struct Vertex {
  Eigen::Vector3f point;  // camera-0 frame, metres
  cv::Vec3f color;        // BGR 0..255
  int label = 0;
  bool valid = false;
};

struct RenderedFrame {
  cv::Mat color, depth_mm, label;
};

// z-buffered rasterisation of the depth mesh seen from camera k (T_k0 maps camera-0 points).
RenderedFrame render(const std::vector<Vertex>& vertices, int width, int height,
                     const dasp::Intrinsics& in, const Eigen::Isometry3f& t_k0,
                     float max_jump_ratio) {
  std::vector<Eigen::Vector3f> projected(vertices.size());  // (u, v, z) in camera k
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (!vertices[i].valid) continue;
    const Eigen::Vector3f p = t_k0 * vertices[i].point;
    projected[i] =
        Eigen::Vector3f(in.fx * p.x() / p.z() + in.cx, in.fy * p.y() / p.z() + in.cy, p.z());
  }
  cv::Mat zbuffer(height, width, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  RenderedFrame out;
  out.color = cv::Mat::zeros(height, width, CV_8UC3);
  out.depth_mm = cv::Mat::zeros(height, width, CV_16UC1);
  out.label = cv::Mat::zeros(height, width, CV_16UC1);
  auto triangle = [&](std::size_t i0, std::size_t i1, std::size_t i2) {
    const Vertex* v[3] = {&vertices[i0], &vertices[i1], &vertices[i2]};
    if (!v[0]->valid || !v[1]->valid || !v[2]->valid) return;
    const float z0 = v[0]->point.z(), z1 = v[1]->point.z(), z2 = v[2]->point.z();
    const float zmin = std::min({z0, z1, z2}), zmax = std::max({z0, z1, z2});
    if (zmax - zmin > max_jump_ratio * zmin) return;  // depth discontinuity: no surface here
    const Eigen::Vector3f& a = projected[i0];
    const Eigen::Vector3f& b = projected[i1];
    const Eigen::Vector3f& c = projected[i2];
    if (a.z() <= 0.05f || b.z() <= 0.05f || c.z() <= 0.05f) return;
    const float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-6f) return;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x1 =
        std::min(width - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y1 =
        std::min(height - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const float px = static_cast<float>(x), py = static_cast<float>(y);
        // Screen-space barycentrics; 1/z is affine in screen space (perspective-correct depth).
        const float w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const float w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const float w2 = 1.0f - w0 - w1;
        constexpr float kEps = -1e-5f;
        if (w0 < kEps || w1 < kEps || w2 < kEps) continue;
        const float inv_z = w0 / a.z() + w1 / b.z() + w2 / c.z();
        const float z = 1.0f / inv_z;
        float& zb = zbuffer.at<float>(y, x);
        if (z >= zb) continue;
        zb = z;
        // Perspective-correct attribute weights.
        const float p0 = w0 / a.z() * z, p1 = w1 / b.z() * z, p2 = w2 / c.z() * z;
        const cv::Vec3f col = v[0]->color * p0 + v[1]->color * p1 + v[2]->color * p2;
        out.color.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<std::uint8_t>(col[0]),
                                                  cv::saturate_cast<std::uint8_t>(col[1]),
                                                  cv::saturate_cast<std::uint8_t>(col[2]));
        const int nearest = p0 >= p1 && p0 >= p2 ? 0 : (p1 >= p2 ? 1 : 2);
        out.label.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(v[nearest]->label);
        out.depth_mm.at<std::uint16_t>(y, x) = 1;  // marks coverage; real depth set below
      }
    }
  };
  for (int y = 0; y + 1 < height; ++y) {
    for (int x = 0; x + 1 < width; ++x) {
      const std::size_t i00 = static_cast<std::size_t>(y) * width + x;
      const std::size_t i10 = i00 + 1, i01 = i00 + width, i11 = i01 + 1;
      triangle(i00, i10, i01);
      triangle(i10, i11, i01);
    }
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (out.depth_mm.at<std::uint16_t>(y, x) == 0) continue;
      const float mm = zbuffer.at<float>(y, x) * 1000.0f;
      out.depth_mm.at<std::uint16_t>(y, x) =
          static_cast<std::uint16_t>(std::clamp(std::lround(mm), 1L, 65535L));
    }
  }
  return out;
}

// Kinect-like axial depth noise sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 m (Nguyen et al. 2012),
// re-quantised to millimetres, and Gaussian colour noise.
void addSensorNoise(RenderedFrame& frame, std::mt19937_64& rng, double color_sigma) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int y = 0; y < frame.depth_mm.rows; ++y) {
    for (int x = 0; x < frame.depth_mm.cols; ++x) {
      std::uint16_t& d = frame.depth_mm.at<std::uint16_t>(y, x);
      if (d == 0) continue;
      const double z = d / 1000.0;
      const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
      d = static_cast<std::uint16_t>(
          std::clamp(std::lround((z + sigma * normal(rng)) * 1000.0), 1L, 65535L));
      if (color_sigma > 0.0) {
        cv::Vec3b& c = frame.color.at<cv::Vec3b>(y, x);
        for (int ch = 0; ch < 3; ++ch) {
          c[ch] = cv::saturate_cast<std::uint8_t>(c[ch] + color_sigma * normal(rng));
        }
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render a labelled RGB-D test video from one OSD frame along a real trajectory"};
  std::string folder, name, trajectory_path, out_folder;
  double start_offset_s = 0.0, fps = 30.0, motion_scale = 0.3, color_sigma = 2.0;
  int frame_count = 30;
  float max_jump_ratio = 0.05f;
  bool noise = true;
  std::uint64_t seed = 0;
  app.add_option("--folder", folder, "OSD-layout folder of the source frame")->required();
  app.add_option("--name", name, "source frame name, e.g. learn5")->required();
  app.add_option("--trajectory", trajectory_path, "TUM-format ground-truth trajectory")->required();
  app.add_option("--start", start_offset_s,
                 "excerpt start, seconds after the trajectory's first pose");
  app.add_option("--frames", frame_count, "number of frames")->check(CLI::PositiveNumber);
  app.add_option("--fps", fps, "frame rate (poses sampled at 1/fps)")->check(CLI::PositiveNumber);
  app.add_option("--motion-scale", motion_scale,
                 "factor on the relative translation and rotation angle (small motion)");
  app.add_option("--max-jump", max_jump_ratio,
                 "relative depth jump across which the mesh is cut (disocclusion holes)");
  app.add_flag("!--no-noise", noise, "no sensor noise");
  app.add_option("--color-noise", color_sigma, "colour noise standard deviation, 8-bit units");
  app.add_option("--seed", seed, "seed of the sensor noise");
  app.add_option("--out", out_folder, "output folder")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const dasp::Intrinsics intrinsics;  // OSD: fx = fy = 525, cx = 319.5, cy = 239.5
    dasp::RgbdFramePaths source;
    for (const auto& paths : dasp::listRgbdFolder(folder)) {
      if (paths.name == name) source = paths;
    }
    if (source.name.empty()) throw std::runtime_error("no frame '" + name + "' in " + folder);
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(source, intrinsics);
    const auto labels = dasp::loadLabelImage(source);
    if (!labels) throw std::runtime_error("frame '" + name + "' has no label image");
    const int width = frame.depth.cols, height = frame.depth.rows;
    std::vector<Vertex> vertices(static_cast<std::size_t>(width) * height);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const std::uint16_t d = frame.depth.at<std::uint16_t>(y, x);
        if (d == 0) continue;
        Vertex& v = vertices[static_cast<std::size_t>(y) * width + x];
        const float z = d / 1000.0f;
        v.point = Eigen::Vector3f((x - intrinsics.cx) * z / intrinsics.fx,
                                  (y - intrinsics.cy) * z / intrinsics.fy, z);
        const cv::Vec3b c = frame.color.at<cv::Vec3b>(y, x);
        v.color = cv::Vec3f(c[0], c[1], c[2]);
        v.label = labels->at<int>(y, x);
        v.valid = true;
      }
    }
    const std::vector<StampedPose> trajectory = readTumTrajectory(trajectory_path);
    const double t0 = trajectory.front().time + start_offset_s;
    if (t0 + (frame_count - 1) / fps > trajectory.back().time) {
      throw std::runtime_error("the excerpt runs past the end of the trajectory");
    }
    const Eigen::Isometry3d world_0 = poseAt(trajectory, t0);
    std::filesystem::create_directories(out_folder);
    std::ofstream poses(std::filesystem::path(out_folder) / "poses.txt");
    poses << "# k tx ty tz qx qy qz qw: pose of camera k in the optical frame of camera 0\n";
    poses << std::setprecision(9);
    std::mt19937_64 rng(seed);
    for (int k = 0; k < frame_count; ++k) {
      const Eigen::Isometry3d world_k = poseAt(trajectory, t0 + k / fps);
      const Eigen::Isometry3d t_0k = scaleMotion(world_0.inverse() * world_k, motion_scale);
      RenderedFrame rendered =
          render(vertices, width, height, intrinsics, t_0k.inverse().cast<float>(), max_jump_ratio);
      if (noise) addSensorNoise(rendered, rng, color_sigma);
      const std::string base =
          (std::filesystem::path(out_folder) / ("frame" + std::to_string(k))).string();
      if (!cv::imwrite(base + "_rgb.png", rendered.color) ||
          !cv::imwrite(base + "_depth_mm.png", rendered.depth_mm) ||
          !cv::imwrite(base + "_label_object.png", rendered.label)) {
        throw std::runtime_error("cannot write frame " + base);
      }
      const Eigen::Quaterniond q(t_0k.linear());
      const Eigen::Vector3d t = t_0k.translation();
      poses << k << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y()
            << ' ' << q.z() << ' ' << q.w() << '\n';
    }
    std::cout << "wrote " << frame_count << " frames of " << name << " to " << out_folder << '\n';
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
