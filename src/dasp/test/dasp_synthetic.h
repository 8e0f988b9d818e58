// Synthetic RGB-D scenes with known geometry for the DASP tests.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>
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

/// Depth (uint16 millimetres) of the plane n . P = offset_m seen through `intrinsics`, n unit.
inline float planeDepthMm(const Intrinsics& k, int x, int y, const Eigen::Vector3f& n,
                          float offset_m) {
  const Eigen::Vector3f ray((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0f);
  return 1000.0f * offset_m / n.dot(ray);
}

/// Colour `base` (BGR) with mild deterministic noise of +-3 per channel.
inline cv::Vec3b noisyColor(const cv::Vec3b& base, cv::RNG& rng) {
  cv::Vec3b c;
  for (int i = 0; i < 3; ++i) c[i] = cv::saturate_cast<std::uint8_t>(base[i] + rng.uniform(-3, 4));
  return c;
}

/// A table seen from above at 1 m, tilted by 30 degrees, 320x240: light grey-beige, and on it a
/// thin flat object (a book or a mat, `thickness_m` thick, default 3 mm) in dark blue over the
/// image rectangle columns 110-209, rows 80-159 (`object_mask` marks it). Depth in millimetres
/// (quantised like a Kinect's), so the object's depth step is a few quanta: the colour edge must
/// carry its boundary.
inline RgbdFrame thinObjectOnTable(cv::Mat* object_mask, float thickness_m = 0.003f) {
  const int width = 320, height = 240;
  RgbdFrame frame;
  frame.intrinsics = syntheticIntrinsics(width, height);
  frame.color = cv::Mat(height, width, CV_8UC3);
  frame.depth = cv::Mat(height, width, CV_16UC1);
  const float tilt = 30.0f * 3.14159265f / 180.0f;
  const Eigen::Vector3f n(0.0f, -std::sin(tilt), std::cos(tilt));  // towards +z, table normal
  const cv::Rect object(110, 80, 100, 80);
  cv::RNG rng(7);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool on = object.contains(cv::Point(x, y));
      frame.color.at<cv::Vec3b>(y, x) =
          noisyColor(on ? cv::Vec3b(150, 90, 70) : cv::Vec3b(150, 170, 185), rng);
      frame.depth.at<std::uint16_t>(y, x) = cv::saturate_cast<std::uint16_t>(
          planeDepthMm(frame.intrinsics, x, y, n, 1.0f - (on ? thickness_m : 0.0f)));
    }
  }
  if (object_mask != nullptr) {
    *object_mask = cv::Mat::zeros(height, width, CV_8UC1);
    (*object_mask)(object).setTo(255);
  }
  return frame;
}

/// A cluster of four touching boxes in front of a wall, 320x240: the boxes' front faces are
/// fronto-parallel at 0.90, 0.92, 0.91 and 0.93 m (steps of 1-2 cm where they touch), coloured
/// red, yellow, green and blue; the wall at 1.3 m, grey. `box_labels` (CV_32SC1) gets 1-4 per
/// box, 0 for the wall. Box k covers columns 40 + 60 k .. 99 + 60 k, rows 60-179.
inline RgbdFrame touchingBoxes(cv::Mat* box_labels) {
  const int width = 320, height = 240;
  RgbdFrame frame;
  frame.intrinsics = syntheticIntrinsics(width, height);
  frame.color = cv::Mat(height, width, CV_8UC3);
  frame.depth = cv::Mat(height, width, CV_16UC1);
  const float depth_m[4] = {0.90f, 0.92f, 0.91f, 0.93f};
  const cv::Vec3b colors[4] = {cv::Vec3b(60, 60, 170), cv::Vec3b(60, 170, 180),
                               cv::Vec3b(80, 150, 70), cv::Vec3b(170, 90, 60)};
  cv::Mat labels(height, width, CV_32SC1, cv::Scalar(0));
  cv::RNG rng(11);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int box = (y >= 60 && y < 180 && x >= 40 && x < 280) ? (x - 40) / 60 : -1;
      labels.at<int>(y, x) = box + 1;
      frame.color.at<cv::Vec3b>(y, x) =
          noisyColor(box >= 0 ? colors[box] : cv::Vec3b(128, 128, 128), rng);
      frame.depth.at<std::uint16_t>(y, x) =
          static_cast<std::uint16_t>(1000.0f * (box >= 0 ? depth_m[box] : 1.3f));
    }
  }
  if (box_labels != nullptr) *box_labels = labels;
  return frame;
}

}  // namespace dasp::test
