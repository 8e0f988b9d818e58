#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "edvs/biases.h"
#include "edvs/commands.h"
#include "edvs/event_encoder.h"
#include "edvs/event_format.h"
#include "edvs/event_parser.h"
#include "edvs/format_detection.h"

using ebslam::Event;
using ebslam::EventVector;
using edvs::EventFormat;
using edvs::EventParser;
using edvs::Firmware;
using edvs::ParserConfig;

namespace {

constexpr EventFormat kTimestamped[] = {EventFormat::kDelta, EventFormat::kAbs16,
                                        EventFormat::kAbs24, EventFormat::kAbs32};

/// Seeded random events with steps of 0..max_step_us between them.
EventVector randomEvents(std::size_t n, std::uint32_t seed, std::int64_t t0 = 1000,
                         std::int64_t max_step_us = 300) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> coord(0, 127);
  std::uniform_int_distribution<std::int64_t> step(0, max_step_us);
  EventVector events;
  std::int64_t t = t0;
  for (std::size_t i = 0; i < n; ++i) {
    Event e;
    e.x = static_cast<std::uint16_t>(coord(rng));
    e.y = static_cast<std::uint16_t>(coord(rng));
    e.polarity = (rng() & 1) != 0;
    e.t_us = t;
    events.push_back(e);
    t += step(rng);
  }
  return events;
}

/// Events relative to the first one's time, for comparing device clocks with different origins.
EventVector relative(EventVector events) {
  if (events.empty()) return events;
  const std::int64_t t0 = events.front().t_us;
  for (Event& e : events) e.t_us -= t0;
  return events;
}

EventVector parseAll(const std::vector<std::uint8_t>& bytes, EventFormat format,
                     EventParser* keep = nullptr) {
  ParserConfig cfg;
  cfg.format = format;
  EventParser parser(cfg);
  EventVector out;
  parser.feed(bytes, std::nullopt, out);
  parser.flush(out);
  if (keep) *keep = parser;
  return out;
}

void expectMonotonic(const EventVector& events) {
  for (std::size_t i = 1; i < events.size(); ++i) {
    ASSERT_GE(events[i].t_us, events[i - 1].t_us) << "time ran backwards at event " << i;
  }
}

}  // namespace

TEST(Commands, LinesAndFormatNumbers) {
  namespace cmd = edvs::commands;
  EXPECT_EQ(cmd::reset(), "R\n");
  EXPECT_EQ(cmd::echoOff(), "!U0\n");
  EXPECT_EQ(cmd::startStreaming(), "E+\n");
  EXPECT_EQ(cmd::stopStreaming(), "E-\n");
  EXPECT_EQ(cmd::timestampReset(), "!ET0\n");
  EXPECT_EQ(cmd::masterRun(), "!ETM+\n");
  EXPECT_EQ(cmd::masterStop(), "!ETM0\n");
  EXPECT_EQ(cmd::slave(), "!ETS\n");
  EXPECT_EQ(cmd::flushBiases(), "!BF\n");
  EXPECT_EQ(cmd::setBias(3, 1067), "!B3=1067\n");
  EXPECT_THROW(cmd::setBias(12, 1), std::invalid_argument);
  EXPECT_THROW(cmd::setBias(0, -1), std::invalid_argument);
  EXPECT_THROW(cmd::setBias(0, 1 << 24), std::invalid_argument);

  EXPECT_EQ(cmd::eventFormat(EventFormat::kNone, Firmware::kCurrent), "!E0\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kDelta, Firmware::kCurrent), "!E1\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs16, Firmware::kCurrent), "!E2\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs24, Firmware::kCurrent), "!E3\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs32, Firmware::kCurrent), "!E4\n");
  // Older firmware: the timestamp formats are numbered one lower and there is no delta format.
  EXPECT_EQ(cmd::eventFormat(EventFormat::kNone, Firmware::kLegacy), "!E0\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs16, Firmware::kLegacy), "!E1\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs24, Firmware::kLegacy), "!E2\n");
  EXPECT_EQ(cmd::eventFormat(EventFormat::kAbs32, Firmware::kLegacy), "!E3\n");
  EXPECT_THROW(cmd::eventFormat(EventFormat::kDelta, Firmware::kLegacy), std::invalid_argument);
}

