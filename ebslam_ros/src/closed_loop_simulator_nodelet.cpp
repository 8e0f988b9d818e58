// Closed-loop floor robot for exploration (thesis 7.4) as a nodelet: ebslam::ClosedLoopSimulator
// (closed_loop_simulator.h), a differential-drive disc robot with a bump ring in a room given by
// ~floor_plan, under a seeded ceiling seen by an upward eDVS, driven by velocity commands.
// Topics (relative names):
//  - cmd_vel (geometry_msgs/Twist, in): linear.x [m/s], angular.z [rad/s] in ~base_frame,
//    clamped to the robot's limits; none for ~cmd_timeout (simulated) or a non-finite one: the
//    robot brakes to a stop;
//  - events (ebslam_msgs/EventArray): the eDVS events of each ~step, in ~frame_id, width x
//    height of ~camera; header.stamp = ts of the last event (the step's end when empty);
//  - bump (ebslam_msgs/Bump): the bump ring's reading at each step's end, in ~base_frame;
//  - ground_truth/pose (geometry_msgs/PoseStamped), ground_truth/path (nav_msgs/Path, only
//    while subscribed, the last ~path_length poses) and tf ~map_frame -> ~ground_truth_frame:
//    the true sensor (optical frame) pose at each step's end, as EventSimulator;
//  - floor_plan (visualization_msgs/Marker, latched): walls and obstacles as lines;
//  - /clock (with ~publish_clock; run the other nodes with use_sim_time);
//  - lockstep/pose (geometry_msgs/PoseWithCovarianceStamped, in, with ~lockstep): the pose of the
//    localisation that consumes `events` (EventSlam2d's `pose`, stamped with its last event).
// Frames: ~map_frame has its origin at the robot's start pose (x forward, z up), which is where
// EventSlam2d's map frame lies with its default ~initial_pose (0, 0, 0) and an identity mount.
// Time: simulated time t [s] is stamped anchor + t / ~speed (anchor: wall time at the start) or
// ~clock_start + t with /clock; steps are paced at ~speed times real time (or run as fast as
// they are simulated when that is slower). The simulation runs in a thread of its own.
// Lockstep (~lockstep, needs ~publish_clock): the closed loop of the offline tool ebslam_explore
// (ebslam/simulation/exploration_run.h) through ROS, independent of the machine's load. After each
// step the simulator waits until lockstep/pose carries the stamp of the step's last event (the
// localisation has processed them all), then publishes /clock at the step's end and waits for the
// next cmd_vel (the controller's step on that clock tick, e.g. Exploration with ~control_rate =
// 1 / ~step), which drives the next step. A wait longer than ~lockstep_timeout (wall) is logged
// and the step goes on with what arrived. ~speed is then an upper bound of the pace.
#include <ebslam_msgs/Bump.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <nodelet/nodelet.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <visualization_msgs/Marker.h>

#include <ebslam/events/event_clock.h>
#include <ebslam/simulation/closed_loop_simulator.h>
#include <ebslam/simulation/floor_plan.h>
#include <ebslam/simulation/simulator_scenes.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <thread>

#include "closed_loop_simulator_params.h"
#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/ground_truth_publisher.h"

namespace ebslam_ros {

class ClosedLoopSimulatorNodelet : public nodelet::Nodelet {
 public:
  ~ClosedLoopSimulatorNodelet() override {
    stop_ = true;
    arrived_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  static constexpr double kWarnPeriodS = 5.0;  // throttle of repeated warnings [s, wall]

  void onInit() override {
    const std::string package = ros::package::getPath("ebslam_ros");
    const std::string default_plan =
        package.empty() ? "" : package + "/data/floor_plans/office.txt";
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(
        getPrivateNodeHandle(), "closed-loop simulator " + getName(), [&] {
          config_ = loadClosedLoopSimulatorNodeConfig(getPrivateNodeHandle(), default_plan);
          plan_ = ebslam::readFloorPlan(config_.floor_plan, config_.simulator.robot.radius_m);
          simulator_ = std::make_unique<ebslam::ClosedLoopSimulator>(plan_, config_.simulator);
        });
    ros::NodeHandle& nh = getNodeHandle();
    events_pub_ = nh.advertise<ebslam_msgs::EventArray>("events", 1000);
    bump_pub_ = nh.advertise<ebslam_msgs::Bump>("bump", 100);
    ground_truth_.emplace(nh, config_.map_frame, config_.ground_truth_frame,
                          static_cast<std::size_t>(config_.path_length));
    plan_pub_ = nh.advertise<visualization_msgs::Marker>("floor_plan", 1, true);
    if (config_.publish_clock) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    cmd_sub_ = nh.subscribe("cmd_vel", 10, &ClosedLoopSimulatorNodelet::onCommand, this,
                            ros::TransportHints().tcpNoDelay());
    if (config_.lockstep) {
      pose_sub_ = nh.subscribe("lockstep/pose", 10, &ClosedLoopSimulatorNodelet::onPose, this,
                               ros::TransportHints().tcpNoDelay());
    }
    NODELET_INFO("closed-loop simulation of '%s' (%s), step %.3f s at %.2fx%s%s",
                 plan_.name.c_str(), config_.floor_plan.c_str(), config_.step_s, config_.speed,
                 config_.publish_clock ? " with /clock" : "",
                 config_.lockstep ? " in lockstep with lockstep/pose and cmd_vel" : "");
    worker_ = std::thread([this] { run(); });
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (msg->header.stamp > pose_stamp_) pose_stamp_ = msg->header.stamp;
    }
    arrived_.notify_all();
  }

