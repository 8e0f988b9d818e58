#include "dasp_ros/conversions.h"

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstring>
#include <limits>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace dasp_ros {
namespace enc = sensor_msgs::image_encodings;

namespace {

// Shares the message's data without copying; callers clone what they keep.
cv::Mat shareImage(const sensor_msgs::Image& image, int expected_type) {
  if (image.width == 0 || image.height == 0) {
    throw std::invalid_argument("image message is empty (" + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + ")");
  }
  // All size arithmetic in size_t: width, height and step are uint32, and their products
  // overflow 32 bits for images such as 65536 x 65537 (step x height wrapped to a small number
  // once passed this check, and cloning the "image" read far beyond the data).
  const std::size_t element_bytes = CV_ELEM_SIZE(expected_type);
  const std::size_t channel_bytes = CV_ELEM_SIZE1(expected_type);
  const std::size_t width = image.width, height = image.height, step = image.step;
  // cv::Mat holds rows and columns in int, and its row step must be a whole number of channels.
  constexpr std::size_t kIntMax = static_cast<std::size_t>(std::numeric_limits<int>::max());
  if (width > kIntMax || height > kIntMax || width * element_bytes > kIntMax) {
    throw std::invalid_argument("image message of " + std::to_string(width) + "x" +
                                std::to_string(height) + " " + image.encoding +
                                " is larger than OpenCV can hold");
  }
  const std::size_t row_bytes = width * element_bytes;
  if (step < row_bytes || step % channel_bytes != 0 || image.data.size() / step < height) {
    throw std::invalid_argument("image message data (" + std::to_string(image.data.size()) +
                                " bytes, step " + std::to_string(step) + ") too small for " +
                                std::to_string(width) + "x" + std::to_string(height) + " " +
                                image.encoding);
  }
  if (image.is_bigendian) {
    throw std::invalid_argument("big-endian image data is not supported");
  }
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), expected_type,
                 const_cast<uint8_t*>(image.data.data()), image.step);
}

// One copy of the pixels into the message (what cv_bridge::CvImage::toImageMsg writes, without
// its intermediate message).
sensor_msgs::Image makeImageMsg(const cv::Mat& mat, const std::string& encoding,
                                const std_msgs::Header& header) {
  sensor_msgs::Image msg;
  msg.header = header;
  msg.height = static_cast<uint32_t>(mat.rows);
  msg.width = static_cast<uint32_t>(mat.cols);
  msg.encoding = encoding;
  msg.is_bigendian = 0;
  const std::size_t row_bytes = static_cast<std::size_t>(mat.cols) * mat.elemSize();
  msg.step = static_cast<uint32_t>(row_bytes);
  msg.data.resize(row_bytes * static_cast<std::size_t>(mat.rows));
  if (mat.isContinuous()) {
    if (!msg.data.empty()) std::memcpy(msg.data.data(), mat.data, msg.data.size());
  } else {
    for (int r = 0; r < mat.rows; ++r) {
      std::memcpy(msg.data.data() + r * row_bytes, mat.ptr(r), row_bytes);
    }
  }
  return msg;
}

cv::Mat copyOrShare(const cv::Mat& shared, ImageData data) {
  return data == ImageData::kShare ? shared : shared.clone();
}

// The fields dasp::Superpixel and ebslam_msgs::Superpixel share, one list for both directions:
// copy(core field, message field) for each pair (Core and Msg const on the side read from).
template <class Core, class Msg, class Copy>
void forSharedFields(Core& sp, Msg& msg, Copy copy) {
  copy(sp.id, msg.id);
  copy(sp.u, msg.u);
  copy(sp.v, msg.v);
  copy(sp.pixel_count, msg.pixel_count);
  copy(sp.color.x(), msg.color.r);
  copy(sp.color.y(), msg.color.g);
  copy(sp.color.z(), msg.color.b);
  copy(sp.position.x(), msg.position.x);
  copy(sp.position.y(), msg.position.y);
  copy(sp.position.z(), msg.position.z);
  copy(sp.normal.x(), msg.normal.x);
  copy(sp.normal.y(), msg.normal.y);
  copy(sp.normal.z(), msg.normal.z);
  copy(sp.radius_m, msg.radius);
  copy(sp.density, msg.density);
  copy(sp.area_m2, msg.area);
  copy(sp.thickness, msg.thickness);
  copy(sp.eccentricity, msg.eccentricity);
  copy(sp.flatness, msg.flatness);
}

