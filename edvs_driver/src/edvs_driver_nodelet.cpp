// The eDVS driver nodelet: publishes `events` (ebslam_msgs/EventArray), `camera_info` and
// diagnostics; biases and publishing rate through dynamic_reconfigure.
//
// Threads: the device is opened and read in the nodelet's own worker thread, never in a
// callback of the nodelet manager. A supervisor wall timer (10 Hz) asks the worker to (re)open
// the device once the backoff delay after a failure has passed; the worker does the blocking
// open (reset, banner wait) and then reads until the device goes away.
//
// Time semantics: see README.md and ebslam/event_clock.h. Event ts = ROS time of the read that
// delivered the first event of the stream (the anchor, taken once per stream) + (unwrapped device
// time - device time of that first event). Never runs backwards, not even across reconnects.

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>

#include <camera_info_manager/camera_info_manager.h>
#include <pluginlib/class_list_macros.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "ebslam/event_clock.h"
#include "ebslam_msgs/event_conversions.h"
#include "edvs_driver/EdvsConfig.h"
#include "edvs_driver/device.h"
#include "edvs_driver/ros_params.h"

namespace edvs_driver {

class EdvsDriverNodelet : public nodelet::Nodelet {
 public:
  ~EdvsDriverNodelet() override { shutdown(); }

 private:
  enum class Link { kConnecting, kStreaming, kDisconnected, kCaptureEnded };

  void onInit() override;
  void shutdown();
  void supervise(const ros::WallTimerEvent&);
  void worker();
  bool connect();
  void readLoop();
  void stampAndQueue(ebslam::EventVector& batch);
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
  std::unique_ptr<dynamic_reconfigure::Server<EdvsConfig>> reconfigure_server_;
  ros::WallTimer supervisor_timer_;
  ros::WallTimer publish_timer_;
  ros::WallTimer diagnostics_timer_;

  std::thread worker_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<EdvsDevice> device_;  // worker thread only

  // Shared between the worker and the callbacks, guarded by mutex_.
  std::mutex mutex_;
  std::condition_variable wake_;
  bool connect_requested_ = false;
  Link link_ = Link::kDisconnected;
  ros::WallTime next_attempt_;
  double backoff_s_ = 0.0;
  std::string last_error_;
  bool capture_ended_ = false;       // the capture file was read to its end
  ParserStats parser_at_last_diag_;  // counters at the previous diagnostics update
  std::string last_disconnect_;      // why the last working connection ended
  std::uint64_t connects_ = 0;
  std::uint64_t failed_attempts_ = 0;
  std::uint64_t disconnects_ = 0;
  DeviceStats stats_;
  std::string banner_;
  bool format_suspect_ = false;
  std::int64_t last_data_us_ = 0;  // monotonic time of the last bytes
  std::uint64_t events_total_ = 0;
  std::uint64_t events_at_last_diag_ = 0;
  ros::WallTime last_diag_time_;
  ebslam::EventVector pending_;
  std::vector<std::pair<int, std::int64_t>> bias_changes_;
  std::array<std::optional<std::int64_t>, kNumBiases> biases_{};
  int batch_size_ = 0;
  double publish_rate_hz_ = 0.0;

  std::mutex publish_mutex_;  // keeps messages in order between the timer and batch publishing

  // Worker only: device time -> ROS time, anchored once per stream, never backwards.
  ebslam::EventClock clock_;
};

void EdvsDriverNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    params_ = loadDriverParams(pnh);
  } catch (const std::invalid_argument& e) {
    NODELET_FATAL("edvs_driver: %s", e.what());
    throw;
  }
  biases_ = params_.biases;
  batch_size_ = params_.batch_size;
  publish_rate_hz_ = params_.publish_rate_hz;
  backoff_s_ = params_.reconnect_min_s;
  next_attempt_ = ros::WallTime::now();

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
  supervisor_timer_ =
      nh.createWallTimer(ros::WallDuration(0.1), &EdvsDriverNodelet::supervise, this);
  diagnostics_timer_ = nh.createWallTimer(
      ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) { updater_->update(); });

  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<EdvsConfig>>(reconfigure_mutex_, pnh);
  reconfigure_server_->setCallback(
      [this](EdvsConfig& c, std::uint32_t level) { reconfigure(c, level); });

  worker_ = std::thread([this] { worker(); });
  NODELET_INFO("edvs_driver: device %s, format %s, %s firmware, sync %s, frame %s",
               params_.device.uri.c_str(), toString(params_.device.format),
               toString(params_.device.firmware), toString(params_.device.sync),
               params_.frame_id.c_str());
}

