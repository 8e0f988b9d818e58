#pragma once

// Real event recordings of other sensors as eDVS streams: the events of a larger sensor
// subsampled onto the eDVS's 128 x 128 pixels and retimed to a chosen mean event rate, with the
// recording's own bursts and quiet stretches kept. The emulator and the parser's tests and
// benchmarks stream them. ROS-free.

#include <string>

#include "ebslam/events/event.h"

namespace edvs {

/// Maps `events` of a `sensor` (any size up to 65536 x 65536) onto 128 x 128 by integer
/// subsampling (x / s, y / s with s the smallest factor that fits both sides) and scales their
/// times about the first one so that the stream's mean rate is `rate_hz` [events/s]; the first
/// event is at 0 us. Throws std::invalid_argument for fewer than two events, a time span of
/// zero, times running backwards or a rate <= 0.
ebslam::EventVector edvsStreamFromRecording(const ebslam::EventVector& events,
                                            const ebslam::SensorSize& sensor, double rate_hz);

/// Reads a real recording: an event packet file (".evpk", see ebslam/events/event_packet.h,
/// every packet of one encoding decoded) or any event file ebslam::readEventFile reads (the
/// Event Camera Dataset's events.txt among them). Returns the events sorted by time and sets
/// `sensor`. Throws std::runtime_error when the file cannot be read or holds a damaged stream.
ebslam::EventVector readRecording(const std::string& path, ebslam::SensorSize& sensor);

}  // namespace edvs