// Assignment with the conversion of the target's type (float <-> double, int <-> uint32).
template <class To, class From>
void assignConverted(To& to, const From& from) {
  to = static_cast<To>(from);
}

}  // namespace

dasp::Intrinsics toIntrinsics(const sensor_msgs::CameraInfo& info) {
  // K = [fx 0 cx; 0 fy cy; 0 0 1]; P = [fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0].
  const bool k_set = info.K[0] != 0.0;
  dasp::Intrinsics intrinsics;
  intrinsics.fx = static_cast<float>(k_set ? info.K[0] : info.P[0]);
  intrinsics.fy = static_cast<float>(k_set ? info.K[4] : info.P[5]);
  intrinsics.cx = static_cast<float>(k_set ? info.K[2] : info.P[2]);
  intrinsics.cy = static_cast<float>(k_set ? info.K[5] : info.P[6]);
  for (float value : {intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy}) {
    if (!std::isfinite(value)) throw std::invalid_argument("camera_info intrinsics are not finite");
  }
  if (intrinsics.fx <= 0.0f || intrinsics.fy <= 0.0f) {
    throw std::invalid_argument(
        "camera_info focal lengths must be positive (fx = " + std::to_string(intrinsics.fx) +
        ", fy = " + std::to_string(intrinsics.fy) + ")");
  }
  return intrinsics;
}

dasp::Intrinsics intrinsicsFromFieldOfView(double horizontal_fov_rad, double vertical_fov_rad,
                                           int width, int height) {
  for (double fov : {horizontal_fov_rad, vertical_fov_rad}) {
    if (!(fov > 0.0 && fov < M_PI)) {
      throw std::invalid_argument("field of view " + std::to_string(fov) +
                                  " rad is not in (0, pi)");
    }
  }
  if (width <= 0 || height <= 0) throw std::invalid_argument("image size must be positive");
  dasp::Intrinsics intrinsics;
  intrinsics.fx = static_cast<float>(0.5 * width / std::tan(0.5 * horizontal_fov_rad));
  intrinsics.fy = static_cast<float>(0.5 * height / std::tan(0.5 * vertical_fov_rad));
  intrinsics.cx = 0.5f * static_cast<float>(width - 1);
  intrinsics.cy = 0.5f * static_cast<float>(height - 1);
  return intrinsics;
}

