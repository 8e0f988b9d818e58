#include "ebslam_ros/pose_filter_node.h"

#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_msgs/ros_param_helpers.h"

namespace ebslam_ros {

ebslam::Pose2 planarMount(const tf2::Transform& base_to_sensor) {
  const tf2::Matrix3x3& r = base_to_sensor.getBasis();
  // Column 2 is the optical axis in base_link; the filters assume it points straight up.
  if (r[2][2] < std::cos(10.0 * M_PI / 180.0)) {
    throw std::invalid_argument(
        "the sensor's optical axis (z) must point up (within 10 degrees of base_link's z)");
  }
  return {base_to_sensor.getOrigin().x(), base_to_sensor.getOrigin().y(),
          std::atan2(r[1][0], r[0][0])};
}

namespace {

constexpr double kWarnPeriodS = 5.0;  // throttle of repeated input warnings [s]
constexpr double kPathPeriodS = 0.1;  // `path` at most this often [s of wall time]

geometry_msgs::Pose toPoseMsg(const ebslam::Pose2& p) {
  geometry_msgs::Pose pose;
  pose.position.x = p.x;
  pose.position.y = p.y;
  tf2::Quaternion q;
  q.setRPY(0.0, 0.0, p.theta);
  pose.orientation = tf2::toMsg(q);
  return pose;
}

tf2::Transform toTransform(const ebslam::Pose2& p) {
  tf2::Quaternion q;
  q.setRPY(0.0, 0.0, p.theta);
  return tf2::Transform(q, tf2::Vector3(p.x, p.y, 0.0));
}

geometry_msgs::TransformStamped toTransformMsg(const tf2::Transform& t, const ros::Time& stamp,
                                               const std::string& parent,
                                               const std::string& child) {
  geometry_msgs::TransformStamped msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = parent;
  msg.child_frame_id = child;
  msg.transform = tf2::toMsg(t);
  return msg;
}

}  // namespace

PoseFilterNode::PoseFilterNode(ros::NodeHandle nh, ros::NodeHandle private_nh,
                               PoseFilterNodeConfig config, ebslam::EventFilterConfig knobs,
                               Factory factory, std::string name)
    : config_(std::move(config)),
      knobs_(knobs),
      factory_(std::move(factory)),
      name_(std::move(name)),
      nh_(nh),
      private_nh_(private_nh),
      start_pose_(config_.initial_pose),
      guard_(ebslam::SensorSize{static_cast<std::uint32_t>(config_.sensor.camera.width),
                                static_cast<std::uint32_t>(config_.sensor.camera.height)},
             static_cast<std::int64_t>(std::llround(config_.max_backward_s * 1e6)),
             static_cast<std::int64_t>(std::llround(config_.gap_warning_s * 1e6))),
      tf_listener_(tf_buffer_),
      diagnostics_(nh, private_nh) {
  if (!config_.mount_from_tf) {
    tf2::Quaternion q;
    q.setRPY(config_.mount_rpy[0], config_.mount_rpy[1], config_.mount_rpy[2]);
    const tf2::Transform mount(
        q, tf2::Vector3(config_.mount_xyz[0], config_.mount_xyz[1], config_.mount_xyz[2]));
    mount_ = planarMount(mount);  // throws for a sensor not looking up
    static_broadcaster_.sendTransform(
        toTransformMsg(mount, ros::Time(0), config_.base_frame, config_.sensor_frame));
  }
  makeDenoiser();
  pose_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 10);
  path_pub_ = nh_.advertise<nav_msgs::Path>("path", 1, true);
  particles_pub_ = nh_.advertise<geometry_msgs::PoseArray>("particles", 1);
  reset_srv_ = nh_.advertiseService("reset", &PoseFilterNode::onReset, this);

  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<EventFilterKnobsConfig>>(
      reconfigure_mutex_, private_nh_);
  ebslam_msgs::markReconfigureParamsRead<EventFilterKnobsConfig>(private_nh_);
  EventFilterKnobsConfig start;
  start.num_particles = knobs_.num_particles;
  start.batch_size = knobs_.batch_size;
  start.resample_every = knobs_.resample_every;
  start.reset_scores_on_resample = knobs_.experimental.reset_scores_on_resample;
  start.g0 = knobs_.g0;
  start.diffusion_scale = knobs_.experimental.diffusion_scale;
  start.denoise = config_.denoise;
  start.denoise_window = 1e-6 * static_cast<double>(config_.denoiser.window_us);
  start.denoise_min_support = config_.denoiser.min_support;
  start.denoise_polarity_match = config_.denoiser.polarity_match;
  reconfigure_->updateConfig(start);
  reconfigure_->setCallback(
      [this](EventFilterKnobsConfig& k, std::uint32_t level) { onReconfigure(k, level); });

