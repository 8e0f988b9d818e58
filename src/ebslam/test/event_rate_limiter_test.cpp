#include "ebslam/events/event_rate_limiter.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "ebslam/events/event.h"

namespace ebslam {
namespace {

// `rate_eps` events/s for `duration_s` from t0_us, pixels uniform on a 1280 x 720 sensor.
EventVector uniformStream(double rate_eps, double duration_s, std::int64_t t0_us = 1000000,
                          std::uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> col(0, 1279), row(0, 719);
  const std::size_t n = static_cast<std::size_t>(rate_eps * duration_s);
  EventVector events(n);
  for (std::size_t i = 0; i < n; ++i) {
    events[i].t_us = t0_us + static_cast<std::int64_t>(1e6 * static_cast<double>(i) / rate_eps);
    events[i].x = static_cast<std::uint16_t>(col(rng));
    events[i].y = static_cast<std::uint16_t>(row(rng));
    events[i].polarity = (i % 3) != 0;
  }
  return events;
}

EventRateLimiterConfig capAt(double rate_eps, std::uint64_t seed = 1) {
  EventRateLimiterConfig config;
  config.max_rate_eps = rate_eps;
  config.seed = seed;
  return config;
}

TEST(EventRateLimiter, KeepsEverythingBelowTheCapAndWithoutOne) {
  const EventVector events = uniformStream(200000, 0.5);
  for (const EventRateLimiterConfig& config : {capAt(0.0), capAt(1e6)}) {
    EventRateLimiter limiter(config);
    EventVector kept = events;
    EXPECT_EQ(limiter.thinInPlace(kept), 0u);
    EXPECT_EQ(kept, events);
    EXPECT_EQ(limiter.seen(), events.size());
    EXPECT_EQ(limiter.kept(), events.size());
    EXPECT_EQ(limiter.keepProbability(), 1.0);
  }
}

TEST(EventRateLimiter, ThinsA10MegaEventStreamUniformlyToTheCap) {
  const EventVector events = uniformStream(10e6, 0.3);
  EventRateLimiter limiter(capAt(1e6));
  EventVector kept = events;
  const std::size_t dropped = limiter.thinInPlace(kept);
  EXPECT_EQ(dropped + kept.size(), events.size());
  // 1 M events/s over 0.3 s; the first window (no rate known yet) keeps its budget of 2 x cap.
  EXPECT_NEAR(static_cast<double>(kept.size()), 0.3e6, 0.3e6 * 0.02);
  EXPECT_NEAR(limiter.measuredRate(), 10e6, 10e6 * 0.01);
  EXPECT_NEAR(limiter.keepProbability(), 0.1, 0.001);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end(),
                             [](const Event& a, const Event& b) { return a.t_us < b.t_us; }));
  // Uniform: every tenth of the sensor's columns, rows, of the time and each polarity keeps
  // about a tenth of its events (after the first window).
  struct Bands {
    std::vector<double> cols = std::vector<double>(10), rows = std::vector<double>(10),
                        times = std::vector<double>(10);
    double on = 0;
  };
  const std::int64_t t0 = events.front().t_us + 2000;
  const auto bands = [t0](const EventVector& list) {
    Bands b;
    for (const Event& e : list) {
      if (e.t_us < t0) continue;
      b.cols[e.x / 128] += 1;
      b.rows[e.y / 72] += 1;
      b.times[static_cast<std::size_t>(std::min<std::int64_t>(9, (e.t_us - t0) / 29800))] += 1;
      b.on += e.polarity;
    }
    return b;
  };
  const Bands in = bands(events), out = bands(kept);
  for (int i = 0; i < 10; ++i) {
    EXPECT_NEAR(out.cols[i] / in.cols[i], 0.1, 0.003) << "column band " << i;
    EXPECT_NEAR(out.rows[i] / in.rows[i], 0.1, 0.003) << "row band " << i;
    EXPECT_NEAR(out.times[i] / in.times[i], 0.1, 0.003) << "time band " << i;
  }
  EXPECT_NEAR(out.on / in.on, 0.1, 0.002);
}

