// dasp_ros/Dasp: Depth-Adaptive Superpixels (thesis ch. 3) of a registered RGB-D stream.
//
// Subscriptions (relative names, rgbd_launch convention; matched by stamp, see RgbdInput):
//   rgb/image_rect_color        sensor_msgs/Image (bgr8, rgb8, bgra8, rgba8, mono8)
//   depth_registered/image_raw  sensor_msgs/Image (16UC1 mm or 32FC1 m), registered to rgb
//   rgb/camera_info             sensor_msgs/CameraInfo (K; P when K is zero)
// Publications, all with the colour image's header (stamp and frame_id):
//   superpixels                 ebslam_msgs/SuperpixelArray (every field, neighbourhood edges)
//   superpixels/labels          sensor_msgs/Image 32SC1, superpixel index per pixel, -1 = none
//   superpixels/overlay         sensor_msgs/Image bgr8 boundaries over the colour image (lazy)
//   superpixels/markers         visualization_msgs/MarkerArray, one disc per superpixel (lazy)
//   superpixels/cloud           sensor_msgs/PointCloud2 of the superpixel centres (lazy)
// One DaspSegmenter is kept, so its per-pixel buffers are reused from frame to frame.
#include <dasp/dasp.h>
#include <dasp/superpixel_graph.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>
#include <boost/make_shared.hpp>