  // Lockstep: waits (wall time) until `done` holds under mutex_; false (logged) on a timeout.
  template <typename Predicate>
  bool waitFor(Predicate done, const char* what) {
    std::unique_lock<std::mutex> lock(mutex_);
    const bool ok =
        arrived_.wait_for(lock, std::chrono::duration<double>(config_.lockstep_timeout_s),
                          [&] { return stop_ || done(); });
    if (!ok) {
      ++lockstep_timeouts_;
      const ros::WallTime now = ros::WallTime::now();
      if (lockstep_warned_.isZero() || (now - lockstep_warned_).toSec() >= kWarnPeriodS) {
        lockstep_warned_ = now;
        NODELET_WARN("lockstep: no %s within %.1f s (wall); going on (%zu such waits so far)", what,
                     config_.lockstep_timeout_s, lockstep_timeouts_);
      }
    }
    return ok;
  }

  void onCommand(const geometry_msgs::Twist::ConstPtr& msg) {
    struct Notify {
      std::condition_variable& cv;
      ~Notify() { cv.notify_all(); }
    } notify{arrived_};
    std::lock_guard<std::mutex> lock(mutex_);
    ++commands_;
    if (!std::isfinite(msg->linear.x) || !std::isfinite(msg->angular.z)) {
      command_.reset();  // brake
      const ros::WallTime now = ros::WallTime::now();
      if (warned_.isZero() || (now - warned_).toSec() >= kWarnPeriodS) {
        warned_ = now;
        NODELET_ERROR("non-finite cmd_vel (%g m/s, %g rad/s): braking", msg->linear.x,
                      msg->angular.z);
      }
      return;
    }
    command_ = ebslam::VelocityCommand{msg->linear.x, msg->angular.z};
    command_time_s_ = sim_time_s_;
  }

  // Room frame -> ~map_frame (origin at the start pose).
  ebslam::Pose2 toMap(const ebslam::Pose2& room) const {
    const ebslam::Pose2& s = plan_.start;
    const double c = std::cos(s.theta), n = std::sin(s.theta);
    const double dx = room.x - s.x, dy = room.y - s.y;
    return {c * dx + n * dy, -n * dx + c * dy, std::remainder(room.theta - s.theta, 2.0 * M_PI)};
  }

