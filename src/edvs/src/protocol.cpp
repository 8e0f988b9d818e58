#include "edvs/protocol.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace edvs {

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
  if (config_.confirm_events < 0) {
    throw std::invalid_argument("ParserConfig::confirm_events must be >= 0");
  }
  if (config_.max_gap_bytes < 0) {
    throw std::invalid_argument("ParserConfig::max_gap_bytes must be >= 0");
  }
}

std::uint64_t noiseCount(const ParserStats& stats) {
  return stats.bytes_dropped + stats.resyncs + stats.rejected_events + stats.implausible_jumps;
}

void EventParser::restart() {
  // Bytes still held are lost with the stream (e.g. an event cut by a disconnect), and so are
  // events held for a gap judgement (flush() first to keep them).
  stats_.bytes_dropped += pendingBytes();
  stats_.events -= staged_.size();
  stats_.bytes_dropped += staged_.size() * static_cast<std::size_t>(minEventBytes(config_.format));
  staged_.clear();
  judging_gap_ = false;
  live_from_ = 0;
  gap_residual_known_ = false;
  unwrapper_ =
      TimestampUnwrapper(wrapPeriodUs(config_.format), config_.format == EventFormat::kDelta);
  mode_decided_ = false;
  chain_mode_ = false;
  held_.clear();
  held_host_.clear();
  held_after_.clear();
  held_idle_.clear();
  previous_read_host_ = kNoHost;
  have_last_ = false;
  have_latency_ = false;
  behind_debt_us_ = 0;
  last_ = FrameRef{};
  last_time_us_ = 0;
  pending_ = 0;
  ts_accum_ = 0;
  in_garbage_ = false;
  consecutive_rejections_ = 0;
  host_time_floor_ = 0;
  any_host_time_ = false;
}

void EventParser::restart(const ParserConfig& config) {
  restart();
  ParserStats kept = stats_;
  *this = EventParser(config);
  stats_ = kept;
}

void EventParser::reset() {
  restart();
  stats_ = ParserStats{};
}

std::size_t EventParser::pendingBytes() const { return chain_mode_ ? held_.size() : pending_; }

bool EventParser::isAbsolute() const { return wrapPeriodUs(config_.format) > 0; }

bool EventParser::frameValid(std::size_t pos) const {
  if ((held_[pos] & 0x80) == 0) return false;
  ebslam::Event e;
  e.y = static_cast<std::uint16_t>(held_[pos] & 0x7F);
  e.x = static_cast<std::uint16_t>(held_[pos + 1] & 0x7F);
  return config_.sensor.contains(e);
}

EventParser::FrameRef EventParser::frameAt(std::size_t pos) const {
  const std::size_t size = static_cast<std::size_t>(minEventBytes(config_.format));
  FrameRef f;
  std::uint64_t raw = 0;
  for (std::size_t k = 2; k < size; ++k) raw = (raw << 8) | held_[pos + k];
  f.raw = static_cast<std::int64_t>(raw);
  f.host_us = held_host_[pos + size - 1];  // the read that completed the frame
  f.arrived_after_us = held_after_[pos];
  f.idle_epoch = held_idle_[pos + size - 1];
  return f;
}

EventParser::Link EventParser::link(const FrameRef& a, const FrameRef& b) const {
  const std::int64_t period = wrapPeriodUs(config_.format);
  Link l;
  std::int64_t step = b.raw - a.raw;
  if (step < 0) {
    step += period;
    l.wraps = 1;
  }
  const std::int64_t host_elapsed = a.host_us != kNoHost && b.host_us != kNoHost
                                        ? std::max<std::int64_t>(0, b.host_us - a.host_us)
                                        : -1;
  // No whole periods from host time here: an idle line followed by a burst may be a quiet
  // device (periods hidden) or a stalled line delivering its backlog (the burst's own times
  // carry the gap). publishFrame() judges that once the stream is live again.
  l.step_us = step;
  // A step longer than the host clock allows is a framing error, not time.
  // Without host time (a capture) only the order is known: a step of half a period or more
  // could as well be a step back.
  l.ok = host_elapsed >= 0 ? step <= hostSpan(a, b.host_us) + tolerance() : step < period / 2;
  return l;
}

std::int64_t EventParser::hostSpan(const FrameRef& a, std::int64_t later_host_us) {
  // Device time from a to a later frame is at most the host time from a's arrival to the later
  // read. a arrived after the read before its own: a reader that woke late and drained a
  // backlog of many milliseconds in one read holds device time that its read times do not show.
  const std::int64_t from = a.arrived_after_us != kNoHost ? a.arrived_after_us : a.host_us;
  return std::max<std::int64_t>(0, later_host_us - from);
}