TEST(Commands, ParseFormatNames) {
  using edvs::parseEventFormat;
  EXPECT_EQ(parseEventFormat("E2", Firmware::kCurrent), EventFormat::kAbs16);
  EXPECT_EQ(parseEventFormat("!E2", Firmware::kLegacy), EventFormat::kAbs24);
  EXPECT_EQ(parseEventFormat("e1", Firmware::kLegacy), EventFormat::kAbs16);
  EXPECT_EQ(parseEventFormat("4", Firmware::kCurrent), EventFormat::kAbs32);
  EXPECT_EQ(parseEventFormat("ts24", Firmware::kLegacy), EventFormat::kAbs24);
  EXPECT_EQ(parseEventFormat("delta", Firmware::kCurrent), EventFormat::kDelta);
  EXPECT_FALSE(parseEventFormat("E4", Firmware::kLegacy).has_value());
  EXPECT_FALSE(parseEventFormat("E5", Firmware::kCurrent).has_value());
  EXPECT_FALSE(parseEventFormat("bogus", Firmware::kCurrent).has_value());
  for (int n = 0; n <= 4; ++n) {
    const auto f = edvs::formatFromCommandNumber(n, Firmware::kCurrent);
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(edvs::formatCommandNumber(*f, Firmware::kCurrent), n);
  }
  for (int n = 0; n <= 3; ++n) {
    const auto f = edvs::formatFromCommandNumber(n, Firmware::kLegacy);
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(edvs::formatCommandNumber(*f, Firmware::kLegacy), n);
  }
}

TEST(Commands, BiasNamesAndBanner) {
  EXPECT_EQ(edvs::biasIndex("cas"), 0);
  EXPECT_EQ(edvs::biasIndex("DIFFON"), 8);
  EXPECT_EQ(edvs::biasIndex("pr"), 11);
  EXPECT_FALSE(edvs::biasIndex("nope").has_value());
  for (int i = 0; i < edvs::kNumBiases; ++i) {
    EXPECT_EQ(edvs::biasIndex(edvs::biasName(i)), i);
  }
  EXPECT_TRUE(edvs::containsBanner("\x81\x02junk\nEDVS-4337 V2.1\n"));
  EXPECT_TRUE(edvs::containsBanner("meDVS128 ready"));
  EXPECT_FALSE(edvs::containsBanner("EDVS-433"));
}

TEST(Polarity, BitOneIsOnByDefault) {
  // 1yyyyyyy pxxxxxxx with y = 5, x = 3: p = 1 then p = 0.
  const std::vector<std::uint8_t> bytes = {0x85, 0x83, 0x85, 0x03};
  EventVector events = parseAll(bytes, EventFormat::kNone);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].x, 3);
  EXPECT_EQ(events[0].y, 5);
  EXPECT_TRUE(events[0].polarity);
  EXPECT_FALSE(events[1].polarity);

  ParserConfig swapped;
  swapped.format = EventFormat::kNone;
  swapped.on_bit = 0;
  EventParser parser(swapped);
  EventVector out;
  parser.feed(bytes, std::nullopt, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_FALSE(out[0].polarity);
  EXPECT_TRUE(out[1].polarity);

  // The encoder writes the same convention back.
  EXPECT_EQ(edvs::encodeEvents(events, EventFormat::kNone), bytes);
}

TEST(Parser, BigEndianTimestampBytes) {
  // y=1, x=2 (p=1), 16-bit time 0x1234; then y=1, x=2, time 0x1240.
  const std::vector<std::uint8_t> bytes = {0x81, 0x82, 0x12, 0x34, 0x81, 0x82, 0x12, 0x40};
  const EventVector events = parseAll(bytes, EventFormat::kAbs16);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].t_us, 0x1234);
  EXPECT_EQ(events[1].t_us, 0x1240);
  // Delta format: 2 groups of 7 bits, most significant first, last byte with the top bit.
  const std::vector<std::uint8_t> delta = {0x81, 0x82, 0x80, 0x81, 0x82, 0x01, 0x85};
  const EventVector d = parseAll(delta, EventFormat::kDelta);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[1].t_us - d[0].t_us, (1 << 7) + 5);
}

