#include "pose_filter_nodelet_base.h"

#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <algorithm>

#include "ebslam_ros/conversions.h"

namespace ebslam_ros {
namespace {

constexpr double kPathPeriodS = 0.1;  // `path` at most this often [s of wall time]

// The odometry transform as the geometry the filter works in.
void fromTransformMsg(const geometry_msgs::Transform& msg, tf2::Transform& out) {
  tf2::fromMsg(msg, out);
}
void fromTransformMsg(const geometry_msgs::Transform& msg, Eigen::Isometry3d& out) {
  out = toIsometry(msg);
}
tf2::Transform identityLike(const tf2::Transform&) { return tf2::Transform::getIdentity(); }
Eigen::Isometry3d identityLike(const Eigen::Isometry3d&) { return Eigen::Isometry3d::Identity(); }

}  // namespace

PoseFilterNodeletBase::~PoseFilterNodeletBase() { stopDiagnostics(); }

void PoseFilterNodeletBase::startOutputs(const PoseNodeConfig& config, std::uint32_t pose_queue) {
  config_ = &config;
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  static_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  ros::NodeHandle& nh = getNodeHandle();
  pose_pub_ = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", pose_queue);
  path_pub_ = nh.advertise<nav_msgs::Path>("path", 1, true);
  particles_pub_ = nh.advertise<geometry_msgs::PoseArray>("particles", 1);
  particlecloud_pub_ = nh.advertise<geometry_msgs::PoseArray>("particlecloud", 1);
}

void PoseFilterNodeletBase::startDiagnostics() {
  diagnostics_ =
      std::make_unique<diagnostic_updater::Updater>(getNodeHandle(), getPrivateNodeHandle());
  diagnostics_->setHardwareID("none");
  diagnostics_->add(getName(), this, &PoseFilterNodeletBase::diagnose);
  diagnostics_timer_ =
      getNodeHandle().createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
        std::lock_guard<std::mutex> lock(mutex_);
        diagnostics_->update();
      });
}

void PoseFilterNodeletBase::stopDiagnostics() { diagnostics_timer_.stop(); }

void PoseFilterNodeletBase::sendStaticMount(const tf2::Transform& mount) {
  static_broadcaster_->sendTransform(
      toTransformMsg(mount, ros::Time(0), config_->base_frame, config_->sensor_frame));
}

void PoseFilterNodeletBase::sendStaticMount(const Eigen::Isometry3d& mount) {
  static_broadcaster_->sendTransform(
      toTransformMsg(mount, ros::Time(0), config_->base_frame, config_->sensor_frame));
}

std::optional<geometry_msgs::Transform> PoseFilterNodeletBase::lookupMount() {
  try {
    return tf_buffer_->lookupTransform(config_->base_frame, config_->sensor_frame, ros::Time(0))
        .transform;
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(kWarnPeriodS, "%s: events dropped until tf has %s -> %s: %s",
                      getName().c_str(), config_->base_frame.c_str(), config_->sensor_frame.c_str(),
                      error.what());
  }
  return std::nullopt;
}

bool PoseFilterNodeletBase::acceptInput(const std::string& frame_id, std::size_t events,
                                        const char* type) {
  ++counters_.messages;
  counters_.events_in += events;
  if (events == 0) {
    ++counters_.empty_messages;
    return false;
  }
  if (!frame_id.empty() && frame_id != config_->sensor_frame) {
    ++counters_.rejected_frame;
    ++counters_.bad_input;
    ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: %s in frame '%s' dropped: this filter's sensor is '%s'",
                       getName().c_str(), type, frame_id.c_str(), config_->sensor_frame.c_str());
    return false;
  }
  return true;
}

void PoseFilterNodeletBase::noteRestart(std::int64_t jump_back_us, const char* what,
                                        const char* restarted) {
  ++counters_.restarts;
  ++counters_.bad_input;
  // Throttled on the wall clock: a stream stepping back in every message would otherwise log
  // with every message, and ROS-time throttling would hide the loops of a bag (the same stamps
  // come back). The count says how many restarts the log did not show.
  if (restart_log_.due()) {
    ROS_WARN(
        "%s: %s time jumped back by %.3f s (a looping bag or a sensor reconnect?): filter "
        "restarted %s (%llu restarts since the previous such message not logged: at most one "
        "per %.0f s; diagnostics count them all)",
        getName().c_str(), what, 1e-6 * static_cast<double>(jump_back_us), restarted,
        static_cast<unsigned long long>(restart_log_.suppressed()), restart_log_.period());
  }
}