std::int64_t EventParser::tolerance() const {
  // Host read scheduling and USB latency; below a quarter period, so that two garbage steps
  // can never add up to a whole period between two reads.
  return std::min(config_.jump_tolerance_us, wrapPeriodUs(config_.format) / 4);
}

EventParser::Link EventParser::linkFromLast(std::size_t pos) const {
  const FrameRef& f = frames_[pos];
  Link l = link(last_, f);
  // The device clock never runs ahead of the host clock: an event's time is at most the host
  // time of its read minus the smallest latency seen so far (plus lead_tolerance_us). This
  // bounds the sum of steps that each looked plausible.
  if (l.ok && f.host_us != kNoHost && have_latency_) {
    l.ok = last_time_us_ + l.step_us <= f.host_us - min_latency_us_ + config_.lead_tolerance_us;
  }
  return l;
}

void EventParser::publishFrame(std::size_t pos, const Link& step, bool first, bool trusted,
                               ebslam::EventVector& out) {
  const FrameRef f = frameAt(pos);
  ebslam::Event e;
  e.y = static_cast<std::uint16_t>(held_[pos] & 0x7F);
  e.x = static_cast<std::uint16_t>(held_[pos + 1] & 0x7F);
  e.polarity = ((held_[pos + 1] >> 7) & 1) == config_.on_bit;
  const std::int64_t period = wrapPeriodUs(config_.format);
  if (!first && !judging_gap_ && config_.infer_wraps_from_host_time &&
      f.idle_epoch != last_.idle_epoch && f.host_us != kNoHost && last_.host_us != kNoHost &&
      hostSpan(last_, f.host_us) + tolerance() >= period) {
    // The line was idle for long enough to hide a wrap period: hold the events until the
    // stream shows how much of the gap its own times explain.
    judging_gap_ = true;
    live_from_ = 0;
    gap_residual_known_ = false;
    // Latency of a live event: the floor, or before one is known the last event's (an upper
    // bound: fewer periods are then inferred, never more).
    gap_latency_us_ = have_latency_ ? min_latency_us_ : last_.host_us - last_time_us_;
    ++stats_.gaps_judged;
  }
  if (first) {
    last_time_us_ = f.raw;
  } else {
    std::int64_t advance = std::max<std::int64_t>(0, step.step_us);
    const std::int64_t repaid = std::min(advance, behind_debt_us_);
    behind_debt_us_ -= repaid;
    last_time_us_ += advance - repaid;
    stats_.wraps += step.wraps;
    stats_.wraps_from_host_time += step.wraps_from_host;
  }
  last_ = f;
  have_last_ = true;
  in_garbage_ = false;
  if (f.host_us != kNoHost && trusted) {
    // Only events with a long chain behind them teach the latency floor: a garbage event
    // that slipped through must not loosen the bound for the next one.
    const std::int64_t latency = f.host_us - last_time_us_;
    if (!have_latency_ || latency < min_latency_us_) min_latency_us_ = latency;
    have_latency_ = true;
  }
  e.t_us = last_time_us_;
  ++stats_.events;
  stageOrEmit(e, f.host_us, out);
}

void EventParser::stageOrEmit(const ebslam::Event& e, std::int64_t host_us,
                              ebslam::EventVector& out) {
  if (!judging_gap_) {
    out.push_back(e);
    return;
  }
  staged_.push_back(Staged{e, host_us});
  if (host_us == kNoHost) return;
  {
    // How far the host clock (less the latency) is ahead of the stream's own time: whole
    // periods the gap hid, plus the backlog still to come, plus this read's latency jitter.
    const std::int64_t residual = host_us - gap_latency_us_ - e.t_us;
    if (!gap_residual_known_ || residual < gap_residual_us_) gap_residual_us_ = residual;
    gap_residual_known_ = true;
  }
  // Live again: over the last live_window_us of host time the device clock advanced no faster
  // than the host clock (a backlog advances it at the line rate over the event rate).
  const std::int64_t window = config_.live_window_us;
  while (live_from_ + 1 < staged_.size() && staged_[live_from_ + 1].host_us != kNoHost &&
         staged_[live_from_ + 1].host_us <= host_us - window) {
    ++live_from_;
  }
  const Staged& m = staged_[live_from_];
  if (m.host_us != kNoHost && m.host_us <= host_us - window) {
    const std::int64_t device = e.t_us - m.event.t_us;
    const std::int64_t host = host_us - m.host_us;
    // The lower bound: a writer or line that hiccups in the middle of a backlog delivers
    // nothing for a while, which is not live either.
    if (device <= host + host / 4 + 2000 && device >= host / 2 - 2000 && resolveGap(out, false)) {
      return;
    }
  }
  if (staged_.front().host_us != kNoHost &&
      host_us - staged_.front().host_us >= config_.max_gap_hold_us) {
    resolveGap(out, true);
  }
}

