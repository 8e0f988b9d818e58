#pragma once
// Parameters of the EventFilePlayer nodelet.

#include <ros/node_handle.h>

#include <ebslam/events/event.h>
#include <ebslam/events/event_io.h>

#include <optional>
#include <string>

namespace ebslam_ros {

/// Configuration of the event file player.
struct EventFilePlayerConfig {
  std::string file;                               ///< ~file: event file to play
  std::optional<ebslam::EventFileFormat> format;  ///< ~format: binary|text|rpg, "" = detect
  std::optional<ebslam::SensorSize> sensor;       ///< ~width, ~height [px]; 0 = from the file
  std::string frame_id = "edvs_optical_frame";    ///< ~frame_id: optical frame of the sensor
  double publish_rate_hz = 100.0;  ///< ~publish_rate: EventArray messages per second [Hz]
  double speed = 1.0;              ///< ~speed: playback speed factor (2 = twice real time)
  bool loop = false;               ///< ~loop: start again at the end of the file
  /// ~max_gap: longest step of the file's clock between two events that is played as it is [s of
  /// stream time]; a longer one is a gap to skip when the next event confirms it, else damage
  double max_gap_s = 10.0;
  bool wait_for_subscribers =
      false;  ///< ~wait_for_subscribers: start playing on the first subscriber
};

EventFilePlayerConfig loadEventFilePlayerConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
