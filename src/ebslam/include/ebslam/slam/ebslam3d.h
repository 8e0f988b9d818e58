#pragma once

// Event-based 3D SLAM (thesis 8.3, alg. 9): a particle filter over SE(3) localises a D-eDVS
// (every event carries its 3D point) against an occurrence map O (voxel_map.h) built from the same
// events. Pose p: camera optical frame -> map frame, map point = R e + t (the thesis writes the
// inverse, eq. 8.7/8.8); map frame = start pose. Diffusion eq. 8.11-8.15, score alg. 9 (batched
// as eq. 6.30), map splat sigma = D / (2 lambda f) [m] (eq. 8.9/8.10). Events with a non-finite
// point or outside [min_range_m, max_range_m] are skipped and counted (rejectedEvents());
// timestamps going backwards throw std::invalid_argument. Events without a depth (a viewing ray
// only) are scored along the ray where the map predicts the surface (never mapped). When the
// tracking state says lost, mapping stops and the filter searches for the pose around the last
// good pose and the keyframes (poses mapped from), resuming mapping once the events fit again.
// Details: docs/ebslam_core.md#eb-slam-3d

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/pose.h"
#include "ebslam/slam/exponential_decay.h"
#include "ebslam/slam/fast_normal_generator.h"
#include "ebslam/slam/gyro_prior.h"
#include "ebslam/slam/tracking_state.h"
#include "ebslam/slam/voxel_map.h"

