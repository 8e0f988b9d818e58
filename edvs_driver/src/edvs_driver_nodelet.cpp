// The eDVS driver nodelet: publishes `events` (ebslam_msgs/EventArray), `camera_info` and
// diagnostics; biases and publishing rate through dynamic_reconfigure. The link (open, reconnect
// with backoff, stall detection, reading, the event clock) is edvs::LinkSupervisor's, on its own
// thread, never in a callback of the nodelet manager.
// Time semantics: see README.md and ebslam/events/event_clock.h. Event ts = ROS time of the read
// that delivered the first event of the stream (the anchor, taken once per stream) + (unwrapped
// device time - device time of that first event). Never runs backwards, not even across reconnects.

#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>

#include <camera_info_manager/camera_info_manager.h>
#include <pluginlib/class_list_macros.hpp>

#include <algorithm>
#include <memory>
#include <mutex>
#include <optional>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros_common/ros_param_helpers.h"
#include "edvs/link_supervisor.h"
#include "edvs_driver/EdvsConfig.h"
#include "edvs_driver/ros_params.h"

namespace edvs_driver {

using edvs::LinkEvent;
using edvs::LinkState;

class EdvsDriverNodelet : public nodelet::Nodelet {
 public:
  ~EdvsDriverNodelet() override { shutdown(); }

 private:
  void onInit() override;
  void shutdown();
  void queue(const ebslam::EventVector& batch);
  void logLink(LinkEvent event, const std::string& message);
  void publishPending(bool full_batches_only);
  void publishTimer(const ros::WallTimerEvent&) { publishPending(false); }
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void reconfigure(EdvsConfig& config, std::uint32_t level);

  DriverParams params_;
  ros::Publisher events_pub_;
  ros::Publisher info_pub_;
  std::unique_ptr<camera_info_manager::CameraInfoManager> info_manager_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<EdvsConfig>> reconfigure_server_;
  ros::WallTimer publish_timer_;
  ros::WallTimer diagnostics_timer_;

  std::unique_ptr<edvs::LinkSupervisor> link_;

  // Shared between the link's thread and the callbacks, guarded by mutex_.
  std::mutex mutex_;
  edvs::ParserStats parser_at_last_diag_;  // counters at the previous diagnostics update
  std::uint64_t events_at_last_diag_ = 0;
  ros::WallTime last_diag_time_;
  ebslam::EventVector pending_;
  int batch_size_ = 0;
  double publish_rate_hz_ = 0.0;

  std::mutex publish_mutex_;  // keeps messages in order between the timer and batch publishing
};

void EdvsDriverNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
  ebslam_ros_common::startOrFail(pnh, "edvs_driver " + getName(),
                                 [&] { params_ = loadDriverParams(pnh); });
  batch_size_ = params_.batch_size;
  publish_rate_hz_ = params_.publish_rate_hz;

  edvs::LinkSupervisor::Callbacks callbacks;
  callbacks.on_events = [this](ebslam::EventVector& batch) { queue(batch); };
  callbacks.on_stream_end = [this] { publishPending(false); };
  callbacks.on_log = [this](LinkEvent event, const std::string& message) {
    logLink(event, message);
  };
  callbacks.now_us = [] { return ebslam_msgs::toMicroseconds(ros::Time::now()); };
  link_ = std::make_unique<edvs::LinkSupervisor>(params_.device, params_.link, callbacks);

