// Simulated D-eDVS (thesis 8.2, ebslam/simulation/dedvs_simulator.h): an eDVS 128x128 (or its lens
// on another sensor size, ~edvs_preset: davis240, davis346, vga, hd720) and a
// PrimeSense-like depth camera with registered colour on a hand-held rig moving along a TUM
// trajectory through a furnished room (ebslam/simulation/dedvs_scene.h). Publications (relative
// names):
//  - events (ebslam_msgs/EventArray): ~publish_rate messages per simulated second in
//    ~edvs_frame; header.stamp = ts of the last event;
//  - depth_registered/image_raw (sensor_msgs/Image 16UC1, millimetres, 0 = no depth) and
//    depth_registered/camera_info, rgb/image_rect_color (bgr8, registered to the depth) and
//    rgb/camera_info, all in ~depth_frame, stamped with the depth camera's own clock (exposure
//    time + ~depth_clock_offset), the names dasp_ros uses;
//  - ground_truth/pose (geometry_msgs/PoseStamped), ground_truth/path (nav_msgs/Path, bounded):
//    the rig (the depth optical frame) in ~map_frame at each event message's end, and the tf
//    ~map_frame -> ~ground_truth_frame;
//  - camera_info (sensor_msgs/CameraInfo, latched, in ~edvs_frame): the event camera's size and
//    lens (as its driver publishes them; DepthEventFusion's ~edvs_camera_info reads them);
//  - /clock (with ~publish_clock; run the other nodes with use_sim_time);
//  - imu (sensor_msgs/Imu in ~imu_frame, with ~publish_imu): the rig IMU's readings
//    (ebslam/simulation/imu_simulator.h; angular velocity and linear acceleration with their
//    noise densities as covariances, no orientation), each event message followed by the readings
//    up to one past its end; the static tf ~edvs_frame -> ~imu_frame (rotation only).
// With ~loop the rig drives ~t_begin..~t_end forth and back endlessly (odd passes backwards, pass k
// seeded ~seed + k in the same room), the trajectory clock running on across passes.
// Time: trajectory time t [s] is stamped anchor + (t - start), the anchor being ~clock_start
// with /clock, else the wall time at the start (stamps then advance with t / ~speed, as the
// EventSimulator). Pacing: the message for t is sent at wall_start + (t - start) / ~speed, or as
// soon as simulated when the simulator is slower. Seeded (~seed): the same run every time.
// The simulation runs in a thread of its own; the nodelet stops it on unload.
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <ebslam/events/trajectory.h>
#include <ebslam/simulation/dedvs_io.h>
#include <ebslam/simulation/dedvs_scene.h>
#include <ebslam/simulation/dedvs_simulator.h>
#include <ebslam/simulation/imu_simulator.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>
#include <thread>

#include "ebslam_ros/conversions.h"
#include "ebslam_ros/ground_truth_publisher.h"
#include "ebslam_ros/paced_event_publisher.h"
#include "rgbd_event_simulator_params.h"

