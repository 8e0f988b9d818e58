// D-eDVS depth fusion (thesis 8.2, ebslam/slam/dedvs_fusion.h) as a nodelet: every eDVS event gets
// the depth where its pixel's ray meets the depth camera's latest surface.
// Subscriptions (relative names):
//  - events (ebslam_msgs/EventArray): the eDVS stream;
//  - depth_registered/image_raw (sensor_msgs/Image, 16UC1 millimetres or 32FC1 metres, 0/NaN =
//    no depth), depth_registered/camera_info (sensor_msgs/CameraInfo: checked against the
//    calibration), the names dasp_ros uses;
//  - camera_info (sensor_msgs/CameraInfo, the event camera driver's, any size and lens) with
//    ~edvs_camera_info only.
// Publications:
//  - depth_events (ebslam_msgs/DepthEventArray): one per EventArray, header.stamp = the input's,
//    header.frame_id = ~edvs_frame; depth [m] along the eDVS optical axis and the 3D point [m]
//    in ~edvs_frame, NaN where there is no depth;
//  - depth_events/cloud (sensor_msgs/PointCloud2, x y z float32 in ~edvs_frame, the events with
//    depth), built only while subscribed;
//  - static tf ~depth_frame -> ~edvs_frame (the calibration's depth_from_edvs), ~publish_tf;
//    the inverse, ~edvs_frame -> ~depth_frame, with ~tf_parent = edvs (the eDVS frame hangs off
//    EventSlam3d's base_link, so the depth camera hangs off the eDVS).
// Time association: the core takes the depth frame nearest in time within ~max_frame_age
// (depth stamps minus the calibration's depth_clock_offset_s on the event clock). An EventArray
// whose last event lies beyond half a frame period after the latest depth frame waits (up to
// ~max_wait of wall time) for the next frame, so events get the nearer frame; output order is
// input order.
// Bad input (reason logged throttled on wall time, counted in diagnostics, no depth invented):
// depth of another encoding or size than the calibration's (frame dropped), depth frames not
// newer than the last, EventArrays of another sensor size (dropped), events older than every
// kept frame or newer than the latest by more than ~max_frame_age (NaN; when frames keep
// arriving that means the event and depth clocks disagree by more than a frame).
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <ebslam/slam/dedvs_fusion.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>
#include <string>

#include "depth_event_fusion_params.h"
#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/conversions.h"
#include "ebslam_ros/event_input.h"

namespace ebslam_ros {

class DepthEventFusionNodelet : public nodelet::Nodelet {
 private:
  static constexpr double kWarnPeriodS = 5.0;     // throttle of repeated input warnings [s]
  static constexpr std::size_t kMaxHeld = 1000;   // EventArrays waiting for a depth frame
  static constexpr std::size_t kStatusCount = 6;  // ebslam::FusionStatus values