namespace ebslam {

/// One depth event: time and the 3D point it saw in the sensor's optical frame (x right, y down,
/// z forward) [m]; or, without a depth (has_depth false: the depth camera saw nothing there), the
/// unit viewing ray of its pixel in the same frame.
struct PointEvent {
  std::int64_t t_us = 0;  ///< [microseconds], non-decreasing within a stream
  Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< [m], or a unit ray without a depth
  bool has_depth = true;
};
using PointEventVector = std::vector<PointEvent>;

/// An event without a depth along `ray` (normalised here; a zero or non-finite ray stays as
/// given and is rejected by EventSlam3d::process).
PointEvent rayEvent(std::int64_t t_us, const Eigen::Vector3f& ray);

/// Where events are splatted into the occurrence map.
enum class MapSplat3d {
  kExpectedPose,  ///< once at p_* (fast; the 2D default)
  kAllParticles,  ///< once per particle, weighted by its normalised score (eq. 8.9)
};

/// Thresholds of the tracking state machine. The fit says whether the events lie where the map
/// predicts their surface: every sample_interval_s of event time one depth event is followed
/// along its ray from p_* through the map; where the strongest value along the ray is at least
/// min_surface_value, the event scores the map value at its own point over that strongest value
/// (1: on the predicted surface; 0: in front of or behind it, which contradicts the map); rays
/// through unexplored space (no such value) say nothing. The scores are smoothed over
/// fast_time_s of event time. Unlike a raw map value the fit does not grow with the map's age
/// or a surface's texture, and new territory is not taken for a loss.
/// Why: docs/ebslam_core.md#eb-slam-3d-relocalisation
struct TrackingHealthConfig {
  double fast_time_s = 0.02;    ///< [s of event time]
  double slow_time_s = 2.0;     ///< [s of event time] smoothing of fit_slow (reported only)
  double lost_fit = 0.2;        ///< fit below this: lost
  double recover_fit = 0.35;    ///< fit at or above this: recovering, then tracking
  double recover_hold_s = 0.5;  ///< [s of event time] above recover_fit before tracking
  double warmup_s = 0.5;        ///< [s of event time] always tracking while the map is new
  double min_surface_value = 3.0;
  double sample_interval_s = 0.0005;  ///< [s of event time]
  /// No event for longer than this [s of event time] (the sensor covered, blinded or
  /// disconnected): the motion in between is unknown, so the state turns lost and the search
  /// starts with the first batch after the gap (the fit alone can miss it: events from the
  /// moved sensor may still meet mapped surfaces). 0 = off. A still sensor in a still scene
  /// fires no events either; then the first search round finds the unchanged pose.
  double max_event_gap_s = 0.5;
};

/// Scoring of events without a depth (thesis 7.2 scores 2D events on the ceiling plane; here the
/// surface is the map's): the ray is followed from the estimate p_* through the map, the depth of
/// the strongest map value is taken as the event's depth, and every particle scores the best of
/// three points one voxel apart around it along its own view of the ray. Rays are never mapped.
struct RayScoringConfig {
  /// Off by default: on the tuning runs scoring rays cost accuracy (docs/results/ebslam3d.md).
  bool enabled = false;
  double max_depth_m = 4.0;  ///< farthest depth searched along a ray [m]
  /// A ray whose strongest map value (at p_*) is below this is not scored (nothing mapped there).
  double min_map_value = 0.5;
  double weight = 1.0;  ///< a scored ray's weight relative to a depth event's
  /// Rays are scored only while the share of events without a depth (smoothed over
  /// share_time_s of event time) is at least this: a fallback for when the depth camera sees
  /// little, since with depth present rays cost accuracy (docs/results/ebslam3d.md). 0 = always.
  double min_depthless_share = 0.5;
  double share_time_s = 0.1;  ///< [s of event time]
};

/// The search when lost (docs/ebslam_core.md#eb-slam-3d-relocalisation): every interval_s of
/// event time while lost, the particles are drawn afresh (their count raised to `particles`)
/// around the last good pose and the keyframes nearest it, the spread growing by `growth` per
/// round from the initial sigmas up to the max ones (coarse to fine: the filter's resampling
/// narrows each round onto the pose that fits); the best elite_share are kept. Keyframes: the
/// estimate while tracking, each keyframe_distance_m or keyframe_angle_rad from the previous
/// one, at most max_keyframes (beyond, every second one is dropped: memory is bounded).
struct RelocalisationConfig {
  bool enabled = true;
  int particles = 300;
  double interval_s = 0.25;             ///< [s of event time]
  double sigma_position_m = 0.05;       ///< first round [m]
  double sigma_rotation_rad = 0.1;      ///< first round [rad]
  double growth = 1.5;                  ///< per round
  double max_sigma_position_m = 0.4;    ///< [m]
  double max_sigma_rotation_rad = 0.8;  ///< [rad]
  double elite_share = 0.1;
  int candidate_keyframes = 8;        ///< keyframes nearest the last good pose searched per round
  double keyframe_distance_m = 0.1;   ///< [m]
  double keyframe_angle_rad = 0.175;  ///< [rad] (10 deg)
  int max_keyframes = 256;
};

/// Health of the filter after the last batch.
struct TrackingHealth {
  TrackingState state = TrackingState::kTracking;
  /// Effective sample size of the normalised scores over N, (0, 1].
  double ess_share = 1.0;
  double fit_fast = 0.0;         ///< the fit, smoothed over fast_time_s (see TrackingHealthConfig)
  double fit_slow = 0.0;         ///< its average over slow_time_s while tracking
  double fit_ratio = 1.0;        ///< fit_fast / fit_slow (1 while fit_slow is 0)
  std::uint64_t lost_count = 0;  ///< transitions into kLost since the (re)start
  double time_lost_s = 0.0;      ///< [s of event time] spent lost since the (re)start
  /// Losses ended by tracking again (LOST -> RELOCALISED), and the event time the last one took
  /// from entering kLost to kTracking [s].
  std::uint64_t relocalisations = 0;
  double last_relocalisation_s = 0.0;
  /// True from a relocalisation's end (back to kTracking after kLost) until the next loss.
  bool relocalised = false;
  /// Share of the depth events that fall near a mapped surface at p_* (smoothed over
  /// fast_time_s): low in unexplored space.
  double mapped_share = 1.0;
  /// Share of the valid events that had no depth (smoothed over RayScoringConfig::share_time_s).
  double depthless_share = 0.0;
  /// Gaps in the events longer than TrackingHealthConfig::max_event_gap_s that turned the
  /// state lost, since the (re)start.
  std::uint64_t event_gaps = 0;
};

/// Gyro rotation prior (used once EventSlam3d::addGyro has delivered samples; without them the
/// filter is unchanged). Each batch, every particle is rotated by the gyro's bias-corrected
/// rotation since the previous batch and the rotation diffusion becomes the gyro's remaining
/// uncertainty: variance (sigma_rotation_per_sqrt_s^2 + noise_density^2) dt + bias variance dt^2
/// (dt uncapped, no speed scaling; the per-event part stays). Batches the samples do not cover
/// fall back to the usual diffusion. The bias is estimated from the filter's own rotation over
/// windows of bias_window_s while tracking. Details: docs/ebslam_core.md#eb-slam-3d-imu
struct Ebslam3dImuConfig {
  bool enabled = true;  ///< false: samples are ignored
  GyroPriorConfig gyro;
  /// Rotation diffusion kept besides the gyro's own noise [rad / sqrt(s) of event time]: room
  /// for the map to correct calibration and model errors.
  double sigma_rotation_per_sqrt_s = 0.1;
  bool estimate_bias = true;
  double bias_window_s = 2.0;  ///< [s of event time] (0.5 s lagged: docs/results/ebslam3d.md)
};

struct Ebslam3dConfig {
  int num_particles = 100;   ///< N (8.4 default set: 100)
  int batch_size = 3;        ///< B in [1, 64] (default set: 3)
  int resample_every = 10;   ///< K: events between resamplings (thesis: 100)
  double event_share = 1.0;  ///< share of the accepted events used, (0, 1] (default set: all)
  /// Upper bound of the rate of events used [events per second of event time] (0 = none): above
  /// it the accepted events are thinned uniformly (share = bound / rate measured over the
  /// previous rate_window_s), so that the filter's cost per second of motion is bounded. Why:
  /// docs/ebslam_core.md#eb-slam-3d-rate-cap
  double max_event_rate = 60000.0;
  double rate_window_s = 0.01;  ///< [s of event time] window of the rate estimate
  /// Per-event diffusion std. devs (eq. 8.11-8.15): position [m], rotation angle [rad]. The
  /// thesis preset uses these (1e-3); the default preset diffuses per time instead (below).
  double sigma_position_m = 0.0;
  double sigma_rotation_rad = 0.0;
  /// Diffusion per time: random-walk std. devs per square root of a second of event time
  /// [m / sqrt(s)], [rad / sqrt(s)]. A batch spanning dt gets variance sigma^2 dt (plus the
  /// per-event part B sigma_event^2), dt capped at max_diffusion_dt_s: the spread the particles
  /// get depends on how far the sensor can have moved, not on how many events it fired.
  double sigma_position_per_sqrt_s = 0.1;
  double sigma_rotation_per_sqrt_s = 0.3;
  double max_diffusion_dt_s = 0.1;  ///< [s]
  /// Diffusion scaled by the recent motion: the per-time sigmas are multiplied by
  /// clamp(speed / reference speed, diffusion_min_scale, diffusion_max_scale), the speed being
  /// the estimate's angular [rad/s] (rotation) or linear [m/s] (position) speed, measured over
  /// windows of motion_window_s of event time and smoothed over motion_time_s. Why: a slow
  /// sensor needs less random walk (it lets the pose wander where nothing pulls it back), a fast
  /// turn more. min = max = 1 keeps the fixed sigmas. Why: docs/ebslam_core.md#eb-slam-3d-speed
  double diffusion_min_scale = 0.1;
  double diffusion_max_scale = 1.0;
  double reference_angular_speed = 0.5;  ///< [rad/s] speed at which the scale is 1
  double reference_linear_speed = 0.3;   ///< [m/s] speed at which the scale is 1
  /// The speeds are the rates between the means of the estimate over consecutive windows of
  /// motion_window_s (means, not end points: the mean's jitter averages out over a window while a
  /// shake of a few Hz does not), as magnitudes, smoothed over motion_time_s: a shake raises
  /// them although it nets no motion. Why: docs/ebslam_core.md#eb-slam-3d-speed
  double motion_window_s = 0.05;  ///< [s of event time]
  double motion_time_s = 0.25;    ///< [s of event time] smoothing of the speeds
  /// alpha of the score update (alg. 9), per event.
  double score_alpha = 0.05;
  double voxel_size_m = 0.02;  ///< occurrence-map voxel edge [m] (thesis: 1 cm)
  double splat_lambda = 1.5;   ///< lambda of eq. 8.10 (8.3: 1.5)
  double focal_px = 160.0;     ///< f of eq. 8.10: the event sensor's focal length [pixels]
  double min_range_m = 0.1;    ///< events nearer than this are rejected [m]
  double max_range_m = 10.0;   ///< events farther than this are rejected [m]
  /// Memory bound of the occurrence map [bytes] (0 = unbounded); the least recently written
  /// chunks are evicted beyond it.
  std::size_t max_map_bytes = 24u << 20;
  MapSplat3d splat = MapSplat3d::kExpectedPose;
  TrackingHealthConfig health;
  RayScoringConfig rays;
  RelocalisationConfig relocalisation;
  Ebslam3dImuConfig imu;
  std::uint64_t seed = 1;  ///< seeds the diffusion noise and the resampling

