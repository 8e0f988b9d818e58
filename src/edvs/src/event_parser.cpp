// EventParser: construction, the byte-by-byte framing with resync of every format, and the
// counters. The absolute formats fed with host times are framed by evidence instead
// (event_framing.cpp).
#include "edvs/event_parser.h"
#include <algorithm>
#include <stdexcept>

namespace edvs {

namespace {

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
  if (!(config_.line_bytes_per_s >= 0) || !(config_.line_saturation > 0)) {
    throw std::invalid_argument(
        "ParserConfig::line_bytes_per_s must be >= 0 and line_saturation > 0");
  }
}

void EventParser::noteRead(std::int64_t host_us, std::size_t bytes) {
  if (!(config_.line_bytes_per_s > 0)) return;
  if (!reads_.empty() && host_us < reads_.back().host_us) host_us = reads_.back().host_us;
  reads_.push_back(Read{host_us, bytes});
  // The span starts at the newest read at least a window old (the bytes after it arrived after
  // it), or at the oldest read kept.
  const std::int64_t window = std::max<std::int64_t>(config_.live_window_us, 1000);
  std::size_t first = 0;
  while (first + 1 < reads_.size() && reads_[first + 1].host_us <= host_us - window) ++first;
  reads_.erase(reads_.begin(), reads_.begin() + static_cast<std::ptrdiff_t>(first));
  std::size_t total = 0;
  for (std::size_t i = 1; i < reads_.size(); ++i) total += reads_[i].bytes;
  const double span_s = static_cast<double>(host_us - reads_.front().host_us) * 1e-6;
  // Slack for a span of a few reads: a USB serial bridge hands over a packet at a time.
  constexpr double kSlackBytes = 512;
  if (reads_.size() >= 2 &&
      static_cast<double>(total) >
          config_.line_saturation * config_.line_bytes_per_s * span_s + kSlackBytes) {
    saturated_host_us_ = host_us;
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
  gap_after_residual_known_ = false;
  unwrapper_ =
      TimestampUnwrapper(wrapPeriodUs(config_.format), config_.format == EventFormat::kDelta);
  mode_decided_ = false;
  chain_mode_ = false;
  held_.clear();
  held_host_.clear();
  held_after_.clear();
  held_idle_.clear();
  previous_read_host_ = kNoHost;
  reads_.clear();
  saturated_host_us_ = kNoHost;
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

std::size_t EventParser::flush(ebslam::EventVector& out) {
  if (!chain_mode_) return 0;
  const std::size_t before = out.size();
  decideAbsolute(true, out);
  // A read found the line idle (or the stream ended): everything the device had queued has
  // arrived, so the newest event is live and the gap can be judged; unless the newest events
  // were still a backlog (the device clock ran faster than the host clock over them: a late
  // reader or a draining line), in which case the line only hiccuped in the middle of the
  // backlog, or the device began to hold its bytes right after it, or the stream ended: then
  // how late they are is not known, and a judgement forced by the wait counts the fewest
  // periods their arrival allows (a late reader, not a quiet device).
  bool newest_backlog = false;
  if (judging_gap_ && !staged_.empty()) {
    const Staged& newest = staged_.back();
    const Staged& m = staged_[live_from_].host_us <= newest.host_us - config_.live_window_us
                          ? staged_[live_from_]
                          : staged_.front();
    const std::int64_t device = newest.event.t_us - m.event.t_us;
    const std::int64_t host = newest.host_us - m.host_us;
    newest_backlog = device > host + host / 4 + 4000;
  }
  if (judging_gap_ && !staged_.empty() && idle_host_us_ && staged_.front().host_us != kNoHost &&
      gapHoldExpired(*idle_host_us_)) {
    resolveGap(out, true, true, *idle_host_us_, false, newest_backlog);  // waited long enough
  }
  // The line was saturated a moment ago: a backlog is draining and the writer paused in the
  // middle of it (a device or line releases its backlog in chunks).
  if (judging_gap_ && !staged_.empty() && idle_host_us_ &&
      saturatedSince(*idle_host_us_ - config_.live_window_us)) {
    return out.size() - before;
  }
  if (newest_backlog) return out.size() - before;
  // Nothing held ever ran faster than the host clock (a quiet gap, then live events): judged at
  // once. After a backlog, the count must come out the same at the next idle read too (a
  // writer that hiccups or is starved in the middle of a backlog also leaves the line idle).
  bool backlog = false;
  if (judging_gap_ && !staged_.empty()) {
    const std::int64_t device = staged_.back().event.t_us - staged_.front().event.t_us;
    const std::int64_t host = staged_.back().host_us - staged_.front().host_us;
    backlog = device > host + host / 4 + 4000;
  }
  resolveGap(out, false, true, 0, !backlog);
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
    if (host_us && size > 0) {
      previous_read_host_ = *host_us;
      noteRead(*host_us, size);
    }
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

}  // namespace edvs