bool EventParser::resolveGap(ebslam::EventVector& out, bool force) {
  if (!judging_gap_) return true;
  const std::int64_t period = wrapPeriodUs(config_.format);
  // The least residual belongs to the liveliest event: k periods plus its latency above the
  // floor, which is at least -lead_tolerance_us (the device clock is never ahead of the host
  // clock) and, for a live event, at most live_lag_us.
  std::int64_t k = 0;
  if (gap_residual_known_ && period > 0) {
    const std::int64_t x = gap_residual_us_ + config_.lead_tolerance_us + 1000;
    k = x > 0 ? x / period : 0;
    // A live event is late by its latency jitter only; more means the newest events are still
    // a backlog that only looked live (a writer that hiccuped): wait for better evidence.
    if (!force && gap_residual_us_ - k * period > config_.live_lag_us) return false;
  }
  const std::int64_t add = k * period;
  for (const Staged& s : staged_) {
    ebslam::Event e = s.event;
    e.t_us += add;
    out.push_back(e);
  }
  last_time_us_ += add;
  stats_.wraps += static_cast<std::uint64_t>(k);
  stats_.wraps_from_host_time += static_cast<std::uint64_t>(k);
  staged_.clear();
  judging_gap_ = false;
  live_from_ = 0;
  gap_residual_known_ = false;
  return true;
}

void EventParser::buildChains() {
  const std::size_t n = held_.size();
  const std::size_t frame = static_cast<std::size_t>(minEventBytes(config_.format));
  const std::size_t gap = static_cast<std::size_t>(config_.max_gap_bytes);
  // Longest chain of plausible steps starting at each position (backwards over the bytes).
  // A chain's whole advance must fit the host time it spans too (a frame misaligned by a byte
  // can make a chain of small forward steps that runs far faster than the clock).
  chain_length_.assign(n, 0);
  chain_score_.assign(n, 0);
  chain_open_.assign(n, 0);
  chain_advance_.assign(n, 0);
  chain_end_host_.assign(n, kNoHost);
  const auto frame_score = static_cast<std::int64_t>(frame);
  // Each complete frame decoded once.
  frames_.resize(n);
  for (std::size_t p = 0; p + frame <= n; ++p) {
    if (frameValid(p)) frames_[p] = frameAt(p);
  }
  for (std::size_t p = n - frame + 1; p-- > 0;) {
    if (!frameValid(p)) continue;
    const FrameRef& a = frames_[p];
    // Score of a chain: bytes its frames explain minus bytes it skips. True events lie back
    // to back, so their chain skips only the garbage; a chain of frames that garbage or a
    // misalignment made up has to skip bytes at nearly every step.
    std::int64_t best_score = frame_score;
    int best_length = 0;
    bool best_open = p + frame + gap + frame > n;  // no successor yet, but one may still come
    std::int64_t best_advance = 0;
    std::int64_t best_end_host = a.host_us;
    // A backlog read (the line stalled, or the reader was descheduled) holds device time that
    // its read times do not show: a frame as far behind the host clock as the stream says may
    // be followed by that much more device time (less host time) within one read.
    std::int64_t lag = 0;
    if (have_last_ && have_latency_ && a.host_us != kNoHost) {
      std::int64_t step = a.raw - last_.raw;
      if (step < 0) step += wrapPeriodUs(config_.format);
      lag = std::max<std::int64_t>(
          0, a.host_us - min_latency_us_ + config_.lead_tolerance_us - (last_time_us_ + step));
    }
    const std::size_t last_q = std::min(p + frame + gap, n - frame);
    for (std::size_t q = p + frame; q <= last_q && q + frame <= n; ++q) {
      if (chain_length_[q] == 0) continue;
      const std::int64_t score =
          frame_score + chain_score_[q] - static_cast<std::int64_t>(q - p - frame);
      if (score <= best_score) continue;
      const Link l = link(a, frames_[q]);
      if (!l.ok) continue;
      const std::int64_t advance = l.step_us + chain_advance_[q];
      if (a.host_us != kNoHost && chain_end_host_[q] != kNoHost &&
          advance > hostSpan(a, chain_end_host_[q]) + tolerance() + lag) {
        continue;
      }
      best_score = score;
      best_length = chain_length_[q];
      best_open = chain_open_[q] != 0;
      best_advance = advance;
      best_end_host = chain_end_host_[q];
    }
    chain_length_[p] = 1 + best_length;
    chain_score_[p] = best_score;
    chain_open_[p] = best_open ? 1 : 0;
    chain_advance_[p] = best_advance;
    chain_end_host_[p] = best_end_host;
  }
}

