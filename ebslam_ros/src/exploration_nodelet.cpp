// Autonomous exploration (thesis 7.4) as a nodelet: ebslam::Explorer (exploration.h, ~planner
// gain) or ebslam::CoverageExplorer (coverage.h, ~planner coverage: lanes on a grid learned from
// bumps) driven by EB-SLAM's pose, its normalisation map (gain only) and the bump ring. Topics
// (relative names):
//  - pose (geometry_msgs/PoseWithCovarianceStamped, in), base_link in ~map_frame as EventSlam2d
//    publishes it; the first pose centres the hex grid (or ~initial_pose, when set, from the first
//    control step until the first pose: the localisation's start, as ebslam_explore starts);
//  - bump (ebslam_msgs/Bump, in): the bump ring's readings; a contact in any reading since the
//    last control step counts (pressed segments of all of them, the last one's direction);
//  - map/normalisation (nav_msgs/OccupancyGrid, in, with ~use_localisation_map): EventSlam2d's
//    normalisation map Z (linearly scaled; the eq. 7.8 normalisation ignores the scale), read
//    into the localisation exploration map at every replanning;
//  - cmd_vel (geometry_msgs/Twist, out): v = linear.x [m/s], omega = angular.z [rad/s] in
//    base_link, every control step (~control_rate); zero while stopped;
//  - plan (nav_msgs/Path, out): the robot's position and the planned cell centres still to
//    drive, in ~map_frame, stamped with the last pose's stamp; sent when it changes;
//  - grid_markers (visualization_msgs/MarkerArray, out, only while subscribed, every
//    ~markers_period): the hex grid as cubes coloured by Z, E and the gain (namespaces
//    "localisation_Z", "obstacle_E", "gain"; blue = low, red = high, cells with a value only),
//    "blocked" cells (near black) and "bumps" (contact points, orange); coverage planner: grid
//    cells "swept" (light red), "blocked" (near black), "open" (lane samples still to sweep:
//    the frontier, green), the "lanes" driven (lines) and "bumps";
//  - done (std_msgs/Bool, out, latched): false until the coverage planner finds nothing reachable
//    left unswept, then true (it then returns to the start and stops); always false for gain.
// Bad input (logged throttled on wall time, counted in diagnostics): no pose for ~pose_timeout
// (zero cmd_vel, state no_pose), a pose jumping (the plan is dropped and made anew), bumps on
// every side or too many in a row (state stuck, zero cmd_vel, retried after 2 s), poses in
// another frame than ~map_frame and malformed bump readings or Z maps (dropped).
// Time: control steps run on ROS time (sim time with /clock).
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_msgs/Bump.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <visualization_msgs/MarkerArray.h>

#include <ebslam/slam/coverage.h>
#include <ebslam/slam/exploration.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <string>
#include <vector>

#include "exploration_params.h"