void EdvsDriverNodelet::shutdown() {
  supervisor_timer_.stop();
  publish_timer_.stop();
  diagnostics_timer_.stop();
  stop_ = true;
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void EdvsDriverNodelet::supervise(const ros::WallTimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (link_ == Link::kDisconnected && !connect_requested_ &&
      ros::WallTime::now() >= next_attempt_) {
    connect_requested_ = true;
    link_ = Link::kConnecting;
    wake_.notify_all();
  }
}

void EdvsDriverNodelet::worker() {
  device_ = std::make_unique<EdvsDevice>(params_.device);
  while (!stop_) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return connect_requested_ || stop_; });
      connect_requested_ = false;
    }
    if (stop_) break;
    if (!connect()) continue;
    readLoop();
    device_->close();
    publishPending(false);
    std::lock_guard<std::mutex> lock(mutex_);
    if (capture_ended_) {
      capture_ended_ = false;
      if (!device_->uri().file_loop) {
        // A capture ends at its end: nothing to reconnect to.
        link_ = Link::kCaptureEnded;
        break;
      }
      connect_requested_ = true;  // loop=1: replay at once
      link_ = Link::kConnecting;
      continue;
    }
    ++disconnects_;
    link_ = Link::kDisconnected;
    backoff_s_ = params_.reconnect_min_s;  // a device that was there is retried soon
    next_attempt_ = ros::WallTime::now() + ros::WallDuration(backoff_s_);
  }
  device_.reset();
}

bool EdvsDriverNodelet::connect() {
  std::array<std::optional<std::int64_t>, kNumBiases> biases;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    biases = biases_;
    bias_changes_.clear();
  }
  try {
    for (int i = 0; i < kNumBiases; ++i) {
      // Remembered by the device and sent only once it streams.
      if (const auto& v = biases[static_cast<std::size_t>(i)]) device_->setBias(i, *v);
    }
    device_->open();
    device_->start();
  } catch (const std::exception& e) {
    device_->close();
    std::lock_guard<std::mutex> lock(mutex_);
    last_error_ = e.what();
    ++failed_attempts_;
    link_ = Link::kDisconnected;
    next_attempt_ = ros::WallTime::now() + ros::WallDuration(backoff_s_);
    NODELET_ERROR_THROTTLE(10.0, "edvs_driver: %s (retrying in %.1f s)", e.what(), backoff_s_);
    backoff_s_ = std::min(backoff_s_ * 2.0, params_.reconnect_max_s);
    return false;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  ++connects_;
  link_ = Link::kStreaming;
  banner_ = device_->banner();
  last_data_us_ = monotonicMicros();
  clock_.unanchor();  // a new stream gets a new anchor
  if (connects_ > 1) {
    NODELET_WARN("edvs_driver: reconnected to %s (reconnect %lu)", device_->describe().c_str(),
                 static_cast<unsigned long>(connects_ - 1));
  } else {
    NODELET_INFO("edvs_driver: streaming from %s (%s)", device_->describe().c_str(),
                 banner_.c_str());
  }
  return true;
}

void EdvsDriverNodelet::readLoop() {
  ebslam::EventVector batch;
  std::uint64_t bytes_seen = device_->stats().bytes_read;
  while (!stop_) {
    std::vector<std::pair<int, std::int64_t>> changes;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      changes.swap(bias_changes_);
    }
    batch.clear();
    try {
      for (const auto& [index, value] : changes) device_->setBias(index, value);
      device_->read(batch, 20);
    } catch (const CaptureEnded& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      capture_ended_ = true;
      NODELET_INFO("edvs_driver: %s%s", e.what(),
                   device_->uri().file_loop ? ": replaying it again (loop=1)" : "");
      return;
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      last_error_ = std::string("device lost: ") + e.what();
      last_disconnect_ = last_error_;
      NODELET_ERROR("edvs_driver: %s", last_error_.c_str());
      return;
    }
    const std::int64_t now = monotonicMicros();
    const DeviceStats& stats = device_->stats();
    bool stalled_out = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stats.bytes_read != bytes_seen) {
        bytes_seen = stats.bytes_read;
        last_data_us_ = now;
      }
      stats_ = stats;
      format_suspect_ = device_->formatSuspect();
      if (now - last_data_us_ > static_cast<std::int64_t>(params_.stall_reconnect_s * 1e6)) {
        last_error_ =
            "no data for " + std::to_string(params_.stall_reconnect_s) + " s: reopening the device";
        last_disconnect_ = last_error_;
        stalled_out = true;
      }
    }
    if (stalled_out) {
      NODELET_ERROR("edvs_driver: %s", last_error_.c_str());
      return;
    }
    if (!batch.empty()) {
      stampAndQueue(batch);
      if (batch_size_ > 0) publishPending(true);
    }
  }
}

