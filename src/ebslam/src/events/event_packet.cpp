#include "ebslam/events/event_packet.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

namespace ebslam {

namespace {

// Little-endian loads through memcpy: no alignment assumptions, no out-of-bounds reads (every
// caller checks the remaining size first); compilers turn them into single loads.
template <typename T>
T loadLE(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  T swapped = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i)
    swapped = (swapped << 8) | ((value >> (8 * i)) & 0xFF);
  value = swapped;
#endif
  return value;
}

// evt3 word codes (4 high bits of each 16-bit word).
enum Evt3Code : std::uint16_t {
  kEvt3AddrY = 0x0,
  kEvt3AddrX = 0x2,
  kEvt3VectBaseX = 0x3,
  kEvt3Vect12 = 0x4,
  kEvt3Vect8 = 0x5,
  kEvt3TimeLow = 0x6,
  kEvt3Continued4 = 0x7,
  kEvt3TimeHigh = 0x8,
  kEvt3ExtTrigger = 0xA,
  kEvt3Others = 0xE,
  kEvt3Continued12 = 0xF,
};

// libcaer_cmp word codes (libcaer_driver's compression tokens).
enum CmpCode : std::uint16_t {
  kCmpTimeHigh = 0,
  kCmpTimeLow = 1,
  kCmpAddrX = 2,
  kCmpAddrY = 3,
  kCmpVectBaseY = 4,
  kCmpVect8 = 5,
};

// The evt3 24-bit time (12 high + 12 low bits [us]) wraps every 16.8 s. A new time-high value
// below the previous one by more than this many steps (of 4.096 ms) is a wrap; smaller steps back
// are sensor bit errors and are not counted as a wrap (as in the reference decoder).
constexpr std::uint64_t kEvt3WrapMinSteps = 10;

// The wrap count lives in the bits above 24.
std::uint64_t evt3UpdateTimeHigh(std::uint16_t t, std::uint64_t time_high) {
  const std::uint64_t last = (time_high >> 12) & 0xFFF;
  const bool wrap = t < last && last - t > kEvt3WrapMinSteps;
  time_high += static_cast<std::uint64_t>(wrap) << 24;
  return (time_high & ~((std::uint64_t{1} << 24) - 1)) | (std::uint64_t{t} << 12);
}

// Writes events into `out` behind its current end: the vector is sized for `expected` more
// events up front (uninitialised: PacketEventVector) and grown on demand; finish() trims it to
// what was written. Keeps the write position in a register instead of the vector's end pointer.
class EventCursor {
 public:
  EventCursor(PacketEventVector& out, std::size_t expected) : out_(out), begin_(out.size()) {
    out_.resize(begin_ + expected);
    dst_ = out_.data() + begin_;
    end_ = out_.data() + out_.size();
  }
  /// Room for n more events.
  void reserve(std::size_t n) {
    if (static_cast<std::size_t>(end_ - dst_) >= n) return;
    const std::size_t used = static_cast<std::size_t>(dst_ - out_.data());
    out_.resize(std::max(2 * out_.size(), used + n + 1024));
    dst_ = out_.data() + used;
    end_ = out_.data() + out_.size();
  }
  /// Writes e and keeps it when `keep` (branch-free: the slot is overwritten otherwise).
  void put(const PacketEvent& e, bool keep) {
    *dst_ = e;
    dst_ += keep ? 1 : 0;
  }
  void finish() { out_.resize(static_cast<std::size_t>(dst_ - out_.data())); }
  std::size_t written() const { return static_cast<std::size_t>(dst_ - out_.data()) - begin_; }

 private:
  PacketEventVector& out_;
  std::size_t begin_;
  PacketEvent* dst_;
  PacketEvent* end_;
};

void checkSide(std::uint32_t side, const char* name) {
  if (side == 0 || side > 65536) {
    throw std::invalid_argument(std::string("EventPacketDecoder: sensor ") + name + " " +
                                std::to_string(side) + " is not in 1..65536");
  }
}

}  // namespace

std::optional<EventEncoding> eventEncodingFromName(std::string_view name) {
  if (name == "evt3") return EventEncoding::kEvt3;
  if (name == "libcaer") return EventEncoding::kLibcaer;
  if (name == "libcaer_cmp") return EventEncoding::kLibcaerCmp;
  if (name == "mono") return EventEncoding::kMono;
  return std::nullopt;
}

