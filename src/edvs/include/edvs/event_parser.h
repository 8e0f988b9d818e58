#pragma once

// Incremental parser of the eDVS4337 event stream: framing with resync, 64-bit timestamp
// unwrapping, framing by evidence for the absolute formats. ROS-free; depends only on
// ebslam/events/event.h. The wire layout: edvs/event_format.h.

#include <climits>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ebslam/events/event.h"
#include "edvs/event_format.h"
#include "edvs/timestamp_unwrapper.h"

namespace edvs {

/// Parser settings.
struct ParserConfig {
  EventFormat format = EventFormat::kAbs16;
  /// Value of the p bit that means ON (see the polarity convention in edvs/event_format.h).
  int on_bit = 1;
  /// Sensor size [pixels]: events outside are dropped as corrupt (the eDVS is 128 x 128, so
  /// with 7-bit coordinates nothing can fall outside unless a smaller size is configured).
  ebslam::SensorSize sensor{128, 128};
  /// A device time advance this much larger than the host time that passed between the
  /// reads that delivered two consecutive events is counted as an implausible jump [us]
  /// (a symptom of a wrong format). Covers host read scheduling and USB latency.
  std::int64_t jump_tolerance_us = 50000;
  /// When host time is known, an event with an implausible jump is treated as a framing error
  /// (garbage that happens to look like an event, or a mis-aligned frame): its first byte is
  /// dropped and parsing resumes at the next byte. After this many rejections in a row the
  /// device clock is taken to have jumped (e.g. a timestamp reset) and the stream is accepted
  /// again, continuing monotonically from the last accepted time.
  bool reject_implausible = true;
  /// Add wrap periods that a quiet gap hid, judged from host time after an idle read (see
  /// TimestampUnwrapper). Absolute formats fed with host times (framing by evidence) count only
  /// the part of the gap that the events after it do not explain: a stalled line or a
  /// descheduled reader delivers a backlog whose own timestamps carry the device time that
  /// passed (see EventParser).
  bool infer_wraps_from_host_time = true;
  /// Absolute formats: the events after a gap that may hide wrap periods are held until the
  /// stream is live again: a read found the line idle, or over the last live_window_us of host
  /// time the device clock advanced as fast as the host clock (within 2 ms plus an eighth).
  std::int64_t live_window_us = 10000;
  /// ...and the liveliest of them is at most this much later than the latency floor, beyond
  /// whole periods [us] (the jitter of a live event's latency).
  std::int64_t live_lag_us = 16000;
  /// ...or until they span this much host time during which the line was not saturated (see
  /// line_bytes_per_s): then the evidence there is decides [us].
  std::int64_t max_gap_hold_us = 1000000;
  /// Rate the line carries [bytes/s] (a serial line at B baud, 8N1: B / 10); 0 = unknown.
  /// Bytes arriving at line_saturation of this rate or faster over live_window_us of host time
  /// are a backlog draining (the device held its bytes, the line stalled, or the reader was
  /// late): the events they carry are not live, so a gap judgement neither counts periods from
  /// them nor ends on them; the host time they arrive over says nothing about device time.
  /// A live stream sends at the sensor's event rate, below the line rate.
  double line_bytes_per_s = 0.0;
  double line_saturation = 0.8;
  /// A backlog still draining after this much host time is judged with the evidence there is
  /// (bounds the memory of the events held) [us].
  std::int64_t max_backlog_hold_us = 60000000;
  /// Absolute-timestamp formats (E2..E4): an unconfirmed stream (no event published yet, or
  /// every frame after the last published event refused) is taken to have a new clock (device
  /// reset) once this many consecutive frames agree with each other; time continues
  /// monotonically from the last published event.
  int max_consecutive_rejections = 8;
  /// Absolute-timestamp formats: an event is published only once this many following events
  /// agree with it (forward steps the host clock allows), or the line went idle (flush()).
  /// Garbage that happens to look like an event almost never has such a chain behind it.
  int confirm_events = 3;
  /// Absolute-timestamp formats: most garbage bytes between two events of one confirming chain.
  int max_gap_bytes = 16;
  /// Absolute-timestamp formats: an event is decided once this many events' worth of bytes
  /// follow it, or its bytes are hold_us old (host time of the newest read), or flush(). The
  /// competing explanations of the bytes are compared over that horizon: a chain of frames
  /// misaligned by one byte can look plausible for ~10 events at high rates (E2), the true
  /// chain goes on.
  int lookahead_events = 32;
  /// Absolute-timestamp formats: an event may be this much later than the host time of its
  /// read minus the smallest latency (host minus device time) seen so far [us]; covers the
  /// jitter of that floor. Larger leads are framing errors.
  std::int64_t lead_tolerance_us = 2000;
  std::int64_t hold_us = 2000;
};

/// Counters of one parser. All counts since construction or reset().
struct ParserStats {
  std::uint64_t bytes_in = 0;              ///< bytes fed
  std::uint64_t bytes_dropped = 0;         ///< bytes discarded while resynchronising
  std::uint64_t resyncs = 0;               ///< times the parser lost and regained the event framing
  std::uint64_t events = 0;                ///< events emitted
  std::uint64_t wraps = 0;                 ///< timestamp wrap-arounds unwrapped
  std::uint64_t wraps_from_host_time = 0;  ///< extra whole wrap periods inferred from host time
  std::uint64_t implausible_jumps = 0;     ///< see ParserConfig::jump_tolerance_us
  std::uint64_t rejected_events = 0;       ///< event-like frames refused as framing errors
  std::uint64_t clock_jumps = 0;           ///< device clock discontinuities accepted
  /// Gaps (an idle line, host time long enough to hide a wrap period) after which the events
  /// were held until the stream was live again to count the hidden periods.
  std::uint64_t gaps_judged = 0;
};

/// Sum of the counters that only line noise or a wrong format raise (dropped bytes, resyncs,
/// rejected events, implausible jumps): a change means garbage arrived.
std::uint64_t noiseCount(const ParserStats& stats);

/// Incremental parser of the event stream. feed() takes each read's bytes with its host time;
/// an event split across reads waits for its last byte; bytes that cannot start an event are
/// dropped and counted. Absolute formats (E2-E4) with host times are framed by evidence: a frame
/// becomes an event only when its step from the last event fits the host time (from the read
/// before its own), it is not ahead of the host clock, and a chain of frames follows it; of
/// competing explanations the one explaining most bytes wins, ties publish nothing. The rules and
/// their measured guarantee: edvs_driver/README.md, "Event formats and robustness".
class EventParser {
 public:
  explicit EventParser(const ParserConfig& config = {});

