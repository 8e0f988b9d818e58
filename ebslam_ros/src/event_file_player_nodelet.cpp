// Plays an event file as ebslam_msgs/EventArray, paced by the wall clock.
//
// Publication (relative name): events (ebslam_msgs/EventArray). Every ~publish_rate a message
// carries the events whose time has come. Event ts = wall time at the start of playback +
// (t_us - first t_us) / ~speed; header.stamp = ts of the last event; header.frame_id = ~frame_id.
// A damaged file is played up to the damage and the damage is logged. Timestamps that run
// backwards in the file are published in file order (counted and reported at the end).
// With ~wait_for_subscribers playback starts 0.5 s after the first subscriber has connected.
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <ebslam/event_io.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>

#include "ebslam_ros/conversions.h"
#include "ebslam_ros/ros_params.h"

namespace ebslam_ros {

class EventFilePlayerNodelet : public nodelet::Nodelet {
 private:
  static constexpr std::size_t kReadBatch = 65536;
  static constexpr double kSubscriberSettleTime = 0.5;  // [s]

  void onInit() override {
    try {
      config_ = loadEventFilePlayerConfig(getPrivateNodeHandle());
      openFile();
    } catch (const std::exception& error) {
      NODELET_ERROR("event file player not started: %s", error.what());
      return;
    }
    publisher_ = getNodeHandle().advertise<ebslam_msgs::EventArray>("events", 100);
    NODELET_INFO("playing '%s' (%s) at %.2fx speed%s", config_.file.c_str(),
                 ebslam::toString(reader_->format()), config_.speed,
                 config_.wait_for_subscribers ? " once a subscriber connects" : "");
    timer_ = getNodeHandle().createWallTimer(ros::WallDuration(1.0 / config_.publish_rate_hz),
                                             &EventFilePlayerNodelet::publishDue, this);
  }

  void openFile() {
    ebslam::EventReadOptions options;
    options.format = config_.format;
    options.sensor = config_.sensor;
    reader_ = std::make_unique<ebslam::EventFileReader>(config_.file, options);
    if (reader_->error()) throw std::runtime_error(*reader_->error());
    pending_.clear();
    pending_index_ = 0;
    anchored_ = false;
  }

  // Publishes every event whose playback time is at or before now.
  void publishDue(const ros::WallTimerEvent&) {
    if (!anchored_ && config_.wait_for_subscribers && !subscriberSettled()) return;
    const ros::Time now = ros::Time::now();
    ebslam::EventVector due;
    while (true) {
      if (pending_index_ == pending_.size()) {
        pending_index_ = 0;
        if (reader_->next(pending_, kReadBatch) == 0) break;
      }
      const ebslam::Event& event = pending_[pending_index_];
      if (!anchored_) {
        anchor_ = TimeAnchor{now, event.t_us, config_.speed};
        anchored_ = true;
      }
      if (toRosTime(event.t_us, anchor_) > now) break;
      due.push_back(event);
      ++pending_index_;
    }
    if (!due.empty()) {
      ebslam_msgs::EventArray msg =
          toEventArrayMsg(due, reader_->sensor(), config_.frame_id, anchor_);
      msg.header.seq = sequence_++;
      publisher_.publish(msg);
    }
    if (pending_index_ == pending_.size() && reader_->done()) finish();
  }

  // roscpp counts a subscriber before its side of the connection is ready, and messages sent in
  // that window are lost; so playback starts once a subscriber has been there for a moment.
  bool subscriberSettled() {
    if (publisher_.getNumSubscribers() == 0) {
      subscriber_seen_ = ros::WallTime();
      return false;
    }
    const ros::WallTime now = ros::WallTime::now();
    if (subscriber_seen_.isZero()) subscriber_seen_ = now;
    return (now - subscriber_seen_).toSec() >= kSubscriberSettleTime;
  }

  void finish() {
    if (reader_->error()) {
      NODELET_ERROR("event file '%s' is damaged, played the %zu events before the damage: %s",
                    config_.file.c_str(), reader_->eventsRead(), reader_->error()->c_str());
    }
    if (reader_->nonMonotonicCount() > 0) {
      NODELET_WARN("%zu events in '%s' run backwards in time", reader_->nonMonotonicCount(),
                   config_.file.c_str());
    }
    NODELET_INFO("played %zu events from '%s'", reader_->eventsRead(), config_.file.c_str());
    if (!config_.loop) {
      timer_.stop();
      return;
    }
    try {
      openFile();
    } catch (const std::exception& error) {
      NODELET_ERROR("cannot reopen '%s' for looping: %s", config_.file.c_str(), error.what());
      timer_.stop();
    }
  }

  EventFilePlayerConfig config_;
  std::unique_ptr<ebslam::EventFileReader> reader_;
  ebslam::EventVector pending_;
  std::size_t pending_index_ = 0;
  bool anchored_ = false;
  TimeAnchor anchor_;
  std::uint32_t sequence_ = 0;
  ros::WallTime subscriber_seen_;
  ros::Publisher publisher_;
  ros::WallTimer timer_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventFilePlayerNodelet, nodelet::Nodelet)