  diagnostics_.setHardwareID("none");
  diagnostics_.add(name_, this, &PoseFilterNode::diagnose);
  diagnostics_timer_ =
      nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
        std::lock_guard<std::mutex> lock(mutex_);
        diagnostics_.update();
      });
  events_sub_ = nh_.subscribe("events", static_cast<std::uint32_t>(config_.queue_size),
                              &PoseFilterNode::onEvents, this, ros::TransportHints().tcpNoDelay());
}

bool PoseFilterNode::resolveMount() {
  if (mount_) return true;
  try {
    const geometry_msgs::TransformStamped t =
        tf_buffer_.lookupTransform(config_.base_frame, config_.sensor_frame, ros::Time(0));
    tf2::Transform mount;
    tf2::fromMsg(t.transform, mount);
    mount_ = planarMount(mount);
    return true;
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(kWarnPeriodS, "%s: events dropped until tf has %s -> %s: %s", name_.c_str(),
                      config_.base_frame.c_str(), config_.sensor_frame.c_str(), error.what());
  } catch (const std::invalid_argument& error) {
    ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: unusable mounting %s -> %s from tf: %s", name_.c_str(),
                       config_.base_frame.c_str(), config_.sensor_frame.c_str(), error.what());
  }
  return false;
}

void PoseFilterNode::makeDenoiser() {
  denoiser_.reset();
  if (config_.denoise) denoiser_.emplace(config_.denoiser, guard_.sensor());
}

void PoseFilterNode::restart(const ebslam::Pose2& base_pose) {
  backend_ = factory_(compose(base_pose, *mount_), knobs_);
  path_.clear();
}