  /// This project's default preset: N 100, B 3, K 10, 2 cm voxels, at most 60k events/s, diffusion
  /// per time scaled by the speed within [0.1, 1] (docs/results/ebslam3d.md: chosen on the tuning
  /// half of its runs).
  static Ebslam3dConfig defaults() { return {}; }
  /// The fast preset: N 50, B 10, at most 35k events/s (the bound chosen on the tuning half,
  /// docs/results/ebslam3d.md), otherwise as defaults().
  static Ebslam3dConfig fast();
  /// The thesis' "default" set (8.4): N 100, K 100, B 3, all events, 1 cm voxels, per-event
  /// diffusion 1e-3 m and 1e-3 rad, no rate bound, no speed scaling.
  static Ebslam3dConfig thesis();

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// N weighted SE(3) hypotheses in structure-of-arrays layout.
class ParticleSet3D {
 public:
  void reset(int n, const Pose3& start, std::uint64_t seed);
  int size() const { return static_cast<int>(x_.size()); }
  Pose3 particle(int i) const;
  /// Score of particle i normalised so that the scores sum to 1 (1/N if all are zero).
  double normalisedWeight(int i) const;
  double score(int i) const { return scores_.score(static_cast<std::size_t>(i)); }
  /// Score-weighted mean pose (plain mean while all scores are zero); quaternions are aligned to
  /// the first particle's sign before averaging.
  Pose3 weightedMean() const;
  /// Weighted covariance of position [m^2] and rotation (small-angle vector about the mean
  /// [rad^2]), order x y z rx ry rz.
  Eigen::Matrix<double, 6, 6> covariance(const Pose3& mean) const;