void EdvsDriverNodelet::stampAndQueue(ebslam::EventVector& batch) {
  if (!clock_.anchored()) {
    // Once per stream: this read's ROS time is the time of the stream's first event.
    clock_.anchor(batch.front().t_us, ebslam_msgs::toMicroseconds(ros::Time::now()));
  }
  for (ebslam::Event& e : batch) {
    // The parser's 64-bit device clock starts near 0: no overflow in practice; were there one,
    // the event keeps the previous stamp rather than a wrapped one.
    const std::optional<std::int64_t> stamp = clock_.stamp(e.t_us);
    e.t_us = stamp ? *stamp : clock_.lastStamp().value_or(clock_.anchorPublished());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.insert(pending_.end(), batch.begin(), batch.end());
  events_total_ += batch.size();
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
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double dt = std::max(1e-3, (now - last_diag_time_).toSec());
  const double rate = static_cast<double>(events_total_ - events_at_last_diag_) / dt;
  events_at_last_diag_ = events_total_;
  last_diag_time_ = now;
  const double quiet_s = static_cast<double>(monotonicMicros() - last_data_us_) * 1e-6;
  const std::uint64_t reconnects = connects_ > 0 ? connects_ - 1 : 0;
  switch (link_) {
    case Link::kStreaming:
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
    case Link::kConnecting:
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "connecting");
      break;
    case Link::kCaptureEnded:
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "capture ended");
      break;
    case Link::kDisconnected:
      status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "disconnected: %s",
                      last_error_.c_str());
      break;
  }
  const ParserStats& p = stats_.parser;
  const ParserStats& q = parser_at_last_diag_;
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
  if (link_ == Link::kStreaming && format_suspect_) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "the stream does not look like format %s (dropped bytes or impossible "
                         "timestamps): check ~format and ~firmware",
                         toString(params_.device.format));
  }
  status.add("uri", params_.device.uri);
  status.add("format", toString(params_.device.format));
  status.add("firmware", toString(params_.device.firmware));
  status.add("sync_mode", toString(params_.device.sync));
  status.add("banner", banner_);
  status.add("event rate [events/s]", rate);
  status.add("events published", events_total_);
  status.add("bytes read", stats_.bytes_read);
  status.add("dropped bytes", p.bytes_dropped);
  status.add("resyncs", p.resyncs);
  status.add("implausible timestamp jumps", p.implausible_jumps);
  status.add("rejected events", p.rejected_events);
  status.add("clock jumps", p.clock_jumps);
  status.add("timestamp wraps", p.wraps);
  status.add("reconnects", reconnects);
  status.add("disconnects", disconnects_);
  status.add("failed open attempts", failed_attempts_);
  status.add("last error", last_error_);
  status.add("last disconnect", last_disconnect_);
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
    const int values[kNumBiases] = {config.bias_cas,  config.bias_injGnd,  config.bias_reqPd,
                                    config.bias_puX,  config.bias_diffOff, config.bias_req,
                                    config.bias_refr, config.bias_puY,     config.bias_diffOn,
                                    config.bias_diff, config.bias_foll,    config.bias_pr};
    for (int i = 0; i < kNumBiases; ++i) {
      if (values[i] < 0) continue;  // keep the device's value
      auto& current = biases_[static_cast<std::size_t>(i)];
      if (current && *current == values[i]) continue;
      current = values[i];
      bias_changes_.emplace_back(i, values[i]);  // the worker sends it while streaming
    }
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
