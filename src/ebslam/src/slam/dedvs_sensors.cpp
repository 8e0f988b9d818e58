#include "ebslam/slam/dedvs_sensors.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/core/persistence.hpp>

namespace ebslam {
namespace {

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

void fail(const std::string& message) { throw std::runtime_error(message); }

}  // namespace

void PinholeCamera::validate() const {
  require(width > 0 && height > 0 && width <= 8192 && height <= 8192,
          "PinholeCamera: width and height must lie in [1, 8192]");
  require(std::isfinite(fx) && fx > 0.0 && std::isfinite(fy) && fy > 0.0,
          "PinholeCamera: focal lengths must be positive");
  require(std::isfinite(cx) && std::isfinite(cy), "PinholeCamera: principal point not finite");
}

PinholeCamera PinholeCamera::scaled(double factor) const {
  require(std::isfinite(factor) && factor > 0.0, "PinholeCamera::scaled: factor must be > 0");
  PinholeCamera result = *this;
  result.width = static_cast<int>(std::lround(width * factor));
  result.height = static_cast<int>(std::lround(height * factor));
  result.fx = fx * factor;
  result.fy = fy * factor;
  result.cx = (cx + 0.5) * factor - 0.5;
  result.cy = (cy + 0.5) * factor - 0.5;
  return result;
}

void writeDedvsSensors(const std::string& path, const DedvsSensors& s) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  if (!fs.isOpened()) fail("writeDedvsSensors: cannot open " + path);
  fs << "edvs_width" << s.edvs.width << "edvs_height" << s.edvs.height;
  fs << "edvs_focal_px" << s.edvs.focal_px << "edvs_cx" << s.edvs.principal_point.x() << "edvs_cy"
     << s.edvs.principal_point.y() << "edvs_kappa1" << s.edvs.kappa1 << "edvs_kappa2"
     << s.edvs.kappa2;
  fs << "depth_width" << s.depth.width << "depth_height" << s.depth.height << "depth_fx"
     << s.depth.fx << "depth_fy" << s.depth.fy << "depth_cx" << s.depth.cx << "depth_cy"
     << s.depth.cy;
  cv::Mat transform(4, 4, CV_64F);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) transform.at<double>(r, c) = s.depth_from_edvs.matrix()(r, c);
  }
  fs << "depth_from_edvs" << transform;
  fs << "depth_clock_offset_s" << s.depth_clock_offset_s;
  fs << "depth_frame_rate_hz" << s.depth_frame_rate_hz;
}

DedvsSensors readDedvsSensors(const std::string& path) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& error) {
    fail("readDedvsSensors: cannot parse " + path + ": " + error.what());
  }
  if (!fs.isOpened()) fail("readDedvsSensors: cannot open " + path);
  auto number = [&](const char* key) {
    const cv::FileNode node = fs[key];
    if (node.empty() || (!node.isReal() && !node.isInt())) {
      fail("readDedvsSensors: " + path + " lacks the number " + key);
    }
    return static_cast<double>(node);
  };
  DedvsSensors s;
  s.edvs.width = static_cast<int>(number("edvs_width"));
  s.edvs.height = static_cast<int>(number("edvs_height"));
  s.edvs.focal_px = number("edvs_focal_px");
  s.edvs.principal_point = Eigen::Vector2d(number("edvs_cx"), number("edvs_cy"));
  s.edvs.kappa1 = number("edvs_kappa1");
  s.edvs.kappa2 = number("edvs_kappa2");
  s.edvs.distortion_model = DistortionModel::kDivideEq81;
  s.depth.width = static_cast<int>(number("depth_width"));
  s.depth.height = static_cast<int>(number("depth_height"));
  s.depth.fx = number("depth_fx");
  s.depth.fy = number("depth_fy");
  s.depth.cx = number("depth_cx");
  s.depth.cy = number("depth_cy");
  cv::Mat transform;
  fs["depth_from_edvs"] >> transform;
  if (transform.rows != 4 || transform.cols != 4 || transform.type() != CV_64F) {
    fail("readDedvsSensors: " + path + " lacks a 4x4 depth_from_edvs");
  }
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = transform.at<double>(r, c);
  }
  s.depth_from_edvs.matrix() = m;
  const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
  if (!m.allFinite() ||
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-4) {
    fail("readDedvsSensors: depth_from_edvs in " + path + " is not a rigid transform");
  }
  s.depth_clock_offset_s =
      fs["depth_clock_offset_s"].empty() ? 0.0 : number("depth_clock_offset_s");
  s.depth_frame_rate_hz = fs["depth_frame_rate_hz"].empty() ? 30.0 : number("depth_frame_rate_hz");
  try {
    s.edvs.validate();
    s.depth.validate();
  } catch (const std::invalid_argument& error) {
    fail("readDedvsSensors: " + path + ": " + error.what());
  }
  return s;
}

}  // namespace ebslam