TEST(Parser, RoundTripEveryFormat) {
  for (EventFormat f : edvs::kAllEventFormats) {
    SCOPED_TRACE(edvs::toString(f));
    const EventVector truth = randomEvents(3000, 7, 123456, 2000);
    const auto bytes = edvs::encodeEvents(truth, f);
    EventParser parser;
    const EventVector got = parseAll(bytes, f, &parser);
    ASSERT_EQ(got.size(), truth.size());
    EXPECT_EQ(parser.stats().bytes_dropped, 0u);
    EXPECT_EQ(parser.pendingBytes(), 0u);
    if (f == EventFormat::kNone) {
      for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].x, truth[i].x);
        EXPECT_EQ(got[i].y, truth[i].y);
        EXPECT_EQ(got[i].polarity, truth[i].polarity);
      }
    } else {
      EXPECT_EQ(relative(got), relative(truth));
    }
  }
}

TEST(Parser, EveryByteBoundarySplit) {
  for (EventFormat f : edvs::kAllEventFormats) {
    SCOPED_TRACE(edvs::toString(f));
    // Steps up to 30 ms: below half the 65.5 ms period of E2, so unambiguous without host time.
    const EventVector truth = randomEvents(12, 3, 5000, 30000);
    const auto bytes = edvs::encodeEvents(truth, f);
    const EventVector whole = parseAll(bytes, f);
    ASSERT_EQ(whole.size(), truth.size());
    // Every pair of split points: three reads.
    for (std::size_t a = 0; a <= bytes.size(); ++a) {
      for (std::size_t b = a; b <= bytes.size(); ++b) {
        ParserConfig cfg;
        cfg.format = f;
        EventParser parser(cfg);
        EventVector out;
        parser.feed(bytes.data(), a, std::nullopt, out);
        parser.feed(bytes.data() + a, b - a, std::nullopt, out);
        parser.feed(bytes.data() + b, bytes.size() - b, std::nullopt, out);
        parser.flush(out);
        ASSERT_EQ(out, whole) << "split at " << a << " and " << b;
        ASSERT_EQ(parser.stats().bytes_dropped, 0u);
      }
    }
    // And one byte per read.
    ParserConfig cfg;
    cfg.format = f;
    EventParser parser(cfg);
    EventVector out;
    for (std::uint8_t byte : bytes) parser.feed(&byte, 1, std::nullopt, out);
    parser.flush(out);
    EXPECT_EQ(out, whole);
  }
}

TEST(Parser, TextGarbageBetweenEventsIsDroppedAndCounted) {
  std::mt19937 rng(11);
  for (EventFormat f : edvs::kAllEventFormats) {
    SCOPED_TRACE(edvs::toString(f));
    const EventVector truth = randomEvents(2000, 5, 0, 500);
    std::vector<std::uint8_t> bytes;
    std::uint64_t garbage = 0;
    std::int64_t prev = truth.front().t_us;
    for (const Event& e : truth) {
      // Top-bit-clear bytes (ASCII replies, noise on an idle line) between events.
      if (rng() % 4 == 0) {
        const int n = 1 + static_cast<int>(rng() % 9);
        for (int k = 0; k < n; ++k) bytes.push_back(static_cast<std::uint8_t>(rng() & 0x7F));
        garbage += static_cast<std::uint64_t>(n);
      }
      edvs::encodeEvent(e, f, prev, 1, bytes);
      prev = e.t_us;
    }
    EventParser parser;
    const EventVector got = parseAll(bytes, f, &parser);
    EXPECT_EQ(parser.stats().bytes_dropped, garbage);
    EXPECT_GT(parser.stats().resyncs, 0u);
    if (f == EventFormat::kNone) {
      ASSERT_EQ(got.size(), truth.size());
    } else {
      EXPECT_EQ(relative(got), relative(truth));
    }
  }
}