void PoseFilterNode::onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto wall_start = std::chrono::steady_clock::now();
  ++messages_;
  events_in_ += msg->events.size();
  if (msg->events.empty()) {
    ++empty_messages_;
    return;
  }
  if (!msg->header.frame_id.empty() && msg->header.frame_id != config_.sensor_frame) {
    ++rejected_frame_;
    ++bad_input_seen_;
    ROS_ERROR_THROTTLE(kWarnPeriodS,
                       "%s: EventArray in frame '%s' dropped: this filter's sensor is '%s'",
                       name_.c_str(), msg->header.frame_id.c_str(), config_.sensor_frame.c_str());
    return;
  }
  if (!resolveMount()) {
    ++waiting_for_mount_;
    return;
  }
  EventInputResult input = guard_.take(*msg);
  if (input.size_mismatch) {
    ++rejected_size_;
    ++bad_input_seen_;
    ROS_ERROR_THROTTLE(kWarnPeriodS,
                       "%s: EventArray of a %ux%u sensor dropped: the filter's camera is %ux%u "
                       "(~camera/width, ~camera/height)",
                       name_.c_str(), msg->width, msg->height, guard_.sensor().width,
                       guard_.sensor().height);
    return;
  }
  if (input.outside > 0) {
    outside_ += input.outside;
    ++bad_input_seen_;
    ROS_WARN_THROTTLE(kWarnPeriodS, "%s: dropped %zu events outside the %ux%u sensor",
                      name_.c_str(), input.outside, msg->width, msg->height);
  }
  if (input.clamped > 0) clamped_ += input.clamped;
  if (input.zero_time > 0) {
    zero_time_ += input.zero_time;
    ++bad_input_seen_;
    if (zero_time_log_.due()) {
      ROS_ERROR(
          "%s: dropped %zu events stamped 0 (unset event time: does the source fill "
          "Event.ts?); %llu messages with them since the previous such message not logged",
          name_.c_str(), input.zero_time,
          static_cast<unsigned long long>(zero_time_log_.suppressed()));
    }
  }
  if (input.gap_us > 0) {
    ++gaps_;
    if (gap_log_.due()) {
      constexpr double kDayS = 86400.0;
      const double gap_s = 1e-6 * static_cast<double>(input.gap_us);
      if (gap_s > kDayS) {
        ROS_WARN(
            "%s: event time jumped forward by %.0f s (a bad stamp or a clock change?); "
            "the filter continues from its last pose",
            name_.c_str(), gap_s);
      } else {
        ROS_WARN("%s: no events for %.3f s; the filter continues from its last pose", name_.c_str(),
                 gap_s);
      }
    }
  }
  for (EventSegment& segment : input.segments) {
    if (segment.restart) {
      ++restarts_;
      ++bad_input_seen_;
      // Throttled on the wall clock: a stream stepping back in every message would otherwise
      // log with every message, and ROS-time throttling would hide the loops of a bag (the same
      // stamps come back). The count says how many restarts the log did not show.
      if (restart_log_.due()) {
        ROS_WARN(
            "%s: event time jumped back by %.3f s (a looping bag or a sensor reconnect?): "
            "filter restarted at the initial pose (%llu restarts since the previous such message "
            "not logged: at most one per %.0f s; diagnostics count them all)",
            name_.c_str(), 1e-6 * static_cast<double>(segment.jump_back_us),
            static_cast<unsigned long long>(restart_log_.suppressed()), restart_log_.period());
      }
      backend_.reset();
      start_pose_ = config_.initial_pose;
      if (denoiser_) denoiser_->reset();
    }
    if (denoiser_) {
      const std::size_t before = segment.events.size();
      try {
        denoiser_->filterInPlace(segment.events);
      } catch (const std::invalid_argument& error) {
        // The guard makes the events valid for the filter; reaching this is a defect.
        ++filter_errors_;
        ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: denoiser rejected %zu events: %s", name_.c_str(),
                           before, error.what());
        continue;
      }
      denoiser_passed_ += segment.events.size();
      denoiser_removed_ += before - segment.events.size();
    }
    if (!backend_) restart(start_pose_);
    const std::size_t chunk = static_cast<std::size_t>(config_.max_events_per_update);
    for (std::size_t i = 0; i < segment.events.size(); i += chunk) {
      const std::size_t n = std::min(chunk, segment.events.size() - i);
      try {
        backend_->process(segment.events.data() + i, n);
      } catch (const std::invalid_argument& error) {
        // The guard makes the events valid for the filter; reaching this is a defect.
        ++filter_errors_;
        ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: filter rejected %zu events: %s", name_.c_str(), n,
                           error.what());
        continue;
      }
      publish(ebslam_msgs::toRosTime(segment.events[i + n - 1].t_us));
    }
  }
  processing_s_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
}

