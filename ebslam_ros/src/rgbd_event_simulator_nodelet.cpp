// Simulated D-eDVS (thesis 8.2, ebslam/dedvs_simulator.h): an eDVS 128x128 and a PrimeSense-like
// depth camera with registered colour on a hand-held rig moving along a TUM trajectory through
// a furnished room (ebslam/dedvs_scene.h). Publications (relative names):
//  - events (ebslam_msgs/EventArray): ~publish_rate messages per simulated second in
//    ~edvs_frame; header.stamp = ts of the last event;
//  - depth_registered/image_raw (sensor_msgs/Image 16UC1, millimetres, 0 = no depth) and
//    depth_registered/camera_info, rgb/image_rect_color (bgr8, registered to the depth) and
//    rgb/camera_info, all in ~depth_frame, stamped with the depth camera's own clock (exposure
//    time + ~depth_clock_offset), the names dasp_ros uses;
//  - ground_truth/pose (geometry_msgs/PoseStamped), ground_truth/path (nav_msgs/Path, bounded):
//    the rig (the depth optical frame) in ~map_frame at each event message's end, and the tf
//    ~map_frame -> ~ground_truth_frame;
//  - /clock (with ~publish_clock; run the other nodes with use_sim_time).
// Time: trajectory time t [s] is stamped anchor + (t - start), the anchor being ~clock_start
// with /clock, else the wall time at the start (stamps then advance with t / ~speed, as the
// EventSimulator). Pacing: the message for t is sent at wall_start + (t - start) / ~speed, or as
// soon as simulated when the simulator is slower. Seeded (~seed): the same run every time.
// The simulation runs in a thread of its own; the nodelet stops it on unload.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_ros/transform_broadcaster.h>

#include <ebslam/dedvs_io.h>
#include <ebslam/dedvs_scene.h>
#include <ebslam/dedvs_simulator.h>
#include <ebslam/event_clock.h>
#include <ebslam/trajectory.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>
#include <thread>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/ros_params.h"