EventParser::Candidates EventParser::findCandidates(std::size_t pos,
                                                    std::size_t window_last) const {
  const std::size_t n = held_.size();
  Candidates c{n, n, n, 0, 0, Link{}};
  for (std::size_t s = pos; s <= window_last; ++s) {
    if (chain_length_[s] == 0) continue;
    // Bytes skipped to reach a candidate count against it like bytes skipped in a chain.
    const std::int64_t value = chain_score_[s] - static_cast<std::int64_t>(s - pos);
    Link l;
    if (have_last_) {
      l = linkFromLast(s);
      if (!l.ok) {
        if (c.unlinked == n || value > c.unlinked_value) {
          c.unlinked = s;
          c.unlinked_value = value;
        }
        continue;
      }
    }
    if (c.best == n || value > c.best_value) {
      c.best = s;
      c.best_value = value;
      c.best_link = l;
      c.tied = n;
    } else if (value == c.best_value) {
      c.tied = s;
    }
  }
  return c;
}

EventParser::Link EventParser::clockJumpLink(std::size_t pos) {
  ++stats_.clock_jumps;
  ++stats_.implausible_jumps;
  const FrameRef f = frameAt(pos);
  Link l;
  l.ok = true;
  const std::int64_t period = wrapPeriodUs(config_.format);
  const std::int64_t behind = ((last_.raw - f.raw) % period + period) % period;
  if (behind < tolerance()) {
    // Slightly behind the last published event, which ran ahead: hold the time until the
    // device clock has caught up, never stepping back.
    l.step_us = 0;
    behind_debt_us_ += behind;
  } else {
    l.step_us = f.host_us != kNoHost && last_.host_us != kNoHost
                    ? std::max<std::int64_t>(0, f.host_us - last_.host_us)
                    : 0;
  }
  have_latency_ = false;
  return l;
}

void EventParser::countSkipped(std::size_t from, std::size_t to) {
  for (std::size_t s = from; s < to; ++s) {
    if (chain_length_[s] > 0) {
      ++stats_.rejected_events;
      if (have_last_ && !linkFromLast(s).ok) ++stats_.implausible_jumps;
    }
  }
  if (to > from) {
    stats_.bytes_dropped += to - from;
    if (!in_garbage_) ++stats_.resyncs;
  }
}

