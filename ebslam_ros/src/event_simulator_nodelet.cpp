// Simulated eDVS on a floor robot under a textured ceiling (thesis 6.5.3; the scene and event
// model of ebslam_simulate_events with the same parameters and seeds, so both give the same
// events). Publications (relative names):
//  - events (ebslam_msgs/EventArray): ~publish_rate messages per simulated second, in
//    ~frame_id, width x height of ~camera; header.stamp = ts of the last event;
//  - ground_truth/pose (geometry_msgs/PoseStamped), ground_truth/path (nav_msgs/Path, bounded):
//    the sensor's optical frame in ~map_frame at each message's end, and the tf
//    ~map_frame -> ~ground_truth_frame (its own frame, so it never fights the estimators' tf);
//  - /clock (with ~publish_clock; run the other nodes with use_sim_time);
//  - camera_info (sensor_msgs/CameraInfo, latched, in ~frame_id): the simulated sensor's size
//    and lens (~camera/*, ~camera/preset), as an event camera driver publishes it.
// Scene and motion from ~scenario (default: the demo's, in the repository) and the parameters.
// With ~loop the robot drives ~t_begin..~t_end forth and back endlessly: pass k runs backwards
// along the path when k is odd (the pose stays continuous) with event seed ~seed + k, and the
// simulated time runs on (pass k covers [k D, (k + 1) D) after the start, D = ~t_end - ~t_begin),
// so stamps and /clock never jump back.
// Time: a simulated time t [s since the trajectory's start] is stamped anchor + t, the anchor
// being ~clock_start with /clock, else the wall time at the start (then stamps advance with
// t / ~speed, as the event file player). Pacing: the message for t is sent at
// wall_start + t / ~speed (or as soon as simulated when the simulator is slower than that).
// The simulation runs in a thread of its own; the nodelet stops it on unload.
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/simulation/simulator.h>
#include <ebslam/simulation/simulator_scenes.h>

#include <opencv2/imgcodecs.hpp>

#include <atomic>
#include <memory>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>
#include <thread>

#include "ebslam_ros/conversions.h"
#include "ebslam_ros/ground_truth_publisher.h"
#include "ebslam_ros/paced_event_publisher.h"
#include "event_simulator_params.h"

namespace ebslam_ros {

class EventSimulatorNodelet : public nodelet::Nodelet {
 public:
  ~EventSimulatorNodelet() override {
    stop_ = true;
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override {
    const std::string package = ros::package::getPath("ebslam_ros");
    const std::string default_scenario =
        package.empty() ? "" : package + "/data/sample_session/pioneer_360_excerpt.yaml";
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "event simulator " + getName(), [&] {
      config_ = loadEventSimulatorNodeConfig(getPrivateNodeHandle(), default_scenario);
      prepare();
    });
    ros::NodeHandle& nh = getNodeHandle();
    ground_truth_.emplace(nh, config_.map_frame, config_.ground_truth_frame,
                          static_cast<std::size_t>(config_.path_length));
    if (!config_.align_frame.empty()) {
      ground_truth_->publishAlignedFrame(ebslam::interpolatePose(path_, t_begin_),
                                         config_.align_frame);
    }
    const PacedEventOptions options = pacedEventOptions(
        config_, config_.frame_id, config_.simulator.camera.width, config_.simulator.camera.height);
    events_.emplace(nh, options, stop_, [this](double t_end_s, const ros::Time& stamp) {
      publishGroundTruth(std::min(t_end_s, pass_end_), stamp);
    });
    camera_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 1, true);
    std_msgs::Header info_header;
    info_header.stamp = ros::Time::now();
    info_header.frame_id = config_.frame_id;
    camera_info_pub_.publish(toCameraInfoMsg(config_.simulator.camera, info_header));
    NODELET_INFO("simulating '%s'%s%s from %.2f to %.2f s at %.2fx%s%s", config_.trajectory.c_str(),
                 config_.scenario.empty() ? "" : " (scenario ",
                 config_.scenario.empty() ? "" : (config_.scenario + ")").c_str(),
                 t_begin_ - path_.front().t_s, t_end_ - path_.front().t_s, config_.speed,
                 config_.publish_clock ? " with /clock" : "",
                 config_.loop ? ", looping forth and back" : "");
    worker_ = std::thread([this] { run(); });
  }

