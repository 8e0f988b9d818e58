#include "ebslam_ros/conversions.h"

#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

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
