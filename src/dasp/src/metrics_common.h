#pragma once

// Argument checks and the dense relabelling shared by the metrics (metrics.cpp,
// metrics_intrinsic.cpp).

#include <opencv2/core.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace dasp::metrics::detail {

inline void checkLabels(const cv::Mat& labels, const char* what) {
  if (labels.empty()) {
    throw std::invalid_argument(std::string(what) + ": label image is empty");
  }
  if (labels.type() != CV_32SC1) {
    throw std::invalid_argument(std::string(what) + ": label image must be CV_32SC1");
  }
}

inline void checkMask(const cv::Mat& mask, const cv::Size& size, const char* what) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1) {
    throw std::invalid_argument(std::string(what) + ": mask must be CV_8UC1");
  }
  if (mask.size() != size) {
    throw std::invalid_argument(std::string(what) + ": mask size differs from the label image");
  }
}

inline bool inMask(const cv::Mat& mask, int y, int x) {
  return mask.empty() || mask.at<std::uint8_t>(y, x) != 0;
}

// Maps arbitrary labels to dense indices 0..n-1 in order of first appearance. Negative labels
// (unlabelled) all map to one index when `merge_negative`, otherwise to -1.
class DenseLabels {
 public:
  DenseLabels(const cv::Mat& labels, const cv::Mat& mask, bool merge_negative)
      : index(labels.size(), CV_32SC1, cv::Scalar(-1)) {
    // Superpixel labels are small non-negative numbers: a lookup table is much faster than a
    // hash map. The hash map remains for huge label values.
    int max_label = -1;
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      for (int x = 0; x < labels.cols; ++x) {
        if (inMask(mask, y, x)) max_label = std::max(max_label, row[x]);
      }
    }
    const bool use_table = max_label < (1 << 24);
    std::vector<int> table(use_table ? static_cast<std::size_t>(max_label) + 2 : 0, -1);
    std::unordered_map<int, int> map;
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      int* out = index.ptr<int>(y);
      for (int x = 0; x < labels.cols; ++x) {
        if (!inMask(mask, y, x)) continue;
        int label = row[x];
        if (label < 0) {
          if (!merge_negative) continue;
          label = -1;
        }
        int* slot = use_table ? &table[static_cast<std::size_t>(label) + 1]
                              : &map.try_emplace(label, -1).first->second;
        if (*slot < 0) {
          *slot = count++;
          original.push_back(label);
        }
        out[x] = *slot;
        ++pixels;
      }
    }
  }
  cv::Mat index;              // CV_32SC1, dense index or -1 outside the domain
  int count = 0;              // number of dense labels
  std::size_t pixels = 0;     // pixels in the domain
  std::vector<int> original;  // dense index -> original label
};

}  // namespace dasp::metrics::detail