  /// One batch: diffuse every particle (sigmas already scaled for the batch), score the batch's
  /// points through its pose against `map` and update its score with `decay`. Points with
  /// is_ray[j] != 0 (is_ray may be null: none) are depth-less events placed at their predicted
  /// depth: each scores ray_weight times the best of three points along its ray, one voxel apart.
  /// Returns the largest summed map value of the batch over the particles.
  float step(const Eigen::Vector3f* points, const std::uint8_t* is_ray, int batch,
             const ChunkedVoxelMap& map, float sigma_position, float sigma_rotation,
             const BatchDecay& decay, float ray_weight = 1.0f);
  /// Effective sample size of the normalised scores over N, (0, 1] (1 if the total is zero).
  double essShare() const;
  /// Systematic resampling (children keep their parent's score, as in EB-SLAM-2D) to `count`
  /// particles (0: as many as now). Returns false (and does nothing) when the total score is
  /// zero or not finite.
  bool resampleSystematic(int count = 0);
  /// Replaces every particle by `poses` (at least one), all with score 1 (alg. 9's start).
  void assign(const std::vector<Pose3>& poses);
  /// Indices of the `count` highest scores, best first.
  std::vector<int> best(int count) const;
  /// Rotates every particle by `delta` in its own (sensor) frame: q <- q delta.
  void rotateBody(const Eigen::Quaternionf& delta);

 private:
  std::vector<float> x_, y_, z_, qw_, qx_, qy_, qz_;
  DecayingScores scores_;
  FastNormalGenerator rng_{1};
  std::vector<float> scratch_;
  std::vector<double> scratch_w_;
};

class EventSlam3d {
 public:
  /// Throws std::invalid_argument for an invalid config.
  explicit EventSlam3d(const Ebslam3dConfig& config, const Pose3& start = {});