void PoseFilterNodeletBase::noteGap(std::int64_t gap_us, const char* what,
                                    const char* continuation) {
  ++counters_.gaps;
  if (!gap_log_.due()) return;
  constexpr double kDayS = 86400.0;
  const double gap_s = 1e-6 * static_cast<double>(gap_us);
  if (gap_s > kDayS) {
    ROS_WARN("%s: %s time jumped forward by %.0f s (a bad stamp or a clock change?); %s",
             getName().c_str(), what, gap_s, continuation);
  } else {
    ROS_WARN("%s: no %ss for %.3f s; %s", getName().c_str(), what, gap_s, continuation);
  }
}

void PoseFilterNodeletBase::noteZeroTime(std::size_t count, const char* what) {
  counters_.zero_time += count;
  ++counters_.bad_input;
  if (zero_time_log_.due()) {
    ROS_ERROR(
        "%s: dropped %zu %ss stamped 0 (unset event time: does the source fill Event.ts?); %llu "
        "messages with them since the previous such message not logged",
        getName().c_str(), count, what,
        static_cast<unsigned long long>(zero_time_log_.suppressed()));
  }
}

void PoseFilterNodeletBase::noteFilterError(const char* who, std::size_t count,
                                            const std::exception& error) {
  ++counters_.filter_errors;
  ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: %s rejected %zu events: %s", getName().c_str(), who, count,
                     error.what());
}

void PoseFilterNodeletBase::publishPose(
    const ros::Time& stamp, const geometry_msgs::Pose& base,
    const geometry_msgs::PoseWithCovariance::_covariance_type& covariance,
    const std::function<std::vector<geometry_msgs::Pose>()>& particles) {
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = config_->map_frame;
  pose.pose.pose = base;
  pose.pose.covariance = covariance;
  pose_pub_.publish(pose);
  last_latency_s_ = (ros::Time::now() - stamp).toSec();

  geometry_msgs::PoseStamped stamped;
  stamped.header = pose.header;
  stamped.pose = base;
  path_.push_back(stamped);
  while (path_.size() > static_cast<std::size_t>(config_->path_length)) path_.pop_front();
  const ros::WallTime now = ros::WallTime::now();
  if (path_pub_.getNumSubscribers() > 0 && (now - last_path_publication_).toSec() >= kPathPeriodS) {
    nav_msgs::Path path;
    path.header = pose.header;
    path.poses.assign(path_.begin(), path_.end());
    path_pub_.publish(path);
    last_path_publication_ = now;
  }
  if (particles_pub_.getNumSubscribers() > 0 || particlecloud_pub_.getNumSubscribers() > 0) {
    geometry_msgs::PoseArray array;
    array.header = pose.header;
    array.poses = particles();
    if (particles_pub_.getNumSubscribers() > 0) particles_pub_.publish(array);
    if (particlecloud_pub_.getNumSubscribers() > 0) particlecloud_pub_.publish(array);
  }
}

template <typename Transform>
void PoseFilterNodeletBase::publishTfOf(const Transform& map_to_base, const ros::Time& stamp) {
  if (!config_->publish_tf) return;
  Transform odom_to_base = identityLike(map_to_base);
  if (config_->odom_from_tf) {
    try {
      fromTransformMsg(
          tf_buffer_->lookupTransform(config_->odom_frame, config_->base_frame, stamp).transform,
          odom_to_base);
    } catch (const tf2::TransformException& error) {
      ROS_WARN_THROTTLE(kWarnPeriodS, "%s: no %s -> %s at the events' time, map -> %s not sent: %s",
                        getName().c_str(), config_->odom_frame.c_str(), config_->base_frame.c_str(),
                        config_->odom_frame.c_str(), error.what());
      return;
    }
  }
  std::vector<geometry_msgs::TransformStamped> transforms{toTransformMsg(
      map_to_base * odom_to_base.inverse(), stamp, config_->map_frame, config_->odom_frame)};
  if (!config_->odom_from_tf) {
    transforms.push_back(
        toTransformMsg(odom_to_base, stamp, config_->odom_frame, config_->base_frame));
  }
  tf_broadcaster_->sendTransform(transforms);
}