namespace ebslam_ros {

class RgbdEventSimulatorNodelet : public nodelet::Nodelet {
 public:
  ~RgbdEventSimulatorNodelet() override {
    stop_ = true;
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override {
    const std::string package = ros::package::getPath("ebslam_ros");
    const std::string default_trajectory =
        package.empty() ? "" : package + "/data/sample_session/pioneer_360_excerpt.txt";
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(
        getPrivateNodeHandle(), "RGB-D event simulator " + getName(), [&] {
          config_ = loadRgbdEventSimulatorNodeConfig(getPrivateNodeHandle(), default_trajectory);
          prepare();
        });
    ros::NodeHandle& nh = getNodeHandle();
    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 10);
    depth_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("depth_registered/camera_info", 10);
    colour_pub_ = nh.advertise<sensor_msgs::Image>("rgb/image_rect_color", 10);
    colour_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 10);
    ground_truth_.emplace(nh, config_.map_frame, config_.ground_truth_frame,
                          static_cast<std::size_t>(config_.path_length));
    const PacedEventOptions options = pacedEventOptions(
        config_, config_.edvs_frame, config_.simulator.edvs.width, config_.simulator.edvs.height);
    events_.emplace(nh, options, stop_, [this](double t_end_s, const ros::Time& stamp) {
      publishGroundTruth(std::min(t_end_s, pass_end_), stamp);
      publishImu(t_end_s + 1.0 / config_.simulator.imu.rate_hz);
    });
    // The event camera's size and lens (latched), as its driver publishes them.
    edvs_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 1, true);
    std_msgs::Header info_header;
    info_header.stamp = ros::Time::now();
    info_header.frame_id = config_.edvs_frame;
    edvs_info_pub_.publish(toCameraInfoMsg(config_.simulator.edvs, info_header));
    if (config_.publish_imu) startImu(nh);
    NODELET_INFO("simulating the D-eDVS along '%s' from %.2f to %.2f s at %.2fx%s%s (%zu planes)",
                 config_.trajectory.c_str(), t_begin_ - path_.front().t_s,
                 t_end_ - path_.front().t_s, config_.speed,
                 config_.publish_clock ? " with /clock" : "",
                 config_.loop ? ", looping forth and back" : "", scene_.planes.size());
    worker_ = std::thread([this] { run(); });
  }

  void prepare() {
    path_ = ebslam::readTumTrajectory(config_.trajectory);
    if (path_.size() < 2) {
      throw std::invalid_argument("trajectory '" + config_.trajectory +
                                  "' holds fewer than two poses");
    }
    const double t0 = path_.front().t_s;
    t_begin_ = t0 + config_.t_begin_s;
    t_end_ = config_.t_end_s < 0.0 ? path_.back().t_s : t0 + config_.t_end_s;
    if (!(t_begin_ < t_end_) || t_end_ > path_.back().t_s) {
      throw std::invalid_argument("~t_begin..~t_end is empty or beyond the trajectory (" +
                                  std::to_string(path_.back().t_s - t0) + " s long)");
    }
    scene_ = ebslam::makeRoomScene(path_, config_.room);
    ebslam::DedvsSimulator check(config_.simulator);  // validates the configuration
    // The path driven backwards over the same span: pose at t' = t_begin + t_end - t.
    reversed_path_.assign(path_.rbegin(), path_.rend());
    for (ebslam::StampedPose& pose : reversed_path_) pose.t_s = t_begin_ + t_end_ - pose.t_s;
    pass_path_ = path_;
    pass_end_ = t_end_;
    if (!config_.write_calibration.empty()) {
      ebslam::writeDedvsSensors(config_.write_calibration, ebslam::sensorsOf(config_.simulator));
    }
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
      double last_frame_t_s = -std::numeric_limits<double>::infinity();
      for (int pass = 0;; ++pass) {
        const double offset = pass * (t_end_ - t_begin_);
        // The ground-truth callback runs on this thread (events_->add / sendUntil).
        pass_path_ = passPath(pass);
        pass_end_ = t_end_ + offset;
        ebslam::DedvsSimulatorConfig config = config_.simulator;
        config.seed += static_cast<std::uint64_t>(pass);
        config.events.seed += static_cast<std::uint64_t>(pass);
        if (config_.publish_imu) {
          ebslam::ImuSimulatorConfig imu = config.imu;
          imu.seed += static_cast<std::uint64_t>(pass);
          imu_readings_ = ebslam::simulateImu(pass_path_, t_begin_ + offset, pass_end_, imu);
          next_imu_ = 0;
        }
        const ebslam::DedvsRun result = ebslam::DedvsSimulator(config).simulate(
            scene_, pass_path_, t_begin_ + offset, pass_end_,
            [&](const std::vector<ebslam::TrueDepthEvent>& events) {
              if (stop_) throw PacedEventPublisher::Stopped{};
              for (const ebslam::TrueDepthEvent& e : events) events_->add(e.event);
            },
            [&](const ebslam::DepthFrame& frame) {
              if (stop_) throw PacedEventPublisher::Stopped{};
              // A pass starts where the previous one ended: a frame at that instant went out.
              if (frame.t_s <= last_frame_t_s) return;
              last_frame_t_s = frame.t_s;
              // Events up to the exposure go out first (pacing), then the frame.
              events_->sendUntil(std::llround(frame.t_s * 1e6));
              publishFrame(frame);
            });
        signal += result.signal_events;
        noise += result.noise_events;
        if (!config_.loop) break;
        if (pass % 10 == 9) {
          NODELET_INFO("simulated %d passes: %zu events in %u messages, %u depth frames", pass + 1,
                       signal + noise, events_->messages(), frames_);
        }
      }
      // The last message ends at ~t_end (a depth frame there may have sent it already).
      events_->finish(std::llround(pass_end_ * 1e6));
      NODELET_INFO(
          "simulation done: %zu events (%zu signal, %zu noise) in %u messages, %u depth "
          "frames",
          signal + noise, signal, noise, events_->messages(), frames_);
    } catch (const PacedEventPublisher::Stopped&) {
    } catch (const std::exception& error) {
      NODELET_ERROR("simulation failed: %s", error.what());
    }
  }

  void publishFrame(const ebslam::DepthFrame& frame) {
    std_msgs::Header header;
    ++frames_;
    header.frame_id = config_.depth_frame;
    // The depth camera's own clock (exposure + offset), mapped as the event clock.
    header.stamp = events_->rosTime(std::llround(frame.stamp_s * 1e6));
    const ebslam::PinholeCamera& camera = config_.simulator.depth.camera;
    const sensor_msgs::CameraInfo info = toCameraInfoMsg(camera.width, camera.height, camera.fx,
                                                         camera.fy, camera.cx, camera.cy, header);
    depth_pub_.publish(
        toImageMsg(frame.depth_mm, sensor_msgs::image_encodings::TYPE_16UC1, header));
    depth_info_pub_.publish(info);
    if (colour_pub_.getNumSubscribers() > 0) {
      colour_pub_.publish(toImageMsg(frame.colour, sensor_msgs::image_encodings::BGR8, header));
    }
    colour_info_pub_.publish(info);
  }

  void startImu(ros::NodeHandle& nh) {
    imu_pub_ = nh.advertise<sensor_msgs::Imu>("imu", 1000);
    imu_tf_.emplace();
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = ros::Time::now();
    mount.header.frame_id = config_.edvs_frame;
    mount.child_frame_id = config_.imu_frame;
    const Eigen::Quaterniond q = ebslam::edvsFromImu(config_.simulator);
    mount.transform.rotation.w = q.w();
    mount.transform.rotation.x = q.x();
    mount.transform.rotation.y = q.y();
    mount.transform.rotation.z = q.z();
    imu_tf_->sendTransform(mount);
  }

  // Readings of the current pass up to t_s [trajectory clock], stamped on the event clock.
  void publishImu(double t_s) {
    if (!config_.publish_imu) return;
    const ebslam::ImuSimulatorConfig& c = config_.simulator.imu;
    // White noise densities as per-reading variances (rate_hz sigma_density^2); the bias is not
    // in them (it drifts; the gyro bias' std. dev. grows by the random walk).
    const double gyro_var = c.gyro_noise_density * c.gyro_noise_density * c.rate_hz;
    const double accel_var = c.accel_noise_density * c.accel_noise_density * c.rate_hz;
    for (; next_imu_ < imu_readings_.size() && imu_readings_[next_imu_].t_s <= t_s; ++next_imu_) {
      const ebslam::ImuReading& r = imu_readings_[next_imu_];
      const std::int64_t t_us = std::llround(r.t_s * 1e6);
      if (t_us <= last_imu_us_) continue;  // a pass starts where the previous one ended
      last_imu_us_ = t_us;
      sensor_msgs::Imu msg;
      msg.header.stamp = events_->rosTime(t_us);
      msg.header.frame_id = config_.imu_frame;
      msg.orientation_covariance[0] = -1.0;  // no orientation estimate
      msg.angular_velocity.x = r.gyro.x();
      msg.angular_velocity.y = r.gyro.y();
      msg.angular_velocity.z = r.gyro.z();
      msg.linear_acceleration.x = r.accel.x();
      msg.linear_acceleration.y = r.accel.y();
      msg.linear_acceleration.z = r.accel.z();
      for (int k = 0; k < 3; ++k) {
        msg.angular_velocity_covariance[static_cast<std::size_t>(4 * k)] = gyro_var;
        msg.linear_acceleration_covariance[static_cast<std::size_t>(4 * k)] = accel_var;
      }
      imu_pub_.publish(msg);
    }
  }

  void publishGroundTruth(double t_s, const ros::Time& stamp) {
    ground_truth_->publish(ebslam::interpolatePose(pass_path_, t_s), stamp,
                           events_->messages() % 10 == 0);
  }

  RgbdEventSimulatorNodeConfig config_;
  ebslam::Trajectory path_;  // rig (depth optical frame) -> world, trajectory clock [s]
  ebslam::Scene scene_;
  ebslam::Trajectory reversed_path_;    // path_ driven backwards over [t_begin_, t_end_]
  ebslam::Trajectory pass_path_;        // the path of the pass being simulated
  double t_begin_ = 0.0, t_end_ = 0.0;  // trajectory clock [s]
  double pass_end_ = 0.0;               // end of the pass being simulated [s, trajectory clock]
  std::uint32_t frames_ = 0;
  ros::Publisher depth_pub_, depth_info_pub_, colour_pub_, colour_info_pub_;
  std::optional<PacedEventPublisher> events_;
  std::optional<GroundTruthPublisher> ground_truth_;
  ros::Publisher imu_pub_;
  std::optional<tf2_ros::StaticTransformBroadcaster> imu_tf_;
  std::vector<ebslam::ImuReading> imu_readings_;  // of the pass being simulated
  std::size_t next_imu_ = 0;
  std::int64_t last_imu_us_ = std::numeric_limits<std::int64_t>::min();
  std::atomic<bool> stop_{false};
  ros::Publisher edvs_info_pub_;
  std::thread worker_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::RgbdEventSimulatorNodelet, nodelet::Nodelet)