const char* eventEncodingName(EventEncoding encoding) {
  switch (encoding) {
    case EventEncoding::kEvt3:
      return "evt3";
    case EventEncoding::kLibcaer:
      return "libcaer";
    case EventEncoding::kLibcaerCmp:
      return "libcaer_cmp";
    case EventEncoding::kMono:
      return "mono";
  }
  return "unknown";
}

bool eventEncodingHasEpochTime(EventEncoding encoding) {
  return encoding == EventEncoding::kLibcaer || encoding == EventEncoding::kLibcaerCmp;
}

EventPacketDecoder::EventPacketDecoder(EventEncoding encoding, const SensorSize& sensor)
    : encoding_(encoding), sensor_(sensor) {
  checkSide(sensor.width, "width");
  checkSide(sensor.height, "height");
}

void EventPacketDecoder::reset() {
  has_time_ = false;
  time_high_ = 0;
  time_low_ = 0;
  row_ = 0;
  column_ = 0;
  vector_polarity_ = false;
}

PacketDecodeStats EventPacketDecoder::decode(const std::uint8_t* data, std::size_t size,
                                             std::uint64_t time_base, PacketEventVector& out,
                                             std::vector<TriggerEvent>* triggers) {
  if (data == nullptr) size = 0;
  const std::size_t before = out.size();
  PacketDecodeStats stats;
  switch (encoding_) {
    case EventEncoding::kEvt3:
      stats = decodeEvt3(data, size, out, triggers);
      break;
    case EventEncoding::kLibcaer:
      stats = decodeLibcaer(data, size, time_base, out);
      break;
    case EventEncoding::kLibcaerCmp:
      stats = decodeLibcaerCmp(data, size, time_base, out);
      break;
    case EventEncoding::kMono:
      stats = decodeMono(data, size, time_base, out);
      break;
  }
  stats.events = out.size() - before;
  return stats;
}

PacketDecodeStats EventPacketDecoder::decodeEvt3(const std::uint8_t* data, std::size_t size,
                                                 PacketEventVector& out,
                                                 std::vector<TriggerEvent>* triggers) {
  PacketDecodeStats stats;
  const std::size_t words = size / 2;
  stats.dropped_bytes = size % 2;
  std::size_t i = 0;
  // Until the stream's first complete time stamp (a TIME_HIGH, then a TIME_LOW, in one packet)
  // event times are unknown: only time words are read.
  bool seen_high = false;
  for (; !has_time_ && i < words; ++i) {
    const std::uint16_t w = loadLE<std::uint16_t>(data + 2 * i);
    const std::uint16_t code = w >> 12;
    if (code == kEvt3TimeLow) {
      time_low_ = w & 0xFFF;
      if (seen_high) has_time_ = true;
    } else if (code == kEvt3TimeHigh) {
      time_high_ = evt3UpdateTimeHigh(w & 0xFFF, time_high_);
      seen_high = true;
    } else {
      ++stats.before_time;
    }
  }
  const std::uint32_t width = sensor_.width;
  const std::uint32_t height = sensor_.height;
  // Sized for one event per word (the most ADDR_X words can give); vectors reserve their own.
  EventCursor cursor(out, words - i);
  // The stream state in locals: the event stores could alias the members, which would force a
  // reload per word.
  std::uint16_t row = row_, column = column_, time_low = time_low_;
  std::uint64_t time_high = time_high_;
  bool vector_polarity = vector_polarity_;
  std::uint64_t t_ns = (time_high | time_low) * 1000;
  std::size_t outside = 0;
  for (; i < words; ++i) {
    const std::uint16_t w = loadLE<std::uint16_t>(data + 2 * i);
    const std::uint16_t rest = w & 0xFFF;
    const std::uint16_t code = w >> 12;
    // The codes of nearly every word first, as branches the predictor learns (a sparse scene is
    // TIME_HIGH, TIME_LOW, ADDR_Y, ADDR_X per event); the rest through the switch.
    if (code == kEvt3AddrX) {
      const auto x = static_cast<std::uint16_t>(rest & 0x7FF);
      const bool inside = x < width && row < height;
      cursor.put(PacketEvent{t_ns, x, row, (rest & 0x800) != 0}, inside);
      outside += inside ? 0 : 1;
      continue;
    }
    if (code == kEvt3AddrY) {
      row = rest & 0x7FF;
      continue;
    }
    if (code == kEvt3TimeLow) {
      time_low = rest;
      t_ns = (time_high | time_low) * 1000;
      continue;
    }
    if (code == kEvt3TimeHigh) {
      time_high = evt3UpdateTimeHigh(rest, time_high);
      t_ns = (time_high | time_low) * 1000;
      continue;
    }
    switch (code) {
      case kEvt3VectBaseX:
        column = rest & 0x7FF;
        vector_polarity = (rest & 0x800) != 0;
        break;
      case kEvt3Vect12:
      case kEvt3Vect8: {
        const int bits = code == kEvt3Vect12 ? 12 : 8;
        std::uint32_t valid = rest & ((1u << bits) - 1);
        cursor.reserve(12 + (words - i));  // keeps one slot per remaining word
        while (valid != 0) {
          const int b = __builtin_ctz(valid);
          valid &= valid - 1;
          const auto x = static_cast<std::uint16_t>(column + b);
          const bool inside = x < width && row < height;
          cursor.put(PacketEvent{t_ns, x, row, vector_polarity}, inside);
          outside += inside ? 0 : 1;
        }
        column = static_cast<std::uint16_t>(column + bits);
        break;
      }
      case kEvt3ExtTrigger:
        if (triggers != nullptr) {
          triggers->push_back(TriggerEvent{t_ns, static_cast<std::uint8_t>(rest & 0x1),
                                           static_cast<std::uint8_t>((rest >> 8) & 0xF)});
        }
        ++stats.triggers;
        break;
      case kEvt3Others:  // system information and its continuation words: no events
      case kEvt3Continued4:
      case kEvt3Continued12:
        break;
      default:  // codes 1, 9, 11, 12, 13 are not defined in EVT 3.0
        stats.dropped_bytes += 2;
        break;
    }
  }
  cursor.finish();
  row_ = row;
  column_ = column;
  time_low_ = time_low;
  time_high_ = time_high;
  vector_polarity_ = vector_polarity;
  stats.outside = outside;
  return stats;
}

