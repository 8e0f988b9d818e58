#pragma once
// The planar pose filters' nodelet (EventParticleFilter, EventSlam2d) on PoseFilterNodeletBase:
// an upward-looking eDVS (its optical axis within 10 degrees of base_link's z) whose events
// (ebslam_msgs/EventArray) drive a core filter with planar particles; the optional denoiser, the
// `reset` service (ebslam_msgs/ResetPose) and the filter knobs (EventFilterKnobs.cfg). The core
// estimates the planar pose of the sensor's optical frame (z up to the ceiling). A backend that
// localises on a known map (EB-PF) also takes AMCL's interface: `initialpose`
// (geometry_msgs/PoseWithCovarianceStamped, rviz's "2D Pose Estimate"), the `global_localization`
// service (std_srvs/Empty) and odom -> base_link from tf as motion prior (~use_odometry).

#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/ResetPose.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <std_srvs/Empty.h>
#include <boost/thread/recursive_mutex.hpp>

#include <ebslam/events/event_denoiser.h>
#include <ebslam/events/pose.h>
#include <ebslam/slam/event_filter.h>
#include <ebslam/slam/particle_set2d.h>
#include <ebslam/slam/tracking_state.h>

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ebslam_ros/EventFilterKnobsConfig.h"
#include "ebslam_ros/event_input.h"
#include "pose_filter_nodelet_base.h"
#include "pose_filter_params.h"

namespace ebslam_ros {

/// What PlanarPoseFilterNodelet needs of a core filter (EventParticleFilter, EventSlam2d).
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
  /// `count` events of the stream left out before process() (~max_event_rate): a filter that
  /// measures the stream's event rate (EB-SLAM-2D's noise-aware diffusion) counts them.
  virtual void countUnprocessed(std::uint64_t /*count*/) {}

  // Localisation on a known map (EB-PF); the defaults are those of a filter without one.
  /// Whether reseed / globalLocalisation / applyOdometry work.
  virtual bool localisesOnMap() const { return false; }
  /// Re-seeds around the sensor's pose with the covariance of (x, y, theta) [m^2, rad^2]; throws
  /// std::invalid_argument for a bad pose or covariance.
  virtual void reseed(const ebslam::Pose2& /*sensor*/, const Eigen::Matrix3d& /*covariance*/) {}
  virtual void globalLocalisation() {}
  /// The sensor's motion in its own frame since the last call.
  virtual void applyOdometry(const ebslam::Pose2& /*sensor_delta*/) {}
  virtual ebslam::TrackingState trackingState() const { return ebslam::TrackingState::kTracking; }
  virtual std::uint64_t recoveries() const { return 0; }
  virtual std::uint64_t convergences() const { return 0; }
  /// Published covariance = scale * the particles' covariance + diag(floor_m^2, floor_m^2,
  /// floor_rad^2) (EbpfLocalisationConfig::covariance_*).
  struct CovarianceModel {
    double scale = 1.0, floor_m = 0.0, floor_rad = 0.0;
  };
  virtual CovarianceModel covarianceModel() const { return {}; }
};

/// Planar part of base_link -> sensor; throws std::invalid_argument unless the sensor's optical
/// axis points up (within 10 degrees).
ebslam::Pose2 planarMount(const tf2::Transform& base_to_sensor);

class PlanarPoseFilterNodelet : public PoseFilterNodeletBase {
 public:
  ~PlanarPoseFilterNodelet() override;

 protected:
  /// Creates the core filter with the sensor's start pose (map frame) and the filter knobs.
  using Factory = std::function<std::unique_ptr<PoseFilterBackend>(
      const ebslam::Pose2& sensor_start, const ebslam::EventFilterConfig& knobs)>;

