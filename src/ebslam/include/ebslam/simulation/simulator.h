#pragma once

// Event simulator: a dynamic vision sensor moving through a static world of textured planes
// (thesis 6.2 and the simulation of 6.5.3): anti-aliased ray casting at a high internal rate and
// the per-pixel event model of event_model.h; everything random is seeded. Event times are the
// trajectory's own clock in us, round(t_s * 1e6), shared with the ground truth.
// Details: docs/event_simulator.md#model

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/event_model.h"
#include "ebslam/slam/camera_model.h"

namespace ebslam {

/// A rectangle in the world with an intensity texture.
///
/// Plane frame: `pose` maps plane coordinates to world coordinates. The plane is z = 0 in its
/// frame; texel (col, row) of the texture covers plane coordinates
/// [col, col + 1) * metres_per_texel in x and [row, row + 1) * metres_per_texel in y, i.e. the
/// texture's top-left corner is at the plane origin. The plane extends over
/// [0, size_m.x()] x [0, size_m.y()]; with `repeat` the texture is tiled over that extent,
/// otherwise the extent is clipped to the texture. Both faces are visible.
struct TexturedPlane {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< plane -> world
  Eigen::Vector2d size_m{1.0, 1.0};                        ///< extent of the plane [m]
  /// Intensity, CV_32FC1 with values in [0, 1] (linear irradiance, arbitrary unit); use
  /// textureFromImage() to convert a photograph.
  cv::Mat texture;
  double metres_per_texel = 0.01;  ///< texel edge length on the plane [m]
  bool repeat = true;              ///< tile the texture over the extent
  /// Reflectance colour (linear RGB factors on the intensity) for colour cameras; event
  /// sensors see the intensity texture alone.
  Eigen::Vector3f colour = Eigen::Vector3f::Ones();

  /// Throws std::invalid_argument with the reason if the plane is unusable (empty or wrongly
  /// typed texture, non-positive sizes, non-finite pose).
  void validate() const;
};

/// The static world the sensor looks at.
struct Scene {
  std::vector<TexturedPlane> planes;
  /// Intensity of rays that hit no plane, in the texture's unit.
  double background_intensity = 0.5;

  /// Throws std::invalid_argument naming the first invalid plane or a negative background.
  void validate() const;
};

/// Converts an 8-bit or 16-bit grey or BGR image, or a float image, to the texture format
/// (CV_32FC1, 8-bit values / 255). Throws std::invalid_argument for an empty image.
cv::Mat textureFromImage(const cv::Mat& image);

/// Parameters of rendering and time stepping.
struct SimulatorConfig {
  CameraModel camera;
  EventModelConfig events;
  /// Minimum render rate [Hz]; steps are subdivided further when the image would move more
  /// than max_step_motion_px between two renders (so fast motion renders at a higher rate).
  double render_rate_hz = 250.0;
  /// Largest image motion between two renders [pixels], estimated at the sensor corners and
  /// centre. Keeps the linear interpolation of event times accurate to a fraction of the time
  /// an edge needs to cross one pixel.
  double max_step_motion_px = 0.2;
  /// Standard deviation of the optical point spread [pixels]. The texture is blurred with this
  /// Gaussian (scaled to the plane at its distance from the first camera pose) combined with
  /// the pixel's own area (a unit box, variance 1/12 per axis).
  double blur_sigma_px = 0.3;
  /// Supersampling: samples per pixel along each axis (1 = one ray through the pixel centre).
  int supersampling = 1;
  /// Rate of the ground-truth camera poses written to SimulationResult [Hz].
  double ground_truth_rate_hz = 200.0;