namespace ebslam_ros {

class ExplorationNodelet : public nodelet::Nodelet {
 private:
  static constexpr double kWarnPeriodS = 5.0;  // throttle of repeated warnings [s, wall]

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "exploration " + getName(), [&] {
      config_ = loadExplorationNodeConfig(getPrivateNodeHandle());
    });
    ros::NodeHandle& nh = getNodeHandle();
    cmd_pub_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 10);
    plan_pub_ = nh.advertise<nav_msgs::Path>("plan", 1, true);
    markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("grid_markers", 1);
    done_pub_ = nh.advertise<std_msgs::Bool>("done", 1, true);
    std_msgs::Bool done;
    done_pub_.publish(done);
    pose_sub_ = nh.subscribe("pose", 10, &ExplorationNodelet::onPose, this);
    bump_sub_ = nh.subscribe("bump", 100, &ExplorationNodelet::onBump, this);
    if (config_.use_localisation_map && !config_.coverage_planner) {
      z_sub_ = nh.subscribe("map/normalisation", 1, &ExplorationNodelet::onNormalisation, this);
    }
    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, getPrivateNodeHandle());
    diagnostics_->setHardwareID("none");
    diagnostics_->add(getName(), this, &ExplorationNodelet::diagnose);
    diagnostics_timer_ =
        nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
          std::lock_guard<std::mutex> lock(mutex_);
          diagnostics_->update();
        });
    control_timer_ = nh.createTimer(ros::Duration(1.0 / config_.control_rate_hz),
                                    &ExplorationNodelet::onControl, this);
    start_time_ = ros::Time::now();
    if (config_.coverage_planner) {
      NODELET_INFO(
          "covering in lanes %.2f m apart on a %.2f m grid of %.1f m, at most %.2f m/s, "
          "%.0f Hz control",
          config_.coverage.lane_spacing_m, config_.coverage.cell_m, config_.coverage.grid_extent_m,
          config_.coverage.max_speed_mps, config_.control_rate_hz);
    } else {
      NODELET_INFO("exploring on a %.2f m hex grid of %.1f m, at most %.2f m/s, %.0f Hz control%s",
                   config_.exploration.hex_spacing_m, config_.exploration.grid_extent_m,
                   config_.exploration.max_speed_mps, config_.control_rate_hz,
                   config_.use_localisation_map ? "" : " (no localisation map Z)");
    }
  }

  // Yaw [rad] of a quaternion about z (NaN for a zero quaternion).
  static double yawOf(const geometry_msgs::Quaternion& q) {
    const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (!(n > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    const double x = q.x / n, y = q.y / n, z = q.z / n, w = q.w / n;
    return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  }

  // ROS_*_THROTTLE runs on ROS time, which a simulation may restart: throttle on wall time.
  static bool due(ros::WallTime& last) {
    const ros::WallTime now = ros::WallTime::now();
    if (!last.isZero() && (now - last).toSec() < kWarnPeriodS) return false;
    last = now;
    return true;
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++poses_;
    if (msg->header.frame_id != config_.map_frame) {
      ++wrong_frame_;
      ++bad_input_seen_;
      if (due(frame_warned_)) {
        NODELET_ERROR("pose in frame '%s' dropped: expected ~map_frame '%s'",
                      msg->header.frame_id.c_str(), config_.map_frame.c_str());
      }
      return;
    }
    const auto& p = msg->pose.pose;
    // A non-finite pose reaches the explorer, which counts it as no pose.
    pending_pose_ = ebslam::Pose2{p.position.x, p.position.y, yawOf(p.orientation)};
    pose_stamp_ = msg->header.stamp;
    pose_seen_ = true;
  }

  void onBump(const ebslam_msgs::Bump::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++bump_messages_;
    const int n = msg->segment_count;
    const bool bad_count = n < 1 || n > 32;
    const bool bad_bits = !bad_count && n < 32 && (msg->segments >> n) != 0u;
    if (bad_count || bad_bits || (msg->segments != 0u && !std::isfinite(msg->direction))) {
      ++bad_bumps_;
      ++bad_input_seen_;
      if (due(bump_warned_)) {
        NODELET_ERROR("bump reading dropped: segment_count %d (1..32), segments 0x%x, direction %g",
                      n, msg->segments, msg->direction);
      }
      return;
    }
    if (msg->segments == 0u) return;
    ++contacts_;
    pending_bump_.segment_count = n;
    pending_bump_.segments |= msg->segments;
    pending_bump_.direction_rad = msg->direction;
  }

  void onNormalisation(const nav_msgs::OccupancyGrid::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& info = msg->info;
    const double origin_yaw = yawOf(info.origin.orientation);  // NaN (zero quaternion): unrotated
    if (msg->header.frame_id != config_.map_frame || info.width == 0 || info.height == 0 ||
        !(info.resolution > 0.0f) ||
        msg->data.size() != static_cast<std::size_t>(info.width) * info.height ||
        std::abs(origin_yaw) > 1e-6) {
      ++bad_maps_;
      ++bad_input_seen_;
      if (due(map_warned_)) {
        NODELET_ERROR(
            "normalisation map dropped: needs frame '%s' (got '%s'), an unrotated origin and "
            "width x height cells (%ux%u, %zu values)",
            config_.map_frame.c_str(), msg->header.frame_id.c_str(), info.width, info.height,
            msg->data.size());
      }
      return;
    }
    z_.emplace(static_cast<int>(info.width), static_cast<int>(info.height), info.resolution,
               info.origin.position.x, info.origin.position.y);
    // -1 (unknown) is a cell never observed: Z = 0.
    for (std::size_t i = 0; i < msg->data.size(); ++i) {
      z_->data[i] = std::max<float>(0.0f, msg->data[i]);
    }
    ++z_maps_;
  }

  void onControl(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time now = ros::Time::now();
    if (!pending_pose_ && !pose_seen_ && config_.initial_pose) {
      pending_pose_ = config_.initial_pose;  // the localisation's start, until its first pose
    }
    if (!started() && pending_pose_ && std::isfinite(pending_pose_->x) &&
        std::isfinite(pending_pose_->y)) {
      try {
        if (config_.coverage_planner) {
          // The start is where the robot returns; its heading does not matter.
          const ebslam::Pose2 start{
              pending_pose_->x, pending_pose_->y,
              std::isfinite(pending_pose_->theta) ? pending_pose_->theta : 0.0};
          coverer_.emplace(config_.coverage, start);
        } else {
          explorer_.emplace(config_.exploration,
                            Eigen::Vector2d(pending_pose_->x, pending_pose_->y));
        }
        NODELET_INFO("%s (%.2f, %.2f) m: the exploration grid is centred there",
                     pose_seen_ ? "first pose" : "~initial_pose", pending_pose_->x,
                     pending_pose_->y);
      } catch (const std::exception& error) {
        NODELET_ERROR_THROTTLE(kWarnPeriodS, "explorer not started: %s", error.what());
      }
    }
    geometry_msgs::Twist cmd;
    if (!started()) {
      if ((now - start_time_).toSec() > config_.exploration.pose_timeout_s && due(nopose_warned_)) {
        NODELET_WARN("no pose received yet on %s: standing still", pose_sub_.getTopic().c_str());
      }
      cmd_pub_.publish(cmd);
      return;
    }
    if (pending_pose_ && std::isfinite(pending_pose_->x) && std::isfinite(pending_pose_->y) &&
        std::isfinite(pending_pose_->theta)) {
      last_pose_ = pending_pose_;
    }
    const ebslam::VelocityCommand command =
        coverer_
            ? coverer_->update(now.toSec(), pending_pose_, pending_bump_)
            : explorer_->update(now.toSec(), pending_pose_, pending_bump_, z_ ? &*z_ : nullptr);
    pending_pose_.reset();
    pending_bump_ = ebslam::BumpReading{};
    cmd.linear.x = command.v_mps;
    cmd.angular.z = command.omega_rps;
    cmd_pub_.publish(cmd);
    if (coverer_) {
      reportCoverage();
      publishPath(coverer_->path());
    } else {
      report();
      publishPlan();
    }
    if (markers_pub_.getNumSubscribers() > 0 &&
        (last_markers_.isZero() ||
         (ros::WallTime::now() - last_markers_).toSec() >= config_.markers_period_s)) {
      last_markers_ = ros::WallTime::now();
      if (coverer_) {
        publishCoverageMarkers();
      } else {
        publishMarkers();
      }
    }
  }

  bool started() const { return explorer_ || coverer_; }

  // The coverage planner's state changes and messages, and "done" once.
  void reportCoverage() {
    const ebslam::CoverageState state = coverer_->state();
    if (coverer_->done() && !done_published_) {
      done_published_ = true;
      std_msgs::Bool done;
      done.data = true;
      done_pub_.publish(done);
      NODELET_INFO("done: %.1f %% of the reachable lane samples swept",
                   100.0 * coverer_->coveredShare());
    }
    if (state == last_coverage_state_ && coverer_->message() == last_message_) return;
    const bool changed = state != last_coverage_state_;
    last_coverage_state_ = state;
    last_message_ = coverer_->message();
    const char* name = ebslam::toString(state);
    const std::string text =
        last_message_.empty() ? name : std::string(name) + ": " + last_message_;
    if (state == ebslam::CoverageState::kNoPose) {
      ++bad_input_seen_;
      if (due(nopose_warned_) || changed) NODELET_WARN("%s", text.c_str());
    } else if (changed) {
      NODELET_INFO("%s", text.c_str());
    }
  }

  // The coverage planner's path still to drive, sent when it changed.
  void publishPath(const std::vector<Eigen::Vector2d>& points) {
    if (points == coverage_path_) return;
    coverage_path_ = points;
    sendPath(points);
  }

  // Logs state changes and pose jumps (the explorer's own words).
  void report() {
    const ebslam::ExplorationState state = explorer_->state();
    if (explorer_->poseJumps() != pose_jumps_) {
      pose_jumps_ = explorer_->poseJumps();
      ++bad_input_seen_;
      if (due(jump_warned_)) NODELET_WARN("%s", explorer_->message().c_str());
    }
    if (state == last_state_ && explorer_->message() == last_message_) return;
    const bool changed = state != last_state_;
    last_state_ = state;
    last_message_ = explorer_->message();
    const char* name = ebslam::toString(state);
    const std::string text =
        last_message_.empty() ? name : std::string(name) + ": " + last_message_;
    switch (state) {
      case ebslam::ExplorationState::kNoPose:
        ++bad_input_seen_;
        if (due(nopose_warned_) || changed) NODELET_WARN("%s", text.c_str());
        break;
      case ebslam::ExplorationState::kStuck:
        ++bad_input_seen_;
        if (due(stuck_warned_) || changed) NODELET_WARN("%s", text.c_str());
        break;
      case ebslam::ExplorationState::kBackingOut:
        NODELET_DEBUG("%s", text.c_str());
        break;
      case ebslam::ExplorationState::kRelocalising:
        if (due(stuck_warned_) || changed) NODELET_WARN("%s", text.c_str());
        break;
      case ebslam::ExplorationState::kExploring:
        if (changed) NODELET_INFO("%s", text.c_str());
        break;
    }
  }

  // The path still to drive: sent when the plan or the progress along it changed.
  void publishPlan() {
    const std::vector<Eigen::Vector2d> points = explorer_->pathPoints();
    if (explorer_->replans() == plan_replans_ && points.size() == plan_size_) return;
    plan_replans_ = explorer_->replans();
    plan_size_ = points.size();
    sendPath(points);
  }

  // points from the robot's position on, each pose facing the next, in ~map_frame.
  void sendPath(const std::vector<Eigen::Vector2d>& points) {
    nav_msgs::Path path;
    path.header.stamp = pose_stamp_;
    path.header.frame_id = config_.map_frame;
    geometry_msgs::PoseStamped pose;
    pose.header = path.header;
    pose.pose.orientation.w = 1.0;
    if (!points.empty()) {
      // Start at the robot; its heading is the heading of the first leg.
      const ebslam::Pose2 robot = lastPose();
      pose.pose.position.x = robot.x;
      pose.pose.position.y = robot.y;
      path.poses.push_back(pose);
    }
    for (const Eigen::Vector2d& p : points) {
      pose.pose.position.x = p.x();
      pose.pose.position.y = p.y();
      path.poses.push_back(pose);
    }
    // Each pose faces the next one.
    for (std::size_t i = 0; i + 1 < path.poses.size(); ++i) {
      const auto& a = path.poses[i].pose.position;
      const auto& b = path.poses[i + 1].pose.position;
      const double yaw = std::atan2(b.y - a.y, b.x - a.x);
      path.poses[i].pose.orientation.z = std::sin(0.5 * yaw);
      path.poses[i].pose.orientation.w = std::cos(0.5 * yaw);
    }
    if (path.poses.size() > 1) {
      path.poses.back().pose.orientation = path.poses[path.poses.size() - 2].pose.orientation;
    }
    plan_pub_.publish(path);
  }

  ebslam::Pose2 lastPose() const { return last_pose_.value_or(ebslam::Pose2{}); }

  // Blue (low) to red (high) over [0, 1].
  static std_msgs::ColorRGBA colour(double value) {
    std_msgs::ColorRGBA c;
    const double v = std::clamp(value, 0.0, 1.0);
    c.r = static_cast<float>(v);
    c.g = static_cast<float>(1.0 - std::abs(2.0 * v - 1.0));
    c.b = static_cast<float>(1.0 - v);
    c.a = 0.8f;
    return c;
  }

  void publishMarkers() {
    const ebslam::ExplorationPlanner& planner = explorer_->planner();
    const ebslam::HexGrid& grid = planner.grid();
    visualization_msgs::MarkerArray array;
    visualization_msgs::Marker base;
    base.header.stamp = pose_stamp_;
    base.header.frame_id = config_.map_frame;
    base.id = 0;
    base.type = visualization_msgs::Marker::CUBE_LIST;
    base.pose.orientation.w = 1.0;
    base.scale.x = base.scale.y = 0.8 * grid.spacing();
    base.scale.z = 0.01;
    // One layer per map, cells with a non-zero value, coloured over [min, max] of those cells.
    const auto layer = [&](const std::string& ns, const std::vector<float>& values, double z) {
      visualization_msgs::Marker m = base;
      m.ns = ns;
      m.pose.position.z = z;
      float lo = 0.0f, hi = 0.0f;
      bool any = false;
      for (float v : values) {
        if (v == 0.0f) continue;
        lo = any ? std::min(lo, v) : v;
        hi = any ? std::max(hi, v) : v;
        any = true;
      }
      for (int cell = 0; cell < static_cast<int>(values.size()); ++cell) {
        if (values[cell] == 0.0f) continue;
        const Eigen::Vector2d c = grid.centre(cell);
        geometry_msgs::Point p;
        p.x = c.x();
        p.y = c.y();
        m.points.push_back(p);
        m.colors.push_back(colour(hi > lo ? (values[cell] - lo) / (hi - lo) : 1.0));
      }
      if (m.points.empty()) m.action = visualization_msgs::Marker::DELETE;
      array.markers.push_back(m);
    };
    layer("localisation_Z", planner.localisationMap(), 0.0);
    layer("obstacle_E", planner.obstacleMap(), 0.01);
    layer("gain", planner.gainMap(), 0.02);
    visualization_msgs::Marker blocked = base;
    blocked.ns = "blocked";
    blocked.pose.position.z = 0.03;
    blocked.color.r = blocked.color.g = blocked.color.b = 0.1f;  // near black
    blocked.color.a = 1.0f;
    for (int cell = 0; cell < grid.size(); ++cell) {
      if (planner.blocked()[cell] == 0) continue;
      const Eigen::Vector2d c = grid.centre(cell);
      geometry_msgs::Point p;
      p.x = c.x();
      p.y = c.y();
      blocked.points.push_back(p);
    }
    if (blocked.points.empty()) blocked.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(blocked);
    visualization_msgs::Marker bumps = base;
    bumps.ns = "bumps";
    bumps.type = visualization_msgs::Marker::SPHERE_LIST;
    bumps.scale.x = bumps.scale.y = bumps.scale.z = 0.05;
    bumps.pose.position.z = 0.05;
    bumps.color.r = 1.0f;
    bumps.color.g = 0.5f;
    bumps.color.a = 1.0f;
    for (const Eigen::Vector2d& b : planner.bumpPoints()) {
      geometry_msgs::Point p;
      p.x = b.x();
      p.y = b.y();
      bumps.points.push_back(p);
    }
    if (bumps.points.empty()) bumps.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(bumps);
    markers_pub_.publish(array);
  }

  void publishCoverageMarkers() {
    const ebslam::CoverageMap& map = coverer_->map();
    const double robot_radius = config_.coverage.robot_radius_m;
    visualization_msgs::MarkerArray array;
    visualization_msgs::Marker base;
    base.header.stamp = pose_stamp_;
    base.header.frame_id = config_.map_frame;
    base.pose.orientation.w = 1.0;
    const auto point = [](const Eigen::Vector2d& v) {
      geometry_msgs::Point p;
      p.x = v.x();
      p.y = v.y();
      return p;
    };
    // Grid cells for which `pick` holds, as one cube list.
    const auto cells = [&](const std::string& ns, double z, float r, float g, float b,
                           const auto& pick) {
      visualization_msgs::Marker m = base;
      m.ns = ns;
      m.type = visualization_msgs::Marker::CUBE_LIST;
      m.scale.x = m.scale.y = config_.coverage.cell_m;
      m.scale.z = 0.01;
      m.pose.position.z = z;
      m.color.r = r;
      m.color.g = g;
      m.color.b = b;
      m.color.a = 0.8f;
      for (int cell = 0; cell < map.size(); ++cell) {
        if (pick(cell)) m.points.push_back(point(map.centre(cell)));
      }
      if (m.points.empty()) m.action = visualization_msgs::Marker::DELETE;
      array.markers.push_back(m);
    };
    cells("swept", 0.0, 1.0f, 0.7f, 0.7f,
          [&](int cell) { return map.visitDistance(cell) <= robot_radius; });
    cells("blocked", 0.01, 0.1f, 0.1f, 0.1f,
          [&](int cell) { return map.hardBlocked()[cell] != 0 || map.softBlocked()[cell] != 0; });
    cells("open", 0.02, 0.1f, 0.8f, 0.1f, [&](int cell) { return map.open(cell); });
    visualization_msgs::Marker lanes = base;
    lanes.ns = "lanes";
    lanes.type = visualization_msgs::Marker::LINE_LIST;
    lanes.scale.x = 0.02;
    lanes.pose.position.z = 0.03;
    lanes.color.b = 1.0f;
    lanes.color.a = 1.0f;
    for (const auto& [from, to] : coverer_->lanes()) {
      lanes.points.push_back(point(from));
      lanes.points.push_back(point(to));
    }
    if (lanes.points.empty()) lanes.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(lanes);
    visualization_msgs::Marker bumps = base;
    bumps.ns = "bumps";
    bumps.type = visualization_msgs::Marker::SPHERE_LIST;
    bumps.scale.x = bumps.scale.y = bumps.scale.z = 0.05;
    bumps.pose.position.z = 0.05;
    bumps.color.r = 1.0f;
    bumps.color.g = 0.5f;
    bumps.color.a = 1.0f;
    for (const Eigen::Vector2d& b : map.contacts()) bumps.points.push_back(point(b));
    if (bumps.points.empty()) bumps.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(bumps);
    markers_pub_.publish(array);
  }

  void diagnoseCoverage(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    const ebslam::CoverageState state = coverer_->state();
    if (state == ebslam::CoverageState::kNoPose) {
      status.summary(DiagnosticStatus::WARN,
                     std::string(ebslam::toString(state)) + ": " + coverer_->message());
    } else if (bad_input_seen_ > bad_input_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else {
      status.summary(DiagnosticStatus::OK, ebslam::toString(state));
    }
    status.add("done", coverer_->done());
    status.add("done at [s, ROS time]", coverer_->doneTime());
    status.add("covered share of the lane samples", coverer_->coveredShare());
    status.add("swept area [m^2]", coverer_->map().sweptArea());
    status.add("lanes", coverer_->lanes().size());
    status.add("bumps", coverer_->bumps());
    status.add("goals given up", coverer_->goalsAbandoned());
    status.add("planned points left", coverer_->path().size());
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (coverer_) {
      diagnoseCoverage(status);
    } else if (!explorer_) {
      status.summary(DiagnosticStatus::WARN, "waiting for the first pose");
    } else if (explorer_->state() == ebslam::ExplorationState::kNoPose ||
               explorer_->state() == ebslam::ExplorationState::kStuck) {
      status.summary(DiagnosticStatus::WARN, std::string(ebslam::toString(explorer_->state())) +
                                                 ": " + explorer_->message());
    } else if (bad_input_seen_ > bad_input_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else {
      status.summary(DiagnosticStatus::OK, ebslam::toString(explorer_->state()));
    }
    bad_input_reported_ = bad_input_seen_;
    status.add("planner", config_.coverage_planner ? "coverage" : "gain");
    if (coverer_) {
      status.add("state", ebslam::toString(coverer_->state()));
      status.add("message", coverer_->message());
    } else {
      status.add("state", explorer_ ? ebslam::toString(explorer_->state()) : "waiting");
      status.add("message", explorer_ ? explorer_->message() : std::string());
    }
    status.add("poses received", poses_);
    status.add("poses in a wrong frame", wrong_frame_);
    status.add("bump readings", bump_messages_);
    status.add("contact readings", contacts_);
    status.add("malformed bump readings", bad_bumps_);
    status.add("normalisation maps", z_maps_);
    status.add("malformed normalisation maps", bad_maps_);
    if (explorer_) {
      const ebslam::ExplorationPlanner& planner = explorer_->planner();
      std::size_t covered = 0, blocked = 0;
      for (float e : planner.obstacleMap()) covered += e > 0.0f ? 1 : 0;
      for (std::uint8_t b : planner.blocked()) blocked += b != 0 ? 1 : 0;
      status.add("replans", explorer_->replans());
      status.add("bumps", explorer_->bumps());
      status.add("pose jumps", explorer_->poseJumps());
      status.add("planned cells left", explorer_->path().size());
      status.add("covered cells", covered);
      status.add("blocked cells", blocked);
      status.add("cells expanded by the last plan", planner.lastExpandedNodes());
    }
  }

  ExplorationNodeConfig config_;
  std::mutex mutex_;
  std::optional<ebslam::Explorer> explorer_;         // from the first pose (~planner gain)
  std::optional<ebslam::CoverageExplorer> coverer_;  // from the first pose (~planner coverage)
  ebslam::CoverageState last_coverage_state_ = ebslam::CoverageState::kTransit;
  std::vector<Eigen::Vector2d> coverage_path_;
  bool done_published_ = false;
  std::optional<ebslam::Pose2> pending_pose_, last_pose_;
  bool pose_seen_ = false;  // a pose arrived (~initial_pose is used until then)
  ros::Time pose_stamp_;
  ebslam::BumpReading pending_bump_;
  std::optional<ebslam::GridMap2f> z_;
  ros::Time start_time_;
  ebslam::ExplorationState last_state_ = ebslam::ExplorationState::kExploring;
  std::string last_message_;
  std::size_t pose_jumps_ = 0, plan_replans_ = 0, plan_size_ = 0;
  ros::Subscriber pose_sub_, bump_sub_, z_sub_;
  ros::Publisher cmd_pub_, plan_pub_, markers_pub_, done_pub_;
  ros::Timer control_timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
  ros::WallTime last_markers_, frame_warned_, bump_warned_, map_warned_, nopose_warned_,
      jump_warned_, stuck_warned_;
  std::uint64_t poses_ = 0, wrong_frame_ = 0, bump_messages_ = 0, contacts_ = 0, bad_bumps_ = 0,
                z_maps_ = 0, bad_maps_ = 0;
  std::uint64_t bad_input_seen_ = 0, bad_input_reported_ = 0;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::ExplorationNodelet, nodelet::Nodelet)
