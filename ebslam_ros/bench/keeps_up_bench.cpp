// Keeps-up measurement of an event filter node (does it keep up with a live event rate; run by
// ebslam_ros/scripts/keeps_up.sh, not a test): publishes `events` at a fixed event rate in
// fixed-rate messages for a while, the events (pixels, polarities, order) taken from an event
// file and re-timed to the rate on the wall clock, and measures
//  - pose latency: receive time of each `pose` minus its stamp (= the last event of the update;
//    an upper bound of publication - stamp by the loopback transport),
//  - messages the filter lost (sent here minus received by the filter, from its diagnostics;
//    header.seq gaps would not do: roscpp renumbers seq per publisher) and poses received,
//  - the filter's events per second of processing (its diagnostics) against the core
//    EventSlam2d / EventParticleFilter run in this process on the same events (same N, B, K).
// Prints one result line per quantity.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/event_conversions.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>
#include <CLI/CLI.hpp>

#include <ebslam/events/event_io.h>
#include <ebslam/slam/ceiling_camera.h>
#include <ebslam/slam/ebslam2d.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  ros::init(argc, argv, "keeps_up_bench");
  CLI::App app{"Publish events at a fixed rate to a filter node and measure latency and losses"};
  std::string events_path;
  double rate = 200000.0, message_rate = 100.0, duration = 60.0;
  int particles = 25;
  app.add_option("--events", events_path, "event file supplying pixels and order")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--rate", rate, "events per second")->capture_default_str();
  app.add_option("--message-rate", message_rate, "EventArray messages per second")
      ->capture_default_str();
  app.add_option("--duration", duration, "seconds of publishing")->capture_default_str();
  app.add_option("-N,--particles", particles, "N of the core comparison run (as the node's)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const ebslam::EventReadResult input = ebslam::readEventFile(events_path);
  if (input.events.empty()) {
    std::fprintf(stderr, "no events in %s\n", events_path.c_str());
    return 1;
  }
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<ebslam_msgs::EventArray>("events", 1000);
  std::mutex mutex;
  std::vector<double> latencies;
  std::map<std::string, std::string> diagnostics;
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "pose", 100000, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
        const double latency = (ros::Time::now() - m->header.stamp).toSec();
        std::lock_guard<std::mutex> lock(mutex);
        latencies.push_back(latency);
      });
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& status : m->status) {
          for (const auto& kv : status.values) diagnostics[kv.key] = kv.value;
        }
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  while (ros::ok() && (pub.getNumSubscribers() == 0 || pose_sub.getNumPublishers() == 0)) {
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(1.0).sleep();

  // Event k is due at start + k / rate; its pixel is event k mod n of the file.
  const std::size_t n = input.events.size();
  const ros::Time start = ros::Time::now() + ros::Duration(0.05);
  const std::int64_t start_us = ebslam_msgs::toMicroseconds(start);
  const std::size_t total = static_cast<std::size_t>(rate * duration);
  const ros::WallDuration period(1.0 / message_rate);
  std::size_t sent = 0, messages = 0;
  ros::WallTime next = ros::WallTime::now();
  while (ros::ok() && sent < total) {
    next += period;
    const ros::WallTime now_wall = ros::WallTime::now();
    if (next > now_wall) (next - now_wall).sleep();
    const double elapsed = (ros::Time::now() - start).toSec();
    const std::size_t due =
        std::min(total, static_cast<std::size_t>(std::max(0.0, elapsed * rate)));
    if (due <= sent) continue;
    // Event k at start + k / rate on the published clock (microseconds since the ROS epoch).
    ebslam::EventVector events(due - sent);
    for (std::size_t k = sent; k < due; ++k) {
      events[k - sent] = input.events[k % n];
      events[k - sent].t_us =
          start_us + static_cast<std::int64_t>(static_cast<double>(k) * 1e6 / rate);
    }
    pub.publish(ebslam_msgs::toMsg(events, input.sensor, "edvs_optical_frame"));
    sent = due;
    ++messages;
  }
  ros::WallDuration(3.0).sleep();  // the last poses and a diagnostics update

  // The core on the same events, same thread count (one), for the overhead ratio.
  ebslam::EventVector core_events(std::min<std::size_t>(total, 3000000));
  for (std::size_t k = 0; k < core_events.size(); ++k) {
    core_events[k] = input.events[k % n];
    core_events[k].t_us = static_cast<std::int64_t>(static_cast<double>(k) * 1e6 / rate);
  }
  ebslam::Ebslam2dConfig config;
  config.filter.num_particles = particles;
  const ebslam::CeilingCamera camera(ebslam::CameraModel{}, 2.59);
  ebslam::EventSlam2d slam(config, camera);
  const std::size_t per_message = static_cast<std::size_t>(rate / message_rate);
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < core_events.size(); i += per_message) {
    slam.process(core_events.data() + i, std::min(per_message, core_events.size() - i));
  }
  const double core_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::lock_guard<std::mutex> lock(mutex);
  std::vector<double> sorted = latencies;
  std::sort(sorted.begin(), sorted.end());
  const auto quantile = [&](double q) {
    return sorted.empty() ? 0.0 : sorted[static_cast<std::size_t>(q * (sorted.size() - 1))];
  };
  std::printf("rate %.0f events/s, %.0f Hz messages, %.0f s: sent %zu events in %zu messages\n",
              rate, message_rate, duration, sent, messages);
  std::printf("poses received %zu; latency median %.2f ms, p99 %.2f ms, max %.2f ms\n",
              sorted.size(), 1e3 * quantile(0.5), 1e3 * quantile(0.99), 1e3 * quantile(1.0));
  const long long received = std::atoll(diagnostics["messages"].c_str());
  std::printf(
      "filter: messages %s, lost (sent - received) %lld, events received %s, events "
      "processed %s\n",
      diagnostics["messages"].c_str(), static_cast<long long>(messages) - received,
      diagnostics["events received"].c_str(), diagnostics["events processed"].c_str());
  const double node_rate = std::atof(diagnostics["events per second of processing"].c_str());
  const double core_rate = static_cast<double>(core_events.size()) / core_s;
  std::printf("events/s of processing: node %.0f, core (this process, N=%d) %.0f, ratio %.3f\n",
              node_rate, particles, core_rate, core_rate > 0 ? node_rate / core_rate : 0.0);
  return 0;
}