PacketDecodeStats EventPacketDecoder::decodeLibcaer(const std::uint8_t* data, std::size_t size,
                                                    std::uint64_t time_base,
                                                    PacketEventVector& out) {
  // 8 bytes per event: uint32 data (bit 1 polarity, bits 2..16 y, bits 17..31 x), int32 time
  // [us] relative to time_base, which carries the host time and the sensor clock's 2^31 us
  // rollovers up to the packet; a rollover inside the packet shows as time going back.
  PacketDecodeStats stats;
  const std::size_t n = size / 8;
  stats.dropped_bytes = size % 8;
  EventCursor cursor(out, n);
  const std::uint32_t width = sensor_.width;
  const std::uint32_t height = sensor_.height;
  std::uint64_t high = time_base;
  std::uint64_t last_low = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t word = loadLE<std::uint32_t>(data + 8 * i);
    // Sign-extended as the reference decoder does (a valid stream never has negative times).
    const auto low = static_cast<std::uint64_t>(static_cast<std::int64_t>(
        static_cast<std::int32_t>(loadLE<std::uint32_t>(data + 8 * i + 4))));
    high += low < last_low ? (std::uint64_t{1} << 31) * 1000 : 0;
    last_low = low;
    const auto x = static_cast<std::uint16_t>((word >> 17) & 0x7FFF);
    const auto y = static_cast<std::uint16_t>((word >> 2) & 0x7FFF);
    cursor.put(PacketEvent{high + low * 1000, x, y, ((word >> 1) & 1) != 0},
               x < width && y < height);
  }
  cursor.finish();
  stats.outside = n - cursor.written();
  return stats;
}

