#include "edvs_driver/protocol.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace edvs_driver {

namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// DVS128 bias registers in the order of the eDVS !B<n> commands.
constexpr std::array<const char*, kNumBiases> kBiasNames = {"cas",     "injGnd", "reqPd", "puX",
                                                            "diffOff", "req",    "refr",  "puY",
                                                            "diffOn",  "diff",   "foll",  "pr"};

// Without host time, a device step larger than this is counted as implausible [us].
std::int64_t jumpLimitWithoutHostTime(EventFormat format) {
  switch (format) {
    case EventFormat::kAbs16:
    case EventFormat::kAbs24:
    case EventFormat::kAbs32:
      return wrapPeriodUs(format) / 4;
    case EventFormat::kDelta:
      return 1000000;  // 1 s without any event is rare at the sensor's noise rate
    case EventFormat::kNone:
      break;
  }
  return 0;
}

}  // namespace

const char* toString(EventFormat format) {
  switch (format) {
    case EventFormat::kNone:
      return "none";
    case EventFormat::kDelta:
      return "delta";
    case EventFormat::kAbs16:
      return "ts16";
    case EventFormat::kAbs24:
      return "ts24";
    case EventFormat::kAbs32:
      return "ts32";
  }
  return "?";
}

const char* toString(Firmware firmware) {
  return firmware == Firmware::kLegacy ? "legacy" : "current";
}

std::optional<Firmware> parseFirmware(std::string_view name) {
  const std::string n = lower(name);
  if (n == "current" || n == "new") return Firmware::kCurrent;
  if (n == "legacy" || n == "old") return Firmware::kLegacy;
  return std::nullopt;
}

std::optional<EventFormat> parseEventFormat(std::string_view text, Firmware firmware) {
  std::string t = lower(text);
  for (EventFormat f : kAllEventFormats) {
    if (t == toString(f)) return f;
  }
  if (!t.empty() && t[0] == '!') t.erase(0, 1);
  if (!t.empty() && t[0] == 'e') t.erase(0, 1);
  if (t.size() != 1 || t[0] < '0' || t[0] > '9') return std::nullopt;
  return formatFromCommandNumber(t[0] - '0', firmware);
}

int formatCommandNumber(EventFormat format, Firmware firmware) {
  const int current = static_cast<int>(format);  // enum order is the current numbering
  if (firmware == Firmware::kCurrent) return current;
  if (format == EventFormat::kDelta) {
    throw std::invalid_argument("legacy eDVS firmware has no delta-timestamp event format");
  }
  return format == EventFormat::kNone ? 0 : current - 1;
}

std::optional<EventFormat> formatFromCommandNumber(int n, Firmware firmware) {
  if (firmware == Firmware::kCurrent) {
    if (n < 0 || n > 4) return std::nullopt;
    return static_cast<EventFormat>(n);
  }
  if (n < 0 || n > 3) return std::nullopt;
  return n == 0 ? EventFormat::kNone : static_cast<EventFormat>(n + 1);
}

int timestampBytes(EventFormat format) {
  switch (format) {
    case EventFormat::kNone:
      return 0;
    case EventFormat::kDelta:
      return 4;
    case EventFormat::kAbs16:
      return 2;
    case EventFormat::kAbs24:
      return 3;
    case EventFormat::kAbs32:
      return 4;
  }
  return 0;
}

std::int64_t wrapPeriodUs(EventFormat format) {
  switch (format) {
    case EventFormat::kAbs16:
      return std::int64_t{1} << 16;
    case EventFormat::kAbs24:
      return std::int64_t{1} << 24;
    case EventFormat::kAbs32:
      return std::int64_t{1} << 32;
    case EventFormat::kNone:
    case EventFormat::kDelta:
      break;
  }
  return 0;
}

int minEventBytes(EventFormat format) {
  return format == EventFormat::kDelta ? 3 : 2 + timestampBytes(format);
}

const char* toString(SyncMode mode) {
  switch (mode) {
    case SyncMode::kNone:
      return "none";
    case SyncMode::kMaster:
      return "master";
    case SyncMode::kSlave:
      return "slave";
  }
  return "?";
}

std::optional<SyncMode> parseSyncMode(std::string_view name) {
  const std::string n = lower(name);
  if (n == "none" || n == "off" || n.empty()) return SyncMode::kNone;
  if (n == "master") return SyncMode::kMaster;
  if (n == "slave") return SyncMode::kSlave;
  return std::nullopt;
}

