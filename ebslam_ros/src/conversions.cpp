#include "ebslam_ros/conversions.h"

#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace ebslam_ros {

sensor_msgs::CameraInfo toCameraInfoMsg(int width, int height, double fx, double fy, double cx,
                                        double cy, const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = static_cast<std::uint32_t>(width);
  info.height = static_cast<std::uint32_t>(height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

sensor_msgs::Image toImageMsg(const cv::Mat& image, const std::string& encoding,
                              const std_msgs::Header& header) {
  if (image.empty()) throw std::invalid_argument("toImageMsg: empty image");
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  if (row_bytes > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("toImageMsg: a row exceeds the message's 32-bit step");
  }
  sensor_msgs::Image msg;
  msg.header = header;
  msg.height = static_cast<std::uint32_t>(image.rows);
  msg.width = static_cast<std::uint32_t>(image.cols);
  msg.encoding = encoding;
  msg.is_bigendian = 0;
  msg.step = static_cast<std::uint32_t>(row_bytes);
  msg.data.resize(row_bytes * static_cast<std::size_t>(image.rows));
  for (int r = 0; r < image.rows; ++r) {
    std::memcpy(&msg.data[static_cast<std::size_t>(r) * row_bytes], image.ptr(r), row_bytes);
  }
  return msg;
}

}  // namespace ebslam_ros