  void run() {
    if (config_.wait_for_subscribers || config_.lockstep) {
      // roscpp counts a subscriber before its side of the connection is ready.
      while (!stop_ && (events_pub_.getNumSubscribers() == 0 ||
                        (config_.lockstep && (pose_sub_.getNumPublishers() == 0 ||
                                              cmd_sub_.getNumPublishers() == 0)))) {
        ros::WallDuration(0.05).sleep();
      }
      ros::WallDuration(0.5).sleep();
    }
    if (stop_) return;
    const ros::Time anchor =
        config_.publish_clock ? ros::Time(config_.clock_start_s) : ros::Time::now();
    ebslam::EventClock clock(config_.publish_clock ? 1.0 : config_.speed);
    clock.anchor(0, ebslam_msgs::toMicroseconds(anchor));
    const ros::WallTime wall_start = ros::WallTime::now();
    if (config_.lockstep) {
      // The first step runs on the command of the tick at time 0, as every later one.
      std::size_t commands = 0;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        commands = commands_;
      }
      publishClock(anchor);
      waitFor([&] { return commands_ > commands; }, "cmd_vel after the clock tick");
    } else if (config_.publish_clock) {
      publishClock(anchor);
    }
    publishFloorPlan(anchor);
    const ebslam::SensorSize sensor{
        static_cast<std::uint32_t>(config_.simulator.events.camera.width),
        static_cast<std::uint32_t>(config_.simulator.events.camera.height)};
    ebslam::EventVector events;
    try {
      while (!stop_) {
        ebslam::VelocityCommand command;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (command_ && sim_time_s_ - command_time_s_ <= config_.cmd_timeout_s) {
            command = *command_;
          }
        }
        events.clear();
        const ebslam::BumpReading bump = simulator_->step(command, config_.step_s, events);
        const double t = simulator_->time();
        {
          std::lock_guard<std::mutex> lock(mutex_);
          sim_time_s_ = t;
        }
        const ros::WallTime due = wall_start + ros::WallDuration(t / config_.speed);
        while (!stop_ && ros::WallTime::now() < due) {
          std::min(due - ros::WallTime::now(), ros::WallDuration(0.1)).sleep();
        }
        if (stop_) break;
        const ros::Time stamp =
            ebslam_msgs::toRosTime(clock.map(std::llround(t * 1e6)).value_or(0));
        // Lockstep: the clock moves on only once the step's events are localised (below).
        if (config_.publish_clock && !config_.lockstep) publishClock(stamp);
        for (ebslam::Event& e : events) e.t_us = clock.stamp(e.t_us).value_or(0);
        ebslam_msgs::EventArray msg = ebslam_msgs::toMsg(events, sensor, config_.frame_id);
        if (events.empty()) msg.header.stamp = stamp;
        events_pub_.publish(msg);
        ebslam_msgs::Bump reading;
        reading.header.stamp = stamp;
        reading.header.frame_id = config_.base_frame;
        reading.segment_count = static_cast<std::uint8_t>(bump.segment_count);
        reading.segments = bump.segments;
        reading.direction = bump.contact() ? bump.direction_rad : 0.0;
        bump_pub_.publish(reading);
        publishGroundTruth(stamp);
        if (config_.lockstep) {
          if (!events.empty()) {
            const ros::Time last_event = msg.header.stamp;
            waitFor([&] { return pose_stamp_ >= last_event; }, "pose of the step's last event");
          }
          std::size_t commands = 0;
          {
            std::lock_guard<std::mutex> lock(mutex_);
            commands = commands_;
          }
          publishClock(stamp);
          waitFor([&] { return commands_ > commands; }, "cmd_vel after the clock tick");
        }
      }
    } catch (const std::exception& error) {
      NODELET_ERROR("simulation failed: %s", error.what());
    }
  }

  void publishClock(const ros::Time& time) {
    rosgraph_msgs::Clock clock;
    clock.clock = time;
    clock_pub_.publish(clock);
  }

  void publishGroundTruth(const ros::Time& stamp) {
    const ebslam::Pose2 p = toMap(simulator_->pose());
    const ros::WallTime now = ros::WallTime::now();
    const bool path_due = (now - last_path_).toSec() >= 1.0;
    if (path_due) last_path_ = now;
    ground_truth_->publish(ebslam::se2ToFloorPose(0.0, p.x, p.y, p.theta), stamp, path_due);
  }

  void publishFloorPlan(const ros::Time& stamp) {
    visualization_msgs::Marker m;
    m.header.stamp = stamp;
    m.header.frame_id = config_.map_frame;
    m.ns = "floor_plan";
    m.type = visualization_msgs::Marker::LINE_LIST;
    m.pose.orientation.w = 1.0;
    m.scale.x = 0.03;  // line width [m]
    m.color.r = m.color.g = m.color.b = 0.9f;
    m.color.a = 1.0f;
    const auto add = [&](const ebslam::Polygon2& polygon) {
      for (std::size_t i = 0; i < polygon.size(); ++i) {
        for (const Eigen::Vector2d& v : {polygon[i], polygon[(i + 1) % polygon.size()]}) {
          const ebslam::Pose2 q = toMap({v.x(), v.y(), 0.0});
          geometry_msgs::Point p;
          p.x = q.x;
          p.y = q.y;
          m.points.push_back(p);
        }
      }
    };
    add(plan_.walls);
    for (const ebslam::Polygon2& obstacle : plan_.obstacles) add(obstacle);
    plan_pub_.publish(m);
  }

  ClosedLoopSimulatorNodeConfig config_;
  ebslam::FloorPlan plan_;
  std::unique_ptr<ebslam::ClosedLoopSimulator> simulator_;
  std::mutex mutex_;  // guards command_, command_time_s_, sim_time_s_, warned_, lockstep state
  std::condition_variable arrived_;  // lockstep: a pose or a command arrived
  ros::Time pose_stamp_;             // lockstep: latest stamp on lockstep/pose
  std::size_t commands_ = 0;         // cmd_vel messages received
  std::size_t lockstep_timeouts_ = 0;
  ros::WallTime lockstep_warned_;
  std::optional<ebslam::VelocityCommand> command_;
  double command_time_s_ = 0.0;  // simulated time of the last command's arrival [s]
  double sim_time_s_ = 0.0;
  ros::WallTime warned_, last_path_;
  ros::Subscriber cmd_sub_, pose_sub_;
  ros::Publisher events_pub_, bump_pub_, plan_pub_, clock_pub_;
  std::optional<GroundTruthPublisher> ground_truth_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::ClosedLoopSimulatorNodelet, nodelet::Nodelet)
