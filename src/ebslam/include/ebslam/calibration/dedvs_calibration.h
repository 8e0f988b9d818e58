#pragma once

// Calibration of the D-eDVS with a pulsed LED (thesis 8.2, eq. 8.4-8.6, fig. 8.4): a blinking
// diode on a plate gives correspondences (depth pixel u_i, depth D_i, eDVS pixel v_i); eq. 8.5 is
// solved with Levenberg-Marquardt (Ceres) over the extrinsics and the eDVS camera, the depth
// intrinsics fixed. Optical frames, metres, pixel centres at integer coordinates. The R, t of
// eq. 8.4 is edvs_from_depth; the result is stored as DedvsSensors::depth_from_edvs
// (p_depth = depth_from_edvs * p_edvs). Details: docs/dedvs_core.md#calibration

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/event.h"
#include "ebslam/simulation/dedvs_io.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/slam/camera_model.h"

namespace ebslam {

// ---------------------------------------------------------------------------------------------
// Simulated calibration run.

/// A calibration run of the D-eDVS simulator: the rig stands still (its depth optical frame is
/// the world frame) and a checkerboard plate with the LED at the centre of its middle square
/// (the middle 3 x 3 squares light) moves between random poses (stop and go: it moves for move_s,
/// then rests for rest_s). The poses put the LED at random eDVS pixels (a share of them in the
/// image's corners, the rest uniform) and uniform depths, the plate tilted towards the rig: the
/// capture procedure of docs/dedvs_rig.md.
struct LedCalibrationRunConfig {
  /// Sensors, noise and the true calibration. The eDVS events come from the simulator's event
  /// model (noise included), the depth from its depth camera model.
  DedvsSimulatorConfig simulator;
  /// LED square-wave frequency [Hz]. The thesis gives none; 250 Hz is far above the plate's
  /// motion and well below the eDVS' event rate per pixel (100 us refractory period). The
  /// simulator renders 8 times per period, so the frequency sets the simulation's cost.
  double led_frequency_hz = 250.0;
  /// Radius of the diode's diffuser disc [m]: the eDVS sees a spot of sigma = f r / z pixels
  /// (at least 0.6 px), so that several pixels respond and their centroid is sub-pixel exact.
  double led_radius_m = 0.01;
  double led_on_intensity = 4.0;  ///< added intensity while on (texture units, ~9x the plate)
  int poses = 150;                ///< plate poses; duration = poses * (move_s + rest_s) - move_s
  double move_s = 0.05;           ///< time to move from one pose to the next [s]
  /// Time the plate rests at each pose [s]: one or two depth frames whose LED window lies in
  /// the rest (many distinct poses matter more than many frames per pose).
  double rest_s = 0.08;
  double min_depth_m = 0.55;  ///< LED depth range in the depth frame [m]
  double max_depth_m = 1.8;
  double max_tilt_deg = 25.0;  ///< plate tilt about its x and y axes [deg]
  /// Share of the poses with the LED in one of the eDVS image's four corners (the corners in
  /// turn), in [0, 1]; the others put it anywhere in the image. Only LED positions far from the
  /// image centre in both x and y tell a small rotation from a shift of the principal point.
  double corner_pose_fraction = 0.5;
  /// A corner: the square of this fraction of the image width and height at each image corner
  /// (inside border_margin_px), in (0, 0.5].
  double corner_size_fraction = 0.15;
  int squares = 9;               ///< squares per plate side (odd: the LED sits in one)
  double square_size_m = 0.035;  ///< [m]
  /// Margin of the LED's eDVS and depth pixel from the image borders [px].
  double border_margin_px = 4.0;
  /// Standard deviation of the LED's depth-camera pixel [px]: the plate's corners tracked in
  /// the colour image locate it to about a tenth of a pixel.
  double led_pixel_noise_px = 0.1;
  /// The LED's depth: a plane fitted to the measured depth (1/z linear in the pixel) within
  /// this radius [depth px] around the LED's pixel, evaluated at that pixel.
  double depth_fit_radius_px = 4.0;
  /// Fraction of the final event stream made of outlier events: uniformly random pixel,
  /// polarity and time over the run, added to the simulator's events. In [0, 0.9].
  double outlier_event_fraction = 0.0;
  std::uint64_t seed = 1;  ///< plate poses, LED pixel noise and outliers

  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

/// The LED as the depth camera sees it in one frame.
struct DepthLedObservation {
  double t_s = 0.0;            ///< exposure time on the event clock [s]
  Eigen::Vector2d pixel;       ///< depth-camera pixel [px] (with tracking noise)
  double depth_m = 0.0;        ///< measured z of the LED in the depth frame [m]
  Eigen::Vector3d true_point;  ///< true LED position in the depth optical frame [m]
};

struct LedCalibrationRun {
  std::vector<Event> events;  ///< eDVS events sorted by time, outliers included
  std::vector<DepthLedObservation> depth_observations;  ///< frames where the LED has depth
  DedvsSensors truth;  ///< the simulated sensors and their true calibration
  std::size_t outlier_events = 0;
  double duration_s = 0.0;
};

/// Simulates a calibration run. Deterministic for a given config. Every depth frame (with its
/// registered colour image, the LED visible in it) also goes to `frame_sink` when given, in time
/// order. Throws std::invalid_argument for an invalid config.
LedCalibrationRun simulateLedCalibrationRun(const LedCalibrationRunConfig& config = {},
                                            const DedvsSimulator::DepthSink& frame_sink = {});

// ---------------------------------------------------------------------------------------------
// LED extraction from the event stream.

/// Per-pixel periodicity filter. In a window of window_periods LED periods centred on the
/// wanted time, a pixel belongs to the LED when it fired ON and OFF events in at least
/// min_cycle_fraction of the periods of each half of the window (so the LED rested on it for
/// the whole window) and the polarity-signed events are phase-coherent at the
/// LED frequency (|sum p_k exp(-2 pi i f t_k)| / n >= min_phase_coherence; a moving edge fires
/// one polarity once, noise is incoherent). The LED position is the centroid of the LED pixels
/// near the strongest one, weighted by their coherent event count, refined once around itself.
struct LedExtractionConfig {
  double led_frequency_hz = 250.0;   ///< known LED frequency [Hz]
  int window_periods = 8;            ///< window length in periods, in [2, 64]
  double min_cycle_fraction = 0.75;  ///< in (0, 1]
  double min_phase_coherence = 0.5;  ///< in [0, 1]
  /// LED pixels farther than this from the strongest one (then from the first centroid) are
  /// ignored [px]; the spot of a near LED spans about 7 px.
  double centroid_radius_px = 8.0;
  /// Pixels weaker than this fraction of the strongest are ignored.
  double min_weight_fraction = 0.2;
  /// Fewer LED pixels are no LED (a single pixel can pass by chance while the plate moves);
  /// the diffused diode's spot covers about 15 pixels at 1.8 m.
  int min_spot_pixels = 4;
  /// Largest distance between the spot's centroids in the first and the second half of the
  /// window [px]: the LED must rest (the plate held still) during the window.
  double max_motion_px = 0.3;
  int width = 128;  ///< sensor size [px]
  int height = 128;

  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

struct LedObservation {
  double t_s = 0.0;       ///< window centre [s]
  Eigen::Vector2d pixel;  ///< eDVS pixel [px], distorted coordinates
  int pixels = 0;         ///< LED pixels in the centroid
  double score = 0.0;     ///< coherent event count of the strongest pixel
};

/// The LED in the window centred on t_s. `events` must be sorted by time. std::nullopt when
/// no pixel passes the filter (LED hidden, outside the sensor, or moving too fast to stay on a
/// pixel for half the window), when it moved during the window (max_motion_px) or when the
/// spot touches the sensor's border (its centroid would be biased). Throws std::invalid_argument
/// for an invalid config.
std::optional<LedObservation> extractLed(const std::vector<Event>& events, double t_s,
                                         const LedExtractionConfig& config = {});

// ---------------------------------------------------------------------------------------------
// Calibration (eq. 8.4-8.6).

/// One data point of eq. 8.5.
struct LedCorrespondence {
  Eigen::Vector2d depth_pixel;  ///< u [depth px]
  double depth_m = 0.0;         ///< D [m]
  Eigen::Vector2d edvs_pixel;   ///< v [eDVS px]
};

/// Pairs each depth observation with the LED extracted from the events at its time;
/// observations without an LED in the events are dropped.
std::vector<LedCorrespondence> collectLedCorrespondences(
    const std::vector<Event>& events, const std::vector<DepthLedObservation>& depth_observations,
    const LedExtractionConfig& config = {});

struct DedvsCalibrationConfig {
  /// Initial eDVS camera (eq. 8.6: f = 160 px, centre of the 128 x 128 sensor, no distortion);
  /// its width, height and distortion model are kept.
  CameraModel initial_edvs = defaultInitialEdvs();
  /// Initial extrinsics (eq. 8.6: identity; the sensors sit close together, looking the same
  /// way).
  Eigen::Isometry3d initial_depth_from_edvs = Eigen::Isometry3d::Identity();
  /// The solve runs (at least) twice: with a Huber loss of coarse_loss_scale_px from the initial
  /// values (the start may be several pixels off), then with a Cauchy loss of loss_scale_px
  /// (outlier correspondences get almost no weight) [px].
  double coarse_loss_scale_px = 3.0;
  double loss_scale_px = 1.0;
  /// Correspondences whose final residual is below this count as inliers [px]; the RMSE is
  /// over the inliers.
  double inlier_threshold_px = 3.0;
  /// A third solve keeps the correspondences within this many robust standard deviations and
  /// inlier_threshold_px (0 = none). Why: docs/dedvs_core.md#calibration
  double outlier_sigmas = 3.0;
  int max_iterations = 200;  ///< per stage
  /// Fewer correspondences throw (11 parameters; a few per parameter are needed for the
  /// distortion to be determined). At least 6.
  std::size_t min_correspondences = 20;
  /// Expected failures (status, no exception): fewer inliers than min_inlier_fraction of the
  /// correspondences, or an inlier RMSE above max_rmse_px [px].
  double min_inlier_fraction = 0.5;
  double max_rmse_px = 2.0;

