#pragma once
// Decoders for the packed event encodings of event_camera_msgs/EventPacket (the format of
// metavision_driver and libcaer_driver): `evt3` (Prophesee EVT 3.0), `libcaer` and `libcaer_cmp`
// (iniVation DAVIS/DVXplorer through libcaer_driver) and `mono`. ROS-free; the ROS side is
// ebslam_ros/event_input.h. Event times are nanoseconds as the encoding defines them (evt3:
// sensor clock; libcaer, libcaer_cmp: host time, time_base + sensor offset; mono: time_base +
// offset); mapping them to the published clock is the caller's (EventPacketClock below).
// Malformed bytes never throw and are never read out of bounds: they are counted in
// PacketDecodeStats and decoding goes on with the next word. Reading an event packet file
// throws MalformedEventData. Formats and the reference recordings:
// docs/event_file_format.md#event-camera-encodings

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "ebslam/events/event.h"

namespace ebslam {

enum class EventEncoding { kEvt3, kLibcaer, kLibcaerCmp, kMono };

/// "evt3", "libcaer", "libcaer_cmp", "mono" (the EventPacket `encoding` strings); nullopt else.
std::optional<EventEncoding> eventEncodingFromName(std::string_view name);
const char* eventEncodingName(EventEncoding encoding);
/// True for encodings whose decoded time is host time since the epoch (libcaer, libcaer_cmp);
/// evt3 and mono carry a sensor clock that the caller anchors to the host clock.
bool eventEncodingHasEpochTime(EventEncoding encoding);

/// One decoded change-detection event; t_ns as the encoding defines it (see the top).
/// Trivial (no default values, like a C struct): PacketEventVector grows without zeroing.
struct PacketEvent {
  std::uint64_t t_ns;
  std::uint16_t x;
  std::uint16_t y;
  bool polarity;  ///< true = ON
};

/// std::allocator, except that resize() leaves new trivial elements uninitialised (the decoder
/// sizes its output for the worst case and then writes each event once).
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}  // NOLINT: rebinding
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
using PacketEventVector = std::vector<PacketEvent, DefaultInitAllocator<PacketEvent>>;

/// An external trigger (evt3 EXT_TRIGGER).
struct TriggerEvent {
  std::uint64_t t_ns = 0;
  std::uint8_t edge = 0;  ///< 1 = rising
  std::uint8_t id = 0;    ///< trigger channel
};

/// What one decode() call did. Nothing is dropped from a valid stream except evt3 events
/// before the stream's first complete time stamp (TIME_HIGH then TIME_LOW in one packet: their
/// time is unknown; the reference decoder skips them the same way).
struct PacketDecodeStats {
  std::size_t events = 0;         ///< events appended
  std::size_t triggers = 0;       ///< trigger events appended
  std::size_t outside = 0;        ///< events dropped: x or y outside the sensor
  std::size_t dropped_bytes = 0;  ///< bytes not decoded: trailing partial word, unknown codes
  std::size_t before_time = 0;    ///< evt3 non-time words skipped before the first time stamp
};

/// Decodes one stream's packets in order; keeps the state that spans packets (evt3 time high
/// bits and 24-bit rollover, the current row/column and vector base). One decoder per stream.
class EventPacketDecoder {
 public:
  /// sensor: events outside width x height are dropped (counted as `outside`). Throws
  /// std::invalid_argument for a zero or larger-than-65536 sensor side.
  EventPacketDecoder(EventEncoding encoding, const SensorSize& sensor);

  /// Appends the events of one packet's `events` bytes (little-endian device layout) to `out`
  /// (and triggers to `triggers` when given). time_base: the packet's `time_base` [ns].
  PacketDecodeStats decode(const std::uint8_t* data, std::size_t size, std::uint64_t time_base,
                           PacketEventVector& out, std::vector<TriggerEvent>* triggers = nullptr);
  /// Forgets the stream state (a new stream, e.g. after a reconnect).
  void reset();