  void validate() const;
};

/// Everything a simulation produces.
struct SimulationResult {
  EventVector events;  ///< sorted by time, all inside the sensor
  /// Per event of `events`: 1 for a background noise event, 0 for a signal event (intensity
  /// change); filled by the collecting simulate() only.
  std::vector<std::uint8_t> noise_labels;
  Trajectory ground_truth;        ///< camera poses (camera -> world) at ground_truth_rate_hz
  std::size_t signal_events = 0;  ///< events from intensity changes
  std::size_t noise_events = 0;   ///< background noise events
  std::size_t render_steps = 0;   ///< number of rendered images
};

/// The simulator's state between render steps (reference levels, thresholds, refractory times,
/// noise process, prepared textures), so that the camera can be moved step by step, e.g. by a
/// robot controller in closed loop, instead of along a trajectory known in advance.
/// EventSimulator::simulate runs one stream over the whole trajectory; a stream moved in pieces
/// gives the same events as one moved in one piece whenever the pieces' ends fall on its render
/// steps. Not thread-safe; movable.
class EventStream {
 public:
  /// Camera pose (camera -> world) at time t_s [s].
  using PoseAt = std::function<Eigen::Isometry3d(double t_s)>;
  /// Receives the events of one render step (sorted by time, possibly empty), their noise labels
  /// (1 = background noise event) and the step's end time [s]; called once per render step in
  /// time order.
  using StepSink = std::function<void(const EventVector& events,
                                      const std::vector<std::uint8_t>& is_noise, double t_end_s)>;

  /// Renders the first image at `start_pose` (camera -> world) at time t_s [s]; no events.
  /// Throws std::invalid_argument for an invalid config or scene or a non-finite pose or time.
  EventStream(const SimulatorConfig& config, const Scene& scene,
              const Eigen::Isometry3d& start_pose, double t_s);
  ~EventStream();
  EventStream(EventStream&&) noexcept;
  EventStream& operator=(EventStream&&) noexcept;

  /// Moves the camera along pose_at from time() to t_end_s, rendering at least at
  /// config.render_rate_hz and finer while the image moves more than max_step_motion_px.
  /// pose_at(time()) should equal pose(). Throws std::invalid_argument if t_end_s is not after
  /// time() or not finite, or pose_at returns a non-finite pose (the stream is then unchanged up
  /// to the failing step).
  /// Without `with_labels` the sink receives an empty label vector (the events are the same;
  /// saves sorting the labels with them).
  void advance(double t_end_s, const PoseAt& pose_at, const StepSink& sink,
               bool with_labels = true);
  /// advance() with the camera moving from pose() to `pose` at constant velocity (linear
  /// position, slerp orientation) over [time(), t_end_s]; appends the events to `events` and,
  /// if given, their noise labels to `noise_labels`.
  void moveTo(const Eigen::Isometry3d& pose, double t_end_s, EventVector& events,
              std::vector<std::uint8_t>* noise_labels = nullptr);

  double time() const;
  const Eigen::Isometry3d& pose() const;
  std::size_t signalEvents() const;
  std::size_t noiseEvents() const;
  std::size_t renderSteps() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Simulates an event camera moving along a trajectory through a scene.
class EventSimulator {
 public:
  /// Throws std::invalid_argument if the configuration is invalid.
  explicit EventSimulator(const SimulatorConfig& config = {});

  const SimulatorConfig& config() const { return config_; }

  /// Receives the events of one render interval, sorted by time; called in time order.
  using EventSink = std::function<void(const EventVector& events)>;
  /// As EventSink, with is_noise[i] = 1 when events[i] is a background noise event.
  using LabelledEventSink =
      std::function<void(const EventVector& events, const std::vector<std::uint8_t>& is_noise)>;

  /// Simulates the camera (pose = camera -> world, camera frame as in CameraModel) moving
  /// along `camera_trajectory` from t_begin_s to t_end_s [s, trajectory clock] and streams the
  /// events to `sink`. Returns the statistics and the ground truth (result.events stays empty).
  /// Throws std::invalid_argument for an invalid scene or trajectory (fewer than two poses,
  /// non-increasing times, non-finite values) or a time range outside the trajectory or empty.
  SimulationResult simulate(const Scene& scene, const Trajectory& camera_trajectory,
                            double t_begin_s, double t_end_s, const EventSink& sink) const;

  /// As above, with the noise label of every event (for scoring noise filters).
  SimulationResult simulateLabelled(const Scene& scene, const Trajectory& camera_trajectory,
                                    double t_begin_s, double t_end_s,
                                    const LabelledEventSink& sink) const;

  /// As above, collecting all events and their noise labels in the result.
  SimulationResult simulate(const Scene& scene, const Trajectory& camera_trajectory,
                            double t_begin_s, double t_end_s) const;

  /// Renders the intensity image (CV_32FC1, width x height) the sensor sees at `camera_pose`
  /// (camera -> world); for visualisation and tests.
  cv::Mat renderIntensity(const Scene& scene, const Eigen::Isometry3d& camera_pose) const;

 private:
  SimulatorConfig config_;
};

}  // namespace ebslam
