// dasp_ros/Tdasp: t-DASP video segmentation (thesis ch. 5) of a registered RGB-D stream:
// streaming DASP seeded by Delta Density Sampling, superpixel strands, the reduced strand graph,
// its spectral globalisation and Semi-Supervised Hysteresis Segmentation.
//
// Subscriptions: as dasp_ros/Dasp (rgb/image_rect_color, depth_registered/image_raw,
// rgb/camera_info). Publications, all with the colour image's header:
//   superpixels          ebslam_msgs/SuperpixelArray of the frame (ids index the array; the
//                        identity along time is Segmentation.strand_ids)
//   superpixels/labels   sensor_msgs/Image 32SC1
//   segmentation         ebslam_msgs/Segmentation: segment_ids (persistent over frames),
//                        strand_ids (persistent, wrap at 2^31), ultrametric empty (t-DASP's
//                        boundary weights live on the strand graph), threshold = t_normal
//   segments/labels      sensor_msgs/Image 32SC1, persistent segment label per pixel
//   superpixels/overlay, segments/overlay   sensor_msgs/Image bgr8 (lazy)
// Services: ~reset (std_srvs/Trigger) forgets the stream. The stream is also reset when the
// stamp goes back (a looping bag) or the image size changes. State is bounded by
// ~strands/max_strands.
#include <dasp/superpixel_graph.h>
#include <dasp/tdasp.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <std_srvs/Trigger.h>
#include <boost/make_shared.hpp>

#include <algorithm>
#include <ctime>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "dasp_ros/conversions.h"
#include "dasp_ros/rendering.h"
#include "dasp_ros/rgbd_input.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {

class TdaspNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "Tdasp " + getName(), [&] {
      config_ = loadTdaspNodeConfig(pnh);
      tdasp_ = std::make_unique<dasp::TemporalDasp>(config_.tdasp);
    });
    image_transport::ImageTransport transport(nh);
    superpixels_pub_ = nh.advertise<ebslam_msgs::SuperpixelArray>("superpixels", 5);
    labels_pub_ = transport.advertise("superpixels/labels", 5);
    overlay_pub_ = transport.advertise("superpixels/overlay", 1);
    segmentation_pub_ = nh.advertise<ebslam_msgs::Segmentation>("segmentation", 5);
    segment_labels_pub_ = transport.advertise("segments/labels", 5);
    segment_overlay_pub_ = transport.advertise("segments/overlay", 1);
    reset_service_ = pnh.advertiseService("reset", &TdaspNodelet::onReset, this);

    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
    updater_->setHardwareID("none");
    updater_->add("segmentation", this, &TdaspNodelet::diagnose);
    input_ = std::make_unique<RgbdInput>(
        nh, config_.input, [this](const auto& color, const auto& depth, const auto& info) {
          onFrame(color, depth, info);
        });
    // t-DASP costs about as much as a 30 Hz frame period on one core: when it falls behind, the
    // frames that arrive meanwhile are skipped (the subscription queues keep the newest), and the
    // skips are counted here from the camera_infos' arrivals, reported on diagnostics and in a
    // throttled warning instead of being lost silently.
    input_->countArrivals(getMTNodeHandle());
    watchdog_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
      const std::string stall = input_->stallReason();
      if (!stall.empty()) NODELET_WARN_THROTTLE(5.0, "%s", stall.c_str());
      const std::size_t arrived = input_->arrivedCount();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stall_ = stall;
        // Frames in the queues are not skipped yet: a skip counts once the arrivals are ahead
        // by more than the queue.
        const std::size_t handled =
            processed_ + rejected_ + static_cast<std::size_t>(config_.input.queue_size);
        skipped_ = std::max(skipped_, arrived > handled ? arrived - handled : std::size_t{0});
        if (skipped_ > reported_skipped_) {
          NODELET_WARN_THROTTLE(
              10.0,
              "t-DASP is slower than its input (last frame %.1f ms): %zu of %zu frames skipped "
              "so far, each output is the newest frame; lower ~superpixel_count or the input "
              "rate to segment every frame",
              last_total_ms_, skipped_, arrived);
          reported_skipped_ = skipped_;
        }
      }
      updater_->update();
    });
  }

  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::lock_guard<std::mutex> lock(mutex_);
    resetLocked("reset service called");
    response.success = true;
    response.message = "t-DASP stream reset";
    return true;
  }

  // A new stream numbers its strands and segments from 0 again; the offsets keep the published
  // ids unique over resets, so that no subscriber mistakes a new strand for an old one.
  // `log`: false for resets caused by input, which onFrame reports throttled itself.
  void resetLocked(const std::string& why, bool log = true) {
    tdasp_ = std::make_unique<dasp::TemporalDasp>(config_.tdasp);
    strand_offset_ = max_strand_ + 1;
    label_offset_ = max_label_ + 1;
    ++resets_;
    stream_frames_ = 0;
    if (log) NODELET_INFO("t-DASP reset: %s", why.c_str());
  }

  void onFrame(const sensor_msgs::ImageConstPtr& color_msg,
               const sensor_msgs::ImageConstPtr& depth_msg,
               const sensor_msgs::CameraInfoConstPtr& info_msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std_msgs::Header& header = color_msg->header;
    dasp::RgbdFrame frame;
    try {
      frame = input_->convert(*color_msg, *depth_msg, *info_msg);
    } catch (const InputError& e) {
      reject(e.what());
      return;
    }
    if (stream_frames_ > 0 && header.stamp < last_stamp_) {
      const std::string why = input_->colorTopic() + ": stamp went back by " +
                              std::to_string((last_stamp_ - header.stamp).toSec()) +
                              " s (a looping bag?)";
      // Throttled per reason: a stream stepping back with every frame must not flood the log.
      if (throttle_.allow(why)) NODELET_WARN("%s; t-DASP starts a new stream", why.c_str());
      resetLocked(why, false);
    } else if (stream_frames_ > 0 && frame.color.size() != last_size_) {
      const std::string why =
          input_->colorTopic() + ": image size changed from " + std::to_string(last_size_.width) +
          "x" + std::to_string(last_size_.height) + " to " + std::to_string(frame.color.cols) +
          "x" + std::to_string(frame.color.rows);
      if (throttle_.allow(why)) NODELET_WARN("%s; t-DASP starts a new stream", why.c_str());
      resetLocked(why, false);
    }
    dasp::TdaspFrame out;
    try {
      out = tdasp_->process(frame);
    } catch (const std::exception& e) {
      reject(input_->colorTopic() + " frame at " + std::to_string(header.stamp.toSec()) + ": " +
             e.what());
      return;
    }
    last_stamp_ = header.stamp;
    last_size_ = frame.color.size();
    ++stream_frames_;
    const dasp::Superpixels& superpixels = out.superpixels.superpixels;
    ebslam_msgs::SuperpixelArray array = toSuperpixelArrayMsg(superpixels, header);
    array.edges = toEdgeMsgs(dasp::buildSuperpixelGraph(superpixels, config_.tdasp.strands.graph));
    superpixels_pub_.publish(boost::make_shared<ebslam_msgs::SuperpixelArray>(std::move(array)));
    labels_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toLabelImageMsg(superpixels.labels, header)));
    ebslam_msgs::Segmentation segmentation;
    segmentation.header = header;
    segmentation.segment_ids.reserve(out.segment_label.size());
    segmentation.strand_ids.reserve(out.strand_id.size());
    for (std::int64_t label : out.segment_label) {
      max_label_ = std::max(max_label_, label + label_offset_);
      segmentation.segment_ids.push_back(static_cast<int32_t>(label + label_offset_));
    }
    for (std::int64_t id : out.strand_id) {
      max_strand_ = std::max(max_strand_, id + strand_offset_);
      segmentation.strand_ids.push_back(static_cast<int32_t>((id + strand_offset_) & 0x7fffffff));
    }
    if (label_offset_ > 0) out.segment_labels.setTo(-1 - label_offset_, out.segment_labels < 0);
    if (label_offset_ > 0) out.segment_labels += static_cast<int>(label_offset_);
    segmentation.threshold = config_.tdasp.hysteresis.normal;
    segmentation_pub_.publish(
        boost::make_shared<ebslam_msgs::Segmentation>(std::move(segmentation)));
    segment_labels_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toLabelImageMsg(out.segment_labels, header)));
    if (overlay_pub_.getNumSubscribers() > 0) {
      overlay_pub_.publish(
          toColorImageMsg(drawBoundaryOverlay(frame.color, superpixels.labels), header));
    }
    if (segment_overlay_pub_.getNumSubscribers() > 0) {
      segment_overlay_pub_.publish(toColorImageMsg(
          drawSegmentOverlay(superpixels.labels, superpixels.superpixels, out.segment_labels),
          header));
    }
    ++processed_;
    last_strands_ = out.strand_count;
    last_total_ms_ = out.timings.total_ms;
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
    } else if (rejected_ > 0 && processed_ == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, last_error_);
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK,
                     processed_ == 0 ? "waiting for RGB-D frames" : "segmenting");
    }
    status.add("frames arrived", input_->arrivedCount());
    status.add("frames segmented", processed_);
    status.add("frames skipped while busy", skipped_);
    status.add("frames rejected", rejected_);
    status.add("last rejection", last_error_);
    status.add("stream resets", resets_);
    status.add("frames since the last reset", stream_frames_);
    status.add("strands in the graph", last_strands_);
    status.add("max strands", config_.tdasp.strands.max_strands);
    status.add("wall time of the last frame [ms]", last_total_ms_);
  }

  TdaspNodeConfig config_;
  std::unique_ptr<dasp::TemporalDasp> tdasp_;
  std::unique_ptr<RgbdInput> input_;
  ros::Publisher superpixels_pub_, segmentation_pub_;
  image_transport::Publisher labels_pub_, overlay_pub_, segment_labels_pub_, segment_overlay_pub_;
  ros::ServiceServer reset_service_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer watchdog_;

  ReasonThrottle throttle_;
  std::mutex mutex_;
  ros::Time last_stamp_;
  cv::Size last_size_;
  std::size_t processed_ = 0, rejected_ = 0, resets_ = 0, stream_frames_ = 0;
  std::size_t skipped_ = 0, reported_skipped_ = 0;
  std::int64_t strand_offset_ = 0, label_offset_ = 0, max_strand_ = -1, max_label_ = -1;
  int last_strands_ = 0;
  double last_total_ms_ = 0.0;
  std::string last_error_, stall_;
};

}  // namespace dasp_ros

PLUGINLIB_EXPORT_CLASS(dasp_ros::TdaspNodelet, nodelet::Nodelet)
