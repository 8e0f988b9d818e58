// dasp_ros/Sdasp: s-DASP image segmentation (thesis ch. 4) of the superpixels published by Dasp.
//
// Subscriptions (matched by identical stamps):
//   superpixels          ebslam_msgs/SuperpixelArray
//   superpixels/labels   sensor_msgs/Image 32SC1 (image_transport)
// Publications, all with the SuperpixelArray's header:
//   segmentation         ebslam_msgs/Segmentation (segment id per superpixel, ultrametric contour
//                        graph, the frame's cut threshold)
//   segments/labels      sensor_msgs/Image 32SC1, segment id per pixel, -1 = none
//   segments/overlay     sensor_msgs/Image bgr8: superpixel mean colours, segment boundaries red
//   (lazy) segments/ucm         sensor_msgs/Image 32FC1 merge levels or mono8 (~ucm_encoding)
//   (lazy)
// The segments are the core's dasp::computeSdasp: the ultrametric contour graph cut at
// dasp::cutThreshold (~cut adaptive: per frame from its merge levels, the default; global:
// ~threshold), on the superpixels rebuilt from the messages (float fields travel unchanged).
#include <dasp/sdasp.h>
#include <dasp/segmentation.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <sensor_msgs/image_encodings.h>
#include <boost/make_shared.hpp>

#include <cv_bridge/cv_bridge.h>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "dasp_ros/SdaspNodeletConfig.h"
#include "dasp_ros/conversions.h"
#include "dasp_ros/rendering.h"
#include "dasp_ros/rgbd_input.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {

