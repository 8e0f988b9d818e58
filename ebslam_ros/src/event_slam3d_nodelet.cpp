// EB-SLAM-3D (thesis 8.3, alg. 9): a depth-event sensor (D-eDVS) localises itself in 6 DoF
// against a voxel occurrence map it builds from the same events (ebslam/slam/ebslam3d.h).
//
// Frames (REP 105): map -> odom -> base_link -> sensor_frame. The core estimates the pose of the
// sensor's optical frame; the mounting base_link -> sensor_frame (parameters or tf) turns it into
// base_link's pose. The map frame is where base_link stood at the (re)start (~initial_pose).
// Time: every output is stamped with the time of the last event it includes (event `ts`,
// microseconds since the ROS epoch; ebslam_msgs/event_conversions.h), never now().
//
// Outputs (relative names): pose, path, particles (while subscribed), map (PointCloud2 of the
// voxels above ~map_threshold, every ~map_publish_period s of wall time while subscribed), tf,
// /diagnostics; services reset and save_map; dynamic_reconfigure knobs (EventSlam3dKnobs.cfg).
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/ros_param_helpers.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/Trigger.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <boost/thread/recursive_mutex.hpp>

#include <ebslam/slam/ebslam3d.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/EventSlam3dKnobsConfig.h"
#include "ebslam_ros/event_input.h"
#include "ebslam_ros/log_throttle.h"
#include "ebslam_ros/ros_params.h"

namespace ebslam_ros {
namespace {

constexpr double kWarnPeriodS = 5.0;  // throttle of repeated input warnings [s]
constexpr double kPathPeriodS = 0.1;  // `path` at most this often [s of wall time]
constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();

Eigen::Isometry3d toIsometry(const ebslam::Pose3& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = p.orientation.normalized().toRotationMatrix();
  t.translation() = p.position;
  return t;
}

ebslam::Pose3 toPose3(const Eigen::Isometry3d& t) {
  ebslam::Pose3 p;
  p.position = t.translation();
  p.orientation = Eigen::Quaterniond(t.rotation()).normalized();
  return p;
}

Eigen::Isometry3d fromXyzRpy(const std::array<double, 3>& xyz, double roll, double pitch,
                             double yaw) {
  // Fixed-axis roll, pitch, yaw as tf2's setRPY: R = Rz(yaw) Ry(pitch) Rx(roll).
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  return t;
}

Eigen::Isometry3d fromMsg(const geometry_msgs::Transform& m) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(m.translation.x, m.translation.y, m.translation.z);
  return t;
}

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& t) {
  geometry_msgs::Pose pose;
  pose.position.x = t.translation().x();
  pose.position.y = t.translation().y();
  pose.position.z = t.translation().z();
  const Eigen::Quaterniond q(t.rotation());
  pose.orientation.w = q.w();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  return pose;
}

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& t, const ros::Time& stamp,
                                               const std::string& parent,
                                               const std::string& child) {
  geometry_msgs::TransformStamped msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = parent;
  msg.child_frame_id = child;
  const geometry_msgs::Pose pose = toPoseMsg(t);
  msg.transform.translation.x = pose.position.x;
  msg.transform.translation.y = pose.position.y;
  msg.transform.translation.z = pose.position.z;
  msg.transform.rotation = pose.orientation;
  return msg;
}

struct Voxel {
  Eigen::Vector3f centre;  // [m] in the map frame
  float value;
};

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Writes voxel centres [m] and values as ASCII PLY (vertex x y z value) or PCD (x y z intensity),
/// after the extension; throws std::runtime_error naming the problem.
void writeVoxelCloud(const std::string& path, const std::vector<Voxel>& voxels) {
  const bool pcd = endsWith(path, ".pcd");
  if (!pcd && !endsWith(path, ".ply")) {
    throw std::runtime_error("the file name must end in .ply or .pcd: '" + path + "'");
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot open '" + path + "' for writing");
  if (pcd) {
    out << "# .PCD v0.7 - EB-SLAM-3D occurrence map: voxel centres [m], intensity = value\n"
        << "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
        << "WIDTH " << voxels.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
        << "POINTS " << voxels.size() << "\nDATA ascii\n";
  } else {
    out << "ply\nformat ascii 1.0\n"
        << "comment EB-SLAM-3D occurrence map: voxel centres [m] in the map frame\n"
        << "element vertex " << voxels.size() << "\nproperty float x\nproperty float y\n"
        << "property float z\nproperty float value\nend_header\n";
  }
  out.precision(9);  // float round trip
  for (const Voxel& v : voxels) {
    out << v.centre.x() << ' ' << v.centre.y() << ' ' << v.centre.z() << ' ' << v.value << '\n';
  }
  out.close();
  if (!out) throw std::runtime_error("writing '" + path + "' failed");
}

}  // namespace

