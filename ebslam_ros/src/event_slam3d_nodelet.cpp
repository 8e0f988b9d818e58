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
// With ~use_imu, input `imu` (sensor_msgs/Imu, angular velocity in its frame_id, stamps on the
// events' clock) feeds the core's gyro rotation prior; events wait until the IMU covers them (at
// most ~imu_max_wait of event time), so that the result is the offline core's on the same data.
// Mounting, input checks, pose, path, particles, tf and diagnostics: PoseFilterNodeletBase.
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <ebslam_ros_common/runtime_knobs.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
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
#include "ebslam_ros/conversions.h"
#include "ebslam_ros/event_input.h"
#include "ebslam_ros/log_throttle.h"
#include "event_slam3d_params.h"
#include "pose_filter_nodelet_base.h"

namespace ebslam_ros {
namespace {

constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();

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

class EventSlam3dNodelet : public PoseFilterNodeletBase {
 public:
  ~EventSlam3dNodelet() override {
    stopDiagnostics();
    map_timer_.stop();
    events_sub_.shutdown();
    imu_sub_.shutdown();
  }

 private:
  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "EventSlam3d " + getName(), [&] {
      ros::NodeHandle& nh = getNodeHandle();
      ros::NodeHandle& pnh = getPrivateNodeHandle();
      config_ = loadEventSlam3dNodeConfig(pnh);
      const auto& p = config_.initial_pose;
      initial_base_ = fromXyzRpy({p[0], p[1], p[2]}, {p[3], p[4], p[5]});
      // One pose per input message: a backlog drained at once sends a burst (kept for a slow
      // subscriber).
      startOutputs(config_, 1000);
      if (!config_.mount_from_tf) {
        mount_ = fromXyzRpy(config_.mount_xyz, config_.mount_rpy);
        sendStaticMount(*mount_);
      }
      map_pub_ = nh.advertise<sensor_msgs::PointCloud2>("map", 1);
      reset_srv_ = nh.advertiseService("reset", &EventSlam3dNodelet::onReset, this);
      save_srv_ = nh.advertiseService("save_map", &EventSlam3dNodelet::onSave, this);

      reconfigure_ = std::make_unique<ebslam_ros_common::RuntimeKnobs<EventSlam3dKnobsConfig>>(
          reconfigure_mutex_, pnh);
      ebslam_ros_common::markReconfigureParamsRead<EventSlam3dKnobsConfig>(pnh);
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

      startDiagnostics();
      map_timer_ = nh.createWallTimer(ros::WallDuration(config_.map_publish_period_s),
                                      [this](const ros::WallTimerEvent&) { publishMap(); });
      events_sub_ =
          nh.subscribe("depth_events", static_cast<std::uint32_t>(config_.queue_size),
                       &EventSlam3dNodelet::onEvents, this, ros::TransportHints().tcpNoDelay());
      startImu();
      NODELET_INFO("EB-SLAM-3D: %.3f m voxels, N=%d B=%d K=%d, ranges %.2f..%.2f m",
                   config_.slam.voxel_size_m, config_.slam.num_particles, config_.slam.batch_size,
                   config_.slam.resample_every, config_.slam.min_range_m, config_.slam.max_range_m);
    });
  }

  /// Mounting from tf when ~mount_from_tf; false (and a throttled warning) while tf lacks it.
  bool resolveMount() {
    if (mount_) return true;
    const std::optional<geometry_msgs::Transform> from_tf = lookupMount();
    if (from_tf) mount_ = toIsometry(*from_tf);
    return mount_.has_value();
  }

