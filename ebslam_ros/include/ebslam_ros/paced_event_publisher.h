#pragma once
// Publishes a simulator's events on `events` in messages of fixed stream-time length, each sent
// when its end is due on the wall clock (stream time / speed), and maps stream time (us, the
// trajectory clock) to ROS time: with publish_clock, ROS time starts at clock_start and runs with
// stream time, published on /clock at every message end; otherwise it starts at now() and runs
// at `speed`. Used by the EventSimulator and RgbdEventSimulator nodelets.

#include <ebslam_msgs/event_conversions.h>
#include <ros/ros.h>

#include <ebslam/events/event.h>
#include <ebslam/events/event_clock.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ebslam_ros {

struct PacedEventOptions {
  double speed = 1.0;                 ///< stream time per wall time
  double publish_rate_hz = 100;       ///< messages per second of stream time
  bool publish_clock = false;         ///< publish /clock (then stamps start at clock_start_s)
  double clock_start_s = 0.0;         ///< ROS time of the first event with publish_clock [s]
  bool wait_for_subscribers = false;  ///< start only once `events` has a subscriber
  /// Start only once each of these topics (resolved names) has a subscriber on the master, e.g.
  /// the SLAM's input behind a filter, so that its first event is the stream's first.
  std::vector<std::string> start_when_subscribed;
  std::string frame_id;         ///< frame of the event messages
  ebslam::SensorSize sensor{};  ///< sensor size of the event messages
};

/// The pacing options of a simulator node config (EventSimulatorNodeConfig,
/// RgbdEventSimulatorNodeConfig: the same field names) for an event sensor of width x height.
template <typename SimulatorNodeConfig>
PacedEventOptions pacedEventOptions(const SimulatorNodeConfig& config, const std::string& frame_id,
                                    int width, int height) {
  PacedEventOptions options;
  options.speed = config.speed;
  options.publish_rate_hz = config.publish_rate_hz;
  options.publish_clock = config.publish_clock;
  options.clock_start_s = config.clock_start_s;
  options.wait_for_subscribers = config.wait_for_subscribers;
  options.start_when_subscribed = config.start_when_subscribed;
  options.frame_id = frame_id;
  options.sensor = {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
  return options;
}

class PacedEventPublisher {
 public:
  /// Thrown out of the simulation's callbacks once `stop` is set, to end it early.
  struct Stopped {};
  /// Called after each message end with its stream time [s] and ROS time (ground truth).
  using MessageEndCallback = std::function<void(double t_end_s, const ros::Time& stamp)>;

  /// Advertises `events` (and /clock with publish_clock) in `nh`'s namespace.
  PacedEventPublisher(ros::NodeHandle& nh, PacedEventOptions options, const std::atomic<bool>& stop,
                      MessageEndCallback on_message_end);

  /// Waits for the subscribers asked for, then anchors stream time `begin_us` at the clocks' start.
  /// False if stopped while waiting.
  bool start(std::int64_t begin_us);
  /// Queues an event; sends first every message that ends at or before its time.
  void add(const ebslam::Event& event);
  /// Sends every message that ends at or before stream time `t_us`.
  void sendUntil(std::int64_t t_us);
  /// Sends the next message (ending one period after the last), events or not.
  void sendNext();
  /// Ends the stream at `end_us`: a last message up to it unless one ended there already.
  void finish(std::int64_t end_us);

  /// ROS time of stream time `t_us`.
  ros::Time rosTime(std::int64_t t_us) const;
  std::uint32_t messages() const { return messages_; }

 private:
  std::int64_t periodUs() const;

  PacedEventOptions options_;
  const std::atomic<bool>& stop_;
  MessageEndCallback on_message_end_;
  ros::Publisher events_pub_, clock_pub_;
  ebslam::EventClock clock_;
  ros::WallTime wall_start_;
  std::int64_t begin_us_ = 0, next_boundary_us_ = 0, last_end_us_ = 0;
  ebslam::EventVector pending_;
  std::uint32_t messages_ = 0;
};

}  // namespace ebslam_ros
