#include "ebslam/slam/ebslam2d_tracking.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace ebslam {
namespace {

// A ceiling map with thin bright lines every 0.3 m along x and y (the edges EB-SLAM maps) over a
// faint background, 8 m x 8 m centred on the origin.
GridMap2f striped() {
  GridMap2f map(400, 400, 0.02, -4.0, -4.0, 0.02f);
  for (int r = 0; r < map.height; ++r) {
    for (int c = 0; c < map.width; ++c) {
      if (c % 15 == 0 || r % 15 == 0) map.at(c, r) = 1.0f;
    }
  }
  return map;
}

// Events of a sensor at `pose`: every pixel whose ceiling point falls on a line, up to `limit`.
EventVector eventsAt(const CeilingCamera& camera, const GridMap2f& map, const Pose2& pose,
                     std::size_t limit) {
  EventVector events;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (int y = 0; y < camera.height() && events.size() < limit; ++y) {
    for (int x = 0; x < camera.width() && events.size() < limit; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * camera.width() + x;
      const double ox = camera.offsetX()[p], oy = camera.offsetY()[p];
      if (map.lookup(pose.x + c * ox - s * oy, pose.y + s * ox + c * oy) > 0.5f) {
        Event e;
        e.t_us = static_cast<std::int64_t>(events.size());
        e.x = static_cast<std::uint16_t>(x);
        e.y = static_cast<std::uint16_t>(y);
        events.push_back(e);
      }
    }
  }
  return events;
}

TEST(TrackingMonitor, TellsATrackedFromALostEstimateAndRecovers) {
  const CeilingCamera camera{CameraModel{}};
  const GridMap2f map = striped();
  TrackingMonitor monitor(TrackingMonitorConfig{}, camera);
  const Pose2 truth{0.4, -0.2, 0.3};
  const EventVector events = eventsAt(camera, map, truth, 2000);
  ASSERT_GE(events.size(), 1000u);
  double t = 0.0;
  // Warm-up (10 s) on a wrong estimate: no verdict yet.
  const Pose2 wrong{0.47, -0.2, 0.47};
  for (int k = 0; k < 100; ++k, t += 0.05) monitor.update(t, events, wrong, map);
  EXPECT_EQ(monitor.state(), TrackingState::kTracking);
  for (int k = 0; k < 200; ++k, t += 0.05) {
    EXPECT_EQ(monitor.update(t, events, truth, map), TrackingState::kTracking);
  }
  EXPECT_GT(monitor.contrast(), 3.0);
  // The estimate is off by 7 cm and 10 degrees: the events land off the lines.
  for (int k = 0; k < 6; ++k, t += 0.05) monitor.update(t, events, wrong, map);
  EXPECT_EQ(monitor.state(), TrackingState::kTracking) << "not before lost_after_s";
  for (int k = 0; k < 40; ++k, t += 0.05) monitor.update(t, events, wrong, map);
  EXPECT_EQ(monitor.state(), TrackingState::kLost) << monitor.contrast();
  EXPECT_LT(monitor.contrast(), 1.6);
  EXPECT_EQ(monitor.collapses(), 1u);
  // Back on the lines for longer than recovered_after_s: tracking again.
  for (int k = 0; k < 40; ++k, t += 0.05) monitor.update(t, events, truth, map);
  EXPECT_EQ(monitor.state(), TrackingState::kTracking);
  EXPECT_EQ(monitor.collapses(), 1u);
}

TEST(TrackingMonitor, AContrastFarAboveTheReferenceIsACollapseToo) {
  const CeilingCamera camera{CameraModel{}};
  GridMap2f map = striped();
  TrackingMonitor monitor(TrackingMonitorConfig{}, camera);
  const Pose2 truth{0.4, -0.2, 0.3};
  const EventVector events = eventsAt(camera, map, truth, 600);  // a part of the view
  double t = 0.0;
  for (int k = 0; k < 400; ++k, t += 0.05) monitor.update(t, events, truth, map);
  const double reference = monitor.reference();
  ASSERT_GT(reference, 2.0);
  // The cells under the events grow fourfold (as where a lost estimate keeps writing its own
  // events into the map): the events' contrast more than doubles.
  const double c = std::cos(truth.theta), s = std::sin(truth.theta);
  for (const Event& e : events) {
    const std::size_t p = static_cast<std::size_t>(e.y) * camera.width() + e.x;
    const double ox = camera.offsetX()[p], oy = camera.offsetY()[p];
    const double x = truth.x + c * ox - s * oy, y = truth.y + s * ox + c * oy;
    map.at(static_cast<int>((x - map.origin_x_m) / map.resolution_m),
           static_cast<int>((y - map.origin_y_m) / map.resolution_m)) = 4.0f;
  }
  for (int k = 0; k < 40; ++k, t += 0.05) monitor.update(t, events, truth, map);
  EXPECT_GT(monitor.contrast(), 2.0 * reference);
  EXPECT_EQ(monitor.state(), TrackingState::kLost);
  EXPECT_EQ(monitor.collapses(), 1u);
}

TEST(TrackingMonitor, GivesNoVerdictOnFewEventsOrAnUnmappedView) {
  const CeilingCamera camera{CameraModel{}};
  const GridMap2f map = striped();
  TrackingMonitorConfig config;
  TrackingMonitor monitor(config, camera);
  // A robot standing still sees a few noise events: however wrong they look, no alarm.
  const Pose2 truth{0.0, 0.0, 0.0};
  const Pose2 wrong{0.08, 0.05, 0.4};
  const EventVector few =
      eventsAt(camera, map, truth, static_cast<std::size_t>(config.min_events) - 1);
  for (int k = 0; k < 200; ++k) monitor.update(0.05 * k, few, wrong, map);
  EXPECT_EQ(monitor.state(), TrackingState::kTracking);
  EXPECT_EQ(monitor.verdicts(), 0u);
  // A view of ceiling not mapped yet (far outside the map) gives no verdict either.
  const EventVector many = eventsAt(camera, map, truth, 2000);
  for (int k = 0; k < 200; ++k) monitor.update(10.0 + 0.05 * k, many, Pose2{20.0, 20.0, 0.0}, map);
  EXPECT_EQ(monitor.state(), TrackingState::kTracking);
  EXPECT_EQ(monitor.verdicts(), 0u);
  config.recovered_contrast = 1.0;  // below lost_contrast
  EXPECT_THROW(TrackingMonitor(config, camera), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam
