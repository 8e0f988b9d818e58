// Background-activity filter (ebslam/events/event_denoiser.h) as a nodelet: subscribes `events`
// (ebslam_msgs/EventArray) and publishes `events_denoised` (ebslam_msgs/EventArray), one message
// per input message with the input's header (stamp, frame) and width x height, holding the events
// that pass, unchanged and in order (an empty input gives an empty output).
//
// Bad input (logged throttled on wall time, counted in diagnostics, the node runs on):
//  - a message of another width x height than the stream's first: dropped (no output);
//  - events outside width x height: dropped from the output;
//  - an event earlier than its predecessor by at most ~max_backward: filtered at the
//    predecessor's time (its own stamp is kept in the output); earlier by more: the stream
//    restarted (a looping bag, a reconnect): the filter forgets its activity and goes on.
// Parameters: ~window, ~min_support, ~polarity_match, ~refractory_filter, ~refractory_period
// (dynamic_reconfigure), ~queue_size, ~max_backward; see README.md.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <boost/thread/recursive_mutex.hpp>

#include <ebslam/events/event_denoiser.h>
#include <ebslam_msgs/EventArray.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/EventDenoiserKnobsConfig.h"
#include "ebslam_ros/event_input.h"
#include "event_denoiser_params.h"

namespace ebslam_ros {

class EventDenoiserNodelet : public nodelet::Nodelet {
 private:
  static constexpr double kWarnPeriodS = 5.0;  // throttle of repeated input warnings [s]
  static constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "event denoiser " + getName(), [&] {
      config_ = loadEventDenoiserNodeConfig(getPrivateNodeHandle());
      input_type_ = readEventInputType(getPrivateNodeHandle());
    });
    ros::NodeHandle& nh = getNodeHandle();
    reconfigure_ = std::make_unique<ebslam_ros_common::RuntimeKnobs<EventDenoiserKnobsConfig>>(
        reconfigure_mutex_, getPrivateNodeHandle());
    ebslam_ros_common::markReconfigureParamsRead<EventDenoiserKnobsConfig>(getPrivateNodeHandle());
    EventDenoiserKnobsConfig start;
    start.window = 1e-6 * static_cast<double>(config_.filter.window_us);
    start.min_support = config_.filter.min_support;
    start.polarity_match = config_.filter.polarity_match;
    start.refractory_filter = config_.filter.refractory_filter;
    start.refractory_period = 1e-6 * static_cast<double>(config_.filter.refractory_period_us);
    reconfigure_->updateConfig(start);
    reconfigure_->setCallback(
        [this](EventDenoiserKnobsConfig& k, std::uint32_t level) { onReconfigure(k, level); });

    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, getPrivateNodeHandle());
    diagnostics_->setHardwareID("none");
    diagnostics_->add(getName(), this, &EventDenoiserNodelet::diagnose);
    diagnostics_timer_ =
        nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
          std::lock_guard<std::mutex> lock(mutex_);
          diagnostics_->update();
        });
    events_pub_ = nh.advertise<ebslam_msgs::EventArray>("events_denoised", 100);
    events_sub_.subscribe(
        nh, "events", static_cast<std::uint32_t>(config_.queue_size), input_type_,
        [this](const ebslam_msgs::EventArray::ConstPtr& msg) { onEvents(msg); },
        ros::TransportHints().tcpNoDelay(), getName());
  }

  // ROS_*_THROTTLE runs on ROS time, which a looping bag sends back: throttle on wall time.
  bool due(ros::WallTime& last) {
    const ros::WallTime now = ros::WallTime::now();
    if (!last.isZero() && (now - last).toSec() < kWarnPeriodS) return false;
    last = now;
    return true;
  }

  void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++messages_;
    events_in_ += msg->events.size();
    ebslam_msgs::EventArray out;
    out.header = msg->header;
    out.width = msg->width;
    out.height = msg->height;
    if (msg->events.empty()) {
      ++empty_messages_;
      events_pub_.publish(out);
      return;
    }
    if (!filter_) {
      if (msg->width == 0 || msg->height == 0 || msg->width > 4096 || msg->height > 4096) {
        ++rejected_size_;
        ++bad_input_seen_;
        if (due(size_warned_)) {
          NODELET_ERROR("EventArray of a %ux%u sensor dropped: width and height must be in 1..4096",
                        msg->width, msg->height);
        }
        return;
      }
      filter_.emplace(config_.filter, ebslam::SensorSize{msg->width, msg->height});
    }
    const ebslam::SensorSize sensor = filter_->sensor();
    if (msg->width != sensor.width || msg->height != sensor.height) {
      ++rejected_size_;
      ++bad_input_seen_;
      if (due(size_warned_)) {
        NODELET_ERROR(
            "EventArray of a %ux%u sensor dropped: the stream's sensor is %ux%u (the "
            "size of its first message; restart the node for another sensor)",
            msg->width, msg->height, sensor.width, sensor.height);
      }
      return;
    }
    const std::int64_t max_backward_us =
        static_cast<std::int64_t>(std::llround(config_.max_backward_s * 1e6));
    std::size_t outside = 0, passed = 0;
    out.events.reserve(msg->events.size());
    for (const ebslam_msgs::Event& e : msg->events) {
      if (e.x >= sensor.width || e.y >= sensor.height) {
        ++outside;
        continue;
      }
      std::int64_t t_us = ebslam_msgs::toMicroseconds(e.ts);
      if (last_t_us_ != kNoTime && t_us < last_t_us_) {
        if (last_t_us_ - t_us <= max_backward_us) {
          t_us = last_t_us_;
          ++clamped_;
        } else {
          ++restarts_;
          ++bad_input_seen_;
          if (due(restart_warned_)) {
            NODELET_WARN(
                "event time jumped back by %.3f s (a looping bag or a sensor "
                "reconnect?): the filter forgets its activity",
                1e-6 * static_cast<double>(last_t_us_ - t_us));
          }
          filter_->reset();
        }
      }
      last_t_us_ = t_us;
      if (filter_->accept({t_us, e.x, e.y, e.polarity != 0})) {
        out.events.push_back(e);
        ++passed;
      }
    }
    if (outside > 0) {
      outside_ += outside;
      ++bad_input_seen_;
      if (due(outside_warned_)) {
        NODELET_WARN("dropped %zu events outside the %ux%u sensor", outside, sensor.width,
                     sensor.height);
      }
    }
    passed_ += passed;
    rejected_ += msg->events.size() - outside - passed;
    events_pub_.publish(out);
  }

  void onReconfigure(EventDenoiserKnobsConfig& k, std::uint32_t) {
    std::lock_guard<std::mutex> lock(mutex_);
    ebslam::BackgroundActivityFilterConfig next = config_.filter;
    next.window_us = std::max<std::int64_t>(1, std::llround(k.window * 1e6));
    next.min_support = k.min_support;
    next.polarity_match = k.polarity_match;
    next.refractory_filter = k.refractory_filter;
    next.refractory_period_us = std::llround(k.refractory_period * 1e6);
    try {
      next.validate();
    } catch (const std::invalid_argument& error) {
      NODELET_ERROR("reconfiguration rejected: %s", error.what());
      return;
    }
    config_.filter = next;
    if (filter_) filter_.emplace(config_.filter, filter_->sensor());  // forgets the activity
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (bad_input_seen_ > bad_input_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else if (!filter_) {
      status.summary(DiagnosticStatus::OK, "waiting for events");
    } else {
      status.summary(DiagnosticStatus::OK, "filtering");
    }
    bad_input_reported_ = bad_input_seen_;
    status.add("messages", messages_);
    status.add("events received", events_in_);
    status.add("events passed", passed_);
    status.add("events rejected", rejected_);
    status.add("passed fraction", passed_ + rejected_ > 0
                                      ? static_cast<double>(passed_) / (passed_ + rejected_)
                                      : 0.0);
    status.add("empty messages", empty_messages_);
    status.add("messages of a wrong sensor size", rejected_size_);
    status.add("events outside the sensor", outside_);
    status.add("events clamped in time", clamped_);
    status.add("restarts after time jumps", restarts_);
    status.add("window [s]", 1e-6 * static_cast<double>(config_.filter.window_us));
    status.add("min_support", config_.filter.min_support);
    addDecoderDiagnostics(events_sub_, status);
  }

  EventDenoiserNodeConfig config_;
  std::mutex mutex_;
  std::optional<ebslam::BackgroundActivityFilter> filter_;  // from the first message's size
  std::int64_t last_t_us_ = kNoTime;
  EventInputType input_type_ = EventInputType::kAuto;
  ros::Publisher events_pub_;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<EventDenoiserKnobsConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
  ros::WallTime size_warned_, outside_warned_, restart_warned_;
  std::uint64_t messages_ = 0, events_in_ = 0, passed_ = 0, rejected_ = 0, empty_messages_ = 0,
                rejected_size_ = 0, outside_ = 0, clamped_ = 0, restarts_ = 0;
  std::uint64_t bad_input_seen_ = 0, bad_input_reported_ = 0;
  EventSubscriber events_sub_;  // last member: stopped before the state its callbacks use
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventDenoiserNodelet, nodelet::Nodelet)