void PoseFilterNodeletBase::publishTf(const tf2::Transform& map_to_base, const ros::Time& stamp) {
  publishTfOf(map_to_base, stamp);
}

void PoseFilterNodeletBase::publishTf(const Eigen::Isometry3d& map_to_base,
                                      const ros::Time& stamp) {
  publishTfOf(map_to_base, stamp);
}

void PoseFilterNodeletBase::diagnoseRates(diagnostic_updater::DiagnosticStatusWrapper& status) {
  // Input and processed rates over the last diagnostics period (wall time): a filter that keeps
  // up processes what arrives; the rate cap's share of dropped events in that period and since
  // the start.
  const ros::WallTime now = ros::WallTime::now();
  const std::uint64_t processed = processedEvents();
  const RateSnapshot current{now, counters_.events_in, processed, thinned_};
  const double period_s = last_rates_.time.isZero() ? 0.0 : (now - last_rates_.time).toSec();
  const auto rate = [period_s](std::uint64_t now_count, std::uint64_t before) {
    return period_s > 0.0 && now_count >= before
               ? static_cast<double>(now_count - before) / period_s
               : 0.0;
  };
  const std::uint64_t received =
      current.events_in - std::min(current.events_in, last_rates_.events_in);
  const std::uint64_t thinned = current.thinned - std::min(current.thinned, last_rates_.thinned);
  status.add("input rate [ev/s]", rate(current.events_in, last_rates_.events_in));
  status.add("processed rate [ev/s]", rate(current.processed, last_rates_.processed));
  if (rate_limiter_) {
    status.add("max event rate [ev/s]", rate_limiter_->config().max_rate_eps);
    status.add("event-time input rate [ev/s]", rate_limiter_->measuredRate());
    status.add("keep probability", rate_limiter_->keepProbability());
    status.add("events dropped by the rate cap", thinned_);
    status.add("dropped share (last period)",
               received > 0 ? static_cast<double>(thinned) / static_cast<double>(received) : 0.0);
    status.add("dropped share (since start)",
               counters_.events_in > 0
                   ? static_cast<double>(thinned_) / static_cast<double>(counters_.events_in)
                   : 0.0);
  }
  last_rates_ = current;
}

void PoseFilterNodeletBase::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  if (!mountKnown()) {
    status.summaryf(DiagnosticStatus::WARN, "waiting for tf %s -> %s", config_->base_frame.c_str(),
                    config_->sensor_frame.c_str());
  } else if (counters_.filter_errors > 0) {
    status.summary(DiagnosticStatus::ERROR, "the filter rejected events (see the log)");
  } else if (counters_.bad_input > bad_input_reported_) {
    status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
  } else if (!filterRunning()) {
    status.summary(DiagnosticStatus::OK, "waiting for events");
  } else if (!diagnoseTracking(status)) {
    status.summary(DiagnosticStatus::OK, "tracking");
  }
  bad_input_reported_ = counters_.bad_input;
  status.add("messages", counters_.messages);
  status.add("events received", counters_.events_in);
  status.add("events processed", processedEvents());
  status.add("empty messages", counters_.empty_messages);
  status.add("messages in a wrong frame", counters_.rejected_frame);
  diagnoseInput(status);
  status.add("events clamped in time", counters_.clamped);
  status.add("events stamped 0 (dropped)", counters_.zero_time);
  status.add("restarts after time jumps", counters_.restarts);
  status.add("pauses longer than gap_warning", counters_.gaps);
  status.add("processing time [s]", processing_s_);
  status.add("events per second of processing",
             processing_s_ > 0.0 ? static_cast<double>(counters_.events_in) / processing_s_ : 0.0);
  status.add("last pose latency [s]", last_latency_s_);
  diagnoseRates(status);
  diagnoseFilter(status);
}

}  // namespace ebslam_ros
