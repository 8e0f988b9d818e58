#include "ebslam_ros/conversions.h"

#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "ebslam_ros/flat_yaml.h"

namespace ebslam_ros {

geometry_msgs::Pose toPoseMsg(const ebslam::Pose2& pose) {
  geometry_msgs::Pose msg;
  msg.position.x = pose.x;
  msg.position.y = pose.y;
  tf2::Quaternion q;
  q.setRPY(0.0, 0.0, pose.theta);
  msg.orientation = tf2::toMsg(q);
  return msg;
}

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& transform) {
  geometry_msgs::Pose msg;
  msg.position.x = transform.translation().x();
  msg.position.y = transform.translation().y();
  msg.position.z = transform.translation().z();
  const Eigen::Quaterniond q(transform.rotation());
  msg.orientation.w = q.w();
  msg.orientation.x = q.x();
  msg.orientation.y = q.y();
  msg.orientation.z = q.z();
  return msg;
}

tf2::Transform toTransform(const ebslam::Pose2& pose) {
  tf2::Quaternion q;
  q.setRPY(0.0, 0.0, pose.theta);
  return tf2::Transform(q, tf2::Vector3(pose.x, pose.y, 0.0));
}

namespace {

geometry_msgs::TransformStamped stampedTransform(const ros::Time& stamp, const std::string& parent,
                                                 const std::string& child) {
  geometry_msgs::TransformStamped msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = parent;
  msg.child_frame_id = child;
  return msg;
}

}  // namespace

geometry_msgs::TransformStamped toTransformMsg(const tf2::Transform& transform,
                                               const ros::Time& stamp, const std::string& parent,
                                               const std::string& child) {
  geometry_msgs::TransformStamped msg = stampedTransform(stamp, parent, child);
  msg.transform = tf2::toMsg(transform);
  return msg;
}

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& transform,
                                               const ros::Time& stamp, const std::string& parent,
                                               const std::string& child) {
  geometry_msgs::TransformStamped msg = stampedTransform(stamp, parent, child);
  const geometry_msgs::Pose pose = toPoseMsg(transform);
  msg.transform.translation.x = pose.position.x;
  msg.transform.translation.y = pose.position.y;
  msg.transform.translation.z = pose.position.z;
  msg.transform.rotation = pose.orientation;
  return msg;
}

Eigen::Isometry3d toIsometry(const geometry_msgs::Transform& transform) {
  const geometry_msgs::Quaternion& q = transform.rotation;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  t.translation() =
      Eigen::Vector3d(transform.translation.x, transform.translation.y, transform.translation.z);
  return t;
}

Eigen::Isometry3d fromXyzRpy(const std::array<double, 3>& xyz, const std::array<double, 3>& rpy) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  return t;
}

namespace {

std::array<double, 3> threeNumbers(const std::map<std::string, std::string>& values,
                                   const std::string& key, const std::string& path) {
  const auto it = values.find(key);
  if (it == values.end()) throw std::runtime_error("'" + path + "' has no " + key);
  std::string text = it->second;
  for (char& c : text) {
    if (c == '[' || c == ']' || c == ',') c = ' ';
  }
  std::istringstream in(text);
  std::array<double, 3> out{};
  std::string rest;
  if (!(in >> out[0] >> out[1] >> out[2]) || (in >> rest)) {
    throw std::runtime_error("'" + path + "': " + key + " = '" + it->second +
                             "' is not a list of three numbers");
  }
  return out;
}

}  // namespace

Eigen::Isometry3d readMountFromParams(const std::string& params_yaml) {
  const std::map<std::string, std::string> values = readFlatYaml(params_yaml, "parameter file");
  return fromXyzRpy(threeNumbers(values, "mount_xyz", params_yaml),
                    threeNumbers(values, "mount_rpy", params_yaml));
}

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

namespace {

struct LensName {
  ebslam::DistortionModel model;
  const char* name;
};
constexpr LensName kLensNames[] = {{ebslam::DistortionModel::kPlumbBob, "plumb_bob"},
                                   {ebslam::DistortionModel::kEquidistant, "equidistant"},
                                   {ebslam::DistortionModel::kDistortEq63, "ebslam_eq63"},
                                   {ebslam::DistortionModel::kUndistortEq83, "ebslam_eq83"},
                                   {ebslam::DistortionModel::kDivideEq81, "ebslam_eq81"}};

}  // namespace