void PoseFilterNode::publish(const ros::Time& stamp) {
  // Maps first: a node that acts on the pose (the explorer) then has the maps of the same events.
  if (after_update_) after_update_(*backend_, stamp);
  const ebslam::Pose2 sensor = backend_->estimate();
  const ebslam::Pose2 mount_inverse = inverse(*mount_);
  const ebslam::Pose2 base = compose(sensor, mount_inverse);

  // Covariance of base_link's (x, y, yaw) over the particles, score-weighted; headings as
  // differences to the estimate, wrapped.
  const ebslam::ParticleSet2D& particles = backend_->particles();
  double cxx = 0, cxy = 0, cyy = 0, cxt = 0, cyt = 0, ctt = 0;
  for (int i = 0; i < particles.size(); ++i) {
    const double w = particles.size() == 1 ? 1.0 : particles.normalisedWeight(i);
    const ebslam::Pose2 p = compose(particles.particle(i), mount_inverse);
    const double dx = p.x - base.x, dy = p.y - base.y;
    const double dt = std::remainder(p.theta - base.theta, 2.0 * M_PI);
    cxx += w * dx * dx;
    cxy += w * dx * dy;
    cyy += w * dy * dy;
    cxt += w * dx * dt;
    cyt += w * dy * dt;
    ctt += w * dt * dt;
  }
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = config_.map_frame;
  pose.pose.pose = toPoseMsg(base);
  auto& c = pose.pose.covariance;
  c[0] = cxx;
  c[1] = c[6] = cxy;
  c[7] = cyy;
  c[5] = c[30] = cxt;
  c[11] = c[31] = cyt;
  c[35] = ctt;
  pose_pub_.publish(pose);
  last_latency_s_ = (ros::Time::now() - stamp).toSec();

  geometry_msgs::PoseStamped stamped;
  stamped.header = pose.header;
  stamped.pose = pose.pose.pose;
  path_.push_back(stamped);
  while (path_.size() > static_cast<std::size_t>(config_.path_length)) path_.pop_front();
  const ros::WallTime now = ros::WallTime::now();
  if (path_pub_.getNumSubscribers() > 0 && (now - last_path_publication_).toSec() >= kPathPeriodS) {
    nav_msgs::Path path;
    path.header = pose.header;
    path.poses.assign(path_.begin(), path_.end());
    path_pub_.publish(path);
    last_path_publication_ = now;
  }
  if (particles_pub_.getNumSubscribers() > 0) {
    geometry_msgs::PoseArray array;
    array.header = pose.header;
    array.poses.reserve(particles.size());
    for (int i = 0; i < particles.size(); ++i) {
      array.poses.push_back(toPoseMsg(compose(particles.particle(i), mount_inverse)));
    }
    particles_pub_.publish(array);
  }

  if (config_.publish_tf) {
    const tf2::Transform map_to_base = toTransform(base);
    tf2::Transform odom_to_base = tf2::Transform::getIdentity();
    bool have_odom = true;
    if (config_.odom_from_tf) {
      try {
        tf2::fromMsg(
            tf_buffer_.lookupTransform(config_.odom_frame, config_.base_frame, stamp).transform,
            odom_to_base);
      } catch (const tf2::TransformException& error) {
        have_odom = false;
        ROS_WARN_THROTTLE(kWarnPeriodS,
                          "%s: no %s -> %s at the events' time, map -> %s not sent: %s",
                          name_.c_str(), config_.odom_frame.c_str(), config_.base_frame.c_str(),
                          config_.odom_frame.c_str(), error.what());
      }
    }
    if (have_odom) {
      std::vector<geometry_msgs::TransformStamped> transforms{toTransformMsg(
          map_to_base * odom_to_base.inverse(), stamp, config_.map_frame, config_.odom_frame)};
      if (!config_.odom_from_tf) {
        transforms.push_back(
            toTransformMsg(odom_to_base, stamp, config_.odom_frame, config_.base_frame));
      }
      tf_broadcaster_.sendTransform(transforms);
    }
  }
}

bool PoseFilterNode::onReset(ebslam_msgs::ResetPose::Request& request,
                             ebslam_msgs::ResetPose::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (request.use_pose) {
    if (!std::isfinite(request.pose.x) || !std::isfinite(request.pose.y) ||
        !std::isfinite(request.pose.theta)) {
      response.success = false;
      response.message = "the pose must be finite";
      return true;
    }
    start_pose_ = {request.pose.x, request.pose.y, request.pose.theta};
  } else {
    start_pose_ = config_.initial_pose;
  }
  backend_.reset();  // restarts with the next events
  path_.clear();
  guard_.restart();
  if (denoiser_) denoiser_->reset();
  response.success = true;
  response.message = "filter restarts at (" + std::to_string(start_pose_.x) + ", " +
                     std::to_string(start_pose_.y) + ", " + std::to_string(start_pose_.theta) +
                     ") with the next events";
  ROS_INFO("%s: %s", name_.c_str(), response.message.c_str());
  return true;
}

void PoseFilterNode::onReconfigure(EventFilterKnobsConfig& k, std::uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  ebslam::EventFilterConfig next = knobs_;
  next.num_particles = k.num_particles;
  next.batch_size = k.batch_size;
  next.resample_every = k.resample_every;
  next.experimental.reset_scores_on_resample = k.reset_scores_on_resample;
  next.g0 = k.g0;
  next.experimental.diffusion_scale = k.diffusion_scale;
  ebslam::BackgroundActivityFilterConfig denoiser = config_.denoiser;
  denoiser.window_us = std::max<std::int64_t>(1, std::llround(k.denoise_window * 1e6));
  denoiser.min_support = k.denoise_min_support;
  denoiser.polarity_match = k.denoise_polarity_match;
  try {
    next.validate();
    denoiser.validate();
    if (backend_) backend_->setFilterConfig(next);
    knobs_ = next;
    if (k.denoise != config_.denoise || denoiser.window_us != config_.denoiser.window_us ||
        denoiser.min_support != config_.denoiser.min_support ||
        denoiser.polarity_match != config_.denoiser.polarity_match) {
      config_.denoise = k.denoise;
      config_.denoiser = denoiser;
      makeDenoiser();
    }
  } catch (const std::invalid_argument& error) {
    ROS_ERROR("%s: reconfiguration rejected: %s", name_.c_str(), error.what());
  }
}

void PoseFilterNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  if (!mount_) {
    status.summaryf(DiagnosticStatus::WARN, "waiting for tf %s -> %s", config_.base_frame.c_str(),
                    config_.sensor_frame.c_str());
  } else if (filter_errors_ > 0) {
    status.summary(DiagnosticStatus::ERROR, "the filter rejected events (see the log)");
  } else if (bad_input_seen_ > bad_input_reported_) {
    status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
  } else if (!backend_) {
    status.summary(DiagnosticStatus::OK, "waiting for events");
  } else {
    status.summary(DiagnosticStatus::OK, "tracking");
  }
  bad_input_reported_ = bad_input_seen_;
  status.add("messages", messages_);
  status.add("events received", events_in_);
  status.add("events processed", backend_ ? backend_->processedEvents() : 0);
  status.add("empty messages", empty_messages_);
  status.add("messages of a wrong sensor size", rejected_size_);
  status.add("messages in a wrong frame", rejected_frame_);
  status.add("events outside the sensor", outside_);
  status.add("events clamped in time", clamped_);
  status.add("events stamped 0 (dropped)", zero_time_);
  status.add("restarts after time jumps", restarts_);
  status.add("denoiser", config_.denoise ? "on" : "off");
  status.add("events passed by the denoiser", denoiser_passed_);
  status.add("events removed by the denoiser", denoiser_removed_);
  status.add("pauses longer than gap_warning", gaps_);
  status.add("processing time [s]", processing_s_);
  status.add("events per second of processing",
             processing_s_ > 0.0 ? static_cast<double>(events_in_) / processing_s_ : 0.0);
  status.add("last pose latency [s]", last_latency_s_);
  if (backend_) {
    status.add("particles", backend_->particles().size());
    status.add("G0", backend_->g0());
  }
}

}  // namespace ebslam_ros
