#include "planar_pose_filter_nodelet.h"

#include <ebslam_ros_common/ros_param_helpers.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/conversions.h"

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

PlanarPoseFilterNodelet::~PlanarPoseFilterNodelet() {
  stopDiagnostics();
  events_sub_.shutdown();
}

void PlanarPoseFilterNodelet::startFilter(PoseFilterNodeConfig config,
                                          ebslam::EventFilterConfig knobs, Factory factory) {
  config_ = std::move(config);
  knobs_ = knobs;
  factory_ = std::move(factory);
  start_pose_ = config_.initial_pose;
  input_type_ = readEventInputType(getPrivateNodeHandle());
  guard_.emplace(ebslam::SensorSize{static_cast<std::uint32_t>(config_.sensor.camera.width),
                                    static_cast<std::uint32_t>(config_.sensor.camera.height)},
                 static_cast<std::int64_t>(std::llround(config_.max_backward_s * 1e6)),
                 static_cast<std::int64_t>(std::llround(config_.gap_warning_s * 1e6)));
  startOutputs(config_, 10);
  if (!config_.mount_from_tf) {
    tf2::Quaternion q;
    q.setRPY(config_.mount_rpy[0], config_.mount_rpy[1], config_.mount_rpy[2]);
    const tf2::Transform mount(
        q, tf2::Vector3(config_.mount_xyz[0], config_.mount_xyz[1], config_.mount_xyz[2]));
    mount_ = planarMount(mount);  // throws for a sensor not looking up
    sendStaticMount(mount);
  }
  makeDenoiser();
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& private_nh = getPrivateNodeHandle();
  reset_srv_ = nh.advertiseService("reset", &PlanarPoseFilterNodelet::onReset, this);

  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<EventFilterKnobsConfig>>(
      reconfigure_mutex_, private_nh);
  ebslam_ros_common::markReconfigureParamsRead<EventFilterKnobsConfig>(private_nh);
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

  startDiagnostics();
  events_sub_.subscribe(
      nh, "events", static_cast<std::uint32_t>(config_.queue_size), input_type_,
      [this](const ebslam_msgs::EventArray::ConstPtr& msg) { onEvents(msg); },
      ros::TransportHints().tcpNoDelay(), getName());
}

bool PlanarPoseFilterNodelet::resolveMount() {
  if (mount_) return true;
  const std::optional<geometry_msgs::Transform> from_tf = lookupMount();
  if (!from_tf) return false;
  try {
    tf2::Transform mount;
    tf2::fromMsg(*from_tf, mount);
    mount_ = planarMount(mount);
    return true;
  } catch (const std::invalid_argument& error) {
    ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: unusable mounting %s -> %s from tf: %s",
                       getName().c_str(), config_.base_frame.c_str(), config_.sensor_frame.c_str(),
                       error.what());
  }
  return false;
}

void PlanarPoseFilterNodelet::makeDenoiser() {
  denoiser_.reset();
  if (config_.denoise) denoiser_.emplace(config_.denoiser, guard_->sensor());
}

void PlanarPoseFilterNodelet::restart(const ebslam::Pose2& base_pose) {
  backend_ = factory_(ebslam::compose(base_pose, *mount_), knobs_);
  clearPath();
}

bool PlanarPoseFilterNodelet::checkInput(const ebslam_msgs::EventArray& msg,
                                         const EventInputResult& input) {
  InputCounters& counters = this->counters();
  if (input.size_mismatch) {
    ++rejected_size_;
    ++counters.bad_input;
    ROS_ERROR_THROTTLE(kWarnPeriodS,
                       "%s: EventArray of a %ux%u sensor dropped: the filter's camera is %ux%u "
                       "(~camera/width, ~camera/height)",
                       getName().c_str(), msg.width, msg.height, guard_->sensor().width,
                       guard_->sensor().height);
    return false;
  }
  if (input.outside > 0) {
    outside_ += input.outside;
    ++counters.bad_input;
    ROS_WARN_THROTTLE(kWarnPeriodS, "%s: dropped %zu events outside the %ux%u sensor",
                      getName().c_str(), input.outside, msg.width, msg.height);
  }
  counters.clamped += input.clamped;
  if (input.zero_time > 0) noteZeroTime(input.zero_time, "event");
  if (input.gap_us > 0) noteGap(input.gap_us, "event", "the filter continues from its last pose");
  return true;
}

void PlanarPoseFilterNodelet::onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex());
  const auto wall_start = std::chrono::steady_clock::now();
  if (!acceptInput(msg->header.frame_id, msg->events.size(), "EventArray")) return;
  if (!resolveMount()) {
    ++counters().waiting_for_mount;
    return;
  }
  EventInputResult input = guard_->take(*msg);
  if (!checkInput(*msg, input)) return;
  for (EventSegment& segment : input.segments) processSegment(segment);
  addProcessingTime(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count());
}

