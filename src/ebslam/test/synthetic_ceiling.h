#pragma once

// Minimal, self-contained event generator for the EB-PF / EB-SLAM-2D tests and benchmarks: a
// ceiling of dark lines and circles on a bright background, an upward-looking camera moved
// along a planar path, and the ideal log-intensity event model (one event per contrast step
// per pixel, no noise). The full simulator (simulator.h) is used for the experiments; this one
// keeps the tests independent of it and fast.

#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam::testing {

struct SyntheticCeiling {
  cv::Mat intensity;  // CV_32FC1 in [0, 1]
  cv::Mat edges;      // CV_8UC1 Canny edges of intensity
  double metres_per_pixel = 0.01;
  Eigen::Vector2d origin_centre_m{0.0, 0.0};  // world position of pixel (0, 0)'s centre
};

/// size_m x size_m of ceiling centred on the world origin, lines and circles placed at random.
inline SyntheticCeiling makeSyntheticCeiling(double size_m, double metres_per_pixel,
                                             std::uint64_t seed, int lines = 20, int circles = 10) {
  SyntheticCeiling c;
  c.metres_per_pixel = metres_per_pixel;
  const int n = static_cast<int>(std::lround(size_m / metres_per_pixel));
  c.origin_centre_m = Eigen::Vector2d::Constant(-0.5 * (n - 1) * metres_per_pixel);
  cv::Mat img(n, n, CV_8UC1, cv::Scalar(200));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pos(0, n - 1);
  std::uniform_int_distribution<int> radius(n / 60 + 3, n / 12 + 4);
  const int stroke = std::max(1, static_cast<int>(std::lround(0.03 / metres_per_pixel)));
  for (int i = 0; i < lines; ++i) {
    cv::line(img, {pos(rng), pos(rng)}, {pos(rng), pos(rng)}, cv::Scalar(110), stroke, cv::LINE_AA);
  }
  for (int i = 0; i < circles; ++i) {
    cv::circle(img, {pos(rng), pos(rng)}, radius(rng), cv::Scalar(110), stroke, cv::LINE_AA);
  }
  cv::Mat blurred;
  cv::GaussianBlur(img, blurred, cv::Size(), 0.01 / metres_per_pixel);
  cv::Canny(blurred, c.edges, 20, 50);
  blurred.convertTo(c.intensity, CV_32F, 1.0 / 255.0);
  return c;
}

/// Events of the camera moving along path(t) for t in [t0, t1] [s]. Renders whenever the image
/// moved by about max_step_px; per pixel an event fires for every full contrast step C of log
/// intensity since the pixel's reference level; timestamps are the render times [us].
/// ground_truth (optional) receives the pose at every render step with its time.
inline EventVector generateSyntheticEvents(
    const SyntheticCeiling& ceiling, const CeilingCamera& camera,
    const std::function<Pose2(double)>& path, double t0, double t1, double contrast = 0.15,
    std::vector<std::pair<double, Pose2>>* ground_truth = nullptr, double max_step_px = 0.2) {
  const int w = camera.width();
  const int h = camera.height();
  const auto& ox = camera.offsetX();
  const auto& oy = camera.offsetY();
  const double inv_res = 1.0 / ceiling.metres_per_pixel;
  const auto sample = [&](double x, double y) {
    const double fc = (x - ceiling.origin_centre_m.x()) * inv_res;
    const double fr = (y - ceiling.origin_centre_m.y()) * inv_res;
    const int c = static_cast<int>(std::floor(fc));
    const int r = static_cast<int>(std::floor(fr));
    if (c < 0 || r < 0 || c + 1 >= ceiling.intensity.cols || r + 1 >= ceiling.intensity.rows) {
      return 200.0 / 255.0;
    }
    const double a = fc - c;
    const double b = fr - r;
    const float* p0 = ceiling.intensity.ptr<float>(r);
    const float* p1 = ceiling.intensity.ptr<float>(r + 1);
    return (1 - b) * ((1 - a) * p0[c] + a * p0[c + 1]) + b * ((1 - a) * p1[c] + a * p1[c + 1]);
  };
  const auto render = [&](const Pose2& p, std::vector<double>& log_i) {
    const double cs = std::cos(p.theta);
    const double sn = std::sin(p.theta);
    for (std::size_t k = 0; k < log_i.size(); ++k) {
      log_i[k] =
          std::log(0.02 + sample(p.x + cs * ox[k] - sn * oy[k], p.y + sn * ox[k] + cs * oy[k]));
    }
  };
  std::vector<double> reference(static_cast<std::size_t>(w) * h);
  std::vector<double> current(reference.size());
  Pose2 last = path(t0);
  render(last, reference);
  EventVector events;
  double t = t0;
  const double radius_px = camera.footprintRadius() / camera.wTrig();
  while (t < t1) {
    // Step so that the image moves by at most max_step_px (probe with a small step).
    const double probe = 1e-3;
    const Pose2 q = path(std::min(t1, t + probe));
    const double motion_px = std::hypot(q.x - last.x, q.y - last.y) / camera.wTrig() +
                             std::abs(q.theta - last.theta) * radius_px;
    const double dt = motion_px > 0 ? std::min(0.05, probe * max_step_px / motion_px) : 0.05;
    t = std::min(t1, t + dt);
    last = path(t);
    render(last, current);
    if (ground_truth) ground_truth->push_back({t, last});
    const auto t_us = static_cast<std::int64_t>(std::llround(t * 1e6));
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * w + x;
        while (std::abs(current[k] - reference[k]) >= contrast) {
          const bool on = current[k] > reference[k];
          reference[k] += on ? contrast : -contrast;
          events.push_back(
              Event{t_us, static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), on});
        }
      }
    }
  }
  return events;
}

/// A smooth test path: a loop of radius r around the origin with a slowly turning heading.
inline Pose2 loopPath(double t, double radius = 0.4, double speed = 0.3) {
  const double a = speed * t / radius;
  return {radius * std::sin(a), radius * (1.0 - std::cos(a)), 0.5 * a};
}

}  // namespace ebslam::testing
