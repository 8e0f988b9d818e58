#include "ebslam/events/event_denoiser.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"

namespace ebslam {
namespace {

Event ev(std::int64_t t, int x, int y, bool on = true) {
  Event e;
  e.t_us = t;
  e.x = static_cast<std::uint16_t>(x);
  e.y = static_cast<std::uint16_t>(y);
  e.polarity = on;
  return e;
}

// The classic filter: one neighbour event of either polarity.
BackgroundActivityFilterConfig windowOf(std::int64_t window_us) {
  BackgroundActivityFilterConfig config;
  config.window_us = window_us;
  config.min_support = 1;
  config.polarity_match = false;
  return config;
}

TEST(BackgroundActivityFilter, PassesOnlyEventsWithRecentNeighbourSupport) {
  BackgroundActivityFilter filter(windowOf(1000), SensorSize{128, 128});
  EXPECT_FALSE(filter.accept(ev(0, 10, 10)));           // nothing before it
  EXPECT_TRUE(filter.accept(ev(500, 11, 11)));          // diagonal neighbour 500 us earlier
  EXPECT_TRUE(filter.accept(ev(1500, 12, 11)));         // (11, 11) at 500: exactly the window
  EXPECT_FALSE(filter.accept(ev(2600, 13, 11)));        // (12, 11) at 1500: 1100 us, too late
  EXPECT_FALSE(filter.accept(ev(2700, 15, 11)));        // two pixels away: not a neighbour
  EXPECT_FALSE(filter.accept(ev(2800, 20, 20)));        // its own pixel does not support it ...
  EXPECT_FALSE(filter.accept(ev(2900, 20, 20)));        // ... not even at once
  EXPECT_TRUE(filter.accept(ev(3000, 19, 20, false)));  // polarity does not matter
  EXPECT_EQ(filter.passedCount(), 3u);
  EXPECT_EQ(filter.rejectedCount(), 5u);
}

TEST(BackgroundActivityFilter, WorksAtTheSensorBorderAndCorners) {
  BackgroundActivityFilter filter(windowOf(1000), SensorSize{128, 64});
  EXPECT_FALSE(filter.accept(ev(0, 0, 0)));
  EXPECT_TRUE(filter.accept(ev(10, 1, 0)));
  EXPECT_FALSE(filter.accept(ev(20, 127, 63)));
  EXPECT_TRUE(filter.accept(ev(30, 126, 62)));
  EXPECT_FALSE(filter.accept(ev(40, 127, 0)));  // nothing near the top right corner
  EXPECT_FALSE(filter.accept(ev(50, 0, 63)));
  // Row wrap-around: (127, 5) and (0, 6) are not neighbours.
  EXPECT_FALSE(filter.accept(ev(60, 127, 5)));
  EXPECT_FALSE(filter.accept(ev(70, 0, 6)));
}

TEST(BackgroundActivityFilter, RefractoryFilterDropsBurstsOfOnePixel) {
  BackgroundActivityFilterConfig config = windowOf(10000);
  config.refractory_filter = true;
  config.refractory_period_us = 1000;
  BackgroundActivityFilter filter(config, SensorSize{128, 128});
  EXPECT_FALSE(filter.accept(ev(0, 50, 50)));     // no support
  EXPECT_TRUE(filter.accept(ev(100, 51, 50)));    // support, first of its pixel
  EXPECT_FALSE(filter.accept(ev(600, 51, 50)));   // support, but 500 us after its own last
  EXPECT_FALSE(filter.accept(ev(1200, 51, 50)));  // 600 us after the dropped one: still a burst
  EXPECT_TRUE(filter.accept(ev(2200, 51, 50)));   // 1000 us after its last
  // Without the refractory filter the burst passes.
  BackgroundActivityFilter plain(windowOf(10000), SensorSize{128, 128});
  plain.accept(ev(0, 50, 50));
  EXPECT_TRUE(plain.accept(ev(100, 51, 50)));
  EXPECT_TRUE(plain.accept(ev(600, 51, 50)));
}

TEST(BackgroundActivityFilter, BatchAndInPlaceAgreeWithTheEventByEventDecision) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pixel(0, 31);
  EventVector events;
  std::int64_t t = 0;
  for (int i = 0; i < 5000; ++i) {
    t += rng() % 300;
    events.push_back(ev(t, pixel(rng), pixel(rng), rng() % 2));
  }
  BackgroundActivityFilter one(windowOf(2000), SensorSize{32, 32});
  EventVector expected;
  for (const Event& e : events) {
    if (one.accept(e)) expected.push_back(e);
  }
  ASSERT_GT(expected.size(), 400u);
  ASSERT_LT(expected.size(), events.size());
  BackgroundActivityFilter batch(windowOf(2000), SensorSize{32, 32});
  EventVector passed;
  std::size_t n = batch.filter(events.data(), 2500, passed);
  n += batch.filter(events.data() + 2500, events.size() - 2500, passed);
  EXPECT_EQ(n, expected.size());
  EXPECT_EQ(passed, expected);
  BackgroundActivityFilter in_place(windowOf(2000), SensorSize{32, 32});
  EventVector copy = events;
  in_place.filterInPlace(copy);
  EXPECT_EQ(copy, expected);
  EXPECT_EQ(in_place.passedCount() + in_place.rejectedCount(), events.size());
}

TEST(BackgroundActivityFilter, BadInputThrowsAndChangesNothing) {
  BackgroundActivityFilterConfig config;
  config.window_us = 0;
  EXPECT_THROW(BackgroundActivityFilter(config, SensorSize{}), std::invalid_argument);
  config = {};
  config.refractory_period_us = -1;
  EXPECT_THROW(BackgroundActivityFilter(config, SensorSize{}), std::invalid_argument);
  EXPECT_THROW(BackgroundActivityFilter({}, SensorSize{0, 128}), std::invalid_argument);

  BackgroundActivityFilter filter(windowOf(1000), SensorSize{128, 128});
  EventVector passed;
  filter.filter(EventVector{ev(100, 5, 5)}, passed);
  // Outside the sensor: the valid first event of the call is not processed either.
  const EventVector outside = {ev(200, 6, 5), ev(210, 128, 5)};
  EXPECT_THROW(filter.filter(outside, passed), std::invalid_argument);
  const EventVector backwards = {ev(200, 6, 5), ev(50, 7, 5)};
  EXPECT_THROW(filter.filter(backwards, passed), std::invalid_argument);
  EventVector backwards_copy = backwards;
  EXPECT_THROW(filter.filterInPlace(backwards_copy), std::invalid_argument);
  EXPECT_EQ(backwards_copy, backwards);
  const EventVector earlier_than_last_call = {ev(99, 6, 5)};
  EXPECT_THROW(filter.filter(earlier_than_last_call, passed), std::invalid_argument);
  EXPECT_TRUE(passed.empty());
  EXPECT_EQ(filter.passedCount() + filter.rejectedCount(), 1u);
  // (6, 5) at 200 still finds the support of (5, 5) at 100: nothing of the throwing calls stuck.
  EXPECT_EQ(filter.filter(EventVector{ev(200, 6, 5)}, passed), 1u);
  // The output may not alias the input.
  EXPECT_THROW(filter.filter(passed.data(), passed.size(), passed), std::invalid_argument);
  // After reset the stream may start over.
  filter.reset();
  EXPECT_EQ(filter.filter(EventVector{ev(0, 6, 5)}, passed), 0u);
  EXPECT_THROW(scoreDenoising({}, SensorSize{}, EventVector{ev(0, 1, 1)}, {}),
               std::invalid_argument);
}

// Signal kept and noise removed against the simulator's labels with the default config: a floor
// robot under a ceiling of lines and circles at 1 Hz background activity per pixel.
TEST(BackgroundActivityFilter, SeparatesSimulatedSignalFromNoiseAtOneHertzPerPixel) {
  SimulatorConfig config;
  config.events.noise_rate_hz_per_pixel = 1.0;
  FloorRegion region;
  region.min = Eigen::Vector2d(-6.0, -6.0);
  region.max = Eigen::Vector2d(6.0, 6.0);
  const Scene scene = makeCeilingScene(makeLinesAndCirclesTexture(), region, 0.01);
  Trajectory path;  // 0.3 m/s with a turn, as a slow floor robot
  for (int i = 0; i <= 40; ++i) {
    const double t = 0.05 * i;
    path.push_back(se2ToFloorPose(t, 0.3 * t, 0.1 * std::sin(1.5 * t), 0.5 * t));
  }
  const SimulationResult run = EventSimulator(config).simulate(scene, path, 0.0, 2.0);
  ASSERT_GT(run.signal_events, 20000u);
  ASSERT_GT(run.noise_events, 20000u);
  const DenoisingScore score = scoreDenoising(BackgroundActivityFilterConfig{},
                                              SensorSize{128, 128}, run.events, run.noise_labels);
  EXPECT_EQ(score.signal, run.signal_events);
  EXPECT_EQ(score.noise, run.noise_events);
  // Measured 95.4 % kept, 80.7 % removed (the pioneer runs, docs/results/events2d.md: 91.7 %
  // and 87.4 %).
  EXPECT_GE(score.signalKeptFraction(), 0.93);
  EXPECT_GE(score.noiseRemovedFraction(), 0.77);
  // The classic filter (one neighbour of either polarity) at the same window lets half of the
  // noise through; at 10 ms (88.9 % kept, 73.7 % removed) it is worse on both counts.
  const DenoisingScore classic =
      scoreDenoising(windowOf(100000), SensorSize{128, 128}, run.events, run.noise_labels);
  EXPECT_LT(classic.noiseRemovedFraction(), score.noiseRemovedFraction() - 0.2);
  const DenoisingScore classic_short =
      scoreDenoising(windowOf(10000), SensorSize{128, 128}, run.events, run.noise_labels);
  EXPECT_LT(classic_short.noiseRemovedFraction(), score.noiseRemovedFraction());
  EXPECT_LT(classic_short.signalKeptFraction(), score.signalKeptFraction());
}

}  // namespace
}  // namespace ebslam