  /// Statistics of one process() call.
  struct ProcessStats {
    std::size_t used = 0;      ///< events scored and mapped
    std::size_t rejected = 0;  ///< non-finite or out-of-range points (skipped)
    std::size_t skipped = 0;   ///< accepted but left out by event_share or max_event_rate
    /// Of the used: events without a depth scored along their ray, and those not scored (ray
    /// scoring off, or nothing mapped along the ray).
    std::size_t rays_scored = 0;
    std::size_t rays_unscored = 0;
  };
  /// Processes events in order, in batches of B (a trailing partial batch is processed as a
  /// smaller batch with its own decay). Throws std::invalid_argument, processing nothing, if a
  /// timestamp is earlier than its predecessor (or than the last event of the previous call).
  /// An empty span is a no-op.
  ProcessStats process(const PointEvent* events, std::size_t count);
  ProcessStats process(const PointEventVector& events) {
    return process(events.data(), events.size());
  }

  /// Gyro reading for the rotation prior (Ebslam3dImuConfig): mean rate over the interval ending
  /// at t_us (event clock) in the IMU frame [rad/s]. Give samples ahead of the events they
  /// cover (a batch not covered falls back to the usual diffusion). Rejected samples (non-finite,
  /// saturated, not after the previous) change nothing; see GyroPrior::AddResult.
  GyroPrior::AddResult addGyro(std::int64_t t_us, const Eigen::Vector3d& rate_imu);
  /// The gyro integrator (bias estimate, samples).
  const GyroPrior& gyro() const { return gyro_; }
  /// Batches rotated by the gyro / left to the usual diffusion although samples had arrived.
  std::uint64_t gyroPredictedBatches() const { return gyro_predicted_; }
  std::uint64_t gyroUncoveredBatches() const { return gyro_uncovered_; }

  /// Restarts with an empty map and all particles at `start` (the time order starts afresh).
  void reset(const Pose3& start = {});
  /// Changes the filter's knobs while running (the map is kept): particle count, batch size,
  /// resampling interval, event share, diffusion, score alpha, splat, ranges (the seed is used
  /// when the particles restart). A new particle count restarts the particles at the current
  /// estimate p_* (scores zero). Throws std::invalid_argument (nothing changed) for an invalid
  /// config or a change of the map's layout (voxel_size_m, max_map_bytes), which needs a new
  /// EventSlam3d.
  void setConfig(const Ebslam3dConfig& config);

  /// Expected pose p_* (score-weighted mean, updated after every batch).
  const Pose3& estimate() const { return expected_; }
  /// Covariance of the particles about p_* (see ParticleSet3D::covariance).
  Eigen::Matrix<double, 6, 6> covariance() const { return particles_.covariance(expected_); }
  const ParticleSet3D& particles() const { return particles_; }
  const ChunkedVoxelMap& map() const { return map_; }
  const Ebslam3dConfig& config() const { return config_; }
  /// Tracking state and its evidence after the last batch.
  const TrackingHealth& health() const { return health_; }
  std::uint64_t processedEvents() const { return processed_; }
  /// Smoothed speeds of the estimate that scale the diffusion: [rad/s] and [m/s].
  double angularSpeed() const { return angular_speed_; }
  double linearSpeed() const { return linear_speed_; }
  std::uint64_t rejectedEvents() const { return rejected_; }
  /// Events without a depth scored along their ray, and those not scored, since the (re)start.
  std::uint64_t raysScored() const { return rays_scored_; }
  std::uint64_t raysUnscored() const { return rays_unscored_; }
  /// Poses the map was built from, the relocalisation's search candidates (bounded).
  const std::vector<Pose3>& keyframes() const { return keyframes_; }
  /// Whether the events of the last batch were mapped (only while tracking).
  bool mapping() const { return health_.state == TrackingState::kTracking; }
  /// Time of the last event seen [us] (INT64_MIN before the first).
  std::int64_t lastEventTime() const { return last_t_us_; }
  /// Memory of map and particles [bytes], and its peak since construction.
  std::size_t memoryBytes() const;
  std::size_t peakMemoryBytes() const;