sensor_msgs::CameraInfo toCameraInfo(const dasp::Intrinsics& intrinsics, int width, int height,
                                     const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = static_cast<uint32_t>(width);
  info.height = static_cast<uint32_t>(height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {intrinsics.fx, 0.0, intrinsics.cx, 0.0, 0.0, intrinsics.fy,
            intrinsics.cy, 0.0, 0.0,           0.0, 1.0, 0.0};
  return info;
}

cv::Mat toColorMat(const sensor_msgs::Image& image, ImageData data) {
  cv::Mat bgr;
  if (image.encoding == enc::BGR8) {
    bgr = copyOrShare(shareImage(image, CV_8UC3), data);
  } else if (image.encoding == enc::RGB8) {
    cv::cvtColor(shareImage(image, CV_8UC3), bgr, cv::COLOR_RGB2BGR);
  } else if (image.encoding == enc::BGRA8) {
    cv::cvtColor(shareImage(image, CV_8UC4), bgr, cv::COLOR_BGRA2BGR);
  } else if (image.encoding == enc::RGBA8) {
    cv::cvtColor(shareImage(image, CV_8UC4), bgr, cv::COLOR_RGBA2BGR);
  } else if (image.encoding == enc::MONO8) {
    cv::cvtColor(shareImage(image, CV_8UC1), bgr, cv::COLOR_GRAY2BGR);
  } else {
    throw std::invalid_argument("colour image encoding '" + image.encoding +
                                "' is not supported (bgr8, rgb8, bgra8, rgba8, mono8)");
  }
  return bgr;
}

cv::Mat toDepthMat(const sensor_msgs::Image& image, ImageData data) {
  if (image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16) {
    return copyOrShare(shareImage(image, CV_16UC1), data);
  }
  if (image.encoding == enc::TYPE_32FC1) {
    const cv::Mat metres = shareImage(image, CV_32FC1);
    cv::Mat millimetres(metres.size(), CV_16UC1);
    for (int r = 0; r < metres.rows; ++r) {
      const float* in = metres.ptr<float>(r);
      uint16_t* out = millimetres.ptr<uint16_t>(r);
      for (int c = 0; c < metres.cols; ++c) {
        const float mm = in[c] * 1000.0f;
        out[c] = (std::isfinite(mm) && mm > 0.0f && mm < 65535.5f)
                     ? static_cast<uint16_t>(std::lround(mm))
                     : uint16_t{0};
      }
    }
    return millimetres;
  }
  throw std::invalid_argument("depth image encoding '" + image.encoding +
                              "' is not supported (16UC1/mono16 in mm, 32FC1 in m)");
}

dasp::RgbdFrame toRgbdFrame(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                            const sensor_msgs::CameraInfo& info) {
  if (color.width != depth.width || color.height != depth.height) {
    throw std::invalid_argument(
        "colour (" + std::to_string(color.width) + "x" + std::to_string(color.height) +
        ") and depth (" + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
        ") images differ in size: the depth image must be registered to the colour image");
  }
  dasp::RgbdFrame frame;
  frame.color = toColorMat(color);
  frame.depth = toDepthMat(depth);
  frame.intrinsics = toIntrinsics(info);
  return frame;
}

sensor_msgs::Image toColorImageMsg(const cv::Mat& color, const std_msgs::Header& header) {
  if (color.type() != CV_8UC3) throw std::invalid_argument("colour image must be CV_8UC3 BGR");
  return makeImageMsg(color, enc::BGR8, header);
}

sensor_msgs::Image toDepthImageMsg(const cv::Mat& depth_mm, const std_msgs::Header& header) {
  if (depth_mm.type() != CV_16UC1) throw std::invalid_argument("depth image must be CV_16UC1 mm");
  return makeImageMsg(depth_mm, enc::TYPE_16UC1, header);
}

sensor_msgs::Image toLabelImageMsg(const cv::Mat& labels, const std_msgs::Header& header) {
  if (labels.type() != CV_32SC1) throw std::invalid_argument("label image must be CV_32SC1");
  return makeImageMsg(labels, enc::TYPE_32SC1, header);
}

cv::Mat toLabelMat(const sensor_msgs::Image& image, ImageData data) {
  if (image.encoding != enc::TYPE_32SC1) {
    throw std::invalid_argument("label image encoding '" + image.encoding + "' is not 32SC1");
  }
  return copyOrShare(shareImage(image, CV_32SC1), data);
}

ebslam_msgs::SuperpixelArray toSuperpixelArrayMsg(const dasp::Superpixels& superpixels,
                                                  const std_msgs::Header& header) {
  ebslam_msgs::SuperpixelArray msg;
  msg.header = header;
  msg.width = static_cast<uint32_t>(superpixels.labels.cols);
  msg.height = static_cast<uint32_t>(superpixels.labels.rows);
  msg.superpixels.reserve(superpixels.superpixels.size());
  for (const dasp::Superpixel& sp : superpixels.superpixels) {
    ebslam_msgs::Superpixel out;
    forSharedFields(sp, out, [](const auto& from, auto& to) { assignConverted(to, from); });
    out.color.a = 1.0f;
    msg.superpixels.push_back(out);
  }
  return msg;
}

dasp::Superpixels toSuperpixels(const ebslam_msgs::SuperpixelArray& msg,
                                const sensor_msgs::Image& labels, ImageData data) {
  if (labels.width != msg.width || labels.height != msg.height) {
    throw std::invalid_argument("label image size does not match the SuperpixelArray size");
  }
  dasp::Superpixels result;
  result.labels = toLabelMat(labels, data);
  result.superpixels.reserve(msg.superpixels.size());
  for (std::size_t i = 0; i < msg.superpixels.size(); ++i) {
    const ebslam_msgs::Superpixel& in = msg.superpixels[i];
    if (in.id != i) {
      throw std::invalid_argument("superpixel " + std::to_string(i) + " has id " +
                                  std::to_string(in.id) + ": ids must index the array");
    }
    dasp::Superpixel sp;
    forSharedFields(sp, in, [](auto& to, const auto& from) { assignConverted(to, from); });
    result.superpixels.push_back(sp);
  }
  // Labels index the array (the core indexes with them): -1 (none) up to size - 1.
  double min_label = 0.0, max_label = -1.0;
  cv::minMaxLoc(result.labels, &min_label, &max_label);
  if (min_label < -1.0 || max_label >= static_cast<double>(result.superpixels.size())) {
    throw std::invalid_argument("labels " + std::to_string(static_cast<long long>(min_label)) +
                                ".." + std::to_string(static_cast<long long>(max_label)) +
                                " do not index the " + std::to_string(result.superpixels.size()) +
                                " superpixels (-1 = none)");
  }
  return result;
}

std::vector<ebslam_msgs::SuperpixelEdge> toEdgeMsgs(const dasp::WeightedGraph& graph) {
  std::vector<ebslam_msgs::SuperpixelEdge> edges;
  edges.reserve(graph.edges.size());
  for (const dasp::GraphEdge& e : graph.edges) {
    ebslam_msgs::SuperpixelEdge out;
    out.a = static_cast<uint32_t>(e.a);
    out.b = static_cast<uint32_t>(e.b);
    out.weight = e.weight;
    edges.push_back(out);
  }
  return edges;
}

dasp::WeightedGraph toWeightedGraph(const std::vector<ebslam_msgs::SuperpixelEdge>& edges,
                                    int node_count) {
  dasp::WeightedGraph graph;
  graph.node_count = node_count;
  graph.edges.reserve(edges.size());
  for (const ebslam_msgs::SuperpixelEdge& e : edges) {
    if (e.a >= e.b || e.b >= static_cast<uint32_t>(node_count)) {
      throw std::invalid_argument("edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) +
                                  ") is not a < b < " + std::to_string(node_count));
    }
    graph.edges.push_back({static_cast<int>(e.a), static_cast<int>(e.b), e.weight});
  }
  return graph;
}

visualization_msgs::MarkerArray toMarkerArray(const std::vector<dasp::Superpixel>& superpixels,
                                              const std_msgs::Header& header) {
  visualization_msgs::MarkerArray markers;
  markers.markers.reserve(superpixels.size() + 1);
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.ns = "superpixels";
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  for (const dasp::Superpixel& sp : superpixels) {
    visualization_msgs::Marker m;
    m.header = header;
    m.ns = "superpixels";
    m.id = sp.id;
    m.type = visualization_msgs::Marker::CYLINDER;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.position.x = sp.position.x();
    m.pose.position.y = sp.position.y();
    m.pose.position.z = sp.position.z();
    // The cylinder's axis is its local z: rotate z onto the normal.
    const Eigen::Quaternionf q =
        Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), sp.normal.normalized());
    m.pose.orientation.x = q.x();
    m.pose.orientation.y = q.y();
    m.pose.orientation.z = q.z();
    m.pose.orientation.w = q.w();
    m.scale.x = m.scale.y = 2.0 * sp.radius_m;
    m.scale.z = std::max(sp.thickness, 0.002f);
    m.color.r = sp.color.x();
    m.color.g = sp.color.y();
    m.color.b = sp.color.z();
    m.color.a = 1.0f;
    markers.markers.push_back(m);
  }
  return markers;
}