PacketDecodeStats EventPacketDecoder::decodeLibcaerCmp(const std::uint8_t* data, std::size_t size,
                                                       std::uint64_t time_base,
                                                       PacketEventVector& out) {
  // 16-bit tokens (libcaer_driver's compression): time [us] since the packet's first event in
  // 12 high + 12 low bits, restarting at 0 in every packet; t = time_base + time * 1000.
  PacketDecodeStats stats;
  const std::size_t words = size / 2;
  stats.dropped_bytes = size % 2;
  EventCursor cursor(out, words);  // one slot per word; vectors reserve their own
  std::size_t outside = 0;
  const std::uint32_t width = sensor_.width;
  const std::uint32_t height = sensor_.height;
  std::uint64_t high = 0;
  std::uint64_t low = 0;
  std::uint64_t t_ns = time_base;
  // Stream state in locals (the event stores could alias the members).
  std::uint16_t row = row_, column = column_;
  bool vector_polarity = vector_polarity_;
  for (std::size_t i = 0; i < words; ++i) {
    const std::uint16_t w = loadLE<std::uint16_t>(data + 2 * i);
    const std::uint16_t rest = w & 0xFFF;
    switch (w >> 12) {
      case kCmpTimeHigh:
        high = std::uint64_t{rest} << 12;
        t_ns = time_base + (high | low) * 1000;
        break;
      case kCmpTimeLow:
        low = rest;
        t_ns = time_base + (high | low) * 1000;
        break;
      case kCmpAddrX:
        column = rest & 0x7FF;
        break;
      case kCmpAddrY: {
        const std::uint16_t y = rest & 0x7FF;
        const bool inside = column < width && y < height;
        cursor.put(PacketEvent{t_ns, column, y, (rest & 0x800) != 0}, inside);
        outside += inside ? 0 : 1;
        break;
      }
      case kCmpVectBaseY:
        row = rest & 0x7FF;
        vector_polarity = (rest & 0x800) != 0;
        break;
      case kCmpVect8: {
        std::uint32_t valid = rest & 0xFF;
        cursor.reserve(8 + (words - i));  // keeps one slot per remaining word
        while (valid != 0) {
          const int b = __builtin_ctz(valid);
          valid &= valid - 1;
          const auto y = static_cast<std::uint16_t>(row + b);
          const bool inside = column < width && y < height;
          cursor.put(PacketEvent{t_ns, column, y, vector_polarity}, inside);
          outside += inside ? 0 : 1;
        }
        row = static_cast<std::uint16_t>(row + 8);
        break;
      }
      default:  // not produced by libcaer_driver
        stats.dropped_bytes += 2;
        break;
    }
  }
  cursor.finish();
  row_ = row;
  column_ = column;
  vector_polarity_ = vector_polarity;
  stats.outside = outside;
  return stats;
}

PacketDecodeStats EventPacketDecoder::decodeMono(const std::uint8_t* data, std::size_t size,
                                                 std::uint64_t time_base, PacketEventVector& out) {
  // 8 bytes per event, one little-endian uint64: bits 0..31 time [ns] after time_base, 32..47 x,
  // 48..62 y, 63 polarity.
  PacketDecodeStats stats;
  const std::size_t n = size / 8;
  stats.dropped_bytes = size % 8;
  EventCursor cursor(out, n);
  const std::uint32_t width = sensor_.width;
  const std::uint32_t height = sensor_.height;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t p = loadLE<std::uint64_t>(data + 8 * i);
    const auto x = static_cast<std::uint16_t>((p >> 32) & 0xFFFF);
    const auto y = static_cast<std::uint16_t>((p >> 48) & 0x7FFF);
    cursor.put(PacketEvent{time_base + (p & 0xFFFFFFFFu), x, y, (p >> 63) != 0},
               x < width && y < height);
  }
  cursor.finish();
  stats.outside = n - cursor.written();
  return stats;
}

std::size_t EventPacketClock::append(EventEncoding encoding, const PacketEventVector& events,
                                     std::int64_t stamp_ns, EventVector& out) {
  constexpr auto kMaxNs = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  std::size_t dropped = 0;
  const bool epoch = eventEncodingHasEpochTime(encoding);
  if (!epoch && !events.empty()) {
    const std::uint64_t first = events.front().t_ns;
    if (!anchored_ || (last_sensor_ns_ > first && last_sensor_ns_ - first > restart_ns_)) {
      offset_ns_ = stamp_ns - static_cast<std::int64_t>(first > kMaxNs ? kMaxNs : first);
      anchored_ = true;
    }
  }
  out.reserve(out.size() + events.size());
  for (const PacketEvent& e : events) {
    if (e.t_ns > kMaxNs) {
      ++dropped;
      continue;
    }
    std::int64_t t_ns = static_cast<std::int64_t>(e.t_ns);
    if (!epoch && __builtin_add_overflow(t_ns, offset_ns_, &t_ns)) {
      ++dropped;
      continue;
    }
    if (!epoch) last_sensor_ns_ = e.t_ns;
    const std::int64_t t_us = t_ns / 1000 + (t_ns % 1000 >= 500 ? 1 : 0);
    if (t_ns < 0 || t_us <= 0) {
      ++dropped;
      continue;
    }
    out.push_back(Event{t_us, e.x, e.y, e.polarity});
  }
  return dropped;
}

