// A deterministic megapixel event camera for the high-rate pipeline measurement
// (ebslam_ros/scripts/high_rate_pipeline.sh; not a test): an upward-looking camera of any size
// (default 1280 x 720, the Prophesee IMX636) under a ceiling of random line segments and circles,
// carried along a smooth planar path, publishes `events` as event_camera_msgs/EventPacket evt3
// (metavision_driver's format, one packet per --packet-period of sensor time) or as EventArray
// at a fixed event rate on the wall clock. Events lie on the ceiling's edges in view (what an
// edge-driven sensor sees, and what EB-SLAM-2D's model expects), polarity from the edge's normal
// against the motion, plus --noise-share of uniformly random background events. Seeded: the
// same options give the same events. By default every packet is rendered before the first is
// published (--prerender 1; about 4 bytes per event in memory), so that on a machine with few
// cores the source's rendering does not limit the rate it publishes at.
//
// While publishing it measures, and prints at the end:
//  - `pose` latency (receive time - stamp; the stamp is the last event's time of the update),
//  - messages sent against the messages each node's /diagnostics counts (the subscriber queues
//    never overflowed when they match),
//  - each node's diagnostics values named by --report (rates, dropped share, decoder counters).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/EventPacket.h>
#include <ebslam_msgs/event_conversions.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <CLI/CLI.hpp>

#include <ebslam/events/event.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <vector>

namespace {

struct EdgePoint {
  float x, y;    // on the ceiling [m], map frame
  float nx, ny;  // unit normal of the edge
};

// Random segments and circles over a square ceiling of side `side_m` centred at the origin,
// sampled every `step_m`, binned into cells of `cell_m`.
struct Ceiling {
  double side_m = 14.0, cell_m = 0.25;
  int cells = 0;
  std::vector<std::vector<EdgePoint>> grid;

  Ceiling(std::uint64_t seed, double step_m) {
    cells = static_cast<int>(std::ceil(side_m / cell_m));
    grid.resize(static_cast<std::size_t>(cells * cells));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-side_m / 2, side_m / 2), angle(0, 2 * M_PI),
        length(0.3, 1.5), radius(0.1, 0.5);
    const double density = 1.0;  // segments per m^2 (the eDVS experiments: ~0.6 per m^2)
    const int segments = static_cast<int>(density * side_m * side_m);
    for (int s = 0; s < segments; ++s) {
      const double x0 = pos(rng), y0 = pos(rng), a = angle(rng), l = length(rng);
      const double dx = std::cos(a), dy = std::sin(a);
      for (double u = 0; u <= l; u += step_m) add(x0 + u * dx, y0 + u * dy, -dy, dx);
    }
    for (int c = 0; c < segments / 2; ++c) {
      const double cx = pos(rng), cy = pos(rng), r = radius(rng);
      for (double a = 0; a < 2 * M_PI; a += step_m / r) {
        add(cx + r * std::cos(a), cy + r * std::sin(a), std::cos(a), std::sin(a));
      }
    }
  }
  void add(double x, double y, double nx, double ny) {
    const int cx = static_cast<int>((x + side_m / 2) / cell_m);
    const int cy = static_cast<int>((y + side_m / 2) / cell_m);
    if (cx < 0 || cy < 0 || cx >= cells || cy >= cells) return;
    grid[static_cast<std::size_t>(cy * cells + cx)].push_back(
        {static_cast<float>(x), static_cast<float>(y), static_cast<float>(nx),
         static_cast<float>(ny)});
  }
  // Points within the axis-aligned box [x0, x1] x [y0, y1] (whole cells).
  void collect(double x0, double y0, double x1, double y1,
               std::vector<const EdgePoint*>& out) const {
    out.clear();
    const auto cell = [&](double v) {
      return std::clamp(static_cast<int>((v + side_m / 2) / cell_m), 0, cells - 1);
    };
    for (int cy = cell(y0); cy <= cell(y1); ++cy) {
      for (int cx = cell(x0); cx <= cell(x1); ++cx) {
        for (const EdgePoint& p : grid[static_cast<std::size_t>(cy * cells + cx)])
          out.push_back(&p);
      }
    }
  }
};