#include <ctime>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "dasp_ros/DaspNodeletConfig.h"
#include "dasp_ros/conversions.h"
#include "dasp_ros/rendering.h"
#include "dasp_ros/rgbd_input.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {
namespace {

double threadCpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

class DaspNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "Dasp " + getName(),
                                   [&] { config_ = loadDaspNodeConfig(pnh); });
    segmenter_ = std::make_unique<dasp::DaspSegmenter>(config_.dasp);

    image_transport::ImageTransport transport(nh);
    superpixels_pub_ = nh.advertise<ebslam_msgs::SuperpixelArray>("superpixels", 5);
    labels_pub_ = transport.advertise("superpixels/labels", 5);
    overlay_pub_ = transport.advertise("superpixels/overlay", 1);
    markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("superpixels/markers", 1);
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("superpixels/cloud", 1);

    reconfigure_ = std::make_unique<ebslam_ros_common::RuntimeKnobs<DaspNodeletConfig>>(pnh);
    ebslam_ros_common::markReconfigureParamsRead<DaspNodeletConfig>(pnh);
    reconfigure_->setCallback(
        [this](DaspNodeletConfig& c, uint32_t level) { onReconfigure(c, level); });

    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
    updater_->setHardwareID("none");
    updater_->add("segmentation", this, &DaspNodelet::diagnose);
    input_ = std::make_unique<RgbdInput>(
        nh, config_.input, [this](const auto& color, const auto& depth, const auto& info) {
          onFrame(color, depth, info);
        });
    watchdog_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
      const std::string stall = input_->stallReason();
      if (!stall.empty()) NODELET_WARN_THROTTLE(5.0, "%s", stall.c_str());
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stall_ = stall;
      }
      updater_->update();
    });
    NODELET_INFO("Dasp: %s %s, %s, %s sync; publishing superpixels", input_->colorTopic().c_str(),
                 input_->depthTopic().c_str(), input_->infoTopic().c_str(),
                 config_.input.approximate_sync ? "approximate" : "exact");
  }

  void onReconfigure(DaspNodeletConfig& c, uint32_t /*level*/) {
    std::lock_guard<std::mutex> lock(mutex_);
    dasp::DaspConfig& d = config_.dasp;
    try {
      d.size_mode = parseSizeMode(c.size_mode);
    } catch (const std::invalid_argument& e) {
      NODELET_ERROR("%s; keeping the previous size mode", e.what());
      c.size_mode = d.size_mode == dasp::SizeMode::kCount ? "count" : "radius";
    }
    d.superpixel_count = c.superpixel_count;
    d.radius_m = static_cast<float>(c.radius);
    d.iterations = c.iterations;
    d.weight_spatial = static_cast<float>(c.weight_spatial);
    d.weight_color = static_cast<float>(c.weight_color);
    d.weight_normal = static_cast<float>(c.weight_normal);
    d.enforce_connectivity = c.enforce_connectivity;
    segmenter_->setConfig(d);
  }

  void onFrame(const sensor_msgs::ImageConstPtr& color_msg,
               const sensor_msgs::ImageConstPtr& depth_msg,
               const sensor_msgs::CameraInfoConstPtr& info_msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double cpu_start = threadCpuMilliseconds();
    const std_msgs::Header& header = color_msg->header;
    if (!last_stamp_.isZero() && header.stamp < last_stamp_) {
      // Frames are segmented independently, so the frame is still used; a looping bag does this.
      NODELET_WARN_THROTTLE(1.0, "%s: stamp went back by %.3f s (%.3f after %.3f); processing it",
                            input_->colorTopic().c_str(), (last_stamp_ - header.stamp).toSec(),
                            header.stamp.toSec(), last_stamp_.toSec());
    }
    last_stamp_ = header.stamp;
    dasp::Superpixels superpixels;
    dasp::RgbdFrame frame;
    try {
      // The frame lives only in this callback, while the messages do: no copy of the images.
      frame = input_->convert(*color_msg, *depth_msg, *info_msg, ImageData::kShare);
      superpixels = segmenter_->compute(frame);
    } catch (const InputError& e) {
      reject(e.what());
      return;
    } catch (const std::invalid_argument& e) {
      reject(input_->colorTopic() + " frame at " + std::to_string(header.stamp.toSec()) + ": " +
             e.what());
      return;
    }
    const double dasp_ms = threadCpuMilliseconds() - cpu_start;
    ebslam_msgs::SuperpixelArray array = toSuperpixelArrayMsg(superpixels, header);
    array.edges = toEdgeMsgs(dasp::buildSuperpixelGraph(superpixels, config_.graph));
    superpixels_pub_.publish(boost::make_shared<ebslam_msgs::SuperpixelArray>(std::move(array)));
    labels_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toLabelImageMsg(superpixels.labels, header)));
    if (overlay_pub_.getNumSubscribers() > 0) {
      overlay_pub_.publish(
          toColorImageMsg(drawBoundaryOverlay(frame.color, superpixels.labels), header));
    }
    if (markers_pub_.getNumSubscribers() > 0) {
      markers_pub_.publish(toMarkerArray(superpixels.superpixels, header));
    }
    if (cloud_pub_.getNumSubscribers() > 0) {
      cloud_pub_.publish(toCentreCloud(superpixels.superpixels, header));
    }
    ++processed_;
    last_count_ = superpixels.superpixels.size();
    last_dasp_ms_ = dasp_ms;
    last_total_ms_ = threadCpuMilliseconds() - cpu_start;
  }

  void reject(const std::string& reason) {
    ++rejected_;
    last_error_ = reason;
    if (throttle_.allow(reason)) NODELET_WARN("frame skipped: %s", reason.c_str());
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stall_.empty()) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, stall_);
    } else if (processed_ == 0 && rejected_ == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for RGB-D frames");
    } else if (!last_error_.empty() && rejected_ > 0 && processed_ == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, last_error_);
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "segmenting");
    }
    const auto received = input_->receivedCounts();
    status.add("colour images received", received[0]);
    status.add("depth images received", received[1]);
    status.add("camera_infos received", received[2]);
    status.add("frames matched", input_->matchedCount());
    status.add("frames segmented", processed_);
    status.add("frames rejected", rejected_);
    status.add("last rejection", last_error_);
    status.add("superpixels in the last frame", last_count_);
    status.add("DASP CPU time of the last frame [ms]", last_dasp_ms_);
    status.add("CPU time of the last frame with publishing [ms]", last_total_ms_);
  }

  DaspNodeConfig config_;
  std::unique_ptr<dasp::DaspSegmenter> segmenter_;
  std::unique_ptr<RgbdInput> input_;
  ros::Publisher superpixels_pub_, markers_pub_, cloud_pub_;
  image_transport::Publisher labels_pub_, overlay_pub_;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<DaspNodeletConfig>> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer watchdog_;

  ReasonThrottle throttle_;
  std::mutex mutex_;  // frame callback, reconfigure and diagnostics
  ros::Time last_stamp_;
  std::size_t processed_ = 0, rejected_ = 0, last_count_ = 0;
  double last_dasp_ms_ = 0.0, last_total_ms_ = 0.0;
  std::string last_error_, stall_;
};

}  // namespace dasp_ros

PLUGINLIB_EXPORT_CLASS(dasp_ros::DaspNodelet, nodelet::Nodelet)
