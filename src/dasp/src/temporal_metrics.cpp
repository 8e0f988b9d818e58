// Temporal label consistency with motion compensation.
#include "dasp/temporal_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace dasp {
namespace metrics {
namespace {

float depthMetres(const cv::Mat& depth, int y, int x) {
  if (depth.type() == CV_16UC1) return depth.at<std::uint16_t>(y, x) / 1000.0f;
  const float d = depth.at<float>(y, x);
  return std::isfinite(d) ? d : 0.0f;
}

}  // namespace

TemporalConsistency temporalLabelConsistency(const cv::Mat& labels_t, const cv::Mat& depth_t,
                                             const cv::Mat& labels_next, const cv::Mat& depth_next,
                                             const Intrinsics& intrinsics,
                                             const Eigen::Isometry3f& next_from_current,
                                             LabelMatching matching, float depth_tolerance) {
  if (labels_t.type() != CV_32SC1 || labels_next.type() != CV_32SC1) {
    throw std::invalid_argument("temporalLabelConsistency: labels must be CV_32SC1");
  }
  for (const cv::Mat* d : {&depth_t, &depth_next}) {
    if (d->type() != CV_16UC1 && d->type() != CV_32FC1) {
      throw std::invalid_argument("temporalLabelConsistency: depth must be CV_16UC1 or CV_32FC1");
    }
  }
  if (labels_t.size() != depth_t.size() || labels_next.size() != depth_next.size() ||
      labels_t.size() != labels_next.size()) {
    throw std::invalid_argument("temporalLabelConsistency: image sizes differ");
  }
  if (!(depth_tolerance > 0.0f)) {
    throw std::invalid_argument("temporalLabelConsistency: depth_tolerance must be positive");
  }
  // Corresponding label pairs (label_t, label_next) of all compared pixels.
  std::unordered_map<long long, std::size_t> pair_count;
  TemporalConsistency result;
  std::size_t same = 0;
  for (int y = 0; y < labels_t.rows; ++y) {
    for (int x = 0; x < labels_t.cols; ++x) {
      const int l = labels_t.at<int>(y, x);
      const float z = depthMetres(depth_t, y, x);
      if (l < 0 || !(z > 0.0f)) continue;
      const Eigen::Vector3f p((x - intrinsics.cx) * z / intrinsics.fx,
                              (y - intrinsics.cy) * z / intrinsics.fy, z);
      const Eigen::Vector3f q = next_from_current * p;
      if (!(q.z() > 0.0f)) continue;
      const int u = static_cast<int>(std::lround(intrinsics.fx * q.x() / q.z() + intrinsics.cx));
      const int v = static_cast<int>(std::lround(intrinsics.fy * q.y() / q.z() + intrinsics.cy));
      if (u < 0 || v < 0 || u >= labels_next.cols || v >= labels_next.rows) continue;
      const int ln = labels_next.at<int>(v, u);
      const float zn = depthMetres(depth_next, v, u);
      if (ln < 0 || !(zn > 0.0f) || std::abs(zn - q.z()) > depth_tolerance * q.z()) continue;
      ++result.compared;
      if (matching == LabelMatching::kIdentity) {
        if (ln == l) ++same;
      } else {
        ++pair_count[static_cast<long long>(l) * (1LL << 32) + static_cast<std::uint32_t>(ln)];
      }
    }
  }
  if (matching == LabelMatching::kBestOverlap) {
    std::vector<std::pair<std::size_t, long long>> pairs;
    pairs.reserve(pair_count.size());
    for (const auto& [key, count] : pair_count) pairs.push_back({count, key});
    std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    std::unordered_set<long long> used_t, used_next;
    for (const auto& [count, key] : pairs) {
      const long long lt = key >> 32;
      const long long ln = key & 0xffffffffLL;
      if (used_t.count(lt) || used_next.count(ln)) continue;
      used_t.insert(lt);
      used_next.insert(ln);
      same += count;
    }
  }
  result.kept = same;
  result.consistency =
      result.compared > 0 ? static_cast<double>(same) / static_cast<double>(result.compared) : 0.0;
  return result;
}

}  // namespace metrics
}  // namespace dasp