 private:
  void runBatch(int b, ProcessStats& stats);
  /// Depth along a ray at p_* where the map is strongest (at least min_value; its value in
  /// *value if given); 0 if nothing that strong is mapped along it.
  float predictRayDepth(const Eigen::Vector3f& ray, float min_value, float* value = nullptr) const;
  void updateMotion();
  void restartMotion();
  double diffusionScale(double speed, double reference) const;
  /// Fit of one depth event of the batch at p_* (see TrackingHealthConfig), or false when none
  /// is due or its ray crosses no mapped surface (*mapped_share: 0 in that case, 1 otherwise).
  bool fitAtEstimate(int b, double* fit, double* mapped_share);
  void updateHealth(int b, double dt_s);
  // Into kLost (from kTracking or kRecovering), starting the search when it is enabled.
  void enterLost();
  void updateKeyframes();
  void reseed();
  void splat(const Eigen::Vector3f& point, const Eigen::Quaternionf& q, const Eigen::Vector3f& t,
             float weight);

  Ebslam3dConfig config_;
  ChunkedVoxelMap map_;
  ParticleSet3D particles_;
  std::vector<BatchDecay> batch_decay_;  // index b - 1
  Pose3 expected_;
  Eigen::Vector3f batch_[64];
  std::uint8_t batch_ray_[64] = {};
  std::int64_t batch_end_us_ = 0;       // time of the batch's last event [us]
  std::int64_t prev_batch_end_us_ = 0;  // of the previous batch (0 before the first)
  bool have_prev_batch_ = false;
  // Motion estimate for the speed-scaled diffusion: sums over the current window of the
  // estimate's rotation vector about motion_ref_ [rad], its position [m] and time [s]; the
  // previous window's mean; the smoothed speeds [rad/s], [m/s] (start: the reference speeds).
  Eigen::Quaterniond motion_ref_;
  Eigen::Vector3d motion_rotation_sum_, motion_position_sum_;
  double motion_time_sum_ = 0.0;
  int motion_count_ = 0;
  std::int64_t motion_window_start_us_ = 0;
  bool motion_window_open_ = false;
  Pose3 motion_prev_mean_;
  double motion_prev_t_s_ = 0.0;
  bool motion_prev_set_ = false;
  double angular_speed_ = 0.0;
  double linear_speed_ = 0.0;
  int in_batch_ = 0;
  double share_accumulator_ = 0.0;
  // Rate cap: events accepted in the current window, its start, the share applied in it.
  std::int64_t rate_window_start_us_ = 0;
  std::uint64_t rate_window_count_ = 0;
  double rate_share_ = 1.0;
  bool rate_window_open_ = false;
  TrackingHealth health_;
  bool health_started_ = false;
  std::int64_t health_start_us_ = 0;
  std::int64_t next_health_sample_us_ = 0;
  std::int64_t last_health_sample_us_ = 0;
  bool have_health_sample_ = false;
  double above_recover_s_ = 0.0;
  // Relocalisation: the last pose that fitted, keyframes, the loss's start, the search round.
  Pose3 last_good_;
  std::vector<Pose3> keyframes_;
  std::int64_t lost_since_us_ = 0;
  std::int64_t next_reseed_us_ = 0;
  int search_round_ = 0;
  std::uint64_t reseed_rng_state_ = 0;
  std::int64_t share_last_us_ = 0;  // time of the last event in depthless_share
  bool share_started_ = false;
  std::uint64_t processed_ = 0;
  std::uint64_t rejected_ = 0;
  std::uint64_t rays_scored_ = 0;
  std::uint64_t rays_unscored_ = 0;
  int since_resample_ = 0;
  std::int64_t last_t_us_;

  // ---- Gyro rotation prior (Ebslam3dImuConfig) ----
  // Rotates the particles by the gyro's rotation since the previous batch; returns the rotation
  // variance to diffuse with, or `fallback` when the samples do not cover the batch.
  double applyGyroPrior(double fallback_var, double per_event_var);
  void updateGyroBias();
  GyroPrior gyro_;
  bool gyro_prev_set_ = false;
  std::int64_t gyro_prev_us_ = 0;  // end of the previous batch the prior saw [us]
  bool bias_ref_set_ = false;
  std::int64_t bias_ref_us_ = 0;             // start of the bias window [us]
  Eigen::Quaterniond bias_ref_orientation_;  // estimate at its start
  std::uint64_t gyro_predicted_ = 0;
  std::uint64_t gyro_uncovered_ = 0;
  // ---- end gyro rotation prior ----
};

}  // namespace ebslam