void PlanarPoseFilterNodelet::processSegment(EventSegment& segment) {
  if (segment.restart) {
    noteRestart(segment.jump_back_us, "event", "at the initial pose");
    backend_.reset();
    start_pose_ = config_.initial_pose;
    if (denoiser_) denoiser_->reset();
  }
  if (denoiser_) {
    const std::size_t before = segment.events.size();
    try {
      denoiser_->filterInPlace(segment.events);
    } catch (const std::invalid_argument& error) {
      noteFilterError("denoiser", before, error);
      return;
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
      noteFilterError("filter", n, error);
      continue;
    }
    publish(ebslam_msgs::toRosTime(segment.events[i + n - 1].t_us));
  }
}

void PlanarPoseFilterNodelet::publish(const ros::Time& stamp) {
  // Maps first: a node that acts on the pose (the explorer) then has the maps of the same events.
  afterUpdate(*backend_, stamp);
  const ebslam::Pose2 mount_inverse = ebslam::inverse(*mount_);
  const ebslam::Pose2 base = ebslam::compose(backend_->estimate(), mount_inverse);

  // Covariance of base_link's (x, y, yaw) over the particles, score-weighted; headings as
  // differences to the estimate, wrapped.
  const ebslam::ParticleSet2D& particles = backend_->particles();
  double cxx = 0, cxy = 0, cyy = 0, cxt = 0, cyt = 0, ctt = 0;
  for (int i = 0; i < particles.size(); ++i) {
    const double w = particles.size() == 1 ? 1.0 : particles.normalisedWeight(i);
    const ebslam::Pose2 p = ebslam::compose(particles.particle(i), mount_inverse);
    const double dx = p.x - base.x, dy = p.y - base.y;
    const double dt = std::remainder(p.theta - base.theta, 2.0 * M_PI);
    cxx += w * dx * dx;
    cxy += w * dx * dy;
    cyy += w * dy * dy;
    cxt += w * dx * dt;
    cyt += w * dy * dt;
    ctt += w * dt * dt;
  }
  geometry_msgs::PoseWithCovariance::_covariance_type c{};
  c[0] = cxx;
  c[1] = c[6] = cxy;
  c[7] = cyy;
  c[5] = c[30] = cxt;
  c[11] = c[31] = cyt;
  c[35] = ctt;
  publishPose(stamp, toPoseMsg(base), c, [&] {
    std::vector<geometry_msgs::Pose> poses;
    poses.reserve(static_cast<std::size_t>(particles.size()));
    for (int i = 0; i < particles.size(); ++i) {
      poses.push_back(toPoseMsg(ebslam::compose(particles.particle(i), mount_inverse)));
    }
    return poses;
  });
  publishTf(toTransform(base), stamp);
}

bool PlanarPoseFilterNodelet::onReset(ebslam_msgs::ResetPose::Request& request,
                                      ebslam_msgs::ResetPose::Response& response) {
  std::lock_guard<std::mutex> lock(mutex());
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
  clearPath();
  guard_->restart();
  if (denoiser_) denoiser_->reset();
  response.success = true;
  response.message = "filter restarts at (" + std::to_string(start_pose_.x) + ", " +
                     std::to_string(start_pose_.y) + ", " + std::to_string(start_pose_.theta) +
                     ") with the next events";
  ROS_INFO("%s: %s", getName().c_str(), response.message.c_str());
  return true;
}

void PlanarPoseFilterNodelet::onReconfigure(EventFilterKnobsConfig& k, std::uint32_t) {
  std::lock_guard<std::mutex> lock(mutex());
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
    ROS_ERROR("%s: reconfiguration rejected: %s", getName().c_str(), error.what());
  }
}

void PlanarPoseFilterNodelet::diagnoseInput(
    diagnostic_updater::DiagnosticStatusWrapper& status) const {
  status.add("messages of a wrong sensor size", rejected_size_);
  status.add("events outside the sensor", outside_);
}

void PlanarPoseFilterNodelet::diagnoseFilter(
    diagnostic_updater::DiagnosticStatusWrapper& status) const {
  status.add("denoiser", config_.denoise ? "on" : "off");
  status.add("events passed by the denoiser", denoiser_passed_);
  status.add("events removed by the denoiser", denoiser_removed_);
  if (backend_) {
    status.add("particles", backend_->particles().size());
    status.add("G0", backend_->g0());
  }
}

}  // namespace ebslam_ros