  /// Parses `size` bytes, appending complete events to `out`. host_us is the host time [us]
  /// at which these bytes were read (any monotonic clock), or std::nullopt. Returns the
  /// number of events appended.
  std::size_t feed(const std::uint8_t* data, std::size_t size, std::optional<std::int64_t> host_us,
                   ebslam::EventVector& out);
  std::size_t feed(const std::vector<std::uint8_t>& bytes, std::optional<std::int64_t> host_us,
                   ebslam::EventVector& out) {
    return feed(bytes.data(), bytes.size(), host_us, out);
  }

  /// Decides the events held back for confirmation with the evidence there is and appends the
  /// ones that follow the last published event plausibly (call when the line went idle or the
  /// stream ended). An incomplete event stays pending. Returns the number of events appended.
  std::size_t flush(ebslam::EventVector& out);

  /// Forgets a partial event and the timestamp history (e.g. after a reconnect or a format
  /// change); the bytes still held (an event cut by a disconnect, or events not yet confirmed:
  /// call flush() first to keep those) are counted as dropped; counters are kept. Pass a config
  /// to change the format.
  void restart();
  void restart(const ParserConfig& config);
  /// Clears the counters as well.
  void reset();

  const ParserConfig& config() const { return config_; }
  const ParserStats& stats() const { return stats_; }
  /// Bytes of an incomplete event held back, waiting for the next feed().
  std::size_t pendingBytes() const;
  /// Tells the parser that a read returned no bytes (the line was idle); see TimestampUnwrapper.
  /// host_us: host time of the idle read, if known (lets flush() end a gap judgement that has
  /// waited max_gap_hold_us).
  void noteIdle(std::optional<std::int64_t> host_us = std::nullopt) {
    if (host_us) {
      idle_host_us_ = *host_us;
      noteRead(*host_us, 0);
    }
    if (!config_.infer_wraps_from_host_time) return;
    unwrapper_.noteIdle();
    ++idle_epoch_;
  }

