#include "dasp_ros/rendering.h"

#include <dasp/metrics.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace dasp_ros {

cv::Mat drawBoundaryOverlay(const cv::Mat& bgr, const cv::Mat& labels) {
  if (bgr.type() != CV_8UC3 || labels.type() != CV_32SC1 || bgr.size() != labels.size()) {
    throw std::invalid_argument(
        "drawBoundaryOverlay: CV_8UC3 image and CV_32SC1 labels of one size");
  }
  cv::Mat out = bgr.clone();
  const cv::Mat boundary = dasp::metrics::boundaryMap(labels, cv::Mat());
  for (int y = 0; y < out.rows; ++y) {
    cv::Vec3b* p = out.ptr<cv::Vec3b>(y);
    const std::uint8_t* b = boundary.ptr<std::uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (b[x] != 0) {
        p[x] = cv::Vec3b(0, 0, 255);
      } else if (l[x] < 0) {
        p[x] = cv::Vec3b(p[x][0] / 3, p[x][1] / 3, p[x][2] / 3);
      }
    }
  }
  return out;
}

cv::Mat drawSegmentOverlay(const cv::Mat& superpixel_labels,
                           const std::vector<dasp::Superpixel>& superpixels,
                           const cv::Mat& segment_labels) {
  if (superpixel_labels.type() != CV_32SC1 || segment_labels.type() != CV_32SC1 ||
      superpixel_labels.size() != segment_labels.size()) {
    throw std::invalid_argument("drawSegmentOverlay: CV_32SC1 label images of one size");
  }
  std::vector<cv::Vec3b> mean(superpixels.size());
  for (std::size_t i = 0; i < superpixels.size(); ++i) {
    const Eigen::Vector3f& c = superpixels[i].color;  // RGB in [0, 1]
    mean[i] = cv::Vec3b(cv::saturate_cast<std::uint8_t>(255.0f * c.z()),
                        cv::saturate_cast<std::uint8_t>(255.0f * c.y()),
                        cv::saturate_cast<std::uint8_t>(255.0f * c.x()));
  }
  cv::Mat out(superpixel_labels.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Mat boundary = dasp::metrics::boundaryMap(segment_labels, cv::Mat());
  for (int y = 0; y < out.rows; ++y) {
    cv::Vec3b* p = out.ptr<cv::Vec3b>(y);
    const int* l = superpixel_labels.ptr<int>(y);
    const std::uint8_t* b = boundary.ptr<std::uint8_t>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (b[x] != 0) {
        p[x] = cv::Vec3b(0, 0, 255);
      } else if (l[x] >= 0 && static_cast<std::size_t>(l[x]) < mean.size()) {
        p[x] = mean[static_cast<std::size_t>(l[x])];
      }
    }
  }
  return out;
}

cv::Mat ucmToMono8(const cv::Mat& ucm) {
  if (ucm.type() != CV_32FC1) throw std::invalid_argument("ucmToMono8: CV_32FC1 map");
  cv::Mat out(ucm.size(), CV_8UC1, cv::Scalar(255));
  for (int y = 0; y < out.rows; ++y) {
    const float* level = ucm.ptr<float>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (level[x] < 0.0f) continue;
      o[x] = cv::saturate_cast<std::uint8_t>(255.0f * (1.0f - std::sqrt(std::min(level[x], 1.0f))));
    }
  }
  return out;
}

cv::Vec3b labelColor(long long label) {
  const auto h = static_cast<unsigned>(label) * 2654435761u;
  return cv::Vec3b(64 + (h & 0x7f), 64 + ((h >> 8) & 0x7f), 64 + ((h >> 16) & 0x7f));
}

}  // namespace dasp_ros