class SdaspNodelet : public nodelet::Nodelet {
 private:
  using Array = ebslam_msgs::SuperpixelArray;
  using Policy = message_filters::sync_policies::ExactTime<Array, sensor_msgs::Image>;

  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "Sdasp " + getName(),
                                   [&] { config_ = loadSdaspNodeConfig(pnh); });
    array_topic_ = nh.resolveName("superpixels");
    labels_topic_ = nh.resolveName("superpixels/labels");
    image_transport::ImageTransport transport(nh);
    segmentation_pub_ = nh.advertise<ebslam_msgs::Segmentation>("segmentation", 5);
    labels_pub_ = transport.advertise("segments/labels", 5);
    overlay_pub_ = transport.advertise("segments/overlay", 1);
    ucm_pub_ = transport.advertise("segments/ucm", 1);

    reconfigure_ = std::make_unique<ebslam_ros_common::RuntimeKnobs<SdaspNodeletConfig>>(pnh);
    ebslam_ros_common::markReconfigureParamsRead<SdaspNodeletConfig>(pnh);
    reconfigure_->setCallback([this](SdaspNodeletConfig& c, uint32_t) {
      std::lock_guard<std::mutex> lock(mutex_);
      dasp::SdaspConfig next = config_.sdasp;
      next.threshold = static_cast<float>(c.threshold);
      next.adaptive_scale = static_cast<float>(c.adaptive_scale);
      next.adaptive_quantile = static_cast<float>(c.adaptive_quantile);
      next.adaptive_max_threshold = static_cast<float>(c.adaptive_max_threshold);
      std::string problem;
      try {
        next.cut = parseCutRule(c.cut);
        problem = checkSdaspCut(next);
      } catch (const std::invalid_argument& e) {
        problem = e.what();
      }
      if (problem.empty()) {
        config_.sdasp = next;
        return;
      }
      NODELET_WARN("reconfigure refused, the cut stays as it was: %s", problem.c_str());
      c.cut = cutRuleName(config_.sdasp.cut);
      c.threshold = config_.sdasp.threshold;
      c.adaptive_scale = config_.sdasp.adaptive_scale;
      c.adaptive_quantile = config_.sdasp.adaptive_quantile;
      c.adaptive_max_threshold = config_.sdasp.adaptive_max_threshold;
    });
    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
    updater_->setHardwareID("none");
    updater_->add("segmentation", this, &SdaspNodelet::diagnose);
    diagnostics_timer_ = nh.createWallTimer(
        ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { updater_->update(); });

    const uint32_t queue = static_cast<uint32_t>(config_.queue_size);
    transport_ = std::make_unique<image_transport::ImageTransport>(nh);
    array_sub_.subscribe(nh, "superpixels", queue);
    labels_sub_.subscribe(*transport_, "superpixels/labels", queue);
    sync_ = std::make_unique<message_filters::Synchronizer<Policy>>(Policy(queue), array_sub_,
                                                                    labels_sub_);
    sync_->registerCallback(&SdaspNodelet::onSuperpixels, this);
  }

  void onSuperpixels(const ebslam_msgs::SuperpixelArrayConstPtr& array,
                     const sensor_msgs::ImageConstPtr& labels_msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std_msgs::Header& header = array->header;
    if (!last_stamp_.isZero() && header.stamp < last_stamp_) {
      NODELET_WARN_THROTTLE(1.0, "%s: stamp went back by %.3f s; processing it (no state)",
                            array_topic_.c_str(), (last_stamp_ - header.stamp).toSec());
    }
    last_stamp_ = header.stamp;
    dasp::Superpixels superpixels;
    dasp::SdaspSegmentation result;
    try {
      // Used only in this callback, while the message lives: the labels are not copied.
      superpixels = toSuperpixels(*array, *labels_msg, ImageData::kShare);
    } catch (const std::invalid_argument& e) {
      reject(labels_topic_ + " does not match " + array_topic_ + ": " + e.what());
      return;
    }
    try {
      result = dasp::computeSdasp(superpixels, config_.sdasp);
    } catch (const std::invalid_argument& e) {
      reject(array_topic_ + ": " + e.what());
      return;
    }
    ebslam_msgs::Segmentation segmentation;
    segmentation.header = header;
    segmentation.segment_ids.assign(result.node_segments.begin(), result.node_segments.end());
    segmentation.ultrametric = toEdgeMsgs(result.ucg);
    segmentation.threshold = result.threshold;
    segmentation_pub_.publish(
        boost::make_shared<ebslam_msgs::Segmentation>(std::move(segmentation)));
    labels_pub_.publish(
        boost::make_shared<sensor_msgs::Image>(toLabelImageMsg(result.segments, header)));
    if (overlay_pub_.getNumSubscribers() > 0) {
      overlay_pub_.publish(toColorImageMsg(
          drawSegmentOverlay(superpixels.labels, superpixels.superpixels, result.segments),
          header));
    }
    if (ucm_pub_.getNumSubscribers() > 0) {
      const cv::Mat ucm = dasp::ultrametricContourMap(superpixels.labels, result.ucg);
      if (config_.ucm_encoding == "mono8") {
        ucm_pub_.publish(
            cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, ucmToMono8(ucm))
                .toImageMsg());
      } else {
        ucm_pub_.publish(
            cv_bridge::CvImage(header, sensor_msgs::image_encodings::TYPE_32FC1, ucm).toImageMsg());
      }
    }
    ++processed_;
    last_threshold_ = result.threshold;
    last_segments_ =
        result.node_segments.empty()
            ? 0
            : static_cast<std::size_t>(
                  *std::max_element(result.node_segments.begin(), result.node_segments.end()) + 1);
  }

  void reject(const std::string& reason) {
    ++rejected_;
    last_error_ = reason;
    if (throttle_.allow(reason)) NODELET_WARN("frame skipped: %s", reason.c_str());
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (rejected_ > 0 && processed_ == 0) {
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, last_error_);
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK,
                     processed_ == 0 ? "waiting for superpixels" : "segmenting");
    }
    status.add("frames segmented", processed_);
    status.add("frames rejected", rejected_);
    status.add("last rejection", last_error_);
    status.add("segments in the last frame", last_segments_);
    status.add("cut", cutRuleName(config_.sdasp.cut));
    status.add("threshold in the last frame", last_threshold_);
  }

  SdaspNodeConfig config_;
  std::string array_topic_, labels_topic_;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  message_filters::Subscriber<Array> array_sub_;
  image_transport::SubscriberFilter labels_sub_;
  std::unique_ptr<message_filters::Synchronizer<Policy>> sync_;
  ros::Publisher segmentation_pub_;
  image_transport::Publisher labels_pub_, overlay_pub_, ucm_pub_;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<SdaspNodeletConfig>> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diagnostics_timer_;

  ReasonThrottle throttle_;
  std::mutex mutex_;
  ros::Time last_stamp_;
  std::size_t processed_ = 0, rejected_ = 0, last_segments_ = 0;
  float last_threshold_ = 0.0f;
  std::string last_error_;
};

}  // namespace dasp_ros

PLUGINLIB_EXPORT_CLASS(dasp_ros::SdaspNodelet, nodelet::Nodelet)