  /// Subscribes `events`; advertises pose, path, particles, the `reset` service,
  /// dynamic_reconfigure and diagnostics. Call from onInit().
  void startFilter(PoseFilterNodeConfig config, ebslam::EventFilterConfig knobs, Factory factory);
  /// Call before startFilter for a backend that localisesOnMap(): subscribes `initialpose`,
  /// advertises `global_localization` and, with use_odometry, takes odom -> base_link from tf
  /// as the motion between event batches.
  void enableMapLocalisation(bool use_odometry) {
    map_localisation_ = true;
    use_odometry_ = use_odometry;
  }
  /// Runs after every filter update (mutex held), before its pose is published: the SLAM
  /// nodelet publishes its map from here.
  virtual void afterUpdate(const PoseFilterBackend& /*filter*/, const ros::Time& /*stamp*/) {}
  /// nullptr until the first events arrived with the mounting known; hold mutex() to read it.
  const PoseFilterBackend* backend() const { return backend_.get(); }

 private:
  void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg);
  /// The guard's checks of a message (size, pixels, time) as counts and throttled logs; false:
  /// the message is dropped.
  bool checkInput(const ebslam_msgs::EventArray& msg, const EventInputResult& input);
  void processSegment(EventSegment& segment);
  bool onReset(ebslam_msgs::ResetPose::Request& request,
               ebslam_msgs::ResetPose::Response& response);
  void onReconfigure(EventFilterKnobsConfig& knobs, std::uint32_t level);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  bool onGlobalLocalization(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  /// Applies a pending initial pose or global localisation to a (new) backend.
  void applyPendingSeed();
  /// Feeds odom -> base_link's motion up to `stamp` to the backend (~use_odometry).
  void feedOdometry(const ros::Time& stamp);
  bool diagnoseTracking(diagnostic_updater::DiagnosticStatusWrapper& status) const override;
  /// Mounting from parameters or tf; false (and a throttled warning) while tf lacks it.
  bool resolveMount();
  void restart(const ebslam::Pose2& base_pose);
  void publish(const ros::Time& stamp);
  /// (Re)creates or removes the denoiser after config_.denoise / config_.denoiser (forgets the
  /// activity).
  void makeDenoiser();

  bool mountKnown() const override { return mount_.has_value(); }
  bool filterRunning() const override { return backend_ != nullptr; }
  std::uint64_t processedEvents() const override {
    return backend_ ? backend_->processedEvents() : 0;
  }
  void diagnoseInput(diagnostic_updater::DiagnosticStatusWrapper& status) const override;
  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& status) const override;

  PoseFilterNodeConfig config_;
  ebslam::EventFilterConfig knobs_;
  Factory factory_;

  std::unique_ptr<PoseFilterBackend> backend_;
  ebslam::Pose2 start_pose_;  // base_link in map at the next (re)start
  std::optional<ebslam::Pose2> mount_;
  std::optional<EventInputGuard> guard_;
  /// ~denoise: the background-activity filter between the guard and the pose filter.
  std::optional<ebslam::BackgroundActivityFilter> denoiser_;

  EventInputType input_type_ = EventInputType::kAuto;
  EventSubscriber events_sub_;
  ros::ServiceServer reset_srv_;
  // Map localisation (EB-PF): rviz's initial pose, AMCL's global localisation, odometry.
  bool map_localisation_ = false;
  bool use_odometry_ = false;
  ros::Subscriber initial_pose_sub_;
  ros::ServiceServer global_srv_;
  struct Seed {
    ebslam::Pose2 sensor;
    Eigen::Matrix3d covariance;
  };
  std::optional<Seed> pending_seed_;  // for the next (re)created backend
  bool pending_global_ = false;
  std::optional<tf2::Transform> last_odom_;  // odom -> base_link at the last batch
  std::uint64_t initial_poses_ = 0, rejected_initial_poses_ = 0, global_requests_ = 0,
                odometry_missing_ = 0;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<EventFilterKnobsConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;

  // Counters of this input for diagnostics (since start).
  std::uint64_t rejected_size_ = 0, outside_ = 0, denoiser_passed_ = 0, denoiser_removed_ = 0;
};

}  // namespace ebslam_ros