  /// True when the stream does not look like `config().format`: after at least
  /// `min_events` events, more than `max_ratio` of the bytes were dropped or of the events
  /// had implausible timestamp jumps.
  bool formatSuspect(std::uint64_t min_events = 200, double max_ratio = 0.05) const;

 private:
  // Emits the complete event in frame_; returns false if it was rejected (framing error).
  bool emit(std::int64_t raw_time, std::optional<std::int64_t> host_us, ebslam::EventVector& out);
  // Drops the first byte of the rejected frame and parses the rest again.
  void refeedAfterReject(std::optional<std::int64_t> host_us, ebslam::EventVector& out);

  // Absolute-timestamp formats: framing by chains of plausible steps (see the class comment).
  struct Link {
    bool ok = false;
    std::int64_t step_us = 0;
    std::uint64_t wraps = 0;
    std::uint64_t wraps_from_host = 0;
  };
  struct FrameRef {
    std::int64_t raw = 0;
    std::int64_t host_us = 0;  // kNoHost if unknown
    // Host time of the read before the one that brought the frame's first byte: the byte
    // arrived after it (reads drain the line). kNoHost for the first read.
    std::int64_t arrived_after_us = 0;
    std::uint32_t idle_epoch = 0;
  };
  static constexpr std::int64_t kNoHost = INT64_MIN;
  bool isAbsolute() const;
  bool frameValid(std::size_t pos) const;
  FrameRef frameAt(std::size_t pos) const;
  Link link(const FrameRef& a, const FrameRef& b) const;
  Link linkFromLast(std::size_t pos) const;  // pos: a valid frame decoded into frames_
  std::int64_t tolerance() const;
  static std::int64_t hostSpan(const FrameRef& a, std::int64_t later_host_us);
  void publishFrame(std::size_t pos, const Link& step, bool first, bool trusted,
                    ebslam::EventVector& out);
  void publishDecoded(std::uint8_t y_byte, std::uint8_t x_byte, const FrameRef& f, const Link& step,
                      bool first, bool trusted, ebslam::EventVector& out);
  // A frame read from held bytes at the given indices (frame size of them).
  FrameRef frameFromBytes(const std::size_t* index) const;
  Link linkFromLastRef(const FrameRef& f) const;
  bool between(const FrameRef& f, const FrameRef& next) const;
  // The one explanation of the bytes between the last published event and its confirmed
  // successor at `next`, if there is exactly one (see decideAbsolute()).
  struct Repair {
    std::size_t index[8] = {};
    FrameRef frame;
    Link link;
    std::size_t end = 0;  // held position after the bytes it explains
  };
  int decideRegion(std::size_t pos, std::size_t best, std::size_t next, Repair& repair) const;
  // Candidate frames near a position: the best one that follows the last event plausibly (and
  // another as good, if any), and the best one that does not.
  struct Candidates {
    std::size_t best, unlinked, tied;  // held_.size() if none
    std::int64_t best_value, unlinked_value;
    Link best_link;
  };
  void buildChains();  // chain_* and frames_ for every held position
  Candidates findCandidates(std::size_t pos, std::size_t window_last) const;
  Link clockJumpLink(std::size_t pos);  // counts the jump, forgets the latency floor
  void countSkipped(std::size_t from, std::size_t to);  // bytes [from, to) dropped
  void decideAbsolute(bool flushing, ebslam::EventVector& out);
  // Gap judgement: events published after a gap that may hide wrap periods wait in staged_ with
  // the time the stream alone gives them; once the stream is live again the periods that the
  // host clock shows beyond it are added to all of them (see ParserConfig::live_window_us).
  // arrived_after_us: host time of the read before the event's own (kNoHost if unknown).
  void stageOrEmit(const ebslam::Event& e, std::int64_t host_us, std::int64_t arrived_after_us,
                   ebslam::EventVector& out);
  // Adds the hidden periods to the staged events and emits them; without `force`, only if the
  // liveliest staged event is late by at most live_lag_us beyond whole periods.
  // Without `force`, the count must also come out the same twice (see resolveGap()); `idle`:
  // called after a read found the line idle; now_us: host time of the newest read.
  // at_once: an idle read after events that never ran ahead of the host clock needs no second.
  // fewest: forced while the newest events are still a late read (a reader that woke late,
  // then an idle line: the device may have begun to hold its bytes): the fewest periods the
  // events' arrival after the read before their own allows, instead of the most their
  // lateness allows.
  bool resolveGap(ebslam::EventVector& out, bool force, bool idle, std::int64_t now_us,
                  bool at_once, bool fewest = false);
  // The events staged for a gap judgement have waited long enough to be judged by force.
  bool gapHoldExpired(std::int64_t now_us) const;