sensor_msgs::CameraInfo toCameraInfoMsg(const ebslam::CameraModel& camera,
                                        const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info =
      toCameraInfoMsg(camera.width, camera.height, camera.fx(), camera.fy(),
                      camera.principal_point.x(), camera.principal_point.y(), header);
  for (const LensName& lens : kLensNames) {
    if (lens.model == camera.distortion_model) info.distortion_model = lens.name;
  }
  const auto& k = camera.lens_coefficients;
  switch (camera.distortion_model) {
    case ebslam::DistortionModel::kPlumbBob:
      info.D.assign(k.begin(), k.end());
      break;
    case ebslam::DistortionModel::kEquidistant:
      info.D.assign(k.begin(), k.begin() + 4);
      break;
    default:
      info.D = {camera.kappa1, camera.kappa2};
  }
  return info;
}

ebslam::CameraModel toCameraModel(const sensor_msgs::CameraInfo& info) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("CameraInfo: " + what);
  };
  if (info.width == 0 || info.height == 0 || info.width > 65535 || info.height > 65535) {
    fail("width and height must lie in 1..65535 (uncalibrated camera?)");
  }
  if (info.binning_x > 1 || info.binning_y > 1) fail("binning is not supported");
  if (info.roi.width != 0 || info.roi.height != 0 || info.roi.x_offset != 0 ||
      info.roi.y_offset != 0) {
    fail("a region of interest is not supported");
  }
  for (double v : info.K) {
    if (!std::isfinite(v)) fail("K is not finite");
  }
  if (!(info.K[0] > 0.0) || !(info.K[4] > 0.0)) fail("K's focal lengths must be positive");
  if (info.K[1] != 0.0 || info.K[3] != 0.0 || info.K[6] != 0.0 || info.K[7] != 0.0 ||
      info.K[8] != 1.0) {
    fail("K must be [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");
  }
  ebslam::CameraModel camera;
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  camera.focal_px = info.K[0];
  camera.focal_y_px = info.K[4];
  camera.principal_point = Eigen::Vector2d(info.K[2], info.K[5]);
  camera.distortion_model = ebslam::DistortionModel::kPlumbBob;
  camera.lens_coefficients = {};
  const std::string& model = info.distortion_model;
  const std::vector<double>& d = info.D;
  const auto length = [&](std::initializer_list<std::size_t> allowed) {
    for (std::size_t n : allowed) {
      if (d.size() == n) return;
    }
    fail("distortion model '" + model + "' with " + std::to_string(d.size()) +
         " coefficients in D");
  };
  if (model.empty() || model == "plumb_bob" || model == "rational_polynomial") {
    if (model.empty()) {
      length({0});
    } else if (model == "plumb_bob") {
      length({0, 5});
    } else {
      length({8});
      if (d[5] != 0.0 || d[6] != 0.0 || d[7] != 0.0) {
        fail("rational_polynomial with k4..k6 != 0 is not supported (calibrate with plumb_bob)");
      }
    }
    for (std::size_t i = 0; i < std::min<std::size_t>(5, d.size()); ++i) {
      camera.lens_coefficients[i] = d[i];
    }
  } else if (model == "equidistant" || model == "fisheye") {
    length({4});
    camera.distortion_model = ebslam::DistortionModel::kEquidistant;
    for (std::size_t i = 0; i < 4; ++i) camera.lens_coefficients[i] = d[i];
  } else {
    bool known = false;
    for (const LensName& lens : kLensNames) {
      if (model == lens.name && lens.model != ebslam::DistortionModel::kPlumbBob &&
          lens.model != ebslam::DistortionModel::kEquidistant) {
        known = true;
        camera.distortion_model = lens.model;
      }
    }
    if (!known) {
      fail("unknown distortion model '" + model +
           "' (plumb_bob, equidistant, rational_polynomial with k4..k6 = 0, ebslam_eq63, "
           "ebslam_eq83, ebslam_eq81)");
    }
    length({2});
    camera.kappa1 = d[0];
    camera.kappa2 = d[1];
  }
  for (double v : d) {
    if (!std::isfinite(v)) fail("D is not finite");
  }
  try {
    camera.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  return camera;
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