sensor_msgs::PointCloud2 toCentreCloud(const std::vector<dasp::Superpixel>& superpixels,
                                       const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header = header;
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2Fields(
      8, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z", 1,
      sensor_msgs::PointField::FLOAT32, "normal_x", 1, sensor_msgs::PointField::FLOAT32, "normal_y",
      1, sensor_msgs::PointField::FLOAT32, "normal_z", 1, sensor_msgs::PointField::FLOAT32, "rgb",
      1, sensor_msgs::PointField::FLOAT32, "id", 1, sensor_msgs::PointField::UINT32);
  modifier.resize(superpixels.size());
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), nx(cloud, "normal_x"), rgb(cloud, "rgb");
  sensor_msgs::PointCloud2Iterator<uint32_t> id(cloud, "id");
  for (const dasp::Superpixel& sp : superpixels) {
    x[0] = sp.position.x();
    x[1] = sp.position.y();
    x[2] = sp.position.z();
    nx[0] = sp.normal.x();
    nx[1] = sp.normal.y();
    nx[2] = sp.normal.z();
    auto channel = [](float value) {
      return static_cast<uint32_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
    };
    const uint32_t packed =
        (channel(sp.color.x()) << 16) | (channel(sp.color.y()) << 8) | channel(sp.color.z());
    float packed_float;
    std::memcpy(&packed_float, &packed, sizeof(packed_float));
    *rgb = packed_float;
    *id = static_cast<uint32_t>(sp.id);
    ++x, ++nx, ++rgb, ++id;
  }
  return cloud;
}

}  // namespace dasp_ros