  EventEncoding encoding() const { return encoding_; }
  const SensorSize& sensor() const { return sensor_; }

 private:
  PacketDecodeStats decodeEvt3(const std::uint8_t* data, std::size_t size, PacketEventVector& out,
                               std::vector<TriggerEvent>* triggers);
  PacketDecodeStats decodeLibcaer(const std::uint8_t* data, std::size_t size,
                                  std::uint64_t time_base, PacketEventVector& out);
  PacketDecodeStats decodeLibcaerCmp(const std::uint8_t* data, std::size_t size,
                                     std::uint64_t time_base, PacketEventVector& out);
  PacketDecodeStats decodeMono(const std::uint8_t* data, std::size_t size, std::uint64_t time_base,
                               PacketEventVector& out);

  EventEncoding encoding_;
  SensorSize sensor_;
  // evt3 / libcaer_cmp stream state
  bool has_time_ = false;         ///< evt3: a complete time stamp has been seen
  std::uint64_t time_high_ = 0;   ///< evt3: time-high bits << 12 | rollover count << 24
  std::uint16_t time_low_ = 0;    ///< evt3: 12 low bits [us]
  std::uint16_t row_ = 0;         ///< evt3: current y; libcaer_cmp: vector base y
  std::uint16_t column_ = 0;      ///< evt3: vector base x; libcaer_cmp: current x
  bool vector_polarity_ = false;  ///< polarity of vector events
};

/// Maps decoded times [ns] to the published clock [us since the ROS epoch]. Encodings with
/// epoch time map 1:1; evt3 and mono are anchored once per stream: the first packet's first
/// event is published at that packet's stamp, later events keep their sensor-clock spacing.
/// A step back of the sensor clock by more than restart_ns (a restarted camera) re-anchors.
class EventPacketClock {
 public:
  explicit EventPacketClock(std::uint64_t restart_ns = 1'000'000'000) : restart_ns_(restart_ns) {}
  /// Converts `events` (decoded from one packet stamped stamp_ns) and appends them to `out`;
  /// events whose time falls outside [1 us, 2^63 ns) are dropped and counted in the return
  /// value.
  std::size_t append(EventEncoding encoding, const PacketEventVector& events, std::int64_t stamp_ns,
                     EventVector& out);
  void reset() { anchored_ = false; }

 private:
  std::uint64_t restart_ns_;
  bool anchored_ = false;
  std::int64_t offset_ns_ = 0;  ///< published [ns] - sensor [ns]
  std::uint64_t last_sensor_ns_ = 0;
};

/// Thrown by the event packet file reader for a file that is not one or is cut short.
class MalformedEventData : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One EventPacket message outside ROS (the fields of event_camera_msgs/EventPacket).
struct EventPacket {
  std::int64_t stamp_ns = 0;  ///< header.stamp [ns since the epoch]
  std::string frame_id;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint64_t seq = 0;
  std::uint64_t time_base = 0;
  std::string encoding;
  bool is_bigendian = false;
  std::vector<std::uint8_t> events;
};

/// Event packet files: "EBSLAM-EVENT-PACKETS v1\n", then per packet (little endian) int64
/// stamp_ns, uint32 width, uint32 height, uint64 seq, uint64 time_base, uint8 is_bigendian,
/// uint16 length + encoding, uint16 length + frame_id, uint32 length + event bytes.
/// scripts/event_packets_from_ros2_bag.py writes them from a ROS 2 bag. Throws
/// MalformedEventData for a wrong magic, a cut-off packet, an is_bigendian byte other than 0 or 1
/// or a packet above 256 MiB.
std::vector<EventPacket> parseEventPackets(const std::uint8_t* data, std::size_t size);
/// As parseEventPackets; throws std::runtime_error when the file cannot be read.
std::vector<EventPacket> readEventPacketFile(const std::string& path);
std::string serializeEventPackets(const std::vector<EventPacket>& packets);

}  // namespace ebslam
