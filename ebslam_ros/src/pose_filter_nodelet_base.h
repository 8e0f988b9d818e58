#pragma once
// The ROS side every pose-estimating nodelet shares (EventParticleFilter and EventSlam2d through
// PlanarPoseFilterNodelet; EventSlam3d): the sensor mounting from parameters or tf, the input's
// common checks and their throttled logs, the outputs pose, path, particles and tf (REP 105:
// map -> odom -> base_link -> sensor_frame) and the diagnostics with their counters and tracking
// state. A derived nodelet owns the core filter and its geometry (planar: ebslam::Pose2 and
// tf2::Transform; 6-DoF: Eigen::Isometry3d) and fills the hooks below. Outputs carry the time of
// their last event. Details: docs/ros_nodes_notes.md#pose-filter-nodelets

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/Transform.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2/LinearMath/Transform.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <ebslam/events/event_rate_limiter.h>

#include "ebslam_ros/log_throttle.h"
#include "pose_node_params.h"

namespace ebslam_ros {

class PoseFilterNodeletBase : public nodelet::Nodelet {
 public:
  ~PoseFilterNodeletBase() override;

 protected:
  static constexpr double kWarnPeriodS = 5.0;  // throttle of repeated input warnings [s]

  /// What the input brought since the start (diagnostics); bad_input counts every problem.
  struct InputCounters {
    std::uint64_t messages = 0, events_in = 0, empty_messages = 0, rejected_frame = 0, clamped = 0,
                  zero_time = 0, restarts = 0, gaps = 0, waiting_for_mount = 0, filter_errors = 0,
                  bad_input = 0;
  };

  /// Starts tf and the publishers pose (queue `pose_queue`), path and particles in the node's
  /// namespace. `config` is the derived nodelet's and must live as long as it.
  void startOutputs(const PoseNodeConfig& config, std::uint32_t pose_queue);
  /// The diagnostics task (named after the nodelet), updated every second of wall time with the
  /// mutex held. Call last in onInit().
  void startDiagnostics();
  /// Stops the diagnostics timer: the first thing in the most derived nodelet's destructor, as
  /// the timer calls its hooks.
  void stopDiagnostics();

  /// Publishes the mounting from the parameters (~mount_xyz, ~mount_rpy) as the static
  /// base_link -> sensor_frame.
  void sendStaticMount(const tf2::Transform& mount);
  void sendStaticMount(const Eigen::Isometry3d& mount);
  /// base_link -> sensor_frame from tf at the latest time; none (and a throttled WARN) while tf
  /// lacks it.
  std::optional<geometry_msgs::Transform> lookupMount();

  /// Counts a message of `events` events and checks what every input must satisfy: false for an
  /// empty message or one in a frame other than ~sensor_frame (throttled ERROR naming `type`).
  bool acceptInput(const std::string& frame_id, std::size_t events, const char* type);
  /// Counts and logs (throttled) a restart after the time of the `what` (singular: "event")
  /// jumped back by `jump_back_us`; `restarted` says how the filter restarted.
  void noteRestart(std::int64_t jump_back_us, const char* what, const char* restarted);
  /// Counts and logs (throttled) a pause of the stream of `gap_us` [us] (a forward jump of more
  /// than a day as a bad stamp); `continuation` says how the filter goes on.
  void noteGap(std::int64_t gap_us, const char* what, const char* continuation);
  /// Counts and logs (throttled) `count` dropped events stamped 0.
  void noteZeroTime(std::size_t count, const char* what);
  /// Counts and logs (throttled) events the core filter rejected (a defect: the input checks make
  /// them valid).
  void noteFilterError(const char* who, std::size_t count, const std::exception& error);