namespace {

constexpr char kPacketMagic[] = "EBSLAM-EVENT-PACKETS v1\n";
constexpr std::size_t kPacketMagicSize = sizeof(kPacketMagic) - 1;
constexpr std::size_t kMaxPacketBytes = std::size_t{256} << 20;

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool done() const { return pos_ == size_; }
  template <typename T>
  T get(const char* what) {
    need(sizeof(T), what);
    const T value = loadLE<T>(data_ + pos_);
    pos_ += sizeof(T);
    return value;
  }
  void bytes(std::size_t n, const char* what, std::uint8_t* out) {
    need(n, what);
    if (n > 0) std::memcpy(out, data_ + pos_, n);
    pos_ += n;
  }
  std::size_t pos() const { return pos_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (size_ - pos_ < n) {
      throw MalformedEventData("event packet file cut short in " + std::string(what) + " at byte " +
                               std::to_string(pos_));
    }
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

std::string getString(ByteReader& r, const char* what) {
  const auto n = r.get<std::uint16_t>(what);
  std::string s(n, '\0');
  r.bytes(n, what, reinterpret_cast<std::uint8_t*>(s.data()));
  return s;
}

template <typename T>
void put(std::string& out, T value) {
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    out.push_back(static_cast<char>((static_cast<std::uint64_t>(value) >> (8 * i)) & 0xFF));
  }
}

}  // namespace

std::vector<EventPacket> parseEventPackets(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < kPacketMagicSize ||
      std::memcmp(data, kPacketMagic, kPacketMagicSize) != 0) {
    throw MalformedEventData("not an event packet file (magic \"EBSLAM-EVENT-PACKETS v1\")");
  }
  ByteReader r(data + kPacketMagicSize, size - kPacketMagicSize);
  std::vector<EventPacket> packets;
  while (!r.done()) {
    EventPacket p;
    p.stamp_ns = r.get<std::int64_t>("stamp");
    p.width = r.get<std::uint32_t>("width");
    p.height = r.get<std::uint32_t>("height");
    p.seq = r.get<std::uint64_t>("seq");
    p.time_base = r.get<std::uint64_t>("time_base");
    const auto big_endian = r.get<std::uint8_t>("is_bigendian");
    if (big_endian > 1)
      throw MalformedEventData("event packet file: is_bigendian byte is not 0 or 1");
    p.is_bigendian = big_endian != 0;
    p.encoding = getString(r, "encoding");
    p.frame_id = getString(r, "frame_id");
    const auto n = r.get<std::uint32_t>("event byte count");
    if (n > kMaxPacketBytes) {
      throw MalformedEventData("event packet of " + std::to_string(n) +
                               " bytes exceeds the 256 MiB limit");
    }
    if (size - kPacketMagicSize - r.pos() < n) {
      throw MalformedEventData("event packet file cut short in event bytes");
    }
    p.events.resize(n);
    r.bytes(n, "event bytes", p.events.data());
    packets.push_back(std::move(p));
  }
  return packets;
}

std::vector<EventPacket> readEventPacketFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open event packet file " + path);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error("cannot read event packet file " + path);
  return parseEventPackets(bytes.data(), bytes.size());
}

std::string serializeEventPackets(const std::vector<EventPacket>& packets) {
  std::string out(kPacketMagic, kPacketMagicSize);
  for (const EventPacket& p : packets) {
    if (p.encoding.size() > 0xFFFF || p.frame_id.size() > 0xFFFF ||
        p.events.size() > kMaxPacketBytes) {
      throw std::invalid_argument("serializeEventPackets: field too long for the file format");
    }
    put(out, p.stamp_ns);
    put(out, p.width);
    put(out, p.height);
    put(out, p.seq);
    put(out, p.time_base);
    put(out, static_cast<std::uint8_t>(p.is_bigendian));
    put(out, static_cast<std::uint16_t>(p.encoding.size()));
    out += p.encoding;
    put(out, static_cast<std::uint16_t>(p.frame_id.size()));
    out += p.frame_id;
    put(out, static_cast<std::uint32_t>(p.events.size()));
    out.append(reinterpret_cast<const char*>(p.events.data()), p.events.size());
  }
  return out;
}

}  // namespace ebslam