TEST(Parser, ArbitraryGarbageResynchronises) {
  // Garbage with any bit pattern can look like events; the parser must lock onto the true
  // framing again and never let time run backwards.
  std::mt19937 rng(99);
  for (EventFormat f : edvs::kAllEventFormats) {
    SCOPED_TRACE(edvs::toString(f));
    const EventVector truth = randomEvents(4000, 17, 0, 200);
    // One read per event, arriving at the host when the device stamped it (real time).
    ParserConfig cfg;
    cfg.format = f;
    EventParser parser(cfg);
    EventVector got;
    std::int64_t prev = truth.front().t_us;
    std::size_t bursts = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      std::vector<std::uint8_t> bytes;
      if (i % 200 == 100) {
        const int n = 1 + static_cast<int>(rng() % 7);
        for (int k = 0; k < n; ++k) bytes.push_back(static_cast<std::uint8_t>(rng()));
        ++bursts;
      }
      edvs::encodeEvent(truth[i], f, prev, 1, bytes);
      prev = truth[i].t_us;
      parser.feed(bytes, truth[i].t_us + 7'000'000, got);
    }
    parser.flush(got);
    expectMonotonic(got);
    // True events recovered: longest common subsequence on (pixel, polarity), so phantom events
    // made of garbage neither count nor hide true ones.
    const auto same = [](const Event& a, const Event& b) {
      return a.x == b.x && a.y == b.y && a.polarity == b.polarity;
    };
    std::vector<std::size_t> row(got.size() + 1, 0), prev_row(got.size() + 1, 0);
    for (std::size_t i = 1; i <= truth.size(); ++i) {
      for (std::size_t k = 1; k <= got.size(); ++k) {
        row[k] = same(truth[i - 1], got[k - 1]) ? prev_row[k - 1] + 1
                                                : std::max(prev_row[k], row[k - 1]);
      }
      std::swap(row, prev_row);
    }
    const std::size_t matched = prev_row[got.size()];
    EXPECT_GE(matched, truth.size() - 4 * bursts) << "lost too many events to garbage";
    // The tail after the last burst is parsed exactly, timestamps included for the absolute
    // formats: phantom events with impossible times were rejected and did not shift the clock.
    // (The delta format cannot do that: a lost event loses its delta for good.)
    ASSERT_GE(got.size(), 50u);
    for (std::size_t k = 1; k <= 50; ++k) {
      const Event& a = got[got.size() - k];
      const Event& b = truth[truth.size() - k];
      EXPECT_EQ(a.x, b.x);
      EXPECT_EQ(a.y, b.y);
      EXPECT_EQ(a.polarity, b.polarity);
      if (f == EventFormat::kAbs16 || f == EventFormat::kAbs24 || f == EventFormat::kAbs32) {
        EXPECT_EQ(a.t_us - got.front().t_us, b.t_us - truth.front().t_us);
      }
    }
  }
}

TEST(Parser, ReadsThatDrainALongBacklogLoseNothing) {
  // On a loaded host the reader wakes 0.2-30 ms apart and drains all the device sent
  // meanwhile in one read: at E2's 65.5 ms period, more than the quarter-period step allowance
  // of device time can arrive at one host time. The stream must come through whole and exact.
  for (EventFormat f : {EventFormat::kAbs16, EventFormat::kAbs24, EventFormat::kAbs32}) {
    SCOPED_TRACE(edvs::toString(f));
    for (std::uint32_t seed : {1u, 2u, 3u}) {
      SCOPED_TRACE(seed);
      const EventVector truth = randomEvents(6000, seed, 5000, 100);  // ~20k events/s
      std::mt19937 rng(seed + 100);
      ParserConfig cfg;
      cfg.format = f;
      EventParser parser(cfg);
      EventVector got;
      std::vector<std::uint8_t> bytes;
      std::int64_t prev = truth.front().t_us;
      std::int64_t host = truth.front().t_us;
      std::size_t i = 0;
      while (i < truth.size()) {
        host += 200 + static_cast<std::int64_t>(rng() % 30000);
        const std::int64_t latency = 100 + static_cast<std::int64_t>(rng() % 900);
        bytes.clear();
        while (i < truth.size() && truth[i].t_us <= host - latency) {
          edvs::encodeEvent(truth[i], f, prev, 1, bytes);
          prev = truth[i].t_us;
          ++i;
        }
        if (!bytes.empty()) parser.feed(bytes, host, got);
      }
      parser.flush(got);
      ASSERT_EQ(got.size(), truth.size());
      EXPECT_EQ(relative(got), relative(truth));
      EXPECT_EQ(parser.stats().bytes_dropped, 0u);
      EXPECT_EQ(parser.stats().rejected_events, 0u);
    }
  }
}