  /// Publishes base_link's pose in the map (covariance in geometry_msgs' x y z rx ry rz order),
  /// appends it to `path` (published at most every 0.1 s of wall time while subscribed) and,
  /// while `particles` or `particlecloud` (AMCL's name) is subscribed, the poses `particles()`
  /// gives.
  void publishPose(const ros::Time& stamp, const geometry_msgs::Pose& base,
                   const geometry_msgs::PoseWithCovariance::_covariance_type& covariance,
                   const std::function<std::vector<geometry_msgs::Pose>()>& particles);
  /// map -> odom (odom -> base_link from tf with ~odom_from_tf, else sent as identity too) for
  /// base_link's pose `map_to_base` at `stamp`, when ~publish_tf.
  void publishTf(const tf2::Transform& map_to_base, const ros::Time& stamp);
  void publishTf(const Eigen::Isometry3d& map_to_base, const ros::Time& stamp);
  void clearPath() { path_.clear(); }

  // Diagnostics hooks (mutex held).
  virtual bool mountKnown() const = 0;
  virtual bool filterRunning() const = 0;
  virtual std::uint64_t processedEvents() const = 0;
  /// A WARN summary of the filter's own state (e.g. lost) instead of "tracking"; false: none.
  virtual bool diagnoseTracking(diagnostic_updater::DiagnosticStatusWrapper&) const {
    return false;
  }
  /// Input counters of the derived nodelet, after "empty messages" and "messages in a wrong
  /// frame".
  virtual void diagnoseInput(diagnostic_updater::DiagnosticStatusWrapper&) const {}
  /// The filter's own values, after the common ones.
  virtual void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper&) const {}

  /// The tf buffer of startOutputs (odom -> base_link, frames of incoming poses).
  tf2_ros::Buffer& tfBuffer() { return *tf_buffer_; }
  const PoseNodeConfig& poseNodeConfig() const { return *config_; }
  std::mutex& mutex() { return mutex_; }
  InputCounters& counters() { return counters_; }
  void addProcessingTime(double seconds) { processing_s_ += seconds; }

  /// Thins the events to `config`'s cap from now on (limitRate); the cap and the dropped share
  /// then appear on the diagnostics.
  void startRateLimit(const ebslam::EventRateLimiterConfig& config) {
    if (config.enabled()) rate_limiter_.emplace(config);
  }
  /// ~max_event_rate: thins `events` (time-ordered; any event type with t_us) to the cap before
  /// the filter, counts and returns how many it dropped. Call on every segment after the input
  /// checks.
  template <typename EventVectorT>
  std::size_t limitRate(EventVectorT& events) {
    const std::size_t dropped = rate_limiter_ ? rate_limiter_->thinInPlace(events) : 0;
    thinned_ += dropped;
    return dropped;
  }
  /// Restarts the rate measurement and the thinning's random sequence (a restarted stream).
  void restartRateLimit() {
    if (rate_limiter_) rate_limiter_->reset();
  }

 private:
  template <typename Transform>
  void publishTfOf(const Transform& map_to_base, const ros::Time& stamp);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void diagnoseRates(diagnostic_updater::DiagnosticStatusWrapper& status);

  const PoseNodeConfig* config_ = nullptr;
  std::mutex mutex_;
  InputCounters counters_;
  std::uint64_t bad_input_reported_ = 0;
  double processing_s_ = 0.0;
  double last_latency_s_ = 0.0;
  // ~max_event_rate; the rates on diagnostics are per second of wall time since the last update.
  std::optional<ebslam::EventRateLimiter> rate_limiter_;
  std::uint64_t thinned_ = 0;
  struct RateSnapshot {
    ros::WallTime time;
    std::uint64_t events_in = 0, processed = 0, thinned = 0;
  } last_rates_;
  // Per-message problems, logged at most every kWarnPeriodS of wall time.
  WallThrottle restart_log_{kWarnPeriodS}, gap_log_{kWarnPeriodS}, zero_time_log_{kWarnPeriodS};

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  // particlecloud: the particles under AMCL's name too (rviz configurations made for AMCL).
  ros::Publisher pose_pub_, path_pub_, particles_pub_, particlecloud_pub_;
  std::deque<geometry_msgs::PoseStamped> path_;
  ros::WallTime last_path_publication_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
};

}  // namespace ebslam_ros