namespace ebslam_ros {
namespace {

sensor_msgs::CameraInfo cameraInfoOf(const ebslam::PinholeCamera& c,
                                     const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = static_cast<std::uint32_t>(c.width);
  info.height = static_cast<std::uint32_t>(c.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);  // the simulated images are rectified
  info.K = {c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

// A continuous CV_16UC1 or CV_8UC3 image -> Image message (copied).
sensor_msgs::Image imageOf(const cv::Mat& image, const std::string& encoding,
                           const std_msgs::Header& header) {
  const cv::Mat data = image.isContinuous() ? image : image.clone();
  sensor_msgs::Image msg;
  msg.header = header;
  msg.width = static_cast<std::uint32_t>(data.cols);
  msg.height = static_cast<std::uint32_t>(data.rows);
  msg.encoding = encoding;
  msg.is_bigendian = 0;
  msg.step = static_cast<std::uint32_t>(data.cols * data.elemSize());
  msg.data.resize(static_cast<std::size_t>(msg.step) * msg.height);
  std::memcpy(msg.data.data(), data.data, msg.data.size());
  return msg;
}

}  // namespace

class RgbdEventSimulatorNodelet : public nodelet::Nodelet {
 public:
  ~RgbdEventSimulatorNodelet() override {
    stop_ = true;
    if (worker_.joinable()) worker_.join();
  }

 private:
  struct Stopped {};  // thrown from the sinks to end the simulation early

  void onInit() override {
    const std::string package = ros::package::getPath("ebslam_ros");
    const std::string default_trajectory =
        package.empty() ? "" : package + "/../test/data/sample_session/pioneer_360_excerpt.txt";
    try {
      config_ = loadRgbdEventSimulatorNodeConfig(getPrivateNodeHandle(), default_trajectory);
      prepare();
    } catch (const std::exception& error) {
      NODELET_ERROR("RGB-D event simulator not started: %s", error.what());
      return;
    }
    ros::NodeHandle& nh = getNodeHandle();
    events_pub_ = nh.advertise<ebslam_msgs::EventArray>("events", 1000);
    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth_registered/image_raw", 10);
    depth_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("depth_registered/camera_info", 10);
    colour_pub_ = nh.advertise<sensor_msgs::Image>("rgb/image_rect_color", 10);
    colour_info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 10);
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("ground_truth/pose", 100);
    path_pub_ = nh.advertise<nav_msgs::Path>("ground_truth/path", 1, true);
    if (config_.publish_clock) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    NODELET_INFO("simulating the D-eDVS along '%s' from %.2f to %.2f s at %.2fx%s (%zu planes)",
                 config_.trajectory.c_str(), t_begin_ - path_.front().t_s,
                 t_end_ - path_.front().t_s, config_.speed,
                 config_.publish_clock ? " with /clock" : "", scene_.planes.size());
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
    simulator_ = std::make_unique<ebslam::DedvsSimulator>(config_.simulator);
    if (!config_.write_calibration.empty()) {
      ebslam::writeDedvsSensors(config_.write_calibration, ebslam::sensorsOf(config_.simulator));
    }
  }

  void run() {
    if (config_.wait_for_subscribers) {
      // roscpp counts a subscriber before its side of the connection is ready.
      while (!stop_ && events_pub_.getNumSubscribers() == 0) ros::WallDuration(0.05).sleep();
      ros::WallDuration(0.5).sleep();
    }
    if (stop_) return;
    const double stamp_speed = config_.publish_clock ? 1.0 : config_.speed;
    const ros::Time anchor_time =
        config_.publish_clock ? ros::Time(config_.clock_start_s) : ros::Time::now();
    clock_ = ebslam::EventClock(stamp_speed);
    clock_.anchor(std::llround(t_begin_ * 1e6), ebslam_msgs::toMicroseconds(anchor_time));
    wall_start_ = ros::WallTime::now();
    next_boundary_us_ = std::llround(t_begin_ * 1e6) + periodUs();
    if (config_.publish_clock) publishClock(anchor_time);
    const ebslam::SensorSize sensor{static_cast<std::uint32_t>(config_.simulator.edvs.width),
                                    static_cast<std::uint32_t>(config_.simulator.edvs.height)};
    try {
      const ebslam::DedvsRun result = simulator_->simulate(
          scene_, path_, t_begin_, t_end_,
          [&](const std::vector<ebslam::TrueDepthEvent>& events) {
            if (stop_) throw Stopped{};
            for (const ebslam::TrueDepthEvent& e : events) {
              while (e.event.t_us >= next_boundary_us_) flush(sensor);
              pending_.push_back(e.event);
            }
          },
          [&](const ebslam::DepthFrame& frame) {
            if (stop_) throw Stopped{};
            // Events up to the exposure go out first (pacing), then the frame.
            while (std::llround(frame.t_s * 1e6) >= next_boundary_us_) flush(sensor);
            publishFrame(frame);
          });
      // The last message ends at ~t_end (a depth frame there may have sent it already).
      const std::int64_t end_us = std::llround(t_end_ * 1e6);
      if (last_end_us_ < end_us || !pending_.empty()) {
        next_boundary_us_ = std::min(next_boundary_us_, end_us);
        flush(sensor);
      }
      NODELET_INFO(
          "simulation done: %zu events (%zu signal, %zu noise) in %u messages, %u depth "
          "frames",
          result.signal_events + result.noise_events, result.signal_events, result.noise_events,
          sequence_, frames_);
    } catch (const Stopped&) {
    } catch (const std::exception& error) {
      NODELET_ERROR("simulation failed: %s", error.what());
    }
  }

  std::int64_t periodUs() const { return std::llround(1e6 / config_.publish_rate_hz); }

  // Publishes the events before next_boundary_us_ (the message's end) once its time has come.
  void flush(const ebslam::SensorSize& sensor) {
    const std::int64_t end_us = next_boundary_us_;
    last_end_us_ = end_us;
    next_boundary_us_ += periodUs();
    const double t_end_s = 1e-6 * static_cast<double>(end_us);
    const ros::WallTime due = wall_start_ + ros::WallDuration((t_end_s - t_begin_) / config_.speed);
    while (!stop_) {
      const ros::WallTime now = ros::WallTime::now();
      if (now >= due) break;
      (due - now).sleep();
    }
    if (stop_) throw Stopped{};
    const ros::Time stamp_end = ebslam_msgs::toRosTime(clock_.map(end_us).value_or(-1));
    if (config_.publish_clock) publishClock(stamp_end);
    if (!pending_.empty()) {
      for (ebslam::Event& e : pending_) e.t_us = clock_.stamp(e.t_us).value_or(-1);
      ebslam_msgs::EventArray msg = ebslam_msgs::toMsg(pending_, sensor, config_.edvs_frame);
      msg.header.seq = sequence_++;
      events_pub_.publish(msg);
      pending_.clear();
    }
    publishGroundTruth(std::min(t_end_s, t_end_), stamp_end);
  }

  void publishFrame(const ebslam::DepthFrame& frame) {
    std_msgs::Header header;
    header.seq = frames_++;
    header.frame_id = config_.depth_frame;
    // The depth camera's own clock (exposure + offset), mapped as the event clock.
    header.stamp =
        ebslam_msgs::toRosTime(clock_.map(std::llround(frame.stamp_s * 1e6)).value_or(-1));
    const sensor_msgs::CameraInfo info = cameraInfoOf(config_.simulator.depth.camera, header);
    depth_pub_.publish(imageOf(frame.depth_mm, sensor_msgs::image_encodings::TYPE_16UC1, header));
    depth_info_pub_.publish(info);
    if (colour_pub_.getNumSubscribers() > 0) {
      colour_pub_.publish(imageOf(frame.colour, sensor_msgs::image_encodings::BGR8, header));
    }
    colour_info_pub_.publish(info);
  }

  void publishClock(const ros::Time& time) {
    rosgraph_msgs::Clock clock;
    clock.clock = time;
    clock_pub_.publish(clock);
  }

  void publishGroundTruth(double t_s, const ros::Time& stamp) {
    const ebslam::StampedPose pose = ebslam::interpolatePose(path_, t_s);
    geometry_msgs::PoseStamped msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = config_.map_frame;
    msg.pose.position.x = pose.position.x();
    msg.pose.position.y = pose.position.y();
    msg.pose.position.z = pose.position.z();
    msg.pose.orientation.x = pose.orientation.x();
    msg.pose.orientation.y = pose.orientation.y();
    msg.pose.orientation.z = pose.orientation.z();
    msg.pose.orientation.w = pose.orientation.w();
    pose_pub_.publish(msg);
    geometry_msgs::TransformStamped tf;
    tf.header = msg.header;
    tf.child_frame_id = config_.ground_truth_frame;
    tf.transform.translation.x = msg.pose.position.x;
    tf.transform.translation.y = msg.pose.position.y;
    tf.transform.translation.z = msg.pose.position.z;
    tf.transform.rotation = msg.pose.orientation;
    tf_broadcaster_.sendTransform(tf);
    ground_truth_path_.push_back(msg);
    while (ground_truth_path_.size() > static_cast<std::size_t>(config_.path_length)) {
      ground_truth_path_.pop_front();
    }
    if (path_pub_.getNumSubscribers() > 0 && sequence_ % 10 == 0) {
      nav_msgs::Path path;
      path.header = msg.header;
      path.poses.assign(ground_truth_path_.begin(), ground_truth_path_.end());
      path_pub_.publish(path);
    }
  }

  RgbdEventSimulatorNodeConfig config_;
  ebslam::Trajectory path_;  // rig (depth optical frame) -> world, trajectory clock [s]
  ebslam::Scene scene_;
  std::unique_ptr<ebslam::DedvsSimulator> simulator_;
  double t_begin_ = 0.0, t_end_ = 0.0;  // trajectory clock [s]
  ebslam::EventClock clock_;            // simulated time -> ROS time
  ros::WallTime wall_start_;
  std::int64_t next_boundary_us_ = 0;
  std::int64_t last_end_us_ = 0;  // end of the last message sent [us, trajectory clock]
  ebslam::EventVector pending_;
  std::uint32_t sequence_ = 0, frames_ = 0;
  std::deque<geometry_msgs::PoseStamped> ground_truth_path_;
  ros::Publisher events_pub_, depth_pub_, depth_info_pub_, colour_pub_, colour_info_pub_, pose_pub_,
      path_pub_, clock_pub_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::RgbdEventSimulatorNodelet, nodelet::Nodelet)