  void prepare() {
    const ebslam::Trajectory input = ebslam::readTumTrajectory(config_.trajectory);
    if (input.size() < 2) {
      throw std::invalid_argument("trajectory '" + config_.trajectory +
                                  "' holds fewer than two poses");
    }
    if (config_.raw_camera_poses) {
      path_ = input;
    } else {
      ebslam::FloorRobotTrajectoryConfig floor;
      floor.smoothing_half_window_s = config_.smoothing_half_window_s;
      path_ = ebslam::makeFloorRobotTrajectory(input, floor);
    }
    const double t0 = path_.front().t_s;
    t_begin_ = t0 + config_.t_begin_s;
    t_end_ = config_.t_end_s < 0.0 ? path_.back().t_s : t0 + config_.t_end_s;
    if (!(t_begin_ < t_end_) || t_end_ > path_.back().t_s) {
      throw std::invalid_argument("~t_begin..~t_end is empty or beyond the trajectory (" +
                                  std::to_string(path_.back().t_s - t0) + " s long)");
    }
    const ebslam::FloorRegion region =
        ebslam::visibleCeilingRegion(path_, config_.simulator.camera, config_.ceiling_height_m);
    if (config_.texture == "lines") {
      scene_ = ebslam::makeLinesCeilingScene(region, config_.metres_per_texel, config_.lines,
                                             config_.ceiling_height_m);
    } else {
      const cv::Mat texture = cv::imread(config_.texture, cv::IMREAD_UNCHANGED);
      if (texture.empty()) {
        throw std::runtime_error("cannot read ~texture image '" + config_.texture + "'");
      }
      scene_ = ebslam::makeCeilingScene(texture, region, config_.metres_per_texel,
                                        config_.ceiling_height_m);
    }
    // The path driven backwards over the same span: pose at t' = t_begin + t_end - t.
    reversed_path_.assign(path_.rbegin(), path_.rend());
    for (ebslam::StampedPose& pose : reversed_path_) pose.t_s = t_begin_ + t_end_ - pose.t_s;
    ebslam::EventSimulator check(config_.simulator);  // validates the configuration
  }

  // The path of pass `pass` (forth, back, forth, ...), shifted to start at its pass's time.
  ebslam::Trajectory passPath(int pass) const {
    ebslam::Trajectory path = pass % 2 == 0 ? path_ : reversed_path_;
    const double offset = pass * (t_end_ - t_begin_);
    for (ebslam::StampedPose& pose : path) pose.t_s += offset;
    return path;
  }

  void run() {
    if (!events_->start(std::llround(t_begin_ * 1e6))) return;
    try {
      std::size_t signal = 0, noise = 0;
      for (int pass = 0;; ++pass) {
        pass_path_ = passPath(pass);
        const double offset = pass * (t_end_ - t_begin_);
        pass_end_ = t_end_ + offset;
        ebslam::SimulatorConfig config = config_.simulator;
        config.events.seed += static_cast<std::uint64_t>(pass);
        // Stream time of the simulator is round(t_s * 1e6) on the trajectory clock.
        const ebslam::SimulationResult result = ebslam::EventSimulator(config).simulate(
            scene_, pass_path_, t_begin_ + offset, pass_end_,
            [&](const ebslam::EventVector& events) {
              if (stop_) throw PacedEventPublisher::Stopped{};
              for (const ebslam::Event& e : events) events_->add(e);
            });
        signal += result.signal_events;
        noise += result.noise_events;
        if (!config_.loop) break;
        if (pass % 10 == 9) {
          NODELET_INFO("simulated %d passes: %zu events in %u messages", pass + 1, signal + noise,
                       events_->messages());
        }
      }
      events_->sendNext();
      NODELET_INFO("simulation done: %zu events (%zu signal, %zu noise) in %u messages",
                   signal + noise, signal, noise, events_->messages());
    } catch (const PacedEventPublisher::Stopped&) {
    } catch (const std::exception& error) {
      NODELET_ERROR("simulation failed: %s", error.what());
    }
  }

  void publishGroundTruth(double t_s, const ros::Time& stamp) {
    ground_truth_->publish(ebslam::interpolatePose(pass_path_, t_s), stamp,
                           events_->messages() % 10 == 0);
  }

  EventSimulatorNodeConfig config_;
  ebslam::Trajectory path_;
  ebslam::Scene scene_;
  ebslam::Trajectory reversed_path_;  // path_ driven backwards over [t_begin_, t_end_]
  ebslam::Trajectory pass_path_;      // the path of the pass being simulated
  double t_begin_ = 0.0, t_end_ = 0.0;
  double pass_end_ = 0.0;  // end of the pass being simulated [s, trajectory clock]
  std::optional<PacedEventPublisher> events_;
  std::optional<GroundTruthPublisher> ground_truth_;
  std::atomic<bool> stop_{false};
  ros::Publisher camera_info_pub_;
  std::thread worker_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventSimulatorNodelet, nodelet::Nodelet)