  static CameraModel defaultInitialEdvs();
  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

enum class CalibrationStatus : std::uint8_t {
  kOk = 0,
  kNotConverged,   ///< the solver stopped without convergence (iterations, numerical failure)
  kTooFewInliers,  ///< see DedvsCalibrationConfig::min_inlier_fraction
  kHighError,      ///< inlier RMSE above DedvsCalibrationConfig::max_rmse_px
  kInvalidCamera,  ///< the fitted distortion is not invertible inside the sensor
};
const char* toString(CalibrationStatus status);

/// Standard deviations of the calibration from the covariance Ceres estimates at the solution:
/// (J^T J)^-1 over the correspondences of the final solve, scaled by their residual variance
/// (sum of squares / (n - 11)). A small rotation of the eDVS and a shift of its principal point
/// move the LED almost alike; only LED positions far from the image centre tell them apart, so
/// the rotation is the first to become uncertain when the poses stay near the centre.
struct CalibrationUncertainty {
  /// Rotation of depth_from_edvs [deg]: about the eDVS x, y, z axes, and along the worst
  /// direction (square root of the covariance's largest eigenvalue).
  Eigen::Vector3d rotation_axes_std_deg{0.0, 0.0, 0.0};
  double rotation_std_deg = 0.0;
  Eigen::Vector3d translation_std_mm{0.0, 0.0, 0.0};  ///< x, y, z [mm]
  double focal_std_px = 0.0;
  Eigen::Vector2d principal_point_std_px{0.0, 0.0};
  /// Largest |correlation| between a rotation component and a principal point component (near
  /// 1: the poses do not separate them).
  double rotation_principal_point_correlation = 0.0;
};

struct DedvsCalibrationResult {
  CalibrationStatus status = CalibrationStatus::kOk;
  /// The base sensors with the fitted eDVS camera and depth_from_edvs (filled whatever the
  /// status, for inspection).
  DedvsSensors sensors;
  double rmse_px = 0.0;      ///< eDVS reprojection RMSE over the inliers [px]
  double rmse_all_px = 0.0;  ///< over all correspondences [px]
  std::size_t inliers = 0;
  int iterations = 0;                ///< both stages
  std::vector<double> residuals_px;  ///< per correspondence [px]
  /// The solver's standard deviations; empty when the correspondences leave the parameters
  /// undetermined (a singular covariance).
  std::optional<CalibrationUncertainty> uncertainty;
};

/// Solves eq. 8.5 from `correspondences`. `base` gives the depth camera (fixed), the eDVS size,
/// clock offset and frame rate, which are copied into the result. Throws
/// std::invalid_argument for fewer than config.min_correspondences correspondences, a
/// non-finite value or a depth <= 0 in them, an invalid depth camera or an invalid config.
DedvsCalibrationResult calibrateDedvs(const std::vector<LedCorrespondence>& correspondences,
                                      const DedvsSensors& base,
                                      const DedvsCalibrationConfig& config = {});

/// Where the LED was in the eDVS image over the poses: the pose diversity a calibration needs.
struct LedPoseCoverage {
  std::size_t poses = 0;
  /// Poses with the LED in each corner of the eDVS image (top-left, top-right, bottom-left,
  /// bottom-right; a corner as in LedCalibrationRunConfig::corner_size_fraction).
  std::array<std::size_t, 4> corners{};
  double min_depth_m = 0.0;  ///< LED depth range over the poses [m]
  double max_depth_m = 0.0;
};

/// Counts the correspondences' eDVS pixels in the corners of a width x height eDVS image
/// (corner_size_fraction in (0, 0.5]; throws std::invalid_argument otherwise).
LedPoseCoverage ledPoseCoverage(const std::vector<LedCorrespondence>& correspondences, int width,
                                int height, double corner_size_fraction = 0.15);

/// What the user should do with the LED plate when the calibration's rotation is uncertain
/// (result.uncertainty's worst-direction standard deviation above max_rotation_std_deg, or no
/// uncertainty at all), in words a user can act on; empty when the rotation is determined well
/// enough. The default, 0.033 deg, puts a 0.1 deg error at three standard deviations.
std::string advisePoseDiversity(const DedvsCalibrationResult& result,
                                const LedPoseCoverage& coverage,
                                double max_rotation_std_deg = 0.033);

/// The eDVS pixel (eq. 8.4) of a depth pixel with depth, for the given sensors; std::nullopt
/// behind the eDVS.
std::optional<Eigen::Vector2d> depthToEdvsPixel(const DedvsSensors& sensors,
                                                const Eigen::Vector2d& depth_pixel, double depth_m);

/// Difference of two depth_from_edvs transforms: translation [mm] and rotation angle [deg].
struct ExtrinsicError {
  double translation_mm = 0.0;
  double rotation_deg = 0.0;
};
ExtrinsicError extrinsicError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);

}  // namespace ebslam
