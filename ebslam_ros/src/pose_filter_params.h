#pragma once
// The parameters the planar pose filters share (EventParticleFilter, EventSlam2d): the
// upward-looking eDVS, the start pose, the optional denoiser and the event filter's knobs.

#include <ros/node_handle.h>

#include <ebslam/events/event_denoiser.h>
#include <ebslam/events/event_rate_limiter.h>
#include <ebslam/events/pose.h>
#include <ebslam/slam/event_filter.h>

#include "ceiling_sensor_params.h"
#include "pose_node_params.h"

namespace ebslam_ros {

/// ~max_event_rate's default [events/s]: docs/your_event_camera.md (accuracy cost and the
/// measurement that chose it).
constexpr double kDefaultMaxEventRate = 4e5;

/// ROS side of EventParticleFilter and EventSlam2d (frames, mounting, output, input checks in
/// PoseNodeConfig).
struct PoseFilterNodeConfig : PoseNodeConfig {
  CeilingSensorConfig sensor;
  ebslam::Pose2 initial_pose;  ///< ~initial_pose: base_link in map [m, m, rad]
  /// ~initial_pose: "unknown": global localisation from the start (filters on a known map).
  bool initial_pose_unknown = false;
  /// ~denoise: run the background-activity filter on the events before the pose filter (no
  /// topic hop); its parameters under ~denoiser/ (loadBackgroundActivityFilterConfig).
  bool denoise = false;
  ebslam::BackgroundActivityFilterConfig denoiser;
  /// ~max_event_rate [events/s of event time, 0 = no cap], ~rate_window [s], ~rate_seed: above
  /// the cap the events are thinned uniformly (seeded) before the filter, so that a megapixel
  /// sensor at 1-50 M events/s does not make the filter fall behind
  /// (ebslam/events/event_rate_limiter.h). EventSlam3d's core has its own cap (Ebslam3dConfig).
  ebslam::EventRateLimiterConfig rate_limit{kDefaultMaxEventRate, 2000, 1};
};
PoseFilterNodeConfig loadPoseFilterNodeConfig(const ros::NodeHandle& private_nh);

/// Common filter knobs (~num_particles, ~batch_size, ~resample_every, ~beta, ~g0, ~initial_spread,
/// ~initial_spread_rad, ~estimate (mean|best), ~latency_compensation, ~seed; into `experimental`:
/// ~diffusion_scale, ~reset_scores_on_resample, ~adapt_g0) over `defaults`.
ebslam::EventFilterConfig loadEventFilterConfig(const ros::NodeHandle& private_nh,
                                                const ebslam::EventFilterConfig& defaults);

}  // namespace ebslam_ros
