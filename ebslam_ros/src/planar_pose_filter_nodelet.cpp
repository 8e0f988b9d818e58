#include "planar_pose_filter_nodelet.h"

#include <ebslam_ros_common/ros_param_helpers.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <Eigen/Eigenvalues>

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
  startRateLimit(config_.rate_limit);
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
  if (map_localisation_) {
    initial_pose_sub_ =
        nh.subscribe("initialpose", 2, &PlanarPoseFilterNodelet::onInitialPose, this);
    global_srv_ = nh.advertiseService("global_localization",
                                      &PlanarPoseFilterNodelet::onGlobalLocalization, this);
    pending_global_ = config_.initial_pose_unknown;
  }

  reconfigure_ = std::make_unique<ebslam_ros_common::RuntimeKnobs<EventFilterKnobsConfig>>(
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
  last_odom_.reset();
  applyPendingSeed();
}

void PlanarPoseFilterNodelet::applyPendingSeed() {
  if (!backend_ || !backend_->localisesOnMap()) return;
  if (pending_seed_) {
    backend_->reseed(pending_seed_->sensor, pending_seed_->covariance);  // validated on receipt
    pending_seed_.reset();
    pending_global_ = false;
  } else if (pending_global_) {
    backend_->globalLocalisation();
    pending_global_ = false;
  }
}

namespace {

// Covariance of (x, y, yaw) from a ROS pose covariance (x y z rx ry rz order).
Eigen::Matrix3d planarCovariance(const geometry_msgs::PoseWithCovariance::_covariance_type& c) {
  const int index[3] = {0, 1, 5};
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) m(r, k) = c[static_cast<std::size_t>(6 * index[r] + index[k])];
  }
  return m;
}

// Jacobian of the sensor pose base (+) mount with respect to the base pose (x, y, theta).
Eigen::Matrix3d mountJacobian(const ebslam::Pose2& base, const ebslam::Pose2& mount) {
  const double c = std::cos(base.theta), s = std::sin(base.theta);
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j(0, 2) = -s * mount.x - c * mount.y;
  j(1, 2) = c * mount.x - s * mount.y;
  return j;
}

}  // namespace

void PlanarPoseFilterNodelet::onInitialPose(
    const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex());
  const auto reject = [&](const std::string& why) {
    ++rejected_initial_poses_;
    ++counters().bad_input;
    ROS_ERROR_THROTTLE(kWarnPeriodS, "%s: initialpose ignored: %s", getName().c_str(), why.c_str());
  };
  const geometry_msgs::Pose& p = msg->pose.pose;
  const double q_norm =
      std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
  if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) ||
      !std::isfinite(p.position.z) || !(std::abs(q_norm - 1.0) < 1e-3)) {
    reject("the pose must be finite with a unit quaternion");
    return;
  }
  for (double v : msg->pose.covariance) {
    if (!std::isfinite(v)) {
      reject("the covariance must be finite");
      return;
    }
  }
  // Into the map frame: rviz sends its fixed frame, which may be another one (tf2, latest).
  tf2::Transform in_frame;
  tf2::fromMsg(p, in_frame);
  tf2::Transform map_from_frame = tf2::Transform::getIdentity();
  const std::string& map_frame = poseNodeConfig().map_frame;
  const std::string frame = msg->header.frame_id.empty() ? map_frame : msg->header.frame_id;
  if (frame != map_frame) {
    try {
      tf2::fromMsg(tfBuffer().lookupTransform(map_frame, frame, ros::Time(0)).transform,
                   map_from_frame);
    } catch (const tf2::TransformException& error) {
      reject("no transform from frame " + frame + " to " + map_frame + ": " + error.what());
      return;
    }
  }
  const tf2::Transform base_in_map = map_from_frame * in_frame;
  const tf2::Matrix3x3& r = base_in_map.getBasis();
  const ebslam::Pose2 base{base_in_map.getOrigin().x(), base_in_map.getOrigin().y(),
                           std::atan2(r[1][0], r[0][0])};
  // The covariance turns with the frame (its rotation about z; roll and pitch are ignored).
  const tf2::Matrix3x3& fr = map_from_frame.getBasis();
  const double yaw = std::atan2(fr[1][0], fr[0][0]);
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  rotation.topLeftCorner<2, 2>() << std::cos(yaw), -std::sin(yaw), std::sin(yaw), std::cos(yaw);
  const Eigen::Matrix3d given = planarCovariance(msg->pose.covariance);
  const Eigen::Matrix3d base_cov = rotation * given * rotation.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(base_cov);
  if (!given.isApprox(given.transpose(), 1e-6) || eig.eigenvalues().minCoeff() < -1e-9) {
    reject("the (x, y, yaw) covariance must be symmetric positive semi-definite");
    return;
  }
  if (!resolveMount()) {
    reject("the sensor mounting is not known yet (tf " + config_.base_frame + " -> " +
           config_.sensor_frame + ")");
    return;
  }
  const Eigen::Matrix3d j = mountJacobian(base, *mount_);
  Seed seed{ebslam::compose(base, *mount_), j * base_cov * j.transpose()};
  seed.covariance = 0.5 * (seed.covariance + seed.covariance.transpose());
  if (backend_) {
    try {
      backend_->reseed(seed.sensor, seed.covariance);
    } catch (const std::invalid_argument& error) {
      reject(error.what());
      return;
    }
    clearPath();
  } else {
    pending_seed_ = seed;
  }
  pending_global_ = false;
  start_pose_ = base;
  ++initial_poses_;
  ROS_INFO("%s: initial pose (%.3f, %.3f, %.3f) in %s, std. dev. (%.3f m, %.3f m, %.3f rad)",
           getName().c_str(), base.x, base.y, base.theta, map_frame.c_str(),
           std::sqrt(std::max(0.0, base_cov(0, 0))), std::sqrt(std::max(0.0, base_cov(1, 1))),
           std::sqrt(std::max(0.0, base_cov(2, 2))));
}