  events_pub_ = nh.advertise<ebslam_msgs::EventArray>("events", 100);
  info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 100);
  info_manager_ = std::make_unique<camera_info_manager::CameraInfoManager>(nh, params_.camera_name,
                                                                           params_.camera_info_url);

  updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
  updater_->setHardwareID(params_.device.uri);
  updater_->add("eDVS", this, &EdvsDriverNodelet::diagnose);
  last_diag_time_ = ros::WallTime::now();

  publish_timer_ =
      nh.createWallTimer(ros::WallDuration(publish_rate_hz_ > 0 ? 1.0 / publish_rate_hz_ : 1.0),
                         &EdvsDriverNodelet::publishTimer, this, false, publish_rate_hz_ > 0);
  diagnostics_timer_ = nh.createWallTimer(
      ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) { updater_->update(); });

  reconfigure_server_ =
      std::make_unique<ebslam_ros_common::RuntimeKnobs<EdvsConfig>>(reconfigure_mutex_, pnh);
  ebslam_ros_common::markReconfigureParamsRead<EdvsConfig>(pnh);
  reconfigure_server_->setCallback(
      [this](EdvsConfig& c, std::uint32_t level) { reconfigure(c, level); });

  link_->start();
  NODELET_INFO("edvs_driver: device %s, format %s, %s firmware, sync %s, frame %s",
               params_.device.uri.c_str(), toString(params_.device.format),
               toString(params_.device.firmware), toString(params_.device.sync),
               params_.frame_id.c_str());
}

void EdvsDriverNodelet::shutdown() {
  publish_timer_.stop();
  diagnostics_timer_.stop();
  if (link_) link_->stop();
}

void EdvsDriverNodelet::logLink(LinkEvent event, const std::string& message) {
  switch (event) {
    case LinkEvent::kOpenFailed:
      NODELET_ERROR_THROTTLE(10.0, "edvs_driver: %s", message.c_str());
      break;
    case LinkEvent::kConnected:
    case LinkEvent::kCaptureEnded:
      NODELET_INFO("edvs_driver: %s", message.c_str());
      break;
    case LinkEvent::kReconnected:
      NODELET_WARN("edvs_driver: %s", message.c_str());
      break;
    case LinkEvent::kLost:
    case LinkEvent::kStalled:
      NODELET_ERROR("edvs_driver: %s", message.c_str());
      break;
  }
}

void EdvsDriverNodelet::queue(const ebslam::EventVector& batch) {
  bool batched = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_.insert(pending_.end(), batch.begin(), batch.end());
    batched = batch_size_ > 0;
  }
  if (batched) publishPending(true);
}

void EdvsDriverNodelet::publishPending(bool full_batches_only) {
  std::lock_guard<std::mutex> publish_lock(publish_mutex_);
  std::vector<ebslam::EventVector> messages;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pending_.empty()) return;
    const std::size_t batch = batch_size_ > 0 ? static_cast<std::size_t>(batch_size_) : 0;
    std::size_t begin = 0;
    while (batch > 0 && pending_.size() - begin >= batch) {
      messages.emplace_back(pending_.begin() + static_cast<long>(begin),
                            pending_.begin() + static_cast<long>(begin + batch));
      begin += batch;
    }
    if (!full_batches_only && begin < pending_.size()) {
      messages.emplace_back(pending_.begin() + static_cast<long>(begin), pending_.end());
      begin = pending_.size();
    }
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(begin));
  }
  for (const ebslam::EventVector& events : messages) {
    ebslam_msgs::EventArray msg;
    try {
      msg = ebslam_msgs::toMsg(events, ebslam::SensorSize{128, 128}, params_.frame_id);
    } catch (const std::invalid_argument& e) {
      NODELET_ERROR_THROTTLE(5.0, "edvs_driver: dropping a batch: %s", e.what());
      continue;
    }
    sensor_msgs::CameraInfo info = info_manager_->getCameraInfo();
    info.header = msg.header;
    if (info.width == 0 || info.height == 0) {
      info.width = 128;
      info.height = 128;
    }
    events_pub_.publish(msg);
    info_pub_.publish(info);
  }
}

void EdvsDriverNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const edvs::LinkStatus link = link_->status();
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double dt = std::max(1e-3, (now - last_diag_time_).toSec());
  const double rate = static_cast<double>(link.events - events_at_last_diag_) / dt;
  events_at_last_diag_ = link.events;
  last_diag_time_ = now;
  const double quiet_s = static_cast<double>(edvs::monotonicMicros() - link.last_data_us) * 1e-6;
  const std::uint64_t reconnects = link.reconnects();
  switch (link.state) {
    case LinkState::kStreaming:
      if (quiet_s > params_.stall_warn_s) {
        status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "stalled: no data for %.1f s",
                        quiet_s);
      } else if (reconnects > 0) {
        status.summaryf(diagnostic_msgs::DiagnosticStatus::OK,
                        "streaming (recovered after %lu reconnects)",
                        static_cast<unsigned long>(reconnects));
      } else {
        status.summary(diagnostic_msgs::DiagnosticStatus::OK, "streaming");
      }
      break;
    case LinkState::kConnecting:
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "connecting");
      break;
    case LinkState::kCaptureEnded:
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "capture ended");
      break;
    case LinkState::kDisconnected:
      status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "disconnected: %s",
                      link.last_error.c_str());
      break;
  }
  const edvs::ParserStats& p = link.stats.parser;
  const edvs::ParserStats& q = parser_at_last_diag_;
  if (noiseCount(p) != noiseCount(q)) {
    // Garbage arrived since the last update: say how much, while it lasts.
    status.mergeSummaryf(
        diagnostic_msgs::DiagnosticStatus::WARN,
        "line noise in the last %.1f s: %lu resyncs, %lu rejected events, %lu implausible "
        "timestamp jumps, %lu dropped bytes",
        dt, static_cast<unsigned long>(p.resyncs - q.resyncs),
        static_cast<unsigned long>(p.rejected_events - q.rejected_events),
        static_cast<unsigned long>(p.implausible_jumps - q.implausible_jumps),
        static_cast<unsigned long>(p.bytes_dropped - q.bytes_dropped));
  }
  parser_at_last_diag_ = p;
  if (link.state == LinkState::kStreaming && link.format_suspect) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "the stream does not look like format %s (dropped bytes or impossible "
                         "timestamps): check ~format and ~firmware",
                         toString(params_.device.format));
  }
  status.add("uri", params_.device.uri);
  status.add("format", toString(params_.device.format));
  status.add("firmware", toString(params_.device.firmware));
  status.add("sync_mode", toString(params_.device.sync));
  status.add("banner", link.banner);
  status.add("event rate [events/s]", rate);
  status.add("events published", link.events);
  status.add("bytes read", link.stats.bytes_read);
  status.add("dropped bytes", p.bytes_dropped);
  status.add("resyncs", p.resyncs);
  status.add("implausible timestamp jumps", p.implausible_jumps);
  status.add("rejected events", p.rejected_events);
  status.add("clock jumps", p.clock_jumps);
  status.add("timestamp wraps", p.wraps);
  status.add("reconnects", reconnects);
  status.add("disconnects", link.disconnects);
  status.add("failed open attempts", link.failed_attempts);
  status.add("last error", link.last_error);
  status.add("last disconnect", link.last_disconnect);
}

void EdvsDriverNodelet::reconfigure(EdvsConfig& config, std::uint32_t /*level*/) {
  if (config.publish_rate <= 0 && config.batch_size <= 0) {
    NODELET_WARN("edvs_driver: publish_rate and batch_size both 0; keeping publish_rate %.1f",
                 publish_rate_hz_);
    config.publish_rate = publish_rate_hz_ > 0 ? publish_rate_hz_ : 100.0;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    batch_size_ = config.batch_size;
  }
  const int values[edvs::kNumBiases] = {config.bias_cas,  config.bias_injGnd,  config.bias_reqPd,
                                        config.bias_puX,  config.bias_diffOff, config.bias_req,
                                        config.bias_refr, config.bias_puY,     config.bias_diffOn,
                                        config.bias_diff, config.bias_foll,    config.bias_pr};
  for (int i = 0; i < edvs::kNumBiases; ++i) {
    // -1 keeps the device's value; an unchanged value is not sent again.
    if (values[i] >= 0) link_->setBias(i, values[i]);
  }
  if (config.publish_rate != publish_rate_hz_) {
    publish_rate_hz_ = config.publish_rate;
    if (publish_rate_hz_ > 0) {
      publish_timer_.setPeriod(ros::WallDuration(1.0 / publish_rate_hz_));
      publish_timer_.start();
    } else {
      publish_timer_.stop();
    }
  }
}

}  // namespace edvs_driver

PLUGINLIB_EXPORT_CLASS(edvs_driver::EdvsDriverNodelet, nodelet::Nodelet)