TEST(Parser, TimestampWrapsOfEveryFormat) {
  for (EventFormat f : kTimestamped) {
    SCOPED_TRACE(edvs::toString(f));
    const std::int64_t period = edvs::wrapPeriodUs(f);
    // Start just before a wrap and cross several wraps with steps up to a third of the period
    // (delta format: up to the largest 28-bit delta).
    const std::int64_t max_step = period > 0 ? period / 3 : (std::int64_t{1} << 28) - 1;
    const std::int64_t t0 = period > 0 ? period - 1000 : 0;
    std::mt19937_64 rng(42);
    std::uniform_int_distribution<std::int64_t> step(0, max_step);
    EventVector truth = randomEvents(200, 21, t0);
    truth[1].t_us = truth[0].t_us + 1000;  // exactly at the wrap
    for (std::size_t i = 2; i < truth.size(); ++i) truth[i].t_us = truth[i - 1].t_us + step(rng);
    const auto bytes = edvs::encodeEvents(truth, f);
    EventParser parser;
    const EventVector got = parseAll(bytes, f, &parser);
    ASSERT_EQ(got.size(), truth.size());
    EXPECT_EQ(relative(got), relative(truth));
    expectMonotonic(got);
    if (period > 0) {
      EXPECT_EQ(static_cast<std::int64_t>(parser.stats().wraps),
                truth.back().t_us / period - truth.front().t_us / period);
    }
  }
}