class EventSlam3dNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_msgs::startOrFail(getPrivateNodeHandle(), "EventSlam3d " + getName(), [&] {
      ros::NodeHandle& nh = getNodeHandle();
      ros::NodeHandle& pnh = getPrivateNodeHandle();
      config_ = loadEventSlam3dNodeConfig(pnh);
      const auto& p = config_.initial_pose;
      initial_base_ = fromXyzRpy({p[0], p[1], p[2]}, p[3], p[4], p[5]);
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
      tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
      static_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
      if (!config_.mount_from_tf) {
        mount_ = fromXyzRpy(config_.mount_xyz, config_.mount_rpy[0], config_.mount_rpy[1],
                            config_.mount_rpy[2]);
        static_broadcaster_->sendTransform(
            toTransformMsg(*mount_, ros::Time(0), config_.base_frame, config_.sensor_frame));
      }
      // One pose per input message: a backlog drained at once sends a burst (kept for a slow
      // subscriber).
      pose_pub_ = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 1000);
      path_pub_ = nh.advertise<nav_msgs::Path>("path", 1, true);
      particles_pub_ = nh.advertise<geometry_msgs::PoseArray>("particles", 1);
      map_pub_ = nh.advertise<sensor_msgs::PointCloud2>("map", 1);
      reset_srv_ = nh.advertiseService("reset", &EventSlam3dNodelet::onReset, this);
      save_srv_ = nh.advertiseService("save_map", &EventSlam3dNodelet::onSave, this);

      reconfigure_ = std::make_unique<dynamic_reconfigure::Server<EventSlam3dKnobsConfig>>(
          reconfigure_mutex_, pnh);
      ebslam_msgs::markReconfigureParamsRead<EventSlam3dKnobsConfig>(pnh);
      EventSlam3dKnobsConfig start;
      start.num_particles = config_.slam.num_particles;
      start.batch_size = config_.slam.batch_size;
      start.resample_every = config_.slam.resample_every;
      start.event_share = config_.slam.event_share;
      start.sigma_position = config_.slam.sigma_position_m;
      start.sigma_rotation = config_.slam.sigma_rotation_rad;
      start.score_alpha = config_.slam.score_alpha;
      start.sigma_position_time = config_.slam.sigma_position_per_sqrt_s;
      start.sigma_rotation_time = config_.slam.sigma_rotation_per_sqrt_s;
      start.max_event_rate = config_.slam.max_event_rate;
      reconfigure_->updateConfig(start);
      reconfigure_->setCallback(
          [this](EventSlam3dKnobsConfig& k, std::uint32_t level) { onReconfigure(k, level); });

      diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
      diagnostics_->setHardwareID("none");
      diagnostics_->add(getName(), this, &EventSlam3dNodelet::diagnose);
      diagnostics_timer_ =
          nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
            std::lock_guard<std::mutex> lock(mutex_);
            diagnostics_->update();
          });
      map_timer_ = nh.createWallTimer(ros::WallDuration(config_.map_publish_period_s),
                                      [this](const ros::WallTimerEvent&) { publishMap(); });
      events_sub_ =
          nh.subscribe("depth_events", static_cast<std::uint32_t>(config_.queue_size),
                       &EventSlam3dNodelet::onEvents, this, ros::TransportHints().tcpNoDelay());
      NODELET_INFO("EB-SLAM-3D: %.3f m voxels, N=%d B=%d K=%d, ranges %.2f..%.2f m",
                   config_.slam.voxel_size_m, config_.slam.num_particles, config_.slam.batch_size,
                   config_.slam.resample_every, config_.slam.min_range_m, config_.slam.max_range_m);
    });
  }

  /// Mounting from tf when ~mount_from_tf; false (and a throttled warning) while tf lacks it.
  bool resolveMount() {
    if (mount_) return true;
    try {
      mount_ = fromMsg(
          tf_buffer_->lookupTransform(config_.base_frame, config_.sensor_frame, ros::Time(0))
              .transform);
      return true;
    } catch (const tf2::TransformException& error) {
      NODELET_WARN_THROTTLE(kWarnPeriodS, "events dropped until tf has %s -> %s: %s",
                            config_.base_frame.c_str(), config_.sensor_frame.c_str(), error.what());
    }
    return false;
  }

  /// Splits a message into time-ordered segments of valid events (see the README's bad input)
  /// and logs what it dropped (throttled on the wall clock).
  std::vector<DepthEventSegment> takeEvents(const ebslam_msgs::DepthEventArray& msg) {
    DepthEventInputResult input =
        guard_.take(msg, static_cast<std::int64_t>(std::llround(config_.max_backward_s * 1e6)),
                    static_cast<std::int64_t>(std::llround(config_.gap_warning_s * 1e6)));
    clamped_ += input.clamped;
    if (input.gap_us > 0) {
      ++gaps_;
      if (gap_log_.due()) {
        NODELET_WARN(
            "no depth events for %.3f s: the filter continues from its last pose (call `reset` "
            "if the sensor was moved meanwhile)",
            1e-6 * static_cast<double>(input.gap_us));
      }
    }
    if (input.zero_time > 0) {
      zero_time_ += input.zero_time;
      ++bad_input_seen_;
      if (zero_time_log_.due()) {
        NODELET_ERROR(
            "dropped %zu depth events stamped 0 (unset event time) (%llu messages with "
            "them since the previous such message not logged)",
            input.zero_time, static_cast<unsigned long long>(zero_time_log_.suppressed()));
      }
    }
    if (input.no_depth > 0) {
      // Normal for a D-eDVS (pixels the depth sensor does not see): not a warning.
      no_depth_ += input.no_depth;
      if (no_depth_log_.due()) {
        NODELET_INFO("skipped %zu events without depth (NaN point or depth)", input.no_depth);
      }
    }
    return std::move(input.segments);
  }

  void onEvents(const ebslam_msgs::DepthEventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto wall_start = std::chrono::steady_clock::now();
    ++messages_;
    events_in_ += msg->events.size();
    if (msg->events.empty()) {
      ++empty_messages_;
      NODELET_INFO_THROTTLE(kWarnPeriodS, "empty DepthEventArray messages ignored (%lu so far)",
                            static_cast<unsigned long>(empty_messages_));
      return;
    }
    if (!msg->header.frame_id.empty() && msg->header.frame_id != config_.sensor_frame) {
      ++rejected_frame_;
      ++bad_input_seen_;
      NODELET_ERROR_THROTTLE(kWarnPeriodS,
                             "DepthEventArray in frame '%s' dropped: this filter's sensor is '%s'",
                             msg->header.frame_id.c_str(), config_.sensor_frame.c_str());
      return;
    }
    if (!resolveMount()) {
      ++waiting_for_mount_;
      return;
    }
    std::vector<DepthEventSegment> segments = takeEvents(*msg);
    for (DepthEventSegment& segment : segments) {
      if (segment.restart) {
        ++restarts_;
        ++bad_input_seen_;
        // Throttled on the wall clock: a stream stepping back in every message must not log
        // with every message, and ROS-time throttling would hide the loops of a bag.
        if (restart_log_.due()) {
          NODELET_WARN(
              "depth event time jumped back by %.3f s (a looping bag or a sensor reconnect?): "
              "filter restarted at ~initial_pose with an empty map (%llu restarts since the "
              "previous such message not logged: at most one per %.0f s)",
              1e-6 * static_cast<double>(segment.jump_back_us),
              static_cast<unsigned long long>(restart_log_.suppressed()), restart_log_.period());
        }
        slam_.reset();
        path_.clear();
      }
      if (!slam_) {
        slam_ =
            std::make_unique<ebslam::EventSlam3d>(config_.slam, toPose3(initial_base_ * *mount_));
      }
      const auto chunk = static_cast<std::size_t>(config_.max_events_per_update);
      for (std::size_t i = 0; i < segment.events.size(); i += chunk) {
        const std::size_t n = std::min(chunk, segment.events.size() - i);
        ebslam::EventSlam3d::ProcessStats stats;
        try {
          stats = slam_->process(segment.events.data() + i, n);
        } catch (const std::invalid_argument& error) {
          // The segments are time-ordered; reaching this is a defect.
          ++filter_errors_;
          NODELET_ERROR_THROTTLE(kWarnPeriodS, "filter rejected %zu events: %s", n, error.what());
          continue;
        }
        processed_ += stats.used;
        if (stats.rejected > 0) {
          out_of_range_ += stats.rejected;
          ++bad_input_seen_;
          NODELET_WARN_THROTTLE(kWarnPeriodS,
                                "skipped %zu events nearer than ~min_range (%.2f m) or farther "
                                "than ~max_range (%.2f m)",
                                stats.rejected, config_.slam.min_range_m, config_.slam.max_range_m);
        }
        // No pose from a piece without a usable event: it would repeat the last one.
        if (stats.used > 0) publish(segment.events[i + n - 1].t_us);
      }
    }
    processing_s_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  }

  void publish(std::int64_t t_us) {
    const ros::Time stamp = ebslam_msgs::toRosTime(t_us);
    last_stamp_us_ = t_us;
    const Eigen::Isometry3d mount_inverse = mount_->inverse();
    const Eigen::Isometry3d base = toIsometry(slam_->estimate()) * mount_inverse;

    // Covariance of base_link's pose over the score-weighted particles: position [m^2] and
    // rotation as the rotation vector of particle * estimate^-1 about the map's fixed axes
    // [rad^2] (the order x y z rx ry rz of geometry_msgs/PoseWithCovariance).
    const ebslam::ParticleSet3D& particles = slam_->particles();
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
    std::vector<Eigen::Isometry3d> bases(static_cast<std::size_t>(particles.size()));
    for (int i = 0; i < particles.size(); ++i) {
      const Eigen::Isometry3d b = toIsometry(particles.particle(i)) * mount_inverse;
      bases[static_cast<std::size_t>(i)] = b;
      const double w = particles.size() == 1 ? 1.0 : particles.normalisedWeight(i);
      const Eigen::AngleAxisd r(b.rotation() * base.rotation().transpose());
      Eigen::Matrix<double, 6, 1> d;
      d << b.translation() - base.translation(), r.angle() * r.axis();
      cov += (d * d.transpose()) * w;  // d_i d_j = d_j d_i exactly: symmetric
    }
    geometry_msgs::PoseWithCovarianceStamped pose;
    pose.header.stamp = stamp;
    pose.header.frame_id = config_.map_frame;
    pose.pose.pose = toPoseMsg(base);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c)
        pose.pose.covariance[static_cast<std::size_t>(6 * r + c)] = cov(r, c);
    }
    pose_pub_.publish(pose);
    last_latency_s_ = (ros::Time::now() - stamp).toSec();

    geometry_msgs::PoseStamped stamped;
    stamped.header = pose.header;
    stamped.pose = pose.pose.pose;
    path_.push_back(stamped);
    while (path_.size() > static_cast<std::size_t>(config_.path_length)) path_.pop_front();
    const ros::WallTime now = ros::WallTime::now();
    if (path_pub_.getNumSubscribers() > 0 &&
        (now - last_path_publication_).toSec() >= kPathPeriodS) {
      nav_msgs::Path path;
      path.header = pose.header;
      path.poses.assign(path_.begin(), path_.end());
      path_pub_.publish(path);
      last_path_publication_ = now;
    }
    if (particles_pub_.getNumSubscribers() > 0) {
      geometry_msgs::PoseArray array;
      array.header = pose.header;
      array.poses.reserve(bases.size());
      for (const Eigen::Isometry3d& b : bases) array.poses.push_back(toPoseMsg(b));
      particles_pub_.publish(array);
    }

    if (config_.publish_tf) {
      Eigen::Isometry3d odom_to_base = Eigen::Isometry3d::Identity();
      bool have_odom = true;
      if (config_.odom_from_tf) {
        try {
          odom_to_base = fromMsg(
              tf_buffer_->lookupTransform(config_.odom_frame, config_.base_frame, stamp).transform);
        } catch (const tf2::TransformException& error) {
          have_odom = false;
          NODELET_WARN_THROTTLE(kWarnPeriodS,
                                "no %s -> %s at the events' time, map -> %s not sent: %s",
                                config_.odom_frame.c_str(), config_.base_frame.c_str(),
                                config_.odom_frame.c_str(), error.what());
        }
      }
      if (have_odom) {
        std::vector<geometry_msgs::TransformStamped> transforms{toTransformMsg(
            base * odom_to_base.inverse(), stamp, config_.map_frame, config_.odom_frame)};
        if (!config_.odom_from_tf) {
          transforms.push_back(
              toTransformMsg(odom_to_base, stamp, config_.odom_frame, config_.base_frame));
        }
        tf_broadcaster_->sendTransform(transforms);
      }
    }
  }

  /// Voxels above ~map_threshold (mutex held).
  std::vector<Voxel> voxels() const {
    std::vector<Voxel> out;
    if (!slam_) return out;
    const ebslam::ChunkedVoxelMap& map = slam_->map();
    map.forEachVoxel(static_cast<float>(config_.map_threshold),
                     [&](const ebslam::VoxelIndex& index, float value) {
                       out.push_back({map.voxelCentre(index), value});
                     });
    return out;
  }

  void publishMap() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (map_pub_.getNumSubscribers() == 0 || !slam_ || last_stamp_us_ == kNoTime) return;
    const std::vector<Voxel> cloud_voxels = voxels();
    sensor_msgs::PointCloud2 cloud;
    cloud.header.stamp = ebslam_msgs::toRosTime(last_stamp_us_);
    cloud.header.frame_id = config_.map_frame;
    sensor_msgs::PointCloud2Modifier modifier(cloud);
    modifier.setPointCloud2Fields(
        4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z",
        1, sensor_msgs::PointField::FLOAT32, "intensity", 1, sensor_msgs::PointField::FLOAT32);
    modifier.resize(cloud_voxels.size());
    sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z"),
        value(cloud, "intensity");
    for (const Voxel& v : cloud_voxels) {
      *x = v.centre.x();
      *y = v.centre.y();
      *z = v.centre.z();
      *value = v.value;
      ++x;
      ++y;
      ++z;
      ++value;
    }
    cloud.is_dense = true;
    map_pub_.publish(cloud);
  }

  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::lock_guard<std::mutex> lock(mutex_);
    slam_.reset();  // restarts with the next events
    path_.clear();
    guard_.restart();
    last_stamp_us_ = kNoTime;
    response.success = true;
    response.message = "filter restarts at ~initial_pose with an empty map with the next events";
    NODELET_INFO("%s", response.message.c_str());
    return true;
  }

  bool onSave(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::lock_guard<std::mutex> lock(mutex_);
    // Read at call time: `rosparam set <node>/map_file <path>` chooses the next file.
    const std::string path =
        getPrivateNodeHandle().param<std::string>("map_file", config_.map_file);
    if (!slam_) {
      response.success = false;
      response.message = "no map yet: no events processed since the start or the last reset";
      return true;
    }
    try {
      const std::vector<Voxel> cloud_voxels = voxels();
      writeVoxelCloud(path, cloud_voxels);
      response.success = true;
      response.message = "saved " + std::to_string(cloud_voxels.size()) + " voxels to " + path;
    } catch (const std::exception& error) {
      response.success = false;
      response.message = error.what();
    }
    NODELET_INFO("save_map: %s", response.message.c_str());
    return true;
  }

  void onReconfigure(EventSlam3dKnobsConfig& k, std::uint32_t) {
    std::lock_guard<std::mutex> lock(mutex_);
    ebslam::Ebslam3dConfig next = config_.slam;
    next.num_particles = k.num_particles;
    next.batch_size = k.batch_size;
    next.resample_every = k.resample_every;
    next.event_share = k.event_share;
    next.sigma_position_m = k.sigma_position;
    next.sigma_rotation_rad = k.sigma_rotation;
    next.score_alpha = k.score_alpha;
    next.sigma_position_per_sqrt_s = k.sigma_position_time;
    next.sigma_rotation_per_sqrt_s = k.sigma_rotation_time;
    next.max_event_rate = k.max_event_rate;
    try {
      next.validate();
      if (slam_) slam_->setConfig(next);
      config_.slam = next;
    } catch (const std::invalid_argument& error) {
      NODELET_ERROR("reconfiguration rejected: %s", error.what());
    }
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (!mount_) {
      status.summaryf(DiagnosticStatus::WARN, "waiting for tf %s -> %s", config_.base_frame.c_str(),
                      config_.sensor_frame.c_str());
    } else if (filter_errors_ > 0) {
      status.summary(DiagnosticStatus::ERROR, "the filter rejected events (see the log)");
    } else if (bad_input_seen_ > bad_input_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else if (!slam_) {
      status.summary(DiagnosticStatus::OK, "waiting for events");
    } else if (slam_->health().state == ebslam::TrackingState::kLost) {
      status.summary(DiagnosticStatus::WARN, "lost: the events stopped fitting the map");
    } else if (slam_->health().state == ebslam::TrackingState::kRecovering) {
      status.summary(DiagnosticStatus::WARN, "recovering: the events fit the map again");
    } else {
      status.summary(DiagnosticStatus::OK, "tracking");
    }
    bad_input_reported_ = bad_input_seen_;
    status.add("messages", messages_);
    status.add("events received", events_in_);
    status.add("events processed", processed_);
    status.add("empty messages", empty_messages_);
    status.add("messages in a wrong frame", rejected_frame_);
    status.add("events without depth", no_depth_);
    status.add("events out of range", out_of_range_);
    status.add("events clamped in time", clamped_);
    status.add("events stamped 0 (dropped)", zero_time_);
    status.add("restarts after time jumps", restarts_);
    status.add("pauses longer than gap_warning", gaps_);
    status.add("processing time [s]", processing_s_);
    status.add("events per second of processing",
               processing_s_ > 0.0 ? static_cast<double>(events_in_) / processing_s_ : 0.0);
    status.add("last pose latency [s]", last_latency_s_);
    status.add("particles", config_.slam.num_particles);
    if (slam_) {
      const ebslam::TrackingHealth& health = slam_->health();
      status.add("tracking state", ebslam::toString(health.state));
      status.add("effective sample size share", health.ess_share);
      status.add("fit ratio (fast / slow)", health.fit_ratio);
      status.add("times lost", health.lost_count);
      status.add("time lost [s of event time]", health.time_lost_s);
      status.add("map chunks", slam_->map().chunkCount());
      status.add("map memory [MiB]", static_cast<double>(slam_->memoryBytes()) / (1024.0 * 1024.0));
      status.add("map chunks evicted", slam_->map().evictedChunks());
    }
  }

  EventSlam3dNodeConfig config_;
  Eigen::Isometry3d initial_base_ = Eigen::Isometry3d::Identity();  // base_link in map at start
  std::optional<Eigen::Isometry3d> mount_;                          // base_link -> sensor
  std::mutex mutex_;
  std::unique_ptr<ebslam::EventSlam3d> slam_;  // null until events arrive (or after a reset)
  DepthEventInputGuard guard_;                 // the stream's time and its checks
  std::int64_t last_stamp_us_ = kNoTime;       // stamp of the last pose [us]

  ros::Subscriber events_sub_;
  ros::Publisher pose_pub_, path_pub_, particles_pub_, map_pub_;
  ros::ServiceServer reset_srv_, save_srv_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  std::unique_ptr<dynamic_reconfigure::Server<EventSlam3dKnobsConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_, map_timer_;

  std::deque<geometry_msgs::PoseStamped> path_;
  ros::WallTime last_path_publication_;

  // Counters for diagnostics (since start).
  std::uint64_t messages_ = 0, events_in_ = 0, processed_ = 0, empty_messages_ = 0,
                rejected_frame_ = 0, no_depth_ = 0, out_of_range_ = 0, clamped_ = 0, restarts_ = 0,
                gaps_ = 0, zero_time_ = 0, waiting_for_mount_ = 0, filter_errors_ = 0;
  // Per-message problems, logged at most every kWarnPeriodS of wall time.
  WallThrottle restart_log_{kWarnPeriodS}, gap_log_{kWarnPeriodS}, zero_time_log_{kWarnPeriodS},
      no_depth_log_{kWarnPeriodS};
  std::uint64_t bad_input_seen_ = 0, bad_input_reported_ = 0;
  double processing_s_ = 0.0;
  double last_latency_s_ = 0.0;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventSlam3dNodelet, nodelet::Nodelet)