// The camera's planar pose in the map at t [s]: a Lissajous path of +-amplitude_m, heading
// oscillating by +-0.4 rad; (vx, vy) its velocity [m/s].
struct Pose {
  double x, y, theta, vx, vy;
};
Pose pathAt(double t, double amplitude_m) {
  const double wx = 2 * M_PI / 20.0, wy = 2 * M_PI / 13.0, wt = 2 * M_PI / 17.0;
  return {amplitude_m * std::sin(wx * t), 0.6 * amplitude_m * std::sin(wy * t),
          0.4 * std::sin(wt * t), amplitude_m * wx * std::cos(wx * t),
          0.6 * amplitude_m * wy * std::cos(wy * t)};
}

// splitmix64 as uniform [0, 1): the source must be cheaper than the pipeline it feeds.
struct FastUniform {
  std::uint64_t state;
  double operator()() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  }
};

void putWord(std::vector<std::uint8_t>& out, unsigned type, unsigned payload) {
  const unsigned w = (type << 12) | (payload & 0xFFFu);
  out.push_back(static_cast<std::uint8_t>(w & 0xFF));
  out.push_back(static_cast<std::uint8_t>(w >> 8));
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "high_rate_source");
  CLI::App app{"Publish a deterministic megapixel event stream and measure the pipeline"};
  int width = 1280, height = 720;
  double focal_px = 800.0, ceiling_m = 2.59, rate = 10e6, duration = 20.0, packet_period = 0.001;
  double amplitude = 1.0, noise_share = 0.05;
  std::string encoding = "evt3", frame = "edvs_optical_frame", report;
  bool prerender = true;
  std::uint64_t seed = 1;
  app.add_option("--width", width, "sensor columns")->capture_default_str();
  app.add_option("--height", height, "sensor rows")->capture_default_str();
  app.add_option("--focal", focal_px, "focal length [px]")->capture_default_str();
  app.add_option("--ceiling", ceiling_m, "ceiling distance [m]")->capture_default_str();
  app.add_option("--rate", rate, "events per second")->capture_default_str();
  app.add_option("--duration", duration, "seconds of publishing")->capture_default_str();
  app.add_option("--packet-period", packet_period, "sensor time per message [s]")
      ->capture_default_str();
  app.add_option("--amplitude", amplitude, "path amplitude [m]")->capture_default_str();
  app.add_option("--noise-share", noise_share, "share of random background events")
      ->capture_default_str();
  app.add_option("--encoding", encoding, "evt3 (EventPacket) or array (EventArray)")
      ->capture_default_str();
  app.add_option("--frame", frame, "frame_id of the events")->capture_default_str();
  app.add_option("--prerender", prerender,
                 "render every packet before publishing (1) or while publishing (0)")
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the ceiling and the events")->capture_default_str();
  app.add_option("--report", report,
                 "diagnostics keys to print per node, '|'-separated (default: rates and counts)");
  CLI11_PARSE(app, argc, argv);
  if (encoding != "evt3" && encoding != "array") {
    std::fprintf(stderr, "--encoding must be evt3 or array\n");
    return 2;
  }
  if (width < 1 || height < 1 || width > 2048 || height > 2048 || !(rate > 0) ||
      !(packet_period >= 1e-4)) {
    std::fprintf(stderr, "bad size, rate or packet period\n");
    return 2;
  }

  const Ceiling ceiling(seed, 0.5 * ceiling_m / focal_px);  // two samples per pixel
  ros::NodeHandle nh;
  ros::Publisher pub = encoding == "evt3" ? nh.advertise<ebslam_msgs::EventPacket>("events", 1000)
                                          : nh.advertise<ebslam_msgs::EventArray>("events", 1000);
  std::mutex mutex;
  std::vector<double> latencies;
  std::size_t images = 0;
  std::map<std::string, std::map<std::string, std::string>> diagnostics;  // node -> key -> value
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "pose", 100000, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
        const double latency = (ros::Time::now() - m->header.stamp).toSec();
        std::lock_guard<std::mutex> lock(mutex);
        latencies.push_back(latency);
      });
  ros::Subscriber image_sub =
      nh.subscribe<sensor_msgs::Image>("event_image", 10, [&](const sensor_msgs::Image::ConstPtr&) {
        std::lock_guard<std::mutex> lock(mutex);
        ++images;
      });
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& status : m->status) {
          for (const auto& kv : status.values) diagnostics[status.name][kv.key] = kv.value;
        }
      });
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const ros::WallTime wait_until = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && (pub.getNumSubscribers() == 0 || pose_sub.getNumPublishers() == 0) &&
         ros::WallTime::now() < wait_until) {
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(1.0).sleep();

  FastUniform unit{seed + 1};
  const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
  // Half the view's diagonal on the ceiling [m]: the box of edge points that may be in view.
  const double reach = 0.5 * std::hypot(width, height) * ceiling_m / focal_px + 0.05;
  std::vector<const EdgePoint*> in_view;
  const std::size_t packets = static_cast<std::size_t>(duration / packet_period);
  const double events_per_us = rate * 1e-6;
  double carry = 0.0;
  unsigned last_high = ~0u;
  std::size_t sent_events = 0, sent_messages = 0, late_packets = 0;
  // Renders packet k (sensor time [k, k + 1) * packet_period) into `bytes` (evt3) or `events`
  // (times in microseconds from the stream's start).
  const auto render = [&](std::size_t k, std::vector<std::uint8_t>& bytes,
                          ebslam::EventVector& events) {
    const double t0 = static_cast<double>(k) * packet_period;
    const double t_mid = t0 + 0.5 * packet_period;
    const Pose pose = pathAt(t_mid, amplitude);
    ceiling.collect(pose.x - reach, pose.y - reach, pose.x + reach, pose.y + reach, in_view);
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    // Camera frame: x right, y down, z up to the ceiling; the sensor's x along the heading.
    // A ceiling point (px, py) maps to u = cx + f * (R^T (p - t)).x / D, v = cy - f * (...).y / D.
    const auto project = [&](double px, double py, double& u, double& v) {
      const double dx = px - pose.x, dy = py - pose.y;
      u = cx + focal_px * (c * dx + s * dy) / ceiling_m;
      v = cy - focal_px * (-s * dx + c * dy) / ceiling_m;
    };
    events.clear();
    bytes.clear();
    const std::int64_t us0 = static_cast<std::int64_t>(std::llround(t0 * 1e6));
    const std::int64_t us1 = static_cast<std::int64_t>(std::llround((t0 + packet_period) * 1e6));
    for (std::int64_t us = us0; us < us1; ++us) {
      carry += events_per_us;
      const int n = static_cast<int>(carry);
      carry -= n;
      bool time_written = false;
      for (int i = 0; i < n; ++i) {
        int x, y;
        bool on;
        if (in_view.empty() || unit() < noise_share) {
          x = static_cast<int>(unit() * width);
          y = static_cast<int>(unit() * height);
          on = unit() < 0.5;
        } else {
          // A few tries for a point in the (rotated) view; else a noise event.
          const EdgePoint* p = nullptr;
          double u = -1, v = -1;
          for (int attempt = 0; attempt < 8; ++attempt) {
            p = in_view[static_cast<std::size_t>(unit() * static_cast<double>(in_view.size()))];
            project(p->x, p->y, u, v);
            if (u >= -0.5 && v >= -0.5 && u < width - 0.5 && v < height - 0.5) break;
            p = nullptr;
          }
          if (!p) {
            u = unit() * width - 0.5;
            v = unit() * height - 0.5;
          }
          x = std::clamp(static_cast<int>(std::lround(u)), 0, width - 1);
          y = std::clamp(static_cast<int>(std::lround(v)), 0, height - 1);
          on = p ? (p->nx * pose.vx + p->ny * pose.vy) > 0 : unit() < 0.5;
        }
        if (encoding == "evt3") {
          const std::uint64_t sensor_us = static_cast<std::uint64_t>(us);
          const unsigned high = static_cast<unsigned>((sensor_us >> 12) & 0xFFF);
          if (high != last_high) {
            putWord(bytes, 0x8, high);  // EVT_TIME_HIGH
            last_high = high;
            time_written = false;
          }
          if (!time_written) {
            putWord(bytes, 0x6, static_cast<unsigned>(sensor_us & 0xFFF));  // EVT_TIME_LOW
            time_written = true;
          }
          putWord(bytes, 0x0, static_cast<unsigned>(y));                       // EVT_ADDR_Y
          putWord(bytes, 0x2, static_cast<unsigned>(x) | (on ? 0x800u : 0u));  // EVT_ADDR_X
        } else {
          ebslam::Event e;
          e.t_us = us;
          e.x = static_cast<std::uint16_t>(x);
          e.y = static_cast<std::uint16_t>(y);
          e.polarity = on;
          events.push_back(e);
        }
        ++sent_events;
      }
    }
  };
  // With --prerender every packet is rendered before the first is published, so that the
  // source's own cost does not limit the rate on a machine with few cores.
  std::vector<std::vector<std::uint8_t>> rendered_bytes;
  std::vector<ebslam::EventVector> rendered_events;
  std::vector<std::uint8_t> bytes;
  ebslam::EventVector events;
  if (prerender) {
    const ros::WallTime render_start = ros::WallTime::now();
    rendered_bytes.resize(encoding == "evt3" ? packets : 0);
    rendered_events.resize(encoding == "evt3" ? 0 : packets);
    std::size_t stored = 0;
    for (std::size_t k = 0; k < packets && ros::ok(); ++k) {
      if (encoding == "evt3") {
        render(k, rendered_bytes[k], events);
        stored += rendered_bytes[k].size();
      } else {
        render(k, bytes, rendered_events[k]);
        stored += rendered_events[k].size() * sizeof(ebslam::Event);
      }
    }
    std::printf("source: rendered %zu events in %.1f s (%.0f MiB) before publishing\n", sent_events,
                (ros::WallTime::now() - render_start).toSec(),
                static_cast<double>(stored) / (1024.0 * 1024.0));
    std::fflush(stdout);
  }
  const ros::WallTime start_wall = ros::WallTime::now();
  const std::int64_t start_us = ebslam_msgs::toMicroseconds(ros::Time::now());
  std::uint64_t seq = 0;
  for (std::size_t k = 0; k < packets && ros::ok(); ++k) {
    const double t0 = static_cast<double>(k) * packet_period;
    if (!prerender) render(k, bytes, events);
    // Published when its last event is due on the wall clock.
    const ros::WallTime due = start_wall + ros::WallDuration(t0 + packet_period);
    const ros::WallTime now = ros::WallTime::now();
    if (due > now) {
      (due - now).sleep();
    } else if ((now - due).toSec() > packet_period) {
      ++late_packets;
    }
    if (encoding == "evt3") {
      ebslam_msgs::EventPacket packet;
      packet.header.stamp = ros::Time::now();
      packet.header.frame_id = frame;
      packet.width = static_cast<std::uint32_t>(width);
      packet.height = static_cast<std::uint32_t>(height);
      packet.seq = seq++;
      packet.encoding = "evt3";
      if (prerender) {
        packet.events.swap(rendered_bytes[k]);
      } else {
        packet.events = bytes;
      }
      pub.publish(packet);
    } else {
      ebslam::EventVector& out = prerender ? rendered_events[k] : events;
      for (ebslam::Event& e : out) e.t_us += start_us;
      pub.publish(ebslam_msgs::toMsg(
          out,
          ebslam::SensorSize{static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)},
          frame));
      if (prerender) ebslam::EventVector().swap(out);
    }
    ++sent_messages;
  }
  const double wall_s = (ros::WallTime::now() - start_wall).toSec();
  ros::WallDuration(3.0).sleep();  // the last poses and two diagnostics updates

  std::lock_guard<std::mutex> lock(mutex);
  std::vector<double> sorted = latencies;
  std::sort(sorted.begin(), sorted.end());
  const auto quantile = [&](double q) {
    return sorted.empty() ? 0.0 : sorted[static_cast<std::size_t>(q * (sorted.size() - 1))];
  };
  std::printf(
      "source: %dx%d %s, %.0f events/s: %zu events in %zu messages over %.1f s of wall "
      "time (%.0f events/s), %zu messages published late by more than one period\n",
      width, height, encoding.c_str(), rate, sent_events, sent_messages, wall_s,
      static_cast<double>(sent_events) / wall_s, late_packets);
  std::printf("poses received %zu; latency median %.1f ms, p99 %.1f ms, max %.1f ms\n",
              sorted.size(), 1e3 * quantile(0.5), 1e3 * quantile(0.99), 1e3 * quantile(1.0));
  std::printf("event images received %zu\n", images);
  std::vector<std::string> keys;
  if (report.empty()) {
    report =
        "messages|event packets|events received|events processed|events passed|input rate "
        "[ev/s]|processed rate [ev/s]|event-time input rate [ev/s]|keep probability|events "
        "dropped by the rate cap|dropped share (since start)|dropped share (last period)|events "
        "per second of processing|last pose latency [s]|undecodable bytes|images published";
  }
  for (std::size_t begin = 0; begin <= report.size();) {
    const std::size_t end = std::min(report.find('|', begin), report.size());
    keys.push_back(report.substr(begin, end - begin));
    begin = end + 1;
  }
  for (const auto& [node, values] : diagnostics) {
    std::printf("%s:", node.c_str());
    for (const std::string& key : keys) {
      const auto it = values.find(key);
      if (it != values.end()) std::printf(" [%s] %s;", key.c_str(), it->second.c_str());
    }
    std::printf("\n");
  }
  return 0;
}
