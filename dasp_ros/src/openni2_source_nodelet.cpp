// dasp_ros/OpenNi2Source: a PrimeSense-class RGB-D camera (PrimeSense Carmine, Asus Xtion,
// Kinect through OpenNI2 drivers) as a registered colour/depth stream.
//
// Publications (relative names, the rgbd_launch convention; images through image_transport):
//   rgb/image_rect_color          sensor_msgs/Image rgb8
//   depth_registered/image_raw    sensor_msgs/Image 16UC1, millimetres, registered to rgb
//   rgb/camera_info               sensor_msgs/CameraInfo (from the field of view, or
//   ~camera_info_url) depth_registered/camera_info  sensor_msgs/CameraInfo (the same: depth is
//   registered)
// All four carry the same stamp (arrival of the colour frame) and ~frame_id.
// While no device can be opened, or after it stops delivering frames (unplugged), the nodelet
// logs the reason and tries again after ~retry_min, doubling up to ~retry_max seconds.
#include <OpenNI.h>
#include <camera_info_manager/camera_info_manager.h>
#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstring>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>
#include <thread>

#include "dasp_ros/conversions.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {
namespace {

// OpenNI2's last error without its tabs and line breaks.
std::string oniError() {
  std::string text = openni::OpenNI::getExtendedError();
  for (char& c : text) {
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  }
  const auto first = text.find_first_not_of(' ');
  const auto last = text.find_last_not_of(' ');
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

}  // namespace

class OpenNi2SourceNodelet : public nodelet::Nodelet {
 public:
  ~OpenNi2SourceNodelet() override {
    {
      std::lock_guard<std::mutex> lock(wake_mutex_);
      running_ = false;
    }
    wake_.notify_all();
    if (worker_.joinable()) worker_.join();
    closeDevice();
    if (initialised_) openni::OpenNI::shutdown();
  }

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "OpenNi2Source " + getName(),
                                   [&] { config_ = loadOpenNi2SourceConfig(pnh); });
    image_transport::ImageTransport transport(nh);
    color_pub_ = transport.advertise("rgb/image_rect_color", 2);
    depth_pub_ = transport.advertise("depth_registered/image_raw", 2);
    color_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 2);
    depth_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("depth_registered/camera_info", 2);
    if (!config_.camera_info_url.empty()) {
      info_manager_ = std::make_unique<camera_info_manager::CameraInfoManager>(
          ros::NodeHandle(nh, "rgb"), "openni2_rgb", config_.camera_info_url);
    }
    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
    updater_->setHardwareID(config_.device_uri.empty() ? "first OpenNI2 device"
                                                       : config_.device_uri);
    updater_->add("device", this, &OpenNi2SourceNodelet::diagnose);
    diagnostics_timer_ = nh.createWallTimer(
        ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { updater_->update(); });
    running_ = true;
    worker_ = std::thread([this] { run(); });
  }

  // Connect, stream until the device fails, wait with backoff, repeat.
  void run() {
    double backoff = config_.retry_min_s;
    while (running_) {
      std::string error;
      if (openDevice(&error)) {
        backoff = config_.retry_min_s;
        setState("streaming", "");
        stream(&error);
        closeDevice();
        if (!running_) break;
      }
      ++failures_;
      setState("no device", error);
      NODELET_ERROR("OpenNI2 device '%s': %s; retrying in %.1f s",
                    config_.device_uri.empty() ? "(first found)" : config_.device_uri.c_str(),
                    error.c_str(), backoff);
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_.wait_for(lock, std::chrono::duration<double>(backoff), [this] { return !running_; });
      backoff = std::min(2.0 * backoff, config_.retry_max_s);
    }
  }

  bool openDevice(std::string* error) {
    if (!initialised_) {
      if (openni::OpenNI::initialize() != openni::STATUS_OK) {
        *error = std::string("OpenNI2 initialisation failed: ") + oniError();
        return false;
      }
      initialised_ = true;
    }
    const char* uri = config_.device_uri.empty() ? openni::ANY_DEVICE : config_.device_uri.c_str();
    if (device_.open(uri) != openni::STATUS_OK) {
      *error = std::string("cannot open: ") + oniError() +
               " (is it plugged in, and readable by this user? see README: udev)";
      return false;
    }
    auto fail = [&](const std::string& what) {
      *error = what + ": " + oniError();
      closeDevice();
      return false;
    };
    if (depth_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      return fail("no depth stream");
    }
    if (color_.create(device_, openni::SENSOR_COLOR) != openni::STATUS_OK) {
      return fail("no colour stream");
    }
    openni::VideoMode depth_mode, color_mode;
    depth_mode.setResolution(config_.width, config_.height);
    depth_mode.setFps(config_.fps);
    depth_mode.setPixelFormat(openni::PIXEL_FORMAT_DEPTH_1_MM);
    color_mode.setResolution(config_.width, config_.height);
    color_mode.setFps(config_.fps);
    color_mode.setPixelFormat(openni::PIXEL_FORMAT_RGB888);
    if (depth_.setVideoMode(depth_mode) != openni::STATUS_OK) {
      return fail("depth mode " + std::to_string(config_.width) + "x" +
                  std::to_string(config_.height) + " at " + std::to_string(config_.fps) +
                  " Hz not supported");
    }
    if (color_.setVideoMode(color_mode) != openni::STATUS_OK) {
      return fail("colour mode not supported");
    }
    if (device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
      device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR);
    } else {
      return fail("the device cannot register depth to colour");
    }
    device_.setDepthColorSyncEnabled(true);
    if (depth_.start() != openni::STATUS_OK) return fail("cannot start the depth stream");
    if (color_.start() != openni::STATUS_OK) return fail("cannot start the colour stream");
    open_ = true;
    intrinsics_ =
        intrinsicsFromFieldOfView(color_.getHorizontalFieldOfView(),
                                  color_.getVerticalFieldOfView(), config_.width, config_.height);
    NODELET_INFO("OpenNI2 device '%s' streaming %dx%d at %d Hz (fx %.1f px from the field of view)",
                 device_.getDeviceInfo().getName(), config_.width, config_.height, config_.fps,
                 intrinsics_.fx);
    return true;
  }

  // Publishes frame pairs until the device stops delivering (2 s without a frame) or shutdown.
  void stream(std::string* error) {
    openni::VideoStream* streams[] = {&color_, &depth_};
    openni::VideoFrameRef color_frame, depth_frame;
    bool have_color = false, have_depth = false;
    while (running_) {
      int ready = -1;
      if (openni::OpenNI::waitForAnyStream(streams, 2, &ready, 2000) != openni::STATUS_OK) {
        *error = std::string("no frame for 2 s (unplugged?): ") + oniError();
        return;
      }
      if (ready == 0 && color_.readFrame(&color_frame) == openni::STATUS_OK) have_color = true;
      if (ready == 1 && depth_.readFrame(&depth_frame) == openni::STATUS_OK) have_depth = true;
      if (!(have_color && have_depth)) continue;
      have_color = have_depth = false;
      publish(color_frame, depth_frame);
    }
  }

  void publish(const openni::VideoFrameRef& color, const openni::VideoFrameRef& depth) {
    if (color.getWidth() != depth.getWidth() || color.getHeight() != depth.getHeight()) return;
    std_msgs::Header header;
    header.stamp = ros::Time::now();  // arrival: the device clock is not the ROS clock
    header.frame_id = config_.frame_id;
    const int w = color.getWidth(), h = color.getHeight();
    const cv::Mat rgb(h, w, CV_8UC3, const_cast<void*>(color.getData()),
                      static_cast<size_t>(color.getStrideInBytes()));
    const cv::Mat mm(h, w, CV_16UC1, const_cast<void*>(depth.getData()),
                     static_cast<size_t>(depth.getStrideInBytes()));
    sensor_msgs::CameraInfo info = info_manager_ && info_manager_->isCalibrated()
                                       ? info_manager_->getCameraInfo()
                                       : toCameraInfo(intrinsics_, w, h, header);
    info.header = header;
    color_info_pub_.publish(info);
    depth_info_pub_.publish(info);
    color_pub_.publish(
        cv_bridge::CvImage(header, sensor_msgs::image_encodings::RGB8, rgb).toImageMsg());
    depth_pub_.publish(toDepthImageMsg(mm, header));
    ++published_;
  }

  void closeDevice() {
    if (!open_ && !device_.isValid()) return;
    color_.stop();
    depth_.stop();
    color_.destroy();
    depth_.destroy();
    device_.close();
    open_ = false;
  }

  void setState(const std::string& state, const std::string& error) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    state_ = state;
    if (!error.empty()) last_error_ = error;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    if (state_ == "streaming") {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "streaming");
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "no device: " + last_error_);
    }
    status.add("device URI", config_.device_uri.empty() ? "(first found)" : config_.device_uri);
    status.add("frames published", published_.load());
    status.add("failed connection attempts", failures_.load());
    status.add("last error", last_error_);
  }

  OpenNi2SourceConfig config_;
  image_transport::Publisher color_pub_, depth_pub_;
  ros::Publisher color_info_pub_, depth_info_pub_;
  std::unique_ptr<camera_info_manager::CameraInfoManager> info_manager_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diagnostics_timer_;

  bool initialised_ = false, open_ = false;
  openni::Device device_;
  openni::VideoStream depth_, color_;
  dasp::Intrinsics intrinsics_;

  std::thread worker_;
  std::atomic<bool> running_{false};
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::atomic<std::size_t> published_{0}, failures_{0};
  std::mutex state_mutex_;
  std::string state_ = "connecting", last_error_;
};

}  // namespace dasp_ros

PLUGINLIB_EXPORT_CLASS(dasp_ros::OpenNi2SourceNodelet, nodelet::Nodelet)