  std::vector<std::uint8_t> held_;         // bytes after the last published event
  std::vector<std::int64_t> held_host_;    // host time of the read of each held byte
  std::vector<std::int64_t> held_after_;   // host time of the read before that one (kNoHost)
  std::vector<std::uint32_t> held_idle_;   // idle epoch at the arrival of each held byte
  std::vector<FrameRef> frames_;           // per held position: the frame starting there (if valid)
  std::vector<int> chain_length_;          // per held position: frames in its best chain
  std::vector<std::int64_t> chain_score_;  // per held position: bytes explained minus skipped
  std::vector<char> chain_open_;           // per held position: the chain may grow with more bytes
  std::vector<std::int64_t> chain_advance_;   // per held position: device time its chain spans
  std::vector<std::int64_t> chain_end_host_;  // per held position: host time of its chain's end
  std::vector<std::size_t> chain_next_;       // per held position: next frame of its chain
  struct Staged {
    ebslam::Event event;
    std::int64_t host_us;
  };
  std::vector<Staged> staged_;        // events after a gap, times without the hidden periods
  bool judging_gap_ = false;          // staged_ is in use
  std::size_t live_from_ = 0;         // staged_ index: the newest at least live_window_us old
  std::int64_t gap_residual_us_ = 0;  // least host time minus latency floor minus event time
  bool gap_residual_known_ = false;
  // Most host time of the read before an event's own minus latency floor minus event time: the
  // event arrived after that read, so (sent live) it is at most live_lag_us older.
  std::int64_t gap_after_residual_us_ = 0;
  bool gap_after_residual_known_ = false;
  std::int64_t gap_latency_us_ = 0;
  std::int64_t gap_candidate_k_ = -1;  // periods a first live check found, to be confirmed
  std::int64_t gap_candidate_host_ = 0;
  std::optional<std::int64_t> idle_host_us_;  // host time of the last idle read, if given
  bool gap_candidate_idle_ = false;           // latency of a live event when the gap began
  std::uint32_t idle_epoch_ = 0;
  std::int64_t previous_read_host_ = kNoHost;
  // Line saturation (ParserConfig::line_bytes_per_s): recent reads with their host times and
  // sizes; the newest host time at which the line was seen saturated.
  struct Read {
    std::int64_t host_us;
    std::size_t bytes;
  };
  std::vector<Read> reads_;
  std::int64_t saturated_host_us_ = kNoHost;
  void noteRead(std::int64_t host_us, std::size_t bytes);
  bool saturatedSince(std::int64_t host_us) const {
    return saturated_host_us_ != kNoHost && saturated_host_us_ >= host_us;
  }
  bool mode_decided_ = false;  // set by the first bytes fed
  bool chain_mode_ = false;    // absolute format fed with host times: framing by evidence
  bool have_last_ = false;
  FrameRef last_;
  std::int64_t last_time_us_ = 0;
  std::int64_t behind_debt_us_ = 0;  // device time to absorb before the clock advances again
  bool have_latency_ = false;
  std::int64_t min_latency_us_ = 0;  // smallest host time minus device time published
  ParserConfig config_;
  ParserStats stats_;
  TimestampUnwrapper unwrapper_;
  // Current partial event: state = number of bytes of it seen so far (0 = expecting start).
  std::size_t pending_ = 0;
  std::uint8_t frame_[6] = {};  // bytes of the current event so far
  int consecutive_rejections_ = 0;
  std::uint32_t ts_accum_ = 0;
  bool in_garbage_ = false;           // inside a run of dropped bytes (one resync per run)
  std::int64_t host_time_floor_ = 0;  // kNone: last emitted time
  bool any_host_time_ = false;
};

}  // namespace edvs