namespace commands {
std::string reset() { return "R\n"; }
std::string echoOff() { return "!U0\n"; }
std::string startStreaming() { return "E+\n"; }
std::string stopStreaming() { return "E-\n"; }
std::string eventFormat(EventFormat format, Firmware firmware) {
  return "!E" + std::to_string(formatCommandNumber(format, firmware)) + "\n";
}
std::string timestampReset() { return "!ET0\n"; }
std::string masterRun() { return "!ETM+\n"; }
std::string masterStop() { return "!ETM0\n"; }
std::string slave() { return "!ETS\n"; }
std::string help() { return "??\n"; }
std::string setBias(int index, std::int64_t value) {
  if (index < 0 || index >= kNumBiases) {
    throw std::invalid_argument("bias index " + std::to_string(index) + " outside 0.." +
                                std::to_string(kNumBiases - 1));
  }
  if (value < 0 || value > 0xFFFFFF) {
    throw std::invalid_argument("bias value " + std::to_string(value) +
                                " outside the 24-bit range 0..16777215");
  }
  return "!B" + std::to_string(index) + "=" + std::to_string(value) + "\n";
}
std::string flushBiases() { return "!BF\n"; }
}  // namespace commands

const char* biasName(int index) {
  if (index < 0 || index >= kNumBiases) {
    throw std::invalid_argument("bias index " + std::to_string(index) + " out of range");
  }
  return kBiasNames[static_cast<std::size_t>(index)];
}

std::optional<int> biasIndex(std::string_view name) {
  const std::string n = lower(name);
  for (int i = 0; i < kNumBiases; ++i) {
    if (lower(kBiasNames[static_cast<std::size_t>(i)]) == n) return i;
  }
  return std::nullopt;
}

bool containsBanner(std::string_view text) {
  return text.find("EDVS-4337") != std::string_view::npos ||
         text.find("meDVS128") != std::string_view::npos;
}

// ---------------------------------------------------------------------------------------------

void TimestampUnwrapper::reset() {
  started_ = false;
  last_raw_ = 0;
  last_unwrapped_ = 0;
  last_host_us_.reset();
  idle_since_last_ = false;
  wraps_ = 0;
  wraps_from_host_ = 0;
}

TimestampUnwrapper::Step TimestampUnwrapper::peek(std::int64_t raw_us,
                                                  std::optional<std::int64_t> host_us) const {
  Step s;
  if (host_us && last_host_us_)
    s.host_elapsed_us = std::max<std::int64_t>(0, *host_us - *last_host_us_);
  if (delta_) {
    s.step_us = std::max<std::int64_t>(0, raw_us);
    return s;
  }
  if (!started_) return s;
  s.step_us = raw_us - last_raw_;
  if (period_us_ > 0) {
    if (s.step_us < 0) {
      s.step_us += period_us_;
      s.wraps = 1;
    }
    // Whole periods that the raw values cannot show: the host clock says more time passed.
    if (idle_since_last_ && s.host_elapsed_us > period_us_ / 2) {
      // Rounded down with an eighth of a period of slack for read latency: a host-side stall
      // with events still queued somewhere must not invent a period; a missed one is worse
      // only by a period, and the next idle gap is judged afresh.
      const double missing =
          std::floor(static_cast<double>(s.host_elapsed_us - s.step_us + period_us_ / 8) /
                     static_cast<double>(period_us_));
      if (missing >= 1.0) {
        const auto k = static_cast<std::int64_t>(missing);
        s.step_us += k * period_us_;
        s.wraps += static_cast<std::uint64_t>(k);
        s.wraps_from_host = static_cast<std::uint64_t>(k);
      }
    }
  } else if (s.step_us < 0) {
    s.step_us = 0;  // a 64-bit device clock never runs backwards; clamp corrupt values
  }
  return s;
}

std::int64_t TimestampUnwrapper::commit(std::int64_t raw_us, std::optional<std::int64_t> host_us,
                                        const Step& step) {
  if (host_us) last_host_us_ = host_us;
  if (!started_ && !delta_) {
    last_unwrapped_ = raw_us;
  } else {
    last_unwrapped_ += std::max<std::int64_t>(0, step.step_us);
  }
  started_ = true;
  last_raw_ = raw_us;
  wraps_ += step.wraps;
  wraps_from_host_ += step.wraps_from_host;
  idle_since_last_ = false;
  return last_unwrapped_;
}

std::int64_t TimestampUnwrapper::unwrap(std::int64_t raw_us, std::optional<std::int64_t> host_us) {
  return commit(raw_us, host_us, peek(raw_us, host_us));
}

// ---------------------------------------------------------------------------------------------

