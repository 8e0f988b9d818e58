// Publishes the frames of an RGB-D image folder as a registered colour/depth stream.
//
// Publications (relative names, remap them in the launch file):
//   rgb/image_rect_color          sensor_msgs/Image bgr8
//   depth_registered/image_raw    sensor_msgs/Image 16UC1, millimetres, registered to rgb
//   rgb/camera_info               sensor_msgs/CameraInfo (pinhole, no distortion)
//   depth_registered/camera_info  sensor_msgs/CameraInfo (identical: the depth is registered)
// (the rgbd_launch / openni2_launch names, which dasp_ros/Dasp and Tdasp subscribe to)
// All four carry the same stamp (wall clock at publication) and ~frame_id.
// A source that cannot start (~folder unset, missing or without frames, a bad parameter) logs
// FATAL with the reason and does not load (a node exits). A frame that cannot be published (an
// unreadable or mismatched file, a size whose aspect ratio differs from the calibration's) is
// skipped, and named in an error the first time (also when looping, at any rate). Frames of
// another size with the calibration's aspect ratio get scaled intrinsics (a warning per size).
#include <dasp/rgbd_io.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <boost/make_shared.hpp>

#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dasp_ros/conversions.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {

class RgbdFolderSourceNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "RGB-D folder source " + getName(), [&] {
      config_ = loadRgbdFolderSourceConfig(getPrivateNodeHandle());
      frames_ = dasp::listRgbdFolder(config_.folder);
      if (frames_.empty()) {
        throw std::invalid_argument("no <name>_rgb.png with <name>_depth_mm.png in ~folder '" +
                                    config_.folder + "'");
      }
    });
    color_pub_ = nh.advertise<sensor_msgs::Image>("rgb/image_rect_color", 2);
    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 2);
    color_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 2);
    depth_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("depth_registered/camera_info", 2);
    NODELET_INFO("publishing %zu frames from '%s' at %.1f Hz%s%s", frames_.size(),
                 config_.folder.c_str(), config_.rate_hz, config_.loop ? " in a loop" : "",
                 config_.wait_for_subscribers ? " once a subscriber connects" : "");
    timer_ = nh.createWallTimer(ros::WallDuration(1.0 / config_.rate_hz),
                                &RgbdFolderSourceNodelet::publishNext, this);
  }

  void publishNext(const ros::WallTimerEvent&) {
    if (published_ == 0 && failed_ == 0 && config_.wait_for_subscribers && !subscriberSettled()) {
      return;
    }
    if (next_ >= frames_.size()) {
      if (!config_.loop) {
        NODELET_INFO("published all %zu frames (%zu unreadable)", frames_.size(), failed_);
        timer_.stop();
        return;
      }
      next_ = 0;
    }
    const dasp::RgbdFramePaths& paths = frames_[next_++];
    dasp::RgbdFrame frame;
    try {
      frame = dasp::loadRgbdFrame(paths, config_.intrinsics);
    } catch (const std::exception& error) {
      skip(paths, error.what());
      return;
    }
    const std::optional<dasp::Intrinsics> intrinsics =
        config_.intrinsicsFor(frame.color.cols, frame.color.rows);
    if (!intrinsics) {
      skip(paths, std::to_string(frame.color.cols) + "x" + std::to_string(frame.color.rows) +
                      " pixels, another aspect ratio than the " +
                      std::to_string(config_.calibration_width) + "x" +
                      std::to_string(config_.calibration_height) +
                      " of ~fx..~cy (~calibration_width, ~calibration_height)");
      return;
    }
    frame.intrinsics = *intrinsics;
    if (frame.color.cols != config_.calibration_width &&
        scaled_sizes_.insert({frame.color.cols, frame.color.rows}).second) {
      NODELET_WARN(
          "frames of %dx%d pixels in '%s': the intrinsics of the %dx%d calibration scaled to fx "
          "%.2f fy %.2f cx %.2f cy %.2f",
          frame.color.cols, frame.color.rows, config_.folder.c_str(), config_.calibration_width,
          config_.calibration_height, intrinsics->fx, intrinsics->fy, intrinsics->cx,
          intrinsics->cy);
    }
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = config_.frame_id;
    ++published_;
    // Shared pointers: subscribers in the same nodelet manager get the messages without a
    // serialisation and a copy of every image.
    const auto info = boost::make_shared<sensor_msgs::CameraInfo>(
        toCameraInfo(frame.intrinsics, frame.color.cols, frame.color.rows, header));
    color_info_pub_.publish(info);
    depth_info_pub_.publish(info);
    color_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toColorImageMsg(frame.color, header)));
    depth_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toDepthImageMsg(frame.depth, header)));
  }

  // A frame that cannot be published: named with its reason the first time (a throttle would
  // hide the reasons of other frames at low rates), counted every time.
  void skip(const dasp::RgbdFramePaths& paths, const std::string& reason) {
    ++failed_;
    if (reported_.insert(paths.name).second) {
      NODELET_ERROR("skipping frame %s of '%s': %s", paths.name.c_str(), config_.folder.c_str(),
                    reason.c_str());
    }
  }

  // roscpp counts a subscriber before its side of the connection is ready, and messages sent in
  // that window are lost; so the first frame goes out once a subscriber has been there 0.5 s.
  bool subscriberSettled() {
    if (color_pub_.getNumSubscribers() == 0) {
      subscriber_seen_ = ros::WallTime();
      return false;
    }
    const ros::WallTime now = ros::WallTime::now();
    if (subscriber_seen_.isZero()) subscriber_seen_ = now;
    return (now - subscriber_seen_).toSec() >= 0.5;
  }

  RgbdFolderSourceConfig config_;
  ros::WallTime subscriber_seen_;
  std::vector<dasp::RgbdFramePaths> frames_;
  std::size_t next_ = 0;
  std::size_t published_ = 0;
  std::size_t failed_ = 0;
  std::set<std::string> reported_;              // frames whose skip was logged
  std::set<std::pair<int, int>> scaled_sizes_;  // frame sizes whose scaling was logged
  ros::Publisher color_pub_, depth_pub_, color_info_pub_, depth_info_pub_;
  ros::WallTimer timer_;
};

}  // namespace dasp_ros

PLUGINLIB_EXPORT_CLASS(dasp_ros::RgbdFolderSourceNodelet, nodelet::Nodelet)
