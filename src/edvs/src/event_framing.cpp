// EventParser, absolute formats fed with host times: framing by evidence (chains of frames whose
// steps the host clock allows, competing explanations of the bytes compared over a look-ahead)
// and the gap judgement that adds the wrap periods a quiet gap hid (see the class comment).
#include <algorithm>
#include <cmath>
#include "edvs/event_parser.h"

namespace edvs {

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
  publishDecoded(held_[pos], held_[pos + 1], frameAt(pos), step, first, trusted, out);
}

EventParser::FrameRef EventParser::frameFromBytes(const std::size_t* index) const {
  const std::size_t size = static_cast<std::size_t>(minEventBytes(config_.format));
  FrameRef f;
  std::uint64_t raw = 0;
  for (std::size_t k = 2; k < size; ++k) raw = (raw << 8) | held_[index[k]];
  f.raw = static_cast<std::int64_t>(raw);
  f.host_us = held_host_[index[size - 1]];
  f.arrived_after_us = held_after_[index[0]];
  f.idle_epoch = held_idle_[index[size - 1]];
  return f;
}

EventParser::Link EventParser::linkFromLastRef(const FrameRef& f) const {
  Link l = link(last_, f);
  if (l.ok && f.host_us != kNoHost && have_latency_) {
    l.ok = last_time_us_ + l.step_us <= f.host_us - min_latency_us_ + config_.lead_tolerance_us;
  }
  return l;
}

bool EventParser::between(const FrameRef& f, const FrameRef& next) const {
  // f lies on the arc from the last published event to `next` (its chain successor): the two
  // steps add up to the direct one, without an extra wrap.
  const std::int64_t period = wrapPeriodUs(config_.format);
  auto fwd = [period](std::int64_t a, std::int64_t b) {
    const std::int64_t d = b - a;
    return d < 0 ? d + period : d;
  };
  return fwd(last_.raw, f.raw) + fwd(f.raw, next.raw) == fwd(last_.raw, next.raw);
}

int EventParser::decideRegion(std::size_t pos, std::size_t best, std::size_t next,
                              Repair& repair) const {
  // The bytes from pos to the candidate's end, and the candidate followed by one stray byte
  // before its confirmed successor at `next`, are read every way they can hold one event: a
  // frame at any offset up to the candidate; with exactly one byte too many, also the frame
  // with any one of its inner bytes removed (a garbage byte that landed inside the event).
  // Readings whose time lies between the last published event and the successor are
  // explanations. One: publish it. Several that differ: the garbage may sit inside the event,
  // so publishing any could invent one; none is published. This is what sparse streams pay
  // for: a stray byte next to the last time byte gives a reading whose time differs in the low
  // byte only, which neighbours more than 256 us apart cannot refute (both placements of the
  // byte are equally likely; publishing the unspliced reading was measured to invent events).
  const std::size_t frame = static_cast<std::size_t>(minEventBytes(config_.format));
  const FrameRef& successor = frames_[next];
  int found = 0;
  auto consider = [&](const std::size_t* index, std::size_t end) {
    if ((held_[index[0]] & 0x80) == 0) return;
    ebslam::Event e;
    e.y = static_cast<std::uint16_t>(held_[index[0]] & 0x7F);
    e.x = static_cast<std::uint16_t>(held_[index[1]] & 0x7F);
    if (!config_.sensor.contains(e)) return;
    const FrameRef f = frameFromBytes(index);
    if (!between(f, successor)) return;
    const Link l = linkFromLastRef(f);
    if (!l.ok) return;
    if (found > 0 && held_[index[0]] == held_[repair.index[0]] &&
        held_[index[1]] == held_[repair.index[1]] && f.raw == repair.frame.raw) {
      return;  // the same reading
    }
    ++found;
    if (found == 1) {
      std::copy(index, index + frame, repair.index);
      repair.frame = f;
      repair.link = l;
      repair.end = end;
    }
  };
  std::size_t index[8];
  for (std::size_t start = pos; start <= best; ++start) {
    for (std::size_t k = 0; k < frame; ++k) index[k] = start + k;
    consider(index, start + frame);
    if (found > 1) return found;
  }
  auto splices = [&](std::size_t from) {
    for (std::size_t drop = 1; drop < frame && found <= 1; ++drop) {
      std::size_t j = 0;
      for (std::size_t k = 0; k <= frame; ++k) {
        if (k != drop) index[j++] = from + k;
      }
      consider(index, from + frame + 1);
    }
  };
  if (best + frame - pos == frame + 1) splices(pos);
  if (found > 1) return found;
  if (next - best == frame + 1) splices(best);
  return found;
}