EventParser::EventParser(const ParserConfig& config)
    : config_(config),
      unwrapper_(wrapPeriodUs(config.format), config.format == EventFormat::kDelta) {
  if (config_.on_bit != 0 && config_.on_bit != 1) {
    throw std::invalid_argument("ParserConfig::on_bit must be 0 or 1");
  }
  if (config_.jump_tolerance_us < 0) {
    throw std::invalid_argument("ParserConfig::jump_tolerance_us must be >= 0");
  }
  if (config_.max_consecutive_rejections < 0) {
    throw std::invalid_argument("ParserConfig::max_consecutive_rejections must be >= 0");
  }
}

void EventParser::restart() {
  unwrapper_ =
      TimestampUnwrapper(wrapPeriodUs(config_.format), config_.format == EventFormat::kDelta);
  pending_ = 0;
  ts_accum_ = 0;
  in_garbage_ = false;
  consecutive_rejections_ = 0;
  host_time_floor_ = 0;
  any_host_time_ = false;
}

void EventParser::restart(const ParserConfig& config) {
  ParserStats kept = stats_;
  *this = EventParser(config);
  stats_ = kept;
}

void EventParser::reset() {
  restart();
  stats_ = ParserStats{};
}

bool EventParser::emit(std::int64_t raw_time, std::optional<std::int64_t> host_us,
                       ebslam::EventVector& out) {
  ebslam::Event e;
  e.y = static_cast<std::uint16_t>(frame_[0] & 0x7F);
  e.x = static_cast<std::uint16_t>(frame_[1] & 0x7F);
  e.polarity = ((frame_[1] >> 7) & 1) == config_.on_bit;
  if (!config_.sensor.contains(e)) return false;
  if (config_.format == EventFormat::kNone) {
    // No device clock: host receive time, never running backwards.
    std::int64_t t = host_us ? *host_us : host_time_floor_;
    if (any_host_time_ && t < host_time_floor_) t = host_time_floor_;
    any_host_time_ = any_host_time_ || host_us.has_value();
    host_time_floor_ = t;
    e.t_us = t;
  } else {
    const bool first = !unwrapper_.started();
    TimestampUnwrapper::Step step = unwrapper_.peek(raw_time, host_us);
    if (!first) {
      const bool implausible = step.host_elapsed_us >= 0
                                   ? step.step_us > step.host_elapsed_us + config_.jump_tolerance_us
                                   : step.step_us > jumpLimitWithoutHostTime(config_.format);
      if (implausible) {
        ++stats_.implausible_jumps;
        if (config_.reject_implausible && step.host_elapsed_us >= 0) {
          if (consecutive_rejections_ < config_.max_consecutive_rejections) {
            ++consecutive_rejections_;
            ++stats_.rejected_events;
            return false;
          }
          // The device clock itself jumped: continue from the last accepted time.
          ++stats_.clock_jumps;
          step.step_us = step.host_elapsed_us;
          step.wraps = 0;
          step.wraps_from_host = 0;
        }
      }
    }
    consecutive_rejections_ = 0;
    e.t_us = unwrapper_.commit(raw_time, host_us, step);
  }
  stats_.wraps = unwrapper_.wraps();
  stats_.wraps_from_host_time = unwrapper_.wrapsFromHostTime();
  ++stats_.events;
  out.push_back(e);
  return true;
}

void EventParser::refeedAfterReject(std::optional<std::int64_t> host_us, ebslam::EventVector& out) {
  // The frame's first byte is dropped; the others may hold the true start of an event.
  std::uint8_t held[6];
  const std::size_t n = pending_ - 1;
  std::copy(frame_ + 1, frame_ + pending_, held);
  pending_ = 0;
  ++stats_.bytes_dropped;
  if (!in_garbage_) ++stats_.resyncs;
  in_garbage_ = true;
  stats_.bytes_in -= n;  // counted again by the nested feed
  feed(held, n, host_us, out);
}