bool PlanarPoseFilterNodelet::onGlobalLocalization(std_srvs::Empty::Request&,
                                                   std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(mutex());
  ++global_requests_;
  pending_seed_.reset();
  if (backend_) {
    backend_->globalLocalisation();
    clearPath();
  } else {
    pending_global_ = true;
  }
  ROS_INFO("%s: global localisation: hypotheses spread over the map", getName().c_str());
  return true;
}

void PlanarPoseFilterNodelet::feedOdometry(const ros::Time& stamp) {
  const PoseNodeConfig& frames = poseNodeConfig();
  tf2::Transform odom;
  try {
    tf2::fromMsg(tfBuffer().lookupTransform(frames.odom_frame, frames.base_frame, stamp).transform,
                 odom);
  } catch (const tf2::TransformException& error) {
    ++odometry_missing_;
    ROS_WARN_THROTTLE(
        kWarnPeriodS, "%s: no %s -> %s at the time of the events, processed without odometry: %s",
        getName().c_str(), frames.odom_frame.c_str(), frames.base_frame.c_str(), error.what());
    last_odom_.reset();
    return;
  }
  if (last_odom_) {
    // base_link's motion in its own frame, then the sensor's: mount^-1 (+) delta (+) mount.
    const tf2::Transform d = last_odom_->inverse() * odom;
    const tf2::Matrix3x3& r = d.getBasis();
    const ebslam::Pose2 base_delta{d.getOrigin().x(), d.getOrigin().y(),
                                   std::atan2(r[1][0], r[0][0])};
    backend_->applyOdometry(
        ebslam::compose(ebslam::compose(ebslam::inverse(*mount_), base_delta), *mount_));
  }
  last_odom_ = odom;
}

bool PlanarPoseFilterNodelet::diagnoseTracking(
    diagnostic_updater::DiagnosticStatusWrapper& status) const {
  if (!backend_ || !backend_->localisesOnMap()) return false;
  status.add("tracking state", ebslam::toString(backend_->trackingState()));
  status.add("kidnaps detected", backend_->recoveries());
  status.add("global searches converged", backend_->convergences());
  status.add("initial poses accepted", initial_poses_);
  status.add("initial poses rejected", rejected_initial_poses_);
  status.add("global localisation requests", global_requests_);
  status.add("odometry", use_odometry_ ? "on" : "off");
  if (use_odometry_) status.add("batches without odometry tf", odometry_missing_);
  if (backend_->trackingState() == ebslam::TrackingState::kGlobalSearch) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "global search (%d hypotheses): the pose is not yet known",
                    backend_->particles().size());
    return true;
  }
  return false;
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
    pending_seed_.reset();
    pending_global_ = map_localisation_ && config_.initial_pose_unknown;
    if (denoiser_) denoiser_->reset();
    restartRateLimit();
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
  // After the denoiser, which needs every event's neighbours: the cap thins what reaches the
  // filter.
  // The last pose of a segment carries its last event's time even when the cap dropped that
  // event (the estimate is then that of the last kept event, microseconds earlier).
  const std::int64_t segment_end_us = segment.events.empty() ? 0 : segment.events.back().t_us;
  const std::size_t thinned = limitRate(segment.events);
  if (!backend_) restart(start_pose_);
  if (thinned > 0) backend_->countUnprocessed(thinned);
  const std::size_t chunk = static_cast<std::size_t>(config_.max_events_per_update);
  for (std::size_t i = 0; i < segment.events.size(); i += chunk) {
    const std::size_t n = std::min(chunk, segment.events.size() - i);
    if (use_odometry_) feedOdometry(ebslam_msgs::toRosTime(segment.events[i + n - 1].t_us));
    try {
      backend_->process(segment.events.data() + i, n);
    } catch (const std::invalid_argument& error) {
      noteFilterError("filter", n, error);
      continue;
    }
    publish(ebslam_msgs::toRosTime(
        i + n == segment.events.size() ? segment_end_us : segment.events[i + n - 1].t_us));
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
  const PoseFilterBackend::CovarianceModel model = backend_->covarianceModel();
  const double floor_m2 = model.floor_m * model.floor_m;
  geometry_msgs::PoseWithCovariance::_covariance_type c{};
  c[0] = model.scale * cxx + floor_m2;
  c[1] = c[6] = model.scale * cxy;
  c[7] = model.scale * cyy + floor_m2;
  c[5] = c[30] = model.scale * cxt;
  c[11] = c[31] = model.scale * cyt;
  c[35] = model.scale * ctt + model.floor_rad * model.floor_rad;
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
  pending_seed_.reset();
  pending_global_ = map_localisation_ && !request.use_pose && config_.initial_pose_unknown;
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
  addDecoderDiagnostics(events_sub_, status);
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
