#pragma once
// Parameters of the EventDenoiser nodelet; its filter's also under ~denoiser/ of the pose filters.

#include <ros/node_handle.h>

#include <ebslam/events/event_denoiser.h>

namespace ebslam_ros {

/// Background-activity filter (ebslam/events/event_denoiser.h) from `nh`: ~window [s] 0.1,
/// ~min_support 3, ~polarity_match true, ~refractory_filter false, ~refractory_period [s] 0.001
/// (the core defaults). Times are rounded to microseconds.
ebslam::BackgroundActivityFilterConfig loadBackgroundActivityFilterConfig(
    const ros::NodeHandle& nh);

/// The EventDenoiser nodelet.
struct EventDenoiserNodeConfig {
  ebslam::BackgroundActivityFilterConfig filter;
  int queue_size = 1000;  ///< ~queue_size: EventArray messages queued
  /// ~max_backward: events earlier than their predecessor by up to this are filtered at the
  /// predecessor's time (jitter); earlier by more, the stream restarted: the filter forgets [s]
  double max_backward_s = 0.001;
};
EventDenoiserNodeConfig loadEventDenoiserNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