void EventParser::publishDecoded(std::uint8_t y_byte, std::uint8_t x_byte, const FrameRef& f,
                                 const Link& step, bool first, bool trusted,
                                 ebslam::EventVector& out) {
  ebslam::Event e;
  e.y = static_cast<std::uint16_t>(y_byte & 0x7F);
  e.x = static_cast<std::uint16_t>(x_byte & 0x7F);
  e.polarity = ((x_byte >> 7) & 1) == config_.on_bit;
  const std::int64_t period = wrapPeriodUs(config_.format);
  if (!first && !judging_gap_ && config_.infer_wraps_from_host_time &&
      f.idle_epoch != last_.idle_epoch && f.host_us != kNoHost && last_.host_us != kNoHost &&
      hostSpan(last_, f.host_us) + tolerance() >= period) {
    // The line was idle for long enough to hide a wrap period: hold the events until the
    // stream shows how much of the gap its own times explain.
    judging_gap_ = true;
    live_from_ = 0;
    gap_residual_known_ = false;
    gap_after_residual_known_ = false;
    gap_candidate_k_ = -1;
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
  stageOrEmit(e, f.host_us, f.arrived_after_us, out);
}

void EventParser::stageOrEmit(const ebslam::Event& e, std::int64_t host_us,
                              std::int64_t arrived_after_us, ebslam::EventVector& out) {
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
  if (arrived_after_us != kNoHost) {
    const std::int64_t after = arrived_after_us - gap_latency_us_ - e.t_us;
    if (!gap_after_residual_known_ || after > gap_after_residual_us_) {
      gap_after_residual_us_ = after;
    }
    gap_after_residual_known_ = true;
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
    // Live: the device clock advanced as fast as the host clock over the window, within the
    // jitter of reads. A backlog advances it faster (the line rate over the event rate); a
    // writer or line that hiccups, or that is starved, in the middle of one, slower.
    // The line saturated over the window: a backlog draining at the line rate, whose device
    // time advances as fast as the host clock only because the event rate is near the line's.
    const std::int64_t jitter = 2000 + host / 8;
    if (device <= host + jitter && device >= host - jitter && !saturatedSince(m.host_us) &&
        resolveGap(out, false, false, host_us, false)) {
      return;
    }
  }
  if (staged_.front().host_us != kNoHost && gapHoldExpired(host_us)) {
    resolveGap(out, true, false, host_us, false);
  }
}

bool EventParser::gapHoldExpired(std::int64_t now_us) const {
  const std::int64_t front = staged_.front().host_us;
  if (now_us - front >= config_.max_backlog_hold_us) return true;
  // Host time during which a backlog drained does not count: its events were not live.
  const std::int64_t from =
      saturated_host_us_ != kNoHost ? std::max(front, saturated_host_us_) : front;
  return now_us - from >= config_.max_gap_hold_us;
}

bool EventParser::resolveGap(ebslam::EventVector& out, bool force, bool idle, std::int64_t now_us,
                             bool at_once, bool fewest) {
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
    if (!force && gap_residual_us_ - k * period > config_.live_lag_us) {
      gap_candidate_k_ = -1;
      return false;
    }
  }
  if (!force) {
    // The same count twice: from two idle reads in a row, or from live checks at least
    // live_window_us apart (a backlog only looks live by chance now and then, and then
    // rarely with the same count).
    const bool confirmed =
        (idle && at_once) ||
        (gap_candidate_k_ == k &&
         (idle || gap_candidate_idle_ || now_us - gap_candidate_host_ >= config_.live_window_us));
    if (!confirmed) {
      if (gap_candidate_k_ != k) gap_candidate_host_ = now_us;
      gap_candidate_k_ = k;
      gap_candidate_idle_ = idle;
      return false;
    }
  }
  if (fewest && gap_after_residual_known_ && period > 0) {
    // Sent live, an event is at most live_lag_us older than its arrival after the read before
    // its own: at least this many periods.
    const std::int64_t x = gap_after_residual_us_ - config_.live_lag_us - config_.lead_tolerance_us;
    const std::int64_t least = x > 0 ? (x + period - 1) / period : 0;
    k = std::min(k, least);
  } else if (fewest) {
    k = 0;
  }
  gap_candidate_k_ = -1;
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
  gap_after_residual_known_ = false;
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
  chain_next_.assign(n, n);
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
    std::size_t best_next = n;
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
      best_next = q;
    }
    chain_length_[p] = 1 + best_length;
    chain_score_[p] = best_score;
    chain_open_[p] = best_open ? 1 : 0;
    chain_advance_[p] = best_advance;
    chain_end_host_[p] = best_end_host;
    chain_next_[p] = best_next;
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
    if (best != n && have_last_) {
      const std::size_t next = chain_next_[best];
      if (next != n) {
        Repair repair;
        const int found = decideRegion(pos, best, next, repair);
        if (found == 1) {
          const std::size_t extra = repair.end - pos - frame;
          if (extra > 0) {
            stats_.bytes_dropped += extra;
            if (!in_garbage_) ++stats_.resyncs;
          }
          publishDecoded(held_[repair.index[0]], held_[repair.index[1]], repair.frame, repair.link,
                         false, chain_length_[best] >= 2 * confirm, out);
          pos = repair.end;
        } else {
          countSkipped(pos, best + frame);
          in_garbage_ = true;
          pos = best + frame;
        }
        continue;
      }
    }
    if (best == n && c.best == n && c.unlinked != n) {
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

}  // namespace edvs