  /// Splits a message into time-ordered segments of valid events (see the README's bad input)
  /// and logs what it dropped (throttled on the wall clock).
  std::vector<DepthEventSegment> takeEvents(const ebslam_msgs::DepthEventArray& msg) {
    DepthEventInputResult input =
        guard_.take(msg, static_cast<std::int64_t>(std::llround(config_.max_backward_s * 1e6)),
                    static_cast<std::int64_t>(std::llround(config_.gap_warning_s * 1e6)));
    counters().clamped += input.clamped;
    if (input.gap_us > 0) {
      noteGap(input.gap_us, "depth event",
              "the filter continues from its last pose (call `reset` if the sensor was moved "
              "meanwhile)");
    }
    if (input.zero_time > 0) noteZeroTime(input.zero_time, "depth event");
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
    std::lock_guard<std::mutex> lock(mutex());
    const auto wall_start = std::chrono::steady_clock::now();
    if (!acceptInput(msg->header.frame_id, msg->events.size(), "DepthEventArray")) {
      if (msg->events.empty()) {
        NODELET_INFO_THROTTLE(kWarnPeriodS, "empty DepthEventArray messages ignored (%lu so far)",
                              static_cast<unsigned long>(counters().empty_messages));
      }
      return;
    }
    if (!resolveMount()) {
      ++counters().waiting_for_mount;
      return;
    }
    std::vector<DepthEventSegment> segments = takeEvents(*msg);
    if (config_.use_imu) {
      holdForImu(std::move(segments));
    } else {
      for (DepthEventSegment& segment : segments) processSegment(segment);
    }
    addProcessingTime(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count());
  }

  void processSegment(DepthEventSegment& segment) {
    if (segment.restart) {
      noteRestart(segment.jump_back_us, "depth event", "at ~initial_pose with an empty map");
      slam_.reset();
      clearPath();
    }
    if (!slam_) {
      slam_ = std::make_unique<ebslam::EventSlam3d>(
          config_.slam, ebslam::Pose3::fromIsometry(initial_base_ * *mount_));
      if (imu_rotation_known_) {
        for (const ebslam::GyroSample& sample : imu_recent_) {
          slam_->addGyro(sample.t_us, sample.rate);
        }
      }
    }
    const auto chunk = static_cast<std::size_t>(config_.max_events_per_update);
    for (std::size_t i = 0; i < segment.events.size(); i += chunk) {
      const std::size_t n = std::min(chunk, segment.events.size() - i);
      ebslam::EventSlam3d::ProcessStats stats;
      try {
        stats = slam_->process(segment.events.data() + i, n);
      } catch (const std::invalid_argument& error) {
        // The segments are time-ordered; reaching this is a defect.
        noteFilterError("filter", n, error);
        continue;
      }
      processed_ += stats.used;
      if (stats.rejected > 0) {
        out_of_range_ += stats.rejected;
        ++counters().bad_input;
        NODELET_WARN_THROTTLE(kWarnPeriodS,
                              "skipped %zu events nearer than ~min_range (%.2f m) or farther "
                              "than ~max_range (%.2f m)",
                              stats.rejected, config_.slam.min_range_m, config_.slam.max_range_m);
      }
      // No pose from a piece without a usable event: it would repeat the last one.
      if (stats.used > 0) publish(segment.events[i + n - 1].t_us);
    }
  }

