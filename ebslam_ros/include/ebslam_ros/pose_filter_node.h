#pragma once
// The ROS side shared by the EventParticleFilter and EventSlam2d nodelets (not a nodelet): input
// checks, optional denoising, the filter's life cycle and the outputs (pose, path, particles, tf,
// diagnostics, dynamic_reconfigure). Frames (REP 105): map -> odom -> base_link -> sensor_frame;
// the core estimates the planar pose of the sensor's optical frame (z up to the ceiling). Outputs
// carry the time of their last event. Details: docs/ros_nodes_notes.md#pose-filter-nodelets

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/ResetPose.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2/LinearMath/Transform.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <boost/thread/recursive_mutex.hpp>

#include <ebslam/events/event_denoiser.h>
#include <ebslam/events/pose.h>
#include <ebslam/slam/event_filter.h>
#include <ebslam/slam/particle_set2d.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "ebslam_ros/EventFilterKnobsConfig.h"
#include "ebslam_ros/event_input.h"
#include "ebslam_ros/log_throttle.h"
#include "ebslam_ros/ros_params.h"

namespace ebslam_ros {

/// What PoseFilterNode needs of a core filter (EventParticleFilter, EventSlam2d).
class PoseFilterBackend {
 public:
  virtual ~PoseFilterBackend() = default;
  virtual void process(const ebslam::Event* events, std::size_t count) = 0;
  /// Planar pose of the sensor's optical frame in the map.
  virtual ebslam::Pose2 estimate() const = 0;
  virtual const ebslam::ParticleSet2D& particles() const = 0;
  virtual const ebslam::EventFilterConfig& filterConfig() const = 0;
  virtual void setFilterConfig(const ebslam::EventFilterConfig& config) = 0;
  virtual double g0() const = 0;
  virtual std::uint64_t processedEvents() const = 0;
};

/// Planar part of base_link -> sensor; throws std::invalid_argument unless the sensor's optical
/// axis points up (within 10 degrees).
ebslam::Pose2 planarMount(const tf2::Transform& base_to_sensor);

class PoseFilterNode {
 public:
  /// Creates the core filter with the sensor's start pose (map frame) and the filter knobs.
  using Factory = std::function<std::unique_ptr<PoseFilterBackend>(
      const ebslam::Pose2& sensor_start, const ebslam::EventFilterConfig& knobs)>;
  /// Runs after every filter update (mutex held), before its pose is published: the SLAM
  /// nodelet publishes its map from here.
  using AfterUpdate = std::function<void(const PoseFilterBackend& filter, const ros::Time& stamp)>;

  /// Subscribes `events` in `nh`; advertises pose, path, particles, the `reset` service,
  /// dynamic_reconfigure and diagnostics (private names in `private_nh`). `name` names the
  /// diagnostics task.
  PoseFilterNode(ros::NodeHandle nh, ros::NodeHandle private_nh, PoseFilterNodeConfig config,
                 ebslam::EventFilterConfig knobs, Factory factory, std::string name);

  void setAfterUpdate(AfterUpdate after_update) { after_update_ = std::move(after_update); }
  /// The filter's state is guarded by this mutex; hold it to read the backend.
  std::mutex& mutex() { return mutex_; }
  /// nullptr until the first events arrived with the mounting known.
  const PoseFilterBackend* backend() const { return backend_.get(); }
  const PoseFilterNodeConfig& config() const { return config_; }

 private:
  void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg);
  bool onReset(ebslam_msgs::ResetPose::Request& request,
               ebslam_msgs::ResetPose::Response& response);
  void onReconfigure(EventFilterKnobsConfig& knobs, std::uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// Mounting from parameters or tf; false (and a throttled warning) while tf lacks it.
  bool resolveMount();
  void restart(const ebslam::Pose2& base_pose);
  void publish(const ros::Time& stamp);
  /// (Re)creates or removes the denoiser after config_.denoise / config_.denoiser (forgets the
  /// activity).
  void makeDenoiser();

  PoseFilterNodeConfig config_;
  ebslam::EventFilterConfig knobs_;
  Factory factory_;
  AfterUpdate after_update_;
  std::string name_;
  ros::NodeHandle nh_, private_nh_;
  std::mutex mutex_;

  std::unique_ptr<PoseFilterBackend> backend_;
  ebslam::Pose2 start_pose_;  // base_link in map at the next (re)start
  std::optional<ebslam::Pose2> mount_;
  EventInputGuard guard_;
  /// ~denoise: the background-activity filter between the guard and the pose filter.
  std::optional<ebslam::BackgroundActivityFilter> denoiser_;

  ros::Subscriber events_sub_;
  ros::Publisher pose_pub_, path_pub_, particles_pub_;
  ros::ServiceServer reset_srv_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  std::unique_ptr<dynamic_reconfigure::Server<EventFilterKnobsConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer diagnostics_timer_;

  std::deque<geometry_msgs::PoseStamped> path_;
  ros::WallTime last_path_publication_;

  // Counters for diagnostics (since start).
  std::uint64_t messages_ = 0, events_in_ = 0, empty_messages_ = 0, rejected_size_ = 0,
                rejected_frame_ = 0, outside_ = 0, clamped_ = 0, restarts_ = 0, gaps_ = 0,
                zero_time_ = 0, waiting_for_mount_ = 0, filter_errors_ = 0, denoiser_passed_ = 0,
                denoiser_removed_ = 0;
  std::uint64_t bad_input_seen_ = 0, bad_input_reported_ = 0;
  // Per-message problems, logged at most every 5 s of wall time.
  WallThrottle restart_log_{5.0}, gap_log_{5.0}, zero_time_log_{5.0};
  double processing_s_ = 0.0;
  double last_latency_s_ = 0.0;
};

}  // namespace ebslam_ros
