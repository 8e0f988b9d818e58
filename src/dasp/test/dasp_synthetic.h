// Synthetic RGB-D scenes with known geometry for the DASP tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp::test {

inline Intrinsics syntheticIntrinsics(int width, int height) {
  return {200.0f, 200.0f, 0.5f * (width - 1), 0.5f * (height - 1)};
}

/// Uniform grey colour with mild deterministic noise (so colour carries no edge information).
inline cv::Mat flatColor(int width, int height, std::uint64_t seed = 1) {
  cv::Mat color(height, width, CV_8UC3);
  cv::RNG rng(seed);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int v = 128 + rng.uniform(-3, 4);
      color.at<cv::Vec3b>(y, x) = cv::Vec3b(v, v, v);
    }
  }
  return color;
}

/// Two fronto-parallel planes of the same colour: a centred rectangle at near_m in front of a
/// background at far_m. Returns the frame; `near_mask` (CV_8UC1) marks the rectangle.
inline RgbdFrame twoPlanes(int width, int height, float near_m, float far_m, cv::Mat* near_mask) {
  RgbdFrame frame;
  frame.color = flatColor(width, height);
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(far_m * 1000.0f));
  const cv::Rect rect(width / 4, height / 4, width / 2, height / 2);
  frame.depth(rect).setTo(cv::Scalar(near_m * 1000.0f));
  frame.intrinsics = syntheticIntrinsics(width, height);
  if (near_mask != nullptr) {
    *near_mask = cv::Mat::zeros(height, width, CV_8UC1);
    (*near_mask)(rect).setTo(255);
  }
  return frame;
}

/// Two same-grey boxes side by side, 160x120: the left at 0.9 m, the right at 1.3 m (a 40 cm depth
/// step at column 80), no valid depth around them. Left box columns 20-79, right 80-139, rows
/// 20-99.
inline RgbdFrame twoBoxes() {
  const int width = 160, height = 120;
  RgbdFrame frame;
  frame.color = flatColor(width, height);
  frame.intrinsics = syntheticIntrinsics(width, height);
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(0));
  frame.depth(cv::Rect(20, 20, 60, 80)).setTo(cv::Scalar(900));
  frame.depth(cv::Rect(80, 20, 60, 80)).setTo(cv::Scalar(1300));
  return frame;
}

/// A plane rotated by `angle_rad` about the camera's y axis through (0, 0, centre_m), float
/// depth in metres (no quantisation).
inline RgbdFrame slantedPlane(int width, int height, float centre_m, float angle_rad) {
  RgbdFrame frame;
  frame.color = flatColor(width, height);
  frame.intrinsics = syntheticIntrinsics(width, height);
  frame.depth = cv::Mat(height, width, CV_32FC1);
  // Plane n . P = n . (0, 0, centre) with n = (sin a, 0, -cos a).
  const float nx = std::sin(angle_rad), nz = -std::cos(angle_rad);
  const float d = nz * centre_m;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float rx = (x - frame.intrinsics.cx) / frame.intrinsics.fx;
      frame.depth.at<float>(y, x) = d / (nx * rx + nz);
    }
  }
  return frame;
}

/// Colour `base` (BGR) with mild deterministic noise of +-3 per channel.
inline cv::Vec3b noisyColor(const cv::Vec3b& base, cv::RNG& rng) {
  cv::Vec3b c;
  for (int i = 0; i < 3; ++i) c[i] = cv::saturate_cast<std::uint8_t>(base[i] + rng.uniform(-3, 4));
  return c;
}

/// A box standing on the table of a TabletopScene: table coordinates (metres) of its footprint
/// [x0, x1] x [y0, y1] (x to the right, y away from the camera, origin at the table centre), its
/// height and colour (BGR).
struct TableBox {
  float x0, x1, y0, y1, height;
  cv::Vec3b color;
};

