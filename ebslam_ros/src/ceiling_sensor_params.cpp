#include "ceiling_sensor_params.h"

#include <camera_calibration_parsers/parse.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <ros/console.h>
#include <ros/master.h>
#include <ros/package.h>
#include <ros/topic.h>
#include <sensor_msgs/CameraInfo.h>

#include <stdexcept>
#include <vector>

#include "ebslam_ros/conversions.h"
#include "param_utils.h"

namespace ebslam_ros {

using ebslam_ros_common::param;
using ebslam_ros_common::requirePositive;

CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& nh) {
  CeilingSensorConfig config;
  ebslam::CameraModel& c = config.camera;
  c.width = param<int>(nh, "camera/width", c.width);
  c.height = param<int>(nh, "camera/height", c.height);
  c.focal_px = param<double>(nh, "camera/focal_px", c.focal_px);
  c.principal_point.x() = param<double>(nh, "camera/cx", c.principal_point.x());
  c.principal_point.y() = param<double>(nh, "camera/cy", c.principal_point.y());
  c.kappa1 = param<double>(nh, "camera/kappa1", c.kappa1);
  c.kappa2 = param<double>(nh, "camera/kappa2", c.kappa2);
  config.ceiling_distance_m = param<double>(nh, "ceiling_distance", config.ceiling_distance_m);
  config.camera_info_url = param<std::string>(nh, "camera_info_url", "");
  config.camera_info_wait_s = param<double>(nh, "camera_info_wait", config.camera_info_wait_s);
  if (c.width < 1 || c.height < 1 || c.width > 65535 || c.height > 65535) {
    fail(nh, "camera/width", "and camera/height must be in 1..65535");
  }
  const std::string preset = param<std::string>(nh, "camera/preset", "");
  if (!preset.empty()) {
    try {
      validateCore(nh, c);
      c = ebslam::CameraModel::preset(preset, c);
    } catch (const std::invalid_argument& e) {
      fail(nh, "camera/preset", e.what());
    }
  }
  requirePositive(config.ceiling_distance_m, nh, "ceiling_distance");
  if (!(config.camera_info_wait_s >= 0.0)) fail(nh, "camera_info_wait", "must be >= 0 [s]");
  validateCore(nh, c);
  return config;
}

void logCameraSource(const std::string& nodelet_name, const CeilingSensorConfig& config) {
  const ebslam::CameraModel& c = config.camera;
  ROS_INFO("%s: camera %dx%d, f = (%.2f, %.2f) px, c = (%.2f, %.2f) px, %s lens, from the %s",
           nodelet_name.c_str(), c.width, c.height, c.fx(), c.fy(), c.principal_point.x(),
           c.principal_point.y(),
           c.isSquarePinhole()                                           ? "pinhole"
           : c.distortion_model == ebslam::DistortionModel::kPlumbBob    ? "plumb_bob"
           : c.distortion_model == ebslam::DistortionModel::kEquidistant ? "equidistant"
                                                                         : "radial (kappa)",
           config.camera_source.c_str());
}

std::string cameraInfoUrlPath(const std::string& url) {
  const std::string file = "file://";
  const std::string package = "package://";
  if (url.rfind(file, 0) == 0) return url.substr(file.size());
  if (url.rfind(package, 0) == 0) {
    const std::string rest = url.substr(package.size());
    const std::size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    const std::string root = ros::package::getPath(name);
    if (root.empty()) throw std::invalid_argument("unknown package '" + name + "' in " + url);
    return root + (slash == std::string::npos ? "" : rest.substr(slash));
  }
  if (!url.empty() && url[0] == '/') return url;
  throw std::invalid_argument("camera_info_url '" + url +
                              "': only file://, package:// or an absolute path");
}

void resolveCameraInfo(const ros::NodeHandle& nh, CeilingSensorConfig& config) {
  if (!config.camera_info_url.empty()) {
    const std::string path = cameraInfoUrlPath(config.camera_info_url);
    std::string camera_name;
    sensor_msgs::CameraInfo info;
    if (!camera_calibration_parsers::readCalibration(path, camera_name, info)) {
      throw std::invalid_argument("~camera_info_url: cannot read a calibration from '" + path +
                                  "'");
    }
    try {
      config.camera = toCameraModel(info);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("~camera_info_url '" + path + "': " + e.what());
    }
    config.camera_source = "camera_info_url";
    return;
  }
  if (config.camera_info_wait_s <= 0.0) return;
  const std::string topic = nh.resolveName("camera_info");
  std::vector<ros::master::TopicInfo> topics;
  bool published = false;
  if (ros::master::getTopics(topics)) {
    for (const ros::master::TopicInfo& t : topics) published = published || t.name == topic;
  }
  if (!published) return;          // no publisher: the parameters
  ros::NodeHandle waiting_nh(nh);  // waitForMessage takes a mutable handle
  const sensor_msgs::CameraInfo::ConstPtr info =
      ros::topic::waitForMessage<sensor_msgs::CameraInfo>("camera_info", waiting_nh,
                                                          ros::Duration(config.camera_info_wait_s));
  if (!info) {
    throw std::invalid_argument(topic + " is advertised but sent no CameraInfo within " +
                                std::to_string(config.camera_info_wait_s) +
                                " s (~camera_info_wait; 0 takes the ~camera/* parameters)");
  }
  try {
    config.camera = toCameraModel(*info);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(topic + ": " + e.what());
  }
  config.camera_source = "camera_info topic";
}

}  // namespace ebslam_ros