TEST(EventRateLimiter, DecisionsDependOnlyOnTheEventsAndTheSeed) {
  const EventVector events = uniformStream(5e6, 0.1);
  EventRateLimiter whole(capAt(5e5, 3));
  EventVector at_once = events;
  whole.thinInPlace(at_once);

  // The same stream cut into messages of random sizes, event by event through keep().
  EventRateLimiter chunked(capAt(5e5, 3));
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::size_t> size(1, 5000);
  EventVector pieces;
  for (std::size_t i = 0; i < events.size();) {
    EventVector message(
        events.begin() + static_cast<std::ptrdiff_t>(i),
        events.begin() + static_cast<std::ptrdiff_t>(std::min(events.size(), i + size(rng))));
    i += message.size();
    chunked.thinInPlace(message);
    pieces.insert(pieces.end(), message.begin(), message.end());
  }
  EXPECT_EQ(pieces, at_once);

  EventRateLimiter other_seed(capAt(5e5, 4));
  EventVector other = events;
  other_seed.thinInPlace(other);
  EXPECT_NE(other, at_once);
  EXPECT_NEAR(static_cast<double>(other.size()), static_cast<double>(at_once.size()),
              0.02 * static_cast<double>(at_once.size()));

  // reset() starts the same sequence again.
  whole.reset();
  EventVector again = events;
  whole.thinInPlace(again);
  EXPECT_EQ(again, at_once);
}

TEST(EventRateLimiter, ABurstPassesAtMostTwiceTheCapInItsFirstWindow) {
  EventRateLimiterConfig config = capAt(1e6);
  config.window_us = 2000;
  EventRateLimiter limiter(config);
  EventVector events = uniformStream(1e5, 0.1, 0);              // below the cap
  const EventVector burst = uniformStream(50e6, 0.02, 100000);  // then 50 M events/s
  events.insert(events.end(), burst.begin(), burst.end());
  std::vector<std::uint64_t> kept_per_window(64, 0);
  for (const Event& e : events) {
    if (limiter.keep(e.t_us)) ++kept_per_window[static_cast<std::size_t>(e.t_us / 2000)];
  }
  for (std::size_t w = 50; w < 60; ++w) {
    EXPECT_LE(kept_per_window[w], 4000u) << "window " << w;  // 2 x 1e6 x 2 ms
  }
  // After the burst's first window the rate is known: a tenth of a percent short of the cap.
  EXPECT_NEAR(static_cast<double>(kept_per_window[55]), 2000.0, 200.0);
  EXPECT_NEAR(limiter.keepProbability(), 0.02, 0.001);
}

TEST(EventRateLimiter, APauseDoesNotLookLikeABurst) {
  EventRateLimiter limiter(capAt(1e6));
  // 3000 events in one 2 ms window (1.5 M events/s), then a pause of a second.
  for (int i = 0; i < 3000; ++i) limiter.keep(1000000 + i / 2);
  EXPECT_TRUE(limiter.keep(2000000));
  EXPECT_EQ(limiter.keepProbability(), 1.0);  // 3000 events over 1 s
  EXPECT_LT(limiter.measuredRate(), 4000.0);
}

TEST(EventRateLimiter, WorksOnAnyEventTypeWithATime) {
  struct Timed {
    std::int64_t t_us;
    float depth;
  };
  std::vector<Timed> events;
  for (int i = 0; i < 40000; ++i) events.push_back({i / 10, static_cast<float>(i)});  // 10 M/s
  EventRateLimiter limiter(capAt(2e6));
  limiter.thinInPlace(events);
  EXPECT_NEAR(static_cast<double>(events.size()), 8000.0 + 4000.0, 400.0);  // 2 M/s + budget
  for (std::size_t i = 1; i < events.size(); ++i) EXPECT_LT(events[i - 1].depth, events[i].depth);
}

TEST(EventRateLimiterConfig, RejectsNonsense) {
  for (double rate : {-1.0, 10.0, 999.0, std::numeric_limits<double>::infinity(),
                      std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_THROW(EventRateLimiter{capAt(rate)}, std::invalid_argument) << rate;
  }
  EventRateLimiterConfig config = capAt(1e6);
  config.window_us = 50;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config.window_us = 2000000;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config.window_us = 1000;
  EXPECT_NO_THROW(config.validate());
}

}  // namespace
}  // namespace ebslam