/// An OSD-like RGB-D frame, 640x480 with the Kinect intrinsics: a table of 0.9 x 0.7 m seen from
/// 1 m, the camera pitched down by 45 degrees, light beige, with `boxes` standing on it (ray-cast,
/// faces shaded by their orientation: top 1, front 0.85, sides 0.75), colour noise +-3, depth in
/// whole millimetres, no depth off the table. `labels` (CV_32SC1): 0 off the table, 1 table,
/// 2 + k box k (visible pixels).
inline RgbdFrame tabletopScene(const std::vector<TableBox>& boxes, cv::Mat* labels) {
  const int width = 640, height = 480;
  RgbdFrame frame;
  frame.intrinsics = {525.0f, 525.0f, 319.5f, 239.5f};
  frame.color = cv::Mat(height, width, CV_8UC3);
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(0));
  cv::Mat label(height, width, CV_32SC1, cv::Scalar(0));
  const float pitch = 45.0f * 3.14159265f / 180.0f;
  const Eigen::Vector3f up(0.0f, -std::cos(pitch), -std::sin(pitch));  // table normal
  const Eigen::Vector3f right(1.0f, 0.0f, 0.0f);
  const Eigen::Vector3f away = up.cross(right).normalized();  // along the table, forward
  const Eigen::Vector3f centre(0.0f, 0.0f, 1.0f);
  const Eigen::Vector3f origin = -centre;  // camera centre in table coordinates (before axes)
  const Eigen::Vector3f o(origin.dot(right), origin.dot(away), origin.dot(up));
  cv::RNG rng(7);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3f ray((x - frame.intrinsics.cx) / frame.intrinsics.fx,
                                (y - frame.intrinsics.cy) / frame.intrinsics.fy, 1.0f);
      const Eigen::Vector3f d(ray.dot(right), ray.dot(away), ray.dot(up));
      float best_t = std::numeric_limits<float>::infinity();
      int best_label = 0;
      float shade = 1.0f;
      cv::Vec3b color(0, 0, 0);
      // The table top (z = 0) within its extent.
      if (d.z() < 0.0f) {
        const float t = -o.z() / d.z();
        const Eigen::Vector3f p = o + t * d;
        if (std::abs(p.x()) <= 0.45f && std::abs(p.y()) <= 0.35f) {
          best_t = t;
          best_label = 1;
          color = cv::Vec3b(150, 175, 190);
        }
      }
      for (std::size_t k = 0; k < boxes.size(); ++k) {
        const TableBox& b = boxes[k];
        const float lo[3] = {b.x0, b.y0, 0.0f}, hi[3] = {b.x1, b.y1, b.height};
        float t_in = 0.0f, t_out = std::numeric_limits<float>::infinity();
        int axis_in = -1;
        bool hit = true;
        for (int a = 0; a < 3 && hit; ++a) {
          if (std::abs(d[a]) < 1e-9f) {
            hit = o[a] >= lo[a] && o[a] <= hi[a];
            continue;
          }
          float t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
          if (t0 > t1) std::swap(t0, t1);
          if (t0 > t_in) t_in = t0, axis_in = a;
          t_out = std::min(t_out, t1);
          hit = t_in <= t_out;
        }
        if (hit && axis_in >= 0 && t_in < best_t) {
          best_t = t_in;
          best_label = 2 + static_cast<int>(k);
          color = b.color;
          shade = axis_in == 2 ? 1.0f : axis_in == 1 ? 0.85f : 0.75f;
        }
      }
      label.at<int>(y, x) = best_label;
      if (best_label > 0) {
        frame.depth.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(std::lround(1000.0f * best_t));  // ray z = 1: t is the depth
      } else {
        color = cv::Vec3b(90, 90, 90);  // the floor far below: colour without depth
      }
      cv::Vec3b shaded;
      for (int c = 0; c < 3; ++c) shaded[c] = cv::saturate_cast<std::uint8_t>(shade * color[c]);
      frame.color.at<cv::Vec3b>(y, x) = noisyColor(shaded, rng);
    }
  }
  if (labels != nullptr) *labels = label;
  return frame;
}

/// A thin flat object lying on the table (a 3 mm mat, 0.22 x 0.16 m, dark brown on the light
/// table: its depth step is 3 quanta, so the colour edge must carry its boundary) beside a box
/// standing on the table. Labels: 1 table, 2 the thin object, 3 the box.
inline RgbdFrame thinObjectOnTable(cv::Mat* labels) {
  return tabletopScene({{-0.25f, -0.03f, -0.1f, 0.06f, 0.003f, cv::Vec3b(50, 30, 25)},
                        {0.12f, 0.24f, 0.0f, 0.1f, 0.14f, cv::Vec3b(40, 140, 60)}},
                       labels);
}

/// Four boxes standing on the table in a touching 2 x 2 cluster (shared side faces; the two
/// front boxes' fronts 4 cm apart), 10-18 cm high, red, yellow, green and blue. Labels: 1 table,
/// 2-5 the boxes.
inline RgbdFrame touchingBoxes(cv::Mat* labels) {
  return tabletopScene({{-0.15f, 0.0f, -0.13f, 0.02f, 0.12f, cv::Vec3b(50, 50, 170)},
                        {0.0f, 0.14f, -0.09f, 0.02f, 0.15f, cv::Vec3b(50, 170, 180)},
                        {-0.15f, 0.0f, 0.02f, 0.14f, 0.18f, cv::Vec3b(70, 150, 60)},
                        {0.0f, 0.14f, 0.02f, 0.14f, 0.10f, cv::Vec3b(170, 90, 50)}},
                       labels);
}

}  // namespace dasp::test