void EventParser::decideAbsolute(bool flushing, ebslam::EventVector& out) {
  const std::size_t n = held_.size();
  const std::size_t frame = static_cast<std::size_t>(minEventBytes(config_.format));
  const std::size_t gap = static_cast<std::size_t>(config_.max_gap_bytes);
  if (n < frame) return;
  buildChains();
  const int confirm = config_.confirm_events + 1;
  const std::size_t lookahead_bytes =
      static_cast<std::size_t>(config_.lookahead_events) * frame + gap;
  const int jump_chain = std::max(config_.max_consecutive_rejections, confirm);
  std::size_t pos = 0;
  while (pos + frame <= n) {
    // Candidates: frames starting within one frame plus the gap allowance of the position.
    const std::size_t window_last = std::min(pos + frame + gap, n - frame);
    const bool window_complete = pos + frame + gap + frame <= n;
    Candidates c = findCandidates(pos, window_last);
    std::size_t best = c.best;
    bool clock_jump = false;
    if (best != n && !flushing) {
      if (chain_length_[best] < confirm && chain_open_[best]) break;
      // Enough bytes behind the candidate for chains to be compared: a chain of frames
      // misaligned by a byte can run on for a while, the true one for ever.
      const bool enough_bytes = n - best >= lookahead_bytes;
      const std::int64_t newest_host = held_host_[n - 1];
      const std::int64_t head_host = held_host_[best + frame - 1];
      const bool old_enough = newest_host != kNoHost && head_host != kNoHost &&
                              newest_host - head_host >= config_.hold_us;
      if (!enough_bytes && !old_enough) break;
    }
    if (best != n) {
      if (c.tied != n) {
        // Two frames explain the bytes equally well (garbage whose time fell between two true
        // events): publishing either could invent an event, so neither is.
        for (std::size_t s = pos; s <= c.tied; ++s) {
          if (chain_length_[s] > 0) ++stats_.rejected_events;
        }
        stats_.bytes_dropped += c.tied + 1 - pos;
        if (!in_garbage_) ++stats_.resyncs;
        in_garbage_ = true;
        pos = c.tied + 1;
        continue;
      }
      if (!have_last_ && chain_length_[best] < confirm && !flushing) {
        // The first event of a stream needs the full chain: nothing else vouches for it.
        if (!window_complete) break;
        best = n;
      }
    }
    if (best == n && c.unlinked != n) {
      // Nothing follows the last event plausibly: a long self-consistent chain means the device
      // clock itself jumped (reset, or a misjudged last event); continue monotonically.
      if (chain_length_[c.unlinked] >= jump_chain) {
        best = c.unlinked;
        clock_jump = true;
      } else if (chain_open_[c.unlinked] && !flushing) {
        break;  // not enough evidence yet
      }
    }
    if (best == n && !window_complete && !flushing) break;
    if (best == n) {
      // Nothing usable starts here: drop one byte.
      if (chain_length_[pos] > 0) ++stats_.rejected_events;
      if (chain_length_[pos] > 0 && have_last_ && !linkFromLast(pos).ok) {
        ++stats_.implausible_jumps;
      }
      ++stats_.bytes_dropped;
      if (!in_garbage_) ++stats_.resyncs;
      in_garbage_ = true;
      ++pos;
      continue;
    }
    countSkipped(pos, best);
    const Link step = clock_jump ? clockJumpLink(best) : c.best_link;
    publishFrame(best, step, !have_last_, chain_length_[best] >= 2 * confirm, out);
    pos = best + frame;
  }
  held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(pos));
  held_host_.erase(held_host_.begin(), held_host_.begin() + static_cast<std::ptrdiff_t>(pos));
  held_after_.erase(held_after_.begin(), held_after_.begin() + static_cast<std::ptrdiff_t>(pos));
  held_idle_.erase(held_idle_.begin(), held_idle_.begin() + static_cast<std::ptrdiff_t>(pos));
}

std::size_t EventParser::flush(ebslam::EventVector& out) {
  if (!chain_mode_) return 0;
  const std::size_t before = out.size();
  decideAbsolute(true, out);
  // A read found the line idle (or the stream ended): everything the device had queued has
  // arrived, so the newest event is live and the gap can be judged; unless the newest events
  // were still a backlog (the device clock ran faster than the host clock over them), in which
  // case the line only hiccuped in the middle of the backlog.
  if (judging_gap_ && !staged_.empty()) {
    const Staged& newest = staged_.back();
    const Staged& m = staged_[live_from_].host_us <= newest.host_us - config_.live_window_us
                          ? staged_[live_from_]
                          : staged_.front();
    const std::int64_t device = newest.event.t_us - m.event.t_us;
    const std::int64_t host = newest.host_us - m.host_us;
    if (device > host + host / 4 + 4000) return out.size() - before;
  }
  resolveGap(out, false);
  return out.size() - before;
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
  if (!mode_decided_ && size > 0) {
    // Framing by evidence needs the host clock; a capture without read times keeps the
    // byte-by-byte framing.
    chain_mode_ = isAbsolute() && host_us.has_value();
    mode_decided_ = true;
  }
  if (chain_mode_) {
    held_.insert(held_.end(), data, data + size);
    held_host_.insert(held_host_.end(), size, host_us ? *host_us : kNoHost);
    held_after_.insert(held_after_.end(), size, previous_read_host_);
    if (host_us && size > 0) previous_read_host_ = *host_us;
    held_idle_.insert(held_idle_.end(), size, idle_epoch_);
    decideAbsolute(false, out);
    return out.size() - before;
  }
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
  // Enough evidence: the events, or (a format that yields few events) the bytes of as many.
  if (stats_.events < min_events && stats_.bytes_in < 8 * min_events) return false;
  const double drop_ratio =
      stats_.bytes_in > 0 ? static_cast<double>(stats_.bytes_dropped) / stats_.bytes_in : 0.0;
  const double jump_ratio =
      stats_.events > 0 ? static_cast<double>(stats_.implausible_jumps) / stats_.events : 0.0;
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
    parser.flush(events);
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

}  // namespace edvs