  struct Held {
    ebslam_msgs::EventArray::ConstPtr msg;
    ros::WallTime received;
  };

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "depth event fusion " + getName(), [&] {
      config_ = loadDepthEventFusionNodeConfig(getPrivateNodeHandle());
      input_type_ = readEventInputType(getPrivateNodeHandle());
      if (!config_.edvs_camera_info) fusion_.emplace(config_.sensors, config_.fusion);
    });
    ros::NodeHandle& nh = getNodeHandle();
    if (config_.publish_tf) publishStaticTf();
    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, getPrivateNodeHandle());
    diagnostics_->setHardwareID("none");
    diagnostics_->add(getName(), this, &DepthEventFusionNodelet::diagnose);
    timer_ = nh.createWallTimer(ros::WallDuration(0.05), [this](const ros::WallTimerEvent&) {
      std::lock_guard<std::mutex> lock(mutex_);
      releaseHeld(false);
      if ((ros::WallTime::now() - last_diagnostics_).toSec() >= 1.0) {
        last_diagnostics_ = ros::WallTime::now();
        diagnostics_->update();
      }
    });
    depth_events_pub_ = nh.advertise<ebslam_msgs::DepthEventArray>("depth_events", 100);
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("depth_events/cloud", 5);
    const auto queue = static_cast<std::uint32_t>(config_.queue_size);
    events_sub_.subscribe(
        nh, "events", queue, input_type_,
        [this](const ebslam_msgs::EventArray::ConstPtr& msg) { onEvents(msg); },
        ros::TransportHints().tcpNoDelay(), getName());
    depth_sub_ = nh.subscribe("depth_registered/image_raw", 5, &DepthEventFusionNodelet::onDepth,
                              this, ros::TransportHints().tcpNoDelay());
    depth_info_sub_ = nh.subscribe("depth_registered/camera_info", 5,
                                   &DepthEventFusionNodelet::onDepthInfo, this);
    if (config_.edvs_camera_info) {
      edvs_info_sub_ = nh.subscribe("camera_info", 5, &DepthEventFusionNodelet::onEdvsInfo, this);
    }
    NODELET_INFO("fusing events with depth: calibration '%s', eDVS %dx%d, depth %dx%d%s",
                 config_.calibration.c_str(), config_.sensors.edvs.width,
                 config_.sensors.edvs.height, config_.sensors.depth.width,
                 config_.sensors.depth.height,
                 config_.edvs_camera_info ? ", eDVS intrinsics from camera_info" : "");
  }

  // ROS_*_THROTTLE runs on ROS time, which a looping bag sends back: throttle on wall time.
  bool due(ros::WallTime& last) {
    const ros::WallTime now = ros::WallTime::now();
    if (!last.isZero() && (now - last).toSec() < kWarnPeriodS) return false;
    last = now;
    return true;
  }

  void publishStaticTf() {
    const bool from_edvs = config_.tf_parent == "edvs";
    const Eigen::Isometry3d t =
        from_edvs ? config_.sensors.depth_from_edvs.inverse() : config_.sensors.depth_from_edvs;
    const Eigen::Quaterniond q(t.linear());
    geometry_msgs::TransformStamped tf;
    tf.header.stamp = ros::Time::now();
    tf.header.frame_id = from_edvs ? config_.edvs_frame : config_.depth_frame;
    tf.child_frame_id = from_edvs ? config_.depth_frame : config_.edvs_frame;
    tf.transform.translation.x = t.translation().x();
    tf.transform.translation.y = t.translation().y();
    tf.transform.translation.z = t.translation().z();
    tf.transform.rotation.x = q.x();
    tf.transform.rotation.y = q.y();
    tf.transform.rotation.z = q.z();
    tf.transform.rotation.w = q.w();
    static_tf_.sendTransform(tf);
  }

  void onEdvsInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (fusion_) return;
    ebslam::DedvsSensors sensors = config_.sensors;
    try {
      const ebslam::CameraModel lens = toCameraModel(*info);  // size, f_x, f_y, c and lens
      bool distorted = false;
      for (double d : info->D) distorted = distorted || d != 0.0;
      if (!distorted && (sensors.edvs.kappa1 != 0.0 || sensors.edvs.kappa2 != 0.0) &&
          !sensors.edvs.hasOpenCvLens()) {
        // A driver's uncalibrated CameraInfo (zero D): the calibration's kappa lens stays.
        sensors.edvs.width = lens.width;
        sensors.edvs.height = lens.height;
        sensors.edvs.focal_px = lens.fx();
        sensors.edvs.focal_y_px = lens.fy();
        sensors.edvs.principal_point = lens.principal_point;
        NODELET_INFO("eDVS camera_info has no distortion: the calibration's kappa1/kappa2 stay");
      } else {
        sensors.edvs = lens;
      }
    } catch (const std::invalid_argument& error) {
      ++bad_input_seen_;
      if (due(edvs_info_warned_)) {
        NODELET_ERROR("eDVS camera_info unusable: %s; waiting for another", error.what());
      }
      return;
    }
    try {
      fusion_.emplace(sensors, config_.fusion);
      config_.sensors = sensors;
      NODELET_INFO(
          "eDVS intrinsics from camera_info: %dx%d, f (%.2f, %.2f) px, centre (%.2f, "
          "%.2f), %s",
          sensors.edvs.width, sensors.edvs.height, sensors.edvs.fx(), sensors.edvs.fy(),
          sensors.edvs.principal_point.x(), sensors.edvs.principal_point.y(),
          info->distortion_model.c_str());
    } catch (const std::exception& error) {
      ++bad_input_seen_;
      if (due(edvs_info_warned_)) NODELET_ERROR("eDVS camera_info unusable: %s", error.what());
    }
  }

  void onDepthInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    const ebslam::PinholeCamera& c = config_.sensors.depth;
    const bool same =
        static_cast<int>(info->width) == c.width && static_cast<int>(info->height) == c.height &&
        std::abs(info->K[0] - c.fx) <= 0.01 * c.fx && std::abs(info->K[4] - c.fy) <= 0.01 * c.fy &&
        std::abs(info->K[2] - c.cx) <= 1.0 && std::abs(info->K[5] - c.cy) <= 1.0;
    if (!same) {
      ++depth_info_mismatches_;
      ++bad_input_seen_;
      if (due(depth_info_warned_)) {
        NODELET_WARN(
            "depth camera_info (%ux%u, fx %.1f, fy %.1f, cx %.1f, cy %.1f) differs from "
            "the calibration's (%dx%d, fx %.1f, fy %.1f, cx %.1f, cy %.1f): the fused "
            "depth is only as good as the calibration",
            info->width, info->height, info->K[0], info->K[4], info->K[2], info->K[5], c.width,
            c.height, c.fx, c.fy, c.cx, c.cy);
      }
    }
  }

  // Depth image -> CV_16UC1 mm or CV_32FC1 m sharing the message's data (no copy).
  std::optional<cv::Mat> depthMat(const sensor_msgs::Image& image) {
    namespace enc = sensor_msgs::image_encodings;
    int type = -1;
    std::size_t bytes = 0;
    if (image.encoding == enc::TYPE_16UC1 || image.encoding == enc::MONO16) {
      type = CV_16UC1;
      bytes = 2;
    } else if (image.encoding == enc::TYPE_32FC1) {
      type = CV_32FC1;
      bytes = 4;
    }
    if (type < 0) {
      ++rejected_encoding_;
      ++bad_input_seen_;
      if (due(encoding_warned_)) {
        NODELET_ERROR("depth image of encoding '%s' dropped: 16UC1 (mm) or 32FC1 (m) expected",
                      image.encoding.c_str());
      }
      return std::nullopt;
    }
    const ebslam::PinholeCamera& c = config_.sensors.depth;
    if (static_cast<int>(image.width) != c.width || static_cast<int>(image.height) != c.height ||
        image.step < image.width * bytes || image.step % bytes != 0 ||
        image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
      ++rejected_size_;
      ++bad_input_seen_;
      if (due(size_warned_)) {
        NODELET_ERROR(
            "depth image of %ux%u (step %u, %zu bytes) dropped: the calibration's "
            "depth camera is %dx%d",
            image.width, image.height, image.step, image.data.size(), c.width, c.height);
      }
      return std::nullopt;
    }
    if (image.is_bigendian != 0) {
      ++rejected_encoding_;
      ++bad_input_seen_;
      if (due(encoding_warned_)) NODELET_ERROR("big-endian depth image dropped");
      return std::nullopt;
    }
    return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                   const_cast<std::uint8_t*>(image.data.data()), image.step);
  }

  void onDepth(const sensor_msgs::Image::ConstPtr& image) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++depth_frames_in_;
    if (image->header.frame_id != config_.depth_frame && due(depth_frame_warned_)) {
      NODELET_WARN(
          "depth image in frame '%s', the calibration's depth frame is ~depth_frame = "
          "'%s': used as if it were",
          image->header.frame_id.c_str(), config_.depth_frame.c_str());
    }
    const std::optional<cv::Mat> depth = depthMat(*image);
    if (!depth || !fusion_) return;
    try {
      if (!fusion_->addDepthFrame(*depth, image->header.stamp.toSec())) {
        ++rejected_old_;
        ++bad_input_seen_;
        if (due(old_warned_)) {
          NODELET_WARN("depth frame stamped %.6f s dropped: not newer than the last one",
                       image->header.stamp.toSec());
        }
        return;
      }
    } catch (const std::invalid_argument& error) {
      ++rejected_size_;
      ++bad_input_seen_;
      if (due(size_warned_)) NODELET_ERROR("depth frame dropped: %s", error.what());
      return;
    }
    ++depth_frames_used_;
    latest_frame_s_ = image->header.stamp.toSec() - config_.sensors.depth_clock_offset_s;
    frame_times_s_.push_back(latest_frame_s_);
    while (frame_times_s_.size() > fusion_->frameCount()) frame_times_s_.pop_front();
    latest_frame_wall_ = ros::WallTime::now();
    releaseHeld(false);
  }

  void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++messages_in_;
    held_.push_back({msg, ros::WallTime::now()});
    releaseHeld(false);
  }

  // Fuses held EventArrays in order, stopping at the first that should wait for a nearer depth
  // frame (unless `all` or it waited ~max_wait).
  void releaseHeld(bool all) {
    const double half_period = 0.5 / config_.sensors.depth_frame_rate_hz;
    while (!held_.empty()) {
      const Held& front = held_.front();
      const ebslam_msgs::EventArray& msg = *front.msg;
      const bool waited = (ros::WallTime::now() - front.received).toSec() >= config_.max_wait_s;
      const bool newer = !msg.events.empty() && fusion_ && fusion_->frameCount() > 0 &&
                         msg.events.back().ts.toSec() > latest_frame_s_ + half_period;
      const bool no_frame_yet = fusion_ && fusion_->frameCount() == 0;
      if (!all && !waited && held_.size() < kMaxHeld && (newer || no_frame_yet)) return;
      process(msg);
      held_.pop_front();
    }
  }

  void process(const ebslam_msgs::EventArray& msg) {
    if (!fusion_) {
      ++dropped_no_calibration_;
      if (due(no_intrinsics_warned_)) {
        NODELET_WARN("EventArray dropped: waiting for the eDVS camera_info (~edvs_camera_info)");
      }
      return;
    }
    const ebslam::CameraModel& edvs = config_.sensors.edvs;
    if (msg.width != static_cast<std::uint32_t>(edvs.width) ||
        msg.height != static_cast<std::uint32_t>(edvs.height)) {
      ++rejected_sensor_;
      ++bad_input_seen_;
      if (due(sensor_warned_)) {
        NODELET_ERROR("EventArray of a %ux%u sensor dropped: the calibration's eDVS is %dx%d",
                      msg.width, msg.height, edvs.width, edvs.height);
      }
      return;
    }
    if (!msg.header.frame_id.empty() && msg.header.frame_id != config_.edvs_frame &&
        due(event_frame_warned_)) {
      NODELET_WARN("events in frame '%s' published in ~edvs_frame = '%s'",
                   msg.header.frame_id.c_str(), config_.edvs_frame.c_str());
    }
    ebslam_msgs::DepthEventArray out;
    out.header.stamp = msg.header.stamp;
    out.header.frame_id = config_.edvs_frame;
    out.width = msg.width;
    out.height = msg.height;
    out.events.resize(msg.events.size());
    std::array<std::size_t, kStatusCount> counts{};
    double worst_older_s = 0.0, worst_newer_s = 0.0;
    for (std::size_t i = 0; i < msg.events.size(); ++i) {
      const ebslam_msgs::Event& e = msg.events[i];
      const ebslam::FusedEvent fused = fusion_->fuse(ebslam_msgs::fromMsg(e));
      ebslam_msgs::DepthEvent& d = out.events[i];
      d.x = e.x;
      d.y = e.y;
      d.ts = e.ts;
      d.polarity = e.polarity;
      d.depth = fused.depth_m;
      d.point.x = fused.point.x();
      d.point.y = fused.point.y();
      d.point.z = fused.point.z();
      const auto status = static_cast<std::size_t>(fused.status);
      if (status < kStatusCount) ++counts[status];
      if (fused.status == ebslam::FusionStatus::kOlderThanFrames) {
        worst_older_s = std::max(worst_older_s, oldestFrameS() - e.ts.toSec());
      } else if (fused.status == ebslam::FusionStatus::kNewerThanFrames) {
        worst_newer_s = std::max(worst_newer_s, e.ts.toSec() - latest_frame_s_);
      }
    }
    for (std::size_t k = 0; k < kStatusCount; ++k) status_counts_[k] += counts[k];
    events_in_ += msg.events.size();
    reportTiming(counts, worst_older_s, worst_newer_s);
    if (counts[static_cast<std::size_t>(ebslam::FusionStatus::kOutsideSensor)] > 0) {
      ++bad_input_seen_;
      if (due(outside_warned_)) {
        NODELET_WARN("%zu events outside the %dx%d eDVS: no depth",
                     counts[static_cast<std::size_t>(ebslam::FusionStatus::kOutsideSensor)],
                     edvs.width, edvs.height);
      }
    }
    depth_events_pub_.publish(out);
    if (cloud_pub_.getNumSubscribers() > 0) publishCloud(out);
  }

  double oldestFrameS() const { return frame_times_s_.empty() ? 0.0 : frame_times_s_.front(); }

  void reportTiming(const std::array<std::size_t, kStatusCount>& counts, double older_s,
                    double newer_s) {
    const std::size_t no_frame =
        counts[static_cast<std::size_t>(ebslam::FusionStatus::kNoDepthFrame)];
    const std::size_t older =
        counts[static_cast<std::size_t>(ebslam::FusionStatus::kOlderThanFrames)];
    const std::size_t newer =
        counts[static_cast<std::size_t>(ebslam::FusionStatus::kNewerThanFrames)];
    const double period = 1.0 / config_.sensors.depth_frame_rate_hz;
    // Frames arrive (the latest one is recent on the wall clock) yet events miss them all:
    // the two clocks disagree (by more than a frame when the gap exceeds a period).
    const bool frames_flowing =
        !latest_frame_wall_.isZero() &&
        (ros::WallTime::now() - latest_frame_wall_).toSec() < 1.0 + config_.max_wait_s;
    if (no_frame > 0 && due(no_frame_warned_)) {
      NODELET_WARN(
          "%zu events without depth: no depth frame received yet on "
          "depth_registered/image_raw",
          no_frame);
    }
    if (older > 0) {
      ++bad_input_seen_;
      if (due(older_warned_)) {
        NODELET_WARN(
            "%zu events up to %.3f s older than every kept depth frame (%zu kept): no "
            "depth%s",
            older, older_s, fusion_->frameCount(),
            older_s > period ? "; the event and depth clocks disagree by more than a "
                               "frame, or the events arrive late"
                             : "");
      }
    }
    if (newer > 0) {
      ++bad_input_seen_;
      if (due(newer_warned_)) {
        NODELET_WARN("%zu events up to %.3f s newer than the latest depth frame: no depth; %s",
                     newer, newer_s,
                     frames_flowing ? "depth frames arrive, so the event and depth clocks "
                                      "disagree by more than a frame (check the calibration's "
                                      "depth_clock_offset_s and use_sim_time)"
                                    : "the depth stream is late or stopped");
      }
    }
  }

  void publishCloud(const ebslam_msgs::DepthEventArray& events) {
    sensor_msgs::PointCloud2 cloud;
    cloud.header = events.header;
    sensor_msgs::PointCloud2Modifier modifier(cloud);
    modifier.setPointCloud2FieldsByString(1, "xyz");
    std::size_t valid = 0;
    for (const ebslam_msgs::DepthEvent& e : events.events) valid += std::isfinite(e.depth);
    modifier.resize(valid);
    cloud.height = 1;
    cloud.width = static_cast<std::uint32_t>(valid);
    cloud.is_dense = true;
    sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
    for (const ebslam_msgs::DepthEvent& e : events.events) {
      if (!std::isfinite(e.depth)) continue;
      *x = e.point.x;
      *y = e.point.y;
      *z = e.point.z;
      ++x;
      ++y;
      ++z;
    }
    cloud_pub_.publish(cloud);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (bad_input_seen_ > bad_input_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else if (!fusion_) {
      status.summary(DiagnosticStatus::WARN, "waiting for the eDVS camera_info");
    } else if (depth_frames_used_ == 0) {
      status.summary(DiagnosticStatus::OK, "waiting for depth frames");
    } else {
      status.summary(DiagnosticStatus::OK, "fusing");
    }
    bad_input_reported_ = bad_input_seen_;
    status.add("EventArrays received", messages_in_);
    status.add("EventArrays waiting for depth", held_.size());
    status.add("events fused", events_in_);
    for (std::size_t k = 0; k < kStatusCount; ++k) {
      status.add(std::string("events: ") + ebslam::toString(static_cast<ebslam::FusionStatus>(k)),
                 status_counts_[k]);
    }
    status.add("depth frames received", depth_frames_in_);
    status.add("depth frames used", depth_frames_used_);
    status.add("depth frames of a wrong encoding", rejected_encoding_);
    status.add("depth frames of a wrong size", rejected_size_);
    status.add("depth frames not newer than the last", rejected_old_);
    status.add("depth camera_info mismatches", depth_info_mismatches_);
    status.add("EventArrays of a wrong sensor size", rejected_sensor_);
    status.add("EventArrays without eDVS intrinsics", dropped_no_calibration_);
    status.add("calibration", config_.calibration);
    addDecoderDiagnostics(events_sub_, status);
  }

  DepthEventFusionNodeConfig config_;
  std::mutex mutex_;
  std::optional<ebslam::DepthEventFusion> fusion_;  // after ~edvs_camera_info's message, if set
  std::deque<Held> held_;
  double latest_frame_s_ = -std::numeric_limits<double>::infinity();  // event clock [s]
  std::deque<double> frame_times_s_;  // the core's kept frames, event clock [s]
  ros::WallTime latest_frame_wall_;
  ros::Subscriber depth_sub_, depth_info_sub_, edvs_info_sub_;
  EventInputType input_type_ = EventInputType::kAuto;
  ros::Publisher depth_events_pub_, cloud_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer timer_;
  ros::WallTime last_diagnostics_;
  ros::WallTime encoding_warned_, size_warned_, old_warned_, sensor_warned_, outside_warned_,
      older_warned_, newer_warned_, no_frame_warned_, depth_info_warned_, edvs_info_warned_,
      depth_frame_warned_, event_frame_warned_, no_intrinsics_warned_;
  std::array<std::uint64_t, kStatusCount> status_counts_{};
  std::uint64_t messages_in_ = 0, events_in_ = 0, depth_frames_in_ = 0, depth_frames_used_ = 0,
                rejected_encoding_ = 0, rejected_size_ = 0, rejected_old_ = 0,
                depth_info_mismatches_ = 0, rejected_sensor_ = 0, dropped_no_calibration_ = 0;
  std::uint64_t bad_input_seen_ = 0, bad_input_reported_ = 0;
  EventSubscriber events_sub_;  // last member: stopped before the state its callbacks use
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::DepthEventFusionNodelet, nodelet::Nodelet)
