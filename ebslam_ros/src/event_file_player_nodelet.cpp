// Plays an event file as ebslam_msgs/EventArray, paced by the wall clock.
//
// Publication (relative name): events (ebslam_msgs/EventArray). Every ~publish_rate a message
// carries the events whose time has come. Event ts = wall time at the start of playback +
// (t_us - first t_us) / ~speed (ebslam::EventClock, unclamped: file order is kept);
// header.stamp = ts of the last event; header.frame_id = ~frame_id.
// A damaged file is played up to the damage and the damage is logged. Timestamps that run
// backwards in the file are published in file order (counted and reported at the end).
// Damaged times are reported (throttled error) and never stop playback: a step of the file's
// clock longer than ~max_gap (either way) is a gap in the recording if the next event follows on
// from it (playback goes on at once, the stamps shifted to close the gap: a warning), and a
// damaged line otherwise (that event is dropped); an event whose time falls outside ros::Time is
// dropped. Counts of both are reported at the end of the file.
// With ~wait_for_subscribers playback starts 0.5 s after the first subscriber has connected.
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <ebslam/events/event_clock.h>
#include <ebslam/events/event_io.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>

#include "ebslam_msgs/event_conversions.h"
#include "event_file_player_params.h"

namespace ebslam_ros {

class EventFilePlayerNodelet : public nodelet::Nodelet {
 private:
  static constexpr std::size_t kReadBatch = 65536;
  static constexpr double kSubscriberSettleTime = 0.5;  // [s]

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "event file player " + getName(), [&] {
      config_ = loadEventFilePlayerConfig(getPrivateNodeHandle());
      openFile();
    });
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
    clock_ = ebslam::EventClock(config_.speed);
    file_index_ = 0;
    held_.reset();
    last_t_us_.reset();
    last_stamp_us_ = 0;
    dropped_ = 0;
    gaps_skipped_ = 0;
  }

  // Publishes every event whose playback time is at or before now.
  void publishDue(const ros::WallTimerEvent&) {
    if (!clock_.anchored() && config_.wait_for_subscribers && !subscriberSettled()) return;
    const std::int64_t now_us = ebslam_msgs::toMicroseconds(ros::Time::now());
    // Stamped as each event is accepted: a skipped gap moves the anchor within a batch.
    ebslam_msgs::EventArray msg;
    while (true) {
      if (pending_index_ == pending_.size()) {
        pending_index_ = 0;
        if (reader_->next(pending_, kReadBatch) == 0) break;
      }
      const ebslam::Event& event = pending_[pending_index_];
      if (!clock_.anchored()) clock_.anchor(event.t_us, now_us);
      if (held_) {
        if (std::abs(stepSeconds(held_->event.t_us, event.t_us)) <= config_.max_gap_s) {
          skipGapTo(*held_, now_us);
          msg.events.push_back(eventMsg(held_->event, last_stamp_us_));
        } else {
          drop(*held_, "steps away from both its neighbours");
        }
        held_.reset();
      }
      if (last_t_us_ && std::abs(stepSeconds(*last_t_us_, event.t_us)) > config_.max_gap_s) {
        // A gap in the recording or one damaged line: the next event tells.
        held_ = Held{event, file_index_++};
        ++pending_index_;
        continue;
      }
      const std::optional<std::int64_t> stamp_us = clock_.map(event.t_us);
      if (!stamp_us || !ebslam_msgs::rosTimeOf(*stamp_us)) {
        drop(Held{event, file_index_++}, "maps outside the range of ros::Time");
        ++pending_index_;
        continue;
      }
      if (*stamp_us > now_us) break;
      msg.events.push_back(eventMsg(event, *stamp_us));
      last_t_us_ = event.t_us;
      last_stamp_us_ = *stamp_us;
      ++file_index_;
      ++pending_index_;
    }
    if (!msg.events.empty()) {
      msg.header.frame_id = config_.frame_id;
      msg.header.stamp = msg.events.back().ts;
      msg.width = reader_->sensor().width;
      msg.height = reader_->sensor().height;
      publisher_.publish(msg);
    }
    if (pending_index_ == pending_.size() && reader_->done()) {
      if (held_) drop(*held_, "is the last one and nothing follows on from it");
      held_.reset();
      finish();
    }
  }

  // An event after a step longer than ~max_gap, and its index in the file (from 0).
  struct Held {
    ebslam::Event event;
    std::size_t index = 0;
  };

  // The event at published time stamp_us (checked by the caller to lie within ros::Time).
  static ebslam_msgs::Event eventMsg(const ebslam::Event& event, std::int64_t stamp_us) {
    return ebslam_msgs::toMsg(ebslam::Event{stamp_us, event.x, event.y, event.polarity});
  }

  // Step of the file's clock from a to b [s of stream time] (no integer overflow).
  static double stepSeconds(std::int64_t a, std::int64_t b) {
    return (static_cast<double>(b) - static_cast<double>(a)) * 1e-6;
  }

  // Plays `held` at once, right after the last published event: the anchor moves so that the
  // gap in the file's clock before it takes no wall time (later stamps shift by the same).
  void skipGapTo(const Held& held, std::int64_t now_us) {
    const double gap_s = last_t_us_ ? stepSeconds(*last_t_us_, held.event.t_us) : 0.0;
    clock_.anchor(held.event.t_us, std::max(now_us, last_stamp_us_));
    last_t_us_ = held.event.t_us;
    last_stamp_us_ = clock_.anchorPublished();
    ++gaps_skipped_;
    NODELET_WARN_THROTTLE(1.0,
                          "'%s': the file's clock steps by %.6f s before event %zu (t = %ld us): "
                          "a gap in the recording longer than ~max_gap = %.3f s, played without "
                          "waiting (stamps shifted; %zu gaps so far)",
                          config_.file.c_str(), gap_s, held.index,
                          static_cast<long>(held.event.t_us), config_.max_gap_s, gaps_skipped_);
  }

  void drop(const Held& held, const char* why) {
    ++dropped_;
    NODELET_ERROR_THROTTLE(1.0,
                           "'%s' is damaged: dropped event %zu (t = %ld us, x = %u, y = %u), whose "
                           "time %s (%zu dropped so far)",
                           config_.file.c_str(), held.index, static_cast<long>(held.event.t_us),
                           static_cast<unsigned>(held.event.x), static_cast<unsigned>(held.event.y),
                           why, dropped_);
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
    if (dropped_ > 0) {
      NODELET_ERROR("'%s': dropped %zu events whose times are damaged", config_.file.c_str(),
                    dropped_);
    }
    if (gaps_skipped_ > 0) {
      NODELET_WARN("'%s': skipped %zu gaps longer than ~max_gap = %.3f s", config_.file.c_str(),
                   gaps_skipped_, config_.max_gap_s);
    }
    if (reader_->nonMonotonicCount() > 0) {
      NODELET_WARN("%zu events in '%s' run backwards in time", reader_->nonMonotonicCount(),
                   config_.file.c_str());
    }
    NODELET_INFO("played %zu events from '%s'", reader_->eventsRead() - dropped_,
                 config_.file.c_str());
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
  ebslam::EventClock clock_;    // file time -> ROS time, anchored at the start of playback
  std::size_t file_index_ = 0;  // index in the file of pending_[pending_index_]
  std::optional<Held> held_;    // the event after a long step, until the next one
  std::optional<std::int64_t> last_t_us_;  // file time of the last published event [us]
  std::int64_t last_stamp_us_ = 0;         // its stamp [us since the ROS epoch]
  std::size_t dropped_ = 0;                // events with damaged times
  std::size_t gaps_skipped_ = 0;
  ros::WallTime subscriber_seen_;
  ros::Publisher publisher_;
  ros::WallTimer timer_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventFilePlayerNodelet, nodelet::Nodelet)