  void publish(std::int64_t t_us) {
    const ros::Time stamp = ebslam_msgs::toRosTime(t_us);
    last_stamp_us_ = t_us;
    const Eigen::Isometry3d mount_inverse = mount_->inverse();
    const Eigen::Isometry3d base = slam_->estimate().isometry() * mount_inverse;

    // Covariance of base_link's pose over the score-weighted particles: position [m^2] and
    // rotation as the rotation vector of particle * estimate^-1 about the map's fixed axes
    // [rad^2] (the order x y z rx ry rz of geometry_msgs/PoseWithCovariance).
    const ebslam::ParticleSet3D& particles = slam_->particles();
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
    std::vector<Eigen::Isometry3d> bases(static_cast<std::size_t>(particles.size()));
    for (int i = 0; i < particles.size(); ++i) {
      const Eigen::Isometry3d b = particles.particle(i).isometry() * mount_inverse;
      bases[static_cast<std::size_t>(i)] = b;
      const double w = particles.size() == 1 ? 1.0 : particles.normalisedWeight(i);
      const Eigen::AngleAxisd r(b.rotation() * base.rotation().transpose());
      Eigen::Matrix<double, 6, 1> d;
      d << b.translation() - base.translation(), r.angle() * r.axis();
      cov += (d * d.transpose()) * w;  // d_i d_j = d_j d_i exactly: symmetric
    }
    geometry_msgs::PoseWithCovariance::_covariance_type covariance{};
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) covariance[static_cast<std::size_t>(6 * r + c)] = cov(r, c);
    }
    publishPose(stamp, toPoseMsg(base), covariance, [&] {
      std::vector<geometry_msgs::Pose> poses;
      poses.reserve(bases.size());
      for (const Eigen::Isometry3d& b : bases) poses.push_back(toPoseMsg(b));
      return poses;
    });
    publishTf(base, stamp);
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
    std::lock_guard<std::mutex> lock(mutex());
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
    std::lock_guard<std::mutex> lock(mutex());
    slam_.reset();  // restarts with the next events
    clearPath();
    guard_.restart();
    held_.clear();
    last_stamp_us_ = kNoTime;
    response.success = true;
    response.message = "filter restarts at ~initial_pose with an empty map with the next events";
    NODELET_INFO("%s", response.message.c_str());
    return true;
  }

  bool onSave(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::lock_guard<std::mutex> lock(mutex());
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
    std::lock_guard<std::mutex> lock(mutex());
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

  bool mountKnown() const override { return mount_.has_value(); }
  bool filterRunning() const override { return slam_ != nullptr; }
  std::uint64_t processedEvents() const override { return processed_; }

  bool diagnoseTracking(diagnostic_updater::DiagnosticStatusWrapper& status) const override {
    using diagnostic_msgs::DiagnosticStatus;
    const ebslam::TrackingHealth& health = slam_->health();
    if (health.state == ebslam::TrackingState::kLost) {
      status.summary(DiagnosticStatus::WARN,
                     "lost: the events stopped fitting the map; not mapping, searching");
      return true;
    }
    if (health.state == ebslam::TrackingState::kRecovering) {
      status.summary(DiagnosticStatus::WARN, "recovering: the events fit the map again");
      return true;
    }
    if (health.relocalised) {
      status.summaryf(DiagnosticStatus::OK, "relocalised after %.2f s lost; mapping again",
                      health.last_relocalisation_s);
      return true;
    }
    return false;
  }

  void diagnoseInput(diagnostic_updater::DiagnosticStatusWrapper& status) const override {
    status.add("events without depth", no_depth_);
    status.add("events out of range", out_of_range_);
    if (config_.use_imu) {
      status.add("IMU samples", imu_.accepted);
      status.add("IMU samples rejected", imu_.rejected);
      status.add("IMU samples late", imu_.late);
      status.add("events processed without IMU cover", imu_.uncovered_events);
    }
  }

  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& status) const override {
    status.add("particles", config_.slam.num_particles);
    if (!slam_) return;
    const ebslam::TrackingHealth& health = slam_->health();
    status.add("tracking state", ebslam::toString(health.state));
    status.add("effective sample size share", health.ess_share);
    status.add("fit ratio (fast / slow)", health.fit_ratio);
    status.add("times lost", health.lost_count);
    status.add("time lost [s of event time]", health.time_lost_s);
    status.add("relocalised", health.relocalised ? "true" : "false");
    status.add("relocalisations", health.relocalisations);
    status.add("last relocalisation [s of event time]", health.last_relocalisation_s);
    status.add("share of events without depth", health.depthless_share);
    status.add("gaps in the events that started a search", health.event_gaps);
    status.add("events without depth scored along their ray", slam_->raysScored());
    status.add("share of events in mapped space", health.mapped_share);
    status.add("keyframes", slam_->keyframes().size());
    status.add("map chunks", slam_->map().chunkCount());
    status.add("map memory [MiB]", static_cast<double>(slam_->memoryBytes()) / (1024.0 * 1024.0));
    status.add("map chunks evicted", slam_->map().evictedChunks());
    if (config_.use_imu) {
      const Eigen::Vector3d bias = slam_->gyro().bias();
      status.add("gyro bias [rad/s] (IMU frame)", std::to_string(bias.x()) + " " +
                                                      std::to_string(bias.y()) + " " +
                                                      std::to_string(bias.z()));
      status.add("batches rotated by the gyro", slam_->gyroPredictedBatches());
    }
  }

  // ---- IMU (gyro rotation prior) ----

  void startImu() {
    if (!config_.use_imu) return;
    if (config_.imu_rotation_from_tf) {
      imu_tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      imu_tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*imu_tf_buffer_);
    } else {
      setImuRotation(Eigen::Quaterniond(fromXyzRpy({0.0, 0.0, 0.0}, config_.imu_rpy).rotation()));
    }
    imu_sub_ = getNodeHandle().subscribe("imu", 2000, &EventSlam3dNodelet::onImu, this,
                                         ros::TransportHints().tcpNoDelay());
    NODELET_INFO("gyro rotation prior on: IMU -> %s rotation from %s", config_.sensor_frame.c_str(),
                 config_.imu_rotation_from_tf ? "tf" : "~imu_rpy");
  }

  void setImuRotation(const Eigen::Quaterniond& sensor_from_imu) {
    config_.slam.imu.gyro.sensor_from_imu = sensor_from_imu.normalized();
    imu_rotation_known_ = true;
    if (slam_) {
      slam_->setConfig(config_.slam);
      // Samples kept while the rotation was unknown (rates are stored in the IMU frame).
      for (const ebslam::GyroSample& sample : imu_recent_) slam_->addGyro(sample.t_us, sample.rate);
    }
    if (!imu_recent_.empty()) imu_latest_us_ = imu_recent_.back().t_us;
  }

  void onImu(const sensor_msgs::Imu::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex());
    const auto& w = msg->angular_velocity;
    const std::int64_t t_us = ebslam_msgs::toMicroseconds(msg->header.stamp);
    const auto reject = [&](const char* why) {
      ++imu_.rejected;
      ++counters().bad_input;
      if (imu_reject_log_.due()) {
        NODELET_WARN("IMU message stamped %.6f s dropped: %s (%lu dropped so far)",
                     msg->header.stamp.toSec(), why, static_cast<unsigned long>(imu_.rejected));
      }
    };
    if (msg->header.stamp.isZero()) return reject("stamp is 0");
    if (msg->angular_velocity_covariance[0] == -1.0) return reject("it has no angular velocity");
    if (config_.imu_rotation_from_tf) {
      if (msg->header.frame_id.empty()) return reject("empty frame_id (needed for the tf lookup)");
      if (imu_frame_.empty()) imu_frame_ = msg->header.frame_id;
      if (msg->header.frame_id != imu_frame_) {
        return reject("frame_id differs from the IMU frame of the first message");
      }
    }
    const ebslam::GyroSample sample{t_us, Eigen::Vector3d(w.x, w.y, w.z)};
    if (!sample.rate.allFinite()) return reject("non-finite angular velocity");
    if (!imu_recent_.empty() && t_us <= imu_recent_.back().t_us) {
      return reject("not after the previous IMU message (out of order or repeated)");
    }
    if (sample.rate.cwiseAbs().maxCoeff() > config_.slam.imu.gyro.max_rate) {
      return reject("angular velocity beyond the gyro's range (saturated?)");
    }
    ++imu_.accepted;
    if (!imu_rotation_known_) {
      // Kept (below) until tf has the IMU's mounting; events wait for it up to ~imu_max_wait.
      try {
        const geometry_msgs::TransformStamped t =
            imu_tf_buffer_->lookupTransform(config_.sensor_frame, imu_frame_, ros::Time(0));
        const auto& q = t.transform.rotation;
        NODELET_INFO("IMU frame '%s' -> '%s' from tf", imu_frame_.c_str(),
                     config_.sensor_frame.c_str());
        imu_recent_.push_back(sample);
        setImuRotation(Eigen::Quaterniond(q.w, q.x, q.y, q.z));
        drainHeld(false);
        return;
      } catch (const tf2::TransformException& error) {
        if (imu_tf_log_.due()) {
          NODELET_WARN("IMU samples kept until tf has %s -> %s: %s", imu_frame_.c_str(),
                       config_.sensor_frame.c_str(), error.what());
        }
        imu_recent_.push_back(sample);
        while (imu_recent_.front().t_us < t_us - 1000000) imu_recent_.pop_front();
        return;
      }
    }
    if (slam_) slam_->addGyro(t_us, sample.rate);
    if (processed_event_us_ != kNoTime && t_us < processed_event_us_) {
      ++imu_.late;
      if (imu_late_log_.due()) {
        NODELET_WARN(
            "IMU message %.3f s older than events already processed: it arrives too "
            "late for the gyro prior (raise ~imu_max_wait?)",
            1e-6 * static_cast<double>(processed_event_us_ - t_us));
      }
    }
    imu_recent_.push_back(sample);
    // Kept for a filter (re)started by the next events: the last second.
    while (!imu_recent_.empty() && imu_recent_.front().t_us < t_us - 1000000) {
      imu_recent_.pop_front();
    }
    imu_latest_us_ = t_us;
    drainHeld(false);
  }

  void holdForImu(std::vector<DepthEventSegment> segments) {
    for (DepthEventSegment& segment : segments) {
      if (segment.events.empty()) continue;
      newest_event_us_ = segment.events.back().t_us;
      held_.push_back(std::move(segment));
    }
    drainHeld(false);
  }

  /// Processes held segments the IMU covers, and those waiting longer than ~imu_max_wait.
  void drainHeld(bool all) {
    const auto max_wait_us = static_cast<std::int64_t>(std::llround(config_.imu_max_wait_s * 1e6));
    while (!held_.empty()) {
      DepthEventSegment& segment = held_.front();
      const std::int64_t end_us = segment.events.back().t_us;
      const bool covered = imu_latest_us_ != kNoTime && imu_latest_us_ >= end_us;
      const bool waited = newest_event_us_ - segment.events.front().t_us > max_wait_us;
      if (!covered && !waited && !all) break;
      if (!covered) {
        imu_.uncovered_events += segment.events.size();
        if (imu_uncovered_log_.due()) {
          NODELET_WARN("%s: events processed without the gyro prior (%lu so far)",
                       imu_latest_us_ == kNoTime
                           ? "no IMU message yet"
                           : "the IMU lags the events by more than ~imu_max_wait",
                       static_cast<unsigned long>(imu_.uncovered_events));
        }
      }
      processed_event_us_ = end_us;
      processSegment(segment);
      held_.pop_front();
    }
  }

  struct ImuCounters {
    std::uint64_t accepted = 0, rejected = 0, late = 0, uncovered_events = 0;
  };
  ros::Subscriber imu_sub_;
  std::unique_ptr<tf2_ros::Buffer> imu_tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> imu_tf_listener_;
  bool imu_rotation_known_ = false;
  std::string imu_frame_;                      // frame_id of the first IMU message used
  std::deque<ebslam::GyroSample> imu_recent_;  // the last second, replayed into a new filter
  std::deque<DepthEventSegment> held_;         // events waiting for the IMU to cover them
  std::int64_t imu_latest_us_ = kNoTime;       // newest IMU sample [us]
  std::int64_t newest_event_us_ = kNoTime;     // newest event received [us]
  std::int64_t processed_event_us_ = kNoTime;  // newest event processed [us]
  ImuCounters imu_;
  WallThrottle imu_reject_log_{kWarnPeriodS}, imu_late_log_{kWarnPeriodS},
      imu_uncovered_log_{kWarnPeriodS}, imu_tf_log_{kWarnPeriodS};

  // ---- end IMU ----

  EventSlam3dNodeConfig config_;
  Eigen::Isometry3d initial_base_ = Eigen::Isometry3d::Identity();  // base_link in map at start
  std::optional<Eigen::Isometry3d> mount_;                          // base_link -> sensor
  std::unique_ptr<ebslam::EventSlam3d> slam_;  // null until events arrive (or after a reset)
  DepthEventInputGuard guard_;                 // the stream's time and its checks
  std::int64_t last_stamp_us_ = kNoTime;       // stamp of the last pose [us]

  ros::Subscriber events_sub_;
  ros::Publisher map_pub_;
  ros::ServiceServer reset_srv_, save_srv_;
  std::unique_ptr<ebslam_ros_common::RuntimeKnobs<EventSlam3dKnobsConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
  ros::WallTimer map_timer_;

  // Counters of this input for diagnostics (since start).
  std::uint64_t processed_ = 0, no_depth_ = 0, out_of_range_ = 0;
  WallThrottle no_depth_log_{kWarnPeriodS};
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventSlam3dNodelet, nodelet::Nodelet)