TEST(Parser, GapLongerThanWrapPeriodRecoveredFromHostTime) {
  // 16-bit timestamps wrap every 65.5 ms; a quiet scene can leave longer gaps.
  EventVector truth = randomEvents(3, 1, 60000);
  truth[0].t_us = 60000;
  truth[1].t_us = 61000;
  truth[2].t_us = 61000 + 250000;  // 250 ms later: 3.8 periods, invisible in the raw value
  ParserConfig cfg;
  cfg.format = EventFormat::kAbs16;
  EventParser parser(cfg);
  EventVector out;
  std::vector<std::uint8_t> a, b;
  edvs::encodeEvent(truth[0], cfg.format, 0, 1, a);
  edvs::encodeEvent(truth[1], cfg.format, 0, 1, a);
  edvs::encodeEvent(truth[2], cfg.format, 0, 1, b);
  parser.feed(a, 5'000'000, out);
  parser.noteIdle();                         // reads in between returned nothing
  parser.feed(b, 5'000'000 + 251'000, out);  // host saw it 251 ms later (1 ms latency)
  parser.flush(out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].t_us - out[0].t_us, truth[2].t_us - truth[0].t_us);
  EXPECT_EQ(parser.stats().wraps_from_host_time, 3u);

  // The same host gap without an idle line (a backlog: the reader was late, the device was
  // held back by flow control) must not add periods.
  EventParser busy(cfg);
  EventVector out3;
  std::vector<std::uint8_t> c;
  ebslam::Event late = truth[1];
  late.t_us += 300;
  edvs::encodeEvent(late, cfg.format, 0, 1, c);
  busy.feed(a, 5'000'000, out3);
  busy.feed(c, 5'000'000 + 251'000, out3);
  busy.flush(out3);
  ASSERT_EQ(out3.size(), 3u);
  EXPECT_EQ(out3[2].t_us - out3[1].t_us, 300);
  EXPECT_EQ(busy.stats().wraps_from_host_time, 0u);

  // Without host time the gap folds into one period, but time still does not run backwards.
  EventParser blind(cfg);
  EventVector out2;
  blind.feed(a, std::nullopt, out2);
  blind.feed(b, std::nullopt, out2);
  blind.flush(out2);
  ASSERT_EQ(out2.size(), 3u);
  expectMonotonic(out2);
  EXPECT_NE(out2[2].t_us - out2[0].t_us, truth[2].t_us - truth[0].t_us);
}

TEST(Parser, NoTimestampFormatUsesMonotonicHostTime) {
  ParserConfig cfg;
  cfg.format = EventFormat::kNone;
  EventParser parser(cfg);
  EventVector out;
  const std::vector<std::uint8_t> two = {0x81, 0x01, 0x82, 0x02};
  parser.feed(two, 1000, out);
  parser.feed(two, 900, out);  // host clock stepped back: clamped
  parser.feed(two, 2000, out);
  ASSERT_EQ(out.size(), 6u);
  EXPECT_EQ(out[0].t_us, 1000);
  EXPECT_EQ(out[2].t_us, 1000);
  EXPECT_EQ(out[4].t_us, 2000);
}

TEST(Parser, RandomBytesNeverRunBackwardsNorCrash) {
  std::mt19937 rng(5);
  for (EventFormat f : edvs::kAllEventFormats) {
    std::vector<std::uint8_t> bytes(20000);
    for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
    ParserConfig cfg;
    cfg.format = f;
    EventParser parser(cfg);
    EventVector out;
    std::size_t pos = 0;
    std::int64_t host = 0;
    while (pos < bytes.size()) {
      const std::size_t n = std::min<std::size_t>(bytes.size() - pos, rng() % 64);
      parser.feed(bytes.data() + pos, n, host, out);
      pos += n;
      host += static_cast<std::int64_t>(rng() % 3000);
    }
    parser.flush(out);
    expectMonotonic(out);
    for (const Event& e : out) {
      EXPECT_LT(e.x, 128);
      EXPECT_LT(e.y, 128);
    }
    EXPECT_EQ(parser.stats().bytes_in, bytes.size());
  }
}

TEST(Parser, WrongFormatAnnouncedIsDetected) {
  // The device streams one format while the host was told another (e.g. legacy firmware
  // numbering mix-up): the parser must flag it, and the guess must find the true format.
  std::mt19937 rng(8);
  for (EventFormat sent : edvs::kAllEventFormats) {
    const EventVector truth = randomEvents(3000, 31 + static_cast<std::uint32_t>(sent), 0, 150);
    const auto bytes = edvs::encodeEvents(truth, sent);
    for (EventFormat assumed : edvs::kAllEventFormats) {
      SCOPED_TRACE(std::string("sent ") + toString(sent) + " parsed as " + toString(assumed));
      ParserConfig cfg;
      cfg.format = assumed;
      EventParser parser(cfg);
      EventVector out;
      // Delivered in reads of up to 256 bytes (real-time streaming: a read arrives 1 ms after
      // the device time of its last byte).
      std::size_t pos = 0;
      while (pos < bytes.size()) {
        const std::size_t n = std::min<std::size_t>(bytes.size() - pos, 1 + rng() % 256);
        const std::int64_t host = 1000 + truth.back().t_us * static_cast<std::int64_t>(pos + n) /
                                             static_cast<std::int64_t>(bytes.size());
        parser.feed(bytes.data() + pos, n, host, out);
        pos += n;
      }
      parser.flush(out);
      if (sent == assumed) {
        EXPECT_FALSE(parser.formatSuspect());
        EXPECT_EQ(out.size(), truth.size());
      } else {
        EXPECT_TRUE(parser.formatSuspect())
            << "dropped " << parser.stats().bytes_dropped << "/" << parser.stats().bytes_in
            << " jumps " << parser.stats().implausible_jumps << "/" << parser.stats().events;
      }
    }
    const auto guess = edvs::guessEventFormat(bytes);
    EXPECT_EQ(guess.format, sent) << "guessed " << toString(guess.format) << " for "
                                  << toString(sent);
  }
}

TEST(Parser, RestartForgetsPartialEventKeepsCounters) {
  ParserConfig cfg;
  cfg.format = EventFormat::kAbs24;
  EventParser parser(cfg);
  EventVector out;
  const std::vector<std::uint8_t> partial = {0x81, 0x82, 0x00};
  parser.feed(partial, std::nullopt, out);
  EXPECT_EQ(parser.pendingBytes(), 3u);
  parser.restart();
  EXPECT_EQ(parser.pendingBytes(), 0u);
  EXPECT_EQ(parser.stats().bytes_in, 3u);
  // The bytes of the event cut by the restart (a disconnect) are counted as dropped.
  EXPECT_EQ(parser.stats().bytes_dropped, 3u);
  const std::vector<std::uint8_t> full = {0x83, 0x04, 0x00, 0x00, 0x10};
  parser.feed(full, std::nullopt, out);
  parser.flush(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].y, 3);
  EXPECT_EQ(out[0].x, 4);
  EXPECT_EQ(out[0].t_us, 16);
  EXPECT_THROW(EventParser(ParserConfig{EventFormat::kNone, 2, {}, 0}), std::invalid_argument);
}

TEST(Encoder, RejectsInvalidEvents) {
  std::vector<std::uint8_t> out;
  Event e;
  e.x = 128;
  EXPECT_THROW(edvs::encodeEvent(e, EventFormat::kNone, 0, 1, out), std::invalid_argument);
  e.x = 1;
  e.t_us = 10;
  EXPECT_THROW(edvs::encodeEvent(e, EventFormat::kDelta, 20, 1, out), std::invalid_argument);
  e.t_us = std::int64_t{1} << 29;
  EXPECT_THROW(edvs::encodeEvent(e, EventFormat::kDelta, 0, 1, out), std::invalid_argument);
}