std::size_t EventParser::feed(const std::uint8_t* data, std::size_t size,
                              std::optional<std::int64_t> host_us, ebslam::EventVector& out) {
  const std::size_t before = out.size();
  stats_.bytes_in += size;
  const EventFormat format = config_.format;
  const std::size_t ts_bytes = static_cast<std::size_t>(timestampBytes(format));
  const std::size_t fixed_size = 2 + ts_bytes;
  for (std::size_t i = 0; i < size; ++i) {
    const std::uint8_t b = data[i];
    if (pending_ == 0) {
      if ((b & 0x80) == 0) {
        // Not the start of an event: text, noise or the tail of a broken event.
        ++stats_.bytes_dropped;
        if (!in_garbage_) ++stats_.resyncs;
        in_garbage_ = true;
        continue;
      }
      frame_[0] = b;
      pending_ = 1;
      continue;
    }
    frame_[pending_++] = b;
    if (pending_ == 2) {
      ts_accum_ = 0;
      if (format == EventFormat::kNone) {
        if (emit(0, host_us, out)) {
          in_garbage_ = false;
          pending_ = 0;
        } else {
          refeedAfterReject(host_us, out);
        }
      }
      continue;
    }
    if (format == EventFormat::kDelta) {
      ts_accum_ = (ts_accum_ << 7) | (b & 0x7F);
      if (b & 0x80) {
        if (emit(static_cast<std::int64_t>(ts_accum_), host_us, out)) {
          in_garbage_ = false;
          pending_ = 0;
        } else {
          refeedAfterReject(host_us, out);
        }
      } else if (pending_ == 2 + ts_bytes) {
        // Four timestamp bytes without a terminator: the framing is lost.
        refeedAfterReject(host_us, out);
      }
      continue;
    }
    ts_accum_ = (ts_accum_ << 8) | b;
    if (pending_ == fixed_size) {
      if (emit(static_cast<std::int64_t>(ts_accum_), host_us, out)) {
        in_garbage_ = false;
        pending_ = 0;
      } else {
        refeedAfterReject(host_us, out);
      }
    }
  }
  return out.size() - before;
}

bool EventParser::formatSuspect(std::uint64_t min_events, double max_ratio) const {
  if (stats_.events < min_events) return false;
  const double drop_ratio =
      stats_.bytes_in > 0 ? static_cast<double>(stats_.bytes_dropped) / stats_.bytes_in : 0.0;
  const double jump_ratio = static_cast<double>(stats_.implausible_jumps) / stats_.events;
  return drop_ratio > max_ratio || jump_ratio > max_ratio;
}

FormatGuess guessEventFormat(const std::vector<std::uint8_t>& bytes) {
  FormatGuess best;
  bool have = false;
  for (EventFormat f : kAllEventFormats) {
    ParserConfig cfg;
    cfg.format = f;
    EventParser parser(cfg);
    ebslam::EventVector events;
    parser.feed(bytes, std::nullopt, events);
    const ParserStats& s = parser.stats();
    const double drop = s.bytes_in ? static_cast<double>(s.bytes_dropped) / s.bytes_in : 1.0;
    const double jump = s.events ? static_cast<double>(s.implausible_jumps) / s.events : 1.0;
    const double score = drop + jump;
    // Formats are tried in order of increasing timestamp information; "<=" hands a tie to the
    // richer format.
    if (s.events > 0 && (!have || score <= best.score + 1e-12)) {
      best = FormatGuess{f, score, s.events};
      have = true;
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------

void encodeEvent(const ebslam::Event& event, EventFormat format, std::int64_t previous_us,
                 int on_bit, std::vector<std::uint8_t>& out) {
  if (event.x > 127 || event.y > 127) {
    throw std::invalid_argument("eDVS event coordinates must be 0..127");
  }
  const int p = event.polarity ? on_bit : 1 - on_bit;
  out.push_back(static_cast<std::uint8_t>(0x80 | event.y));
  out.push_back(static_cast<std::uint8_t>((p << 7) | event.x));
  switch (format) {
    case EventFormat::kNone:
      return;
    case EventFormat::kDelta: {
      const std::int64_t delta = event.t_us - previous_us;
      if (delta < 0) throw std::invalid_argument("event times must not run backwards");
      if (delta >= (std::int64_t{1} << 28)) {
        throw std::invalid_argument("delta timestamp does not fit in 4 x 7 bits");
      }
      int groups = 1;
      while (groups < 4 && (delta >> (7 * groups)) != 0) ++groups;
      for (int g = groups - 1; g >= 0; --g) {
        auto byte = static_cast<std::uint8_t>((delta >> (7 * g)) & 0x7F);
        if (g == 0) byte |= 0x80;
        out.push_back(byte);
      }
      return;
    }
    case EventFormat::kAbs16:
    case EventFormat::kAbs24:
    case EventFormat::kAbs32: {
      const int n = timestampBytes(format);
      const std::uint64_t t = static_cast<std::uint64_t>(event.t_us);
      for (int k = n - 1; k >= 0; --k) out.push_back(static_cast<std::uint8_t>(t >> (8 * k)));
      return;
    }
  }
}

std::vector<std::uint8_t> encodeEvents(const ebslam::EventVector& events, EventFormat format,
                                       int on_bit) {
  std::vector<std::uint8_t> out;
  out.reserve(events.size() * static_cast<std::size_t>(2 + timestampBytes(format)));
  std::int64_t previous = events.empty() ? 0 : events.front().t_us;
  for (const ebslam::Event& e : events) {
    encodeEvent(e, format, previous, on_bit, out);
    previous = e.t_us;
  }
  return out;
}

}  // namespace edvs_driver
