// Synthetic RGB-D scenes with known geometry for the DASP tests.
#pragma once

#include <cmath>
#include <cstdint>

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

}  // namespace dasp::test
