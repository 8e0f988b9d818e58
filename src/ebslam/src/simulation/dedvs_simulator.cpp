#include "ebslam/simulation/dedvs_simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "dedvs_room_renderer.h"

namespace ebslam {
namespace {

using dedvs_render::Hits;
using dedvs_render::kNoHit;
using dedvs_render::PreparedPlane;
using dedvs_render::RayGrid;
using dedvs_render::RoomRenderer;

constexpr double kPi = 3.14159265358979323846;

// Small, fast generator for the per-pixel noise of the depth camera (splitmix64; the frames'
// noise does not need a long period).
struct FastRng {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  // Standard normal (Box-Muller).
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }
  // Approximately normal, mean 0, sigma 1 (sum of four uniforms): for colour noise.
  double roughNormal() {
    const std::uint64_t bits = next();
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) sum += static_cast<double>((bits >> (16 * k)) & 0xffff) / 65535.0;
    return (sum - 2.0) * 1.7320508075688772;
  }
};

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// True if pixel i of a w x h depth buffer has a 4-neighbour at a relatively different depth
// (or a neighbour without a hit while it has one).
bool atDepthEdge(const std::vector<float>& z, int w, int h, std::size_t i, float ratio) {
  const int x = static_cast<int>(i % static_cast<std::size_t>(w));
  const int y = static_cast<int>(i / static_cast<std::size_t>(w));
  const float zi = z[i];
  auto differs = [&](std::size_t j) {
    const float zj = z[j];
    if (std::isinf(zi) != std::isinf(zj)) return true;
    if (std::isinf(zi)) return false;
    return std::abs(zi - zj) > ratio * std::min(zi, zj);
  };
  return (x > 0 && differs(i - 1)) || (x + 1 < w && differs(i + 1)) ||
         (y > 0 && differs(i - static_cast<std::size_t>(w))) ||
         (y + 1 < h && differs(i + static_cast<std::size_t>(w)));
}

}  // namespace

void DepthCameraConfig::validate() const {
  camera.validate();
  require(std::isfinite(frame_rate_hz) && frame_rate_hz > 0.0 && frame_rate_hz <= 1000.0,
          "DepthCameraConfig: frame_rate_hz must lie in (0, 1000]");
  require(std::isfinite(min_range_m) && min_range_m > 0.0 && max_range_m > min_range_m &&
              std::isfinite(max_range_m) && max_range_m < 65.0,
          "DepthCameraConfig: need 0 < min_range_m < max_range_m < 65 m");
  require(std::isfinite(baseline_m) && baseline_m > 0.0 && std::isfinite(ir_focal_px) &&
              ir_focal_px > 0.0,
          "DepthCameraConfig: baseline_m and ir_focal_px must be positive");
  require(subpixel_steps >= 1 && subpixel_steps <= 1024,
          "DepthCameraConfig: subpixel_steps must lie in [1, 1024]");
  require(std::isfinite(disparity_noise_px) && disparity_noise_px >= 0.0,
          "DepthCameraConfig: disparity_noise_px must be >= 0");
  require(projector_direction.allFinite() && projector_direction.norm() > 0.5,
          "DepthCameraConfig: projector_direction must be a unit vector");
  require(std::isfinite(max_incidence_deg) && max_incidence_deg > 0.0 && max_incidence_deg <= 90.0,
          "DepthCameraConfig: max_incidence_deg must lie in (0, 90]");
  require(std::isfinite(edge_jump_ratio) && edge_jump_ratio > 0.0,
          "DepthCameraConfig: edge_jump_ratio must be positive");
  require(edge_hole_probability >= 0.0 && edge_hole_probability <= 1.0,
          "DepthCameraConfig: edge_hole_probability must lie in [0, 1]");
  require(std::isfinite(clock_offset_s), "DepthCameraConfig: clock_offset_s must be finite");
  require(std::isfinite(colour_noise_sigma) && colour_noise_sigma >= 0.0,
          "DepthCameraConfig: colour_noise_sigma must be >= 0");
  require(std::isfinite(colour_exposure_s) && colour_exposure_s >= 0.0 &&
              colour_exposure_s * frame_rate_hz <= 1.0,
          "DepthCameraConfig: colour_exposure_s must lie in [0, 1 / frame_rate_hz]");
}

CameraModel DedvsSimulatorConfig::defaultEdvsCamera() {
  CameraModel camera;
  camera.width = 128;
  camera.height = 128;
  camera.focal_px = 154.0;
  camera.principal_point = Eigen::Vector2d(64.7, 62.4);
  camera.kappa1 = 6e-4;
  camera.kappa2 = 2e-6;
  camera.distortion_model = DistortionModel::kDivideEq81;
  return camera;
}

Eigen::Isometry3d DedvsSimulatorConfig::defaultDepthFromEdvs() {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = (Eigen::AngleAxisd(0.8 * kPi / 180.0, Eigen::Vector3d::UnitX()) *
                        Eigen::AngleAxisd(-1.2 * kPi / 180.0, Eigen::Vector3d::UnitY()) *
                        Eigen::AngleAxisd(0.5 * kPi / 180.0, Eigen::Vector3d::UnitZ()))
                           .toRotationMatrix();
  transform.translation() = Eigen::Vector3d(0.012, -0.041, 0.004);
  return transform;
}

void DedvsSimulatorConfig::validate() const {
  edvs.validate();
  events.validate();
  depth.validate();
  require(depth_from_edvs.matrix().allFinite(),
          "DedvsSimulatorConfig: depth_from_edvs is not finite");
  const Eigen::Matrix3d r = depth_from_edvs.linear();
  require((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6,
          "DedvsSimulatorConfig: depth_from_edvs rotation is not orthonormal");
  require(std::isfinite(render_rate_hz) && render_rate_hz > 0.0,
          "DedvsSimulatorConfig: render_rate_hz must be positive");
  require(std::isfinite(max_step_motion_px) && max_step_motion_px > 0.0,
          "DedvsSimulatorConfig: max_step_motion_px must be positive");
  require(std::isfinite(ground_truth_rate_hz) && ground_truth_rate_hz > 0.0,
          "DedvsSimulatorConfig: ground_truth_rate_hz must be positive");
  require(std::isfinite(illumination) && illumination > 0.0,
          "DedvsSimulatorConfig: illumination must be positive");
  imu.validate();
}

double depthNoiseSigma(const DepthCameraConfig& config, double z_m) {
  const double q = 1.0 / config.subpixel_steps;
  return std::sqrt(config.disparity_noise_px * config.disparity_noise_px + q * q / 12.0) * z_m *
         z_m / (config.ir_focal_px * config.baseline_m);
}

namespace {

// Everything one simulate() call needs.
class Session {
 public:
  Session(const DedvsSimulatorConfig& config, const Scene& scene)
      : config_(config), renderer_(scene) {
    const CameraModel& edvs = config.edvs;
    edvs_grid_.build(edvs.width, edvs.height, edvs.focal_px, [&](int col, int row) {
      const std::optional<Eigen::Vector3d> ray = edvs.backprojectRay(Eigen::Vector2d(col, row));
      return ray ? Eigen::Vector2d(ray->head<2>()) : Eigen::Vector2d(0.0, 0.0);
    });
    const PinholeCamera& depth = config.depth.camera;
    depth_grid_.build(depth.width, depth.height, depth.fx, [&](int col, int row) {
      return Eigen::Vector2d((col - depth.cx) / depth.fx, (row - depth.cy) / depth.fy);
    });
  }

  RoomRenderer& renderer() { return renderer_; }
  const RayGrid& edvsGrid() const { return edvs_grid_; }

  void movePlanes(const std::vector<MovingPlane>& moving, double t_s) {
    for (const MovingPlane& m : moving) {
      renderer_.planes()[static_cast<std::size_t>(m.plane_index)].setPose(
          interpolatePose(m.pose, t_s).isometry());
    }
  }

  // eDVS intensity and hits at a rig pose; LEDs added as spots (lens point spread, sigma
  // 0.6 px or the disc's image) when on and not occluded.
  void renderEdvs(const Eigen::Isometry3d& rig, double t_s, const std::vector<BlinkingLed>& leds,
                  Hits& hits, std::vector<float>& intensity) {
    const Eigen::Isometry3d edvs_pose = rig * config_.depth_from_edvs;
    renderer_.trace(edvs_pose, edvs_grid_, hits);
    renderer_.shade(edvs_pose, edvs_grid_, hits, intensity);
    const float illumination = static_cast<float>(config_.illumination);
    for (float& value : intensity) value *= illumination;
    for (const BlinkingLed& led : leds) {
      const double phase = std::fmod((t_s - led.phase_s) * led.frequency_hz, 1.0);
      if (!((phase < 0.0 ? phase + 1.0 : phase) < 0.5)) continue;
      const Eigen::Vector3d world = ledWorldPosition(led);
      const Eigen::Vector3d in_edvs = edvs_pose.inverse() * world;
      const std::optional<Eigen::Vector2d> pixel = config_.edvs.project(in_edvs);
      if (!pixel || !config_.edvs.isInside(*pixel)) continue;
      const int cx = static_cast<int>(std::lround(pixel->x()));
      const int cy = static_cast<int>(std::lround(pixel->y()));
      const std::size_t centre = static_cast<std::size_t>(cy) * config_.edvs.width + cx;
      if (hits.z[centre] < in_edvs.z() * 0.98 - 0.01) continue;  // occluded
      const double sigma = std::max(0.6, config_.edvs.focal_px * led.radius_m / in_edvs.z());
      const int reach = static_cast<int>(std::ceil(3.0 * sigma));
      for (int y = std::max(0, cy - reach); y <= std::min(config_.edvs.height - 1, cy + reach);
           ++y) {
        for (int x = std::max(0, cx - reach); x <= std::min(config_.edvs.width - 1, cx + reach);
             ++x) {
          const double d2 = (Eigen::Vector2d(x, y) - *pixel).squaredNorm();
          intensity[static_cast<std::size_t>(y) * config_.edvs.width + x] +=
              static_cast<float>(led.on_intensity * std::exp(-0.5 * d2 / (sigma * sigma)));
        }
      }
    }
  }

  Eigen::Vector3d ledWorldPosition(const BlinkingLed& led) {
    if (led.plane_index < 0) return led.position;
    const PreparedPlane& p = renderer_.planes()[static_cast<std::size_t>(led.plane_index)];
    return p.origin + led.position.x() * p.axis_u + led.position.y() * p.axis_v +
           led.position.z() * p.normal;
  }

  // Adds the LEDs to the colour camera's linear shade: a spot (sigma 0.6 px or the disc's
  // image) scaled by the LED's on-time fraction during the exposure centred on t_s (an
  // instantaneous sample for a zero exposure), when not occluded.
  void addLedsToColour(const Eigen::Isometry3d& rig, double t_s,
                       const std::vector<BlinkingLed>& leds) {
    const PinholeCamera& cam = config_.depth.camera;
    const double exposure = config_.depth.colour_exposure_s;
    for (const BlinkingLed& led : leds) {
      double on_fraction = 0.0;
      if (exposure > 0.0) {
        // Integral of the square wave (on in the first half of each period) over the exposure.
        const auto on_time = [&led](double t) {
          const double cycles = (t - led.phase_s) * led.frequency_hz;
          const double whole = std::floor(cycles);
          return (0.5 * whole + std::min(cycles - whole, 0.5)) / led.frequency_hz;
        };
        on_fraction = (on_time(t_s + 0.5 * exposure) - on_time(t_s - 0.5 * exposure)) / exposure;
      } else {
        const double phase = std::fmod((t_s - led.phase_s) * led.frequency_hz, 1.0);
        on_fraction = (phase < 0.0 ? phase + 1.0 : phase) < 0.5 ? 1.0 : 0.0;
      }
      if (!(on_fraction > 0.0)) continue;
      const Eigen::Vector3d in_camera = rig.inverse() * ledWorldPosition(led);
      if (!(in_camera.z() > 1e-3)) continue;
      const Eigen::Vector2d pixel(cam.fx * in_camera.x() / in_camera.z() + cam.cx,
                                  cam.fy * in_camera.y() / in_camera.z() + cam.cy);
      const int cx = static_cast<int>(std::lround(pixel.x()));
      const int cy = static_cast<int>(std::lround(pixel.y()));
      if (cx < 0 || cy < 0 || cx >= cam.width || cy >= cam.height) continue;
      const std::size_t centre = static_cast<std::size_t>(cy) * cam.width + cx;
      if (depth_hits_.z[centre] < in_camera.z() * 0.98 - 0.01) continue;  // occluded
      const double sigma = std::max(0.6, cam.fx * led.radius_m / in_camera.z());
      const int reach = static_cast<int>(std::ceil(3.0 * sigma));
      for (int y = std::max(0, cy - reach); y <= std::min(cam.height - 1, cy + reach); ++y) {
        for (int x = std::max(0, cx - reach); x <= std::min(cam.width - 1, cx + reach); ++x) {
          const double d2 = (Eigen::Vector2d(x, y) - pixel).squaredNorm();
          shade_[static_cast<std::size_t>(y) * cam.width + x] += static_cast<float>(
              on_fraction * led.on_intensity * std::exp(-0.5 * d2 / (sigma * sigma)));
        }
      }
    }
  }

  DepthFrame renderDepth(const Eigen::Isometry3d& rig, double t_s, std::uint64_t frame_index,
                         const std::vector<BlinkingLed>& leds) {
    const DepthCameraConfig& dc = config_.depth;
    const PinholeCamera& cam = dc.camera;
    const std::size_t n = depth_grid_.x.size();
    renderer_.trace(rig, depth_grid_, depth_hits_);
    renderer_.shade(rig, depth_grid_, depth_hits_, shade_);
    addLedsToColour(rig, t_s, leds);
    const Eigen::Vector3d projector_offset = dc.baseline_m * dc.projector_direction.normalized();
    Eigen::Isometry3d projector = rig;
    projector.translation() = rig * projector_offset;
    renderer_.trace(projector, depth_grid_, projector_hits_);

    FastRng rng{config_.seed * 0x100000001b3ULL + frame_index * 0x2545f4914f6cdd1dULL + 7};
    if (gamma_.empty()) {
      gamma_.resize(4097);
      for (std::size_t g = 0; g < gamma_.size(); ++g) {
        gamma_[g] = static_cast<float>(255.0 * std::pow(g / 4096.0, 1.0 / 2.2));
      }
    }
    DepthFrame frame;
    frame.t_s = t_s;
    frame.stamp_s = t_s + dc.clock_offset_s;
    frame.depth_mm = cv::Mat(cam.height, cam.width, CV_16UC1, cv::Scalar(0));
    frame.true_depth_m = cv::Mat(cam.height, cam.width, CV_32FC1);
    frame.colour = cv::Mat(cam.height, cam.width, CV_8UC3);
    const Eigen::Matrix3d rt = rig.linear().transpose();
    const double cos_max = std::cos(dc.max_incidence_deg * kPi / 180.0);
    const double fb = dc.ir_focal_px * dc.baseline_m;
    const double step = 1.0 / dc.subpixel_steps;
    for (std::size_t i = 0; i < n; ++i) {
      const int row = static_cast<int>(i / static_cast<std::size_t>(cam.width));
      const int col = static_cast<int>(i % static_cast<std::size_t>(cam.width));
      const float z = depth_hits_.z[i];
      const int k = depth_hits_.plane[i];
      frame.true_depth_m.at<float>(row, col) = k >= 0 ? z : std::numeric_limits<float>::quiet_NaN();
      // Colour (gamma 1/2.2, 8 bit, noise).
      cv::Vec3b& bgr = frame.colour.at<cv::Vec3b>(row, col);
      const Eigen::Vector3f colour =
          k >= 0 ? renderer_.planes()[static_cast<std::size_t>(k)].colour : Eigen::Vector3f::Ones();
      for (int c = 0; c < 3; ++c) {
        const float linear = std::clamp(shade_[i] * colour[2 - c], 0.0f, 1.0f);
        bgr[c] =
            cv::saturate_cast<std::uint8_t>(gamma_[static_cast<std::size_t>(linear * 4096.0f)] +
                                            dc.colour_noise_sigma * rng.roughNormal());
      }
      if (k < 0) continue;
      const double noise = rng.normal();
      const double edge_draw = rng.uniform();
      const Eigen::Vector3d ray(depth_grid_.x[i], depth_grid_.y[i], 1.0);
      // Grazing angle.
      const Eigen::Vector3d n_c = rt * renderer_.planes()[static_cast<std::size_t>(k)].normal;
      if (std::abs(n_c.dot(ray)) / ray.norm() < cos_max) continue;
      // Depth edge.
      if (edge_draw < dc.edge_hole_probability &&
          atDepthEdge(depth_hits_.z, cam.width, cam.height, i,
                      static_cast<float>(dc.edge_jump_ratio))) {
        continue;
      }
      // Projector shadow: the point must be the nearest surface seen from the projector.
      const Eigen::Vector3d point = static_cast<double>(z) * ray;
      const Eigen::Vector3d from_projector = point - projector_offset;
      if (from_projector.z() <= 0.0) continue;
      const int pc =
          static_cast<int>(std::lround(cam.fx * from_projector.x() / from_projector.z() + cam.cx));
      const int pr =
          static_cast<int>(std::lround(cam.fy * from_projector.y() / from_projector.z() + cam.cy));
      if (pc < 0 || pr < 0 || pc >= cam.width || pr >= cam.height) continue;
      const float lit_z = projector_hits_.z[static_cast<std::size_t>(pr) * cam.width + pc];
      if (from_projector.z() > lit_z * 1.01 + 0.005) continue;
      // Disparity, noise, quantisation.
      const double disparity = fb / z + dc.disparity_noise_px * noise;
      const double quantised = std::round(disparity / step) * step;
      if (quantised <= 0.0) continue;
      const double measured = fb / quantised;
      if (measured < dc.min_range_m || measured > dc.max_range_m) continue;
      frame.depth_mm.at<std::uint16_t>(row, col) =
          static_cast<std::uint16_t>(std::lround(measured * 1000.0));
    }
    return frame;
  }

 private:
  const DedvsSimulatorConfig& config_;
  RoomRenderer renderer_;
  RayGrid edvs_grid_;
  RayGrid depth_grid_;
  Hits depth_hits_;
  Hits projector_hits_;
  std::vector<float> shade_;
  std::vector<float> gamma_;  // linear [0, 1] in 4096 steps -> 8-bit sRGB-like (gamma 2.2)
};

void validateInputs(const Scene& scene, const Trajectory& trajectory, double t_begin_s,
                    double t_end_s, const std::vector<BlinkingLed>& leds,
                    const std::vector<MovingPlane>& moving_planes) {
  scene.validate();
  require(trajectory.size() >= 2, "DedvsSimulator: the trajectory needs at least two poses");
  validateTrajectory(trajectory, "DedvsSimulator: rig trajectory");
  require(std::isfinite(t_begin_s) && std::isfinite(t_end_s) && t_begin_s < t_end_s,
          "DedvsSimulator: the time range must be finite and non-empty");
  require(t_begin_s >= trajectory.front().t_s && t_end_s <= trajectory.back().t_s,
          "DedvsSimulator: the time range lies outside the trajectory");
  const int planes = static_cast<int>(scene.planes.size());
  for (const BlinkingLed& led : leds) {
    require(led.position.allFinite() && led.plane_index < planes,
            "DedvsSimulator: LED position not finite or plane index out of range");
    require(std::isfinite(led.frequency_hz) && led.frequency_hz > 0.0 &&
                std::isfinite(led.on_intensity) && led.on_intensity >= 0.0 &&
                std::isfinite(led.radius_m) && led.radius_m >= 0.0 && std::isfinite(led.phase_s),
            "DedvsSimulator: LED frequency, radius, intensity or phase invalid");
  }
  for (const MovingPlane& m : moving_planes) {
    require(m.plane_index >= 0 && m.plane_index < planes,
            "DedvsSimulator: moving plane index out of range");
    require(m.pose.size() >= 2, "DedvsSimulator: a moving plane needs at least two poses");
    validateTrajectory(m.pose, "DedvsSimulator: moving plane");
    require(m.pose.front().t_s <= t_begin_s && m.pose.back().t_s >= t_end_s,
            "DedvsSimulator: a moving plane's poses do not cover the time range");
  }
}

// Probe pixels for the step control: corners, edge midpoints and centre.
std::vector<std::size_t> stepProbes(int width, int height) {
  std::vector<std::size_t> probes;
  for (int py : {0, height / 2, height - 1}) {
    for (int px : {0, width / 2, width - 1}) {
      probes.push_back(static_cast<std::size_t>(py) * width + px);
    }
  }
  return probes;
}

// The largest image motion [px] of the probe pixels' surface points under `to_next` (eDVS frame
// now -> eDVS frame at the next render); 1e9 if one leaves the image model.
double probeMotionPx(const CameraModel& edvs, const RayGrid& grid, const Hits& hits,
                     const std::vector<std::size_t>& probes, const Eigen::Isometry3d& to_next) {
  const int width = edvs.width;
  double motion_px = 0.0;
  for (std::size_t i : probes) {
    const Eigen::Vector3d ray(grid.x[i], grid.y[i], 1.0);
    const Eigen::Vector2d start(static_cast<double>(i % width), static_cast<double>(i / width));
    const float z = hits.z[i];
    // Points without a hit move with the rotation alone (at infinity).
    const Eigen::Vector3d moved = std::isinf(z) ? Eigen::Vector3d(to_next.linear() * ray)
                                                : Eigen::Vector3d(to_next * (z * ray));
    const std::optional<Eigen::Vector2d> end = edvs.project(moved);
    motion_px = end ? std::max(motion_px, (*end - start).norm()) : 1e9;
  }
  return motion_px;
}

// Ground truth of an event between renders at t0 and t1 [s]: the depth at the nearer render in
// time when the two renders see different surfaces, else interpolated; the depth edge flag and
// the 3x3 neighbourhood's depth range from the nearer render.
TrueDepthEvent annotateEvent(const Event& event, bool is_noise, double t0, double t1,
                             const Hits& previous, const Hits& current, int width, int height) {
  const std::size_t i = static_cast<std::size_t>(event.y) * width + event.x;
  const double fraction = std::clamp((event.t_us * 1e-6 - t0) / (t1 - t0), 0.0, 1.0);
  const float z0 = previous.z[i];
  const float z1 = current.z[i];
  const bool use_first = fraction < 0.5;
  float depth;
  if (std::isinf(z0) || std::isinf(z1) || std::abs(z1 - z0) > 0.02f * std::min(z0, z1)) {
    depth = use_first ? z0 : z1;
  } else {
    depth = z0 + static_cast<float>(fraction) * (z1 - z0);
  }
  TrueDepthEvent annotated;
  annotated.event = event;
  annotated.is_noise = is_noise;
  annotated.depth_m = std::isinf(depth) ? std::numeric_limits<float>::quiet_NaN() : depth;
  const std::vector<float>& z_at = use_first ? previous.z : current.z;
  annotated.at_depth_edge = atDepthEdge(z_at, width, height, i, 0.1f);
  float z_min = std::numeric_limits<float>::infinity();
  float z_max = -std::numeric_limits<float>::infinity();
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = event.x + dx, ny = event.y + dy;
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      const float zn = z_at[static_cast<std::size_t>(ny) * width + nx];
      if (std::isinf(zn)) continue;
      z_min = std::min(z_min, zn);
      z_max = std::max(z_max, zn);
    }
  }
  const bool any = z_min <= z_max;
  annotated.neighbourhood_min_depth_m = any ? z_min : std::numeric_limits<float>::quiet_NaN();
  annotated.neighbourhood_max_depth_m = any ? z_max : std::numeric_limits<float>::quiet_NaN();
  return annotated;
}

}  // namespace

DedvsSimulator::DedvsSimulator(const DedvsSimulatorConfig& config) : config_(config) {
  config_.validate();
}

void DedvsSimulator::renderEdvs(const Scene& scene, const Eigen::Isometry3d& rig_pose,
                                cv::Mat& intensity, cv::Mat& depth_m) const {
  scene.validate();
  require(rig_pose.matrix().allFinite(), "renderEdvs: rig pose is not finite");
  Session session(config_, scene);
  Hits hits;
  std::vector<float> values;
  session.renderEdvs(rig_pose, 0.0, {}, hits, values);
  const int w = config_.edvs.width, h = config_.edvs.height;
  intensity = cv::Mat(h, w, CV_32FC1);
  depth_m = cv::Mat(h, w, CV_32FC1);
  for (std::size_t i = 0; i < values.size(); ++i) {
    intensity.at<float>(static_cast<int>(i) / w, static_cast<int>(i) % w) = values[i];
    depth_m.at<float>(static_cast<int>(i) / w, static_cast<int>(i) % w) =
        hits.plane[i] >= 0 ? hits.z[i] : std::numeric_limits<float>::quiet_NaN();
  }
}

DedvsRun DedvsSimulator::simulate(const Scene& scene, const Trajectory& rig_trajectory,
                                  double t_begin_s, double t_end_s,
                                  const std::vector<BlinkingLed>& leds,
                                  const std::vector<MovingPlane>& moving_planes) const {
  std::vector<TrueDepthEvent> events;
  std::vector<DepthFrame> frames;
  DedvsRun run = simulate(
      scene, rig_trajectory, t_begin_s, t_end_s,
      [&events](const std::vector<TrueDepthEvent>& batch) {
        events.insert(events.end(), batch.begin(), batch.end());
      },
      [&frames](const DepthFrame& frame) { frames.push_back(frame); }, leds, moving_planes);
  run.events = std::move(events);
  run.depth_frames = std::move(frames);
  return run;
}

DedvsRun DedvsSimulator::simulate(const Scene& scene, const Trajectory& rig_trajectory,
                                  double t_begin_s, double t_end_s, const EventSink& event_sink,
                                  const DepthSink& depth_sink, const std::vector<BlinkingLed>& leds,
                                  const std::vector<MovingPlane>& moving_planes) const {
  validateInputs(scene, rig_trajectory, t_begin_s, t_end_s, leds, moving_planes);
  Session session(config_, scene);
  const CameraModel& edvs = config_.edvs;
  const int width = edvs.width;
  const int height = edvs.height;
  DedvsRun run;

  session.movePlanes(moving_planes, t_begin_s);
  Eigen::Isometry3d rig = interpolatePose(rig_trajectory, t_begin_s).isometry();
  Hits hits_previous, hits_current;
  std::vector<float> intensity;
  session.renderEdvs(rig, t_begin_s, leds, hits_previous, intensity);
  EventGenerator generator(config_.events, width, height);
  generator.start(intensity, t_begin_s);

  const double gt_step_s = 1.0 / config_.ground_truth_rate_hz;
  std::size_t gt_index = 0;
  auto emitGroundTruth = [&](double up_to_s) {
    for (double t = t_begin_s + gt_index * gt_step_s; t <= up_to_s;
         t = t_begin_s + static_cast<double>(gt_index) * gt_step_s) {
      const Eigen::Isometry3d pose = interpolatePose(rig_trajectory, t).isometry();
      run.rig_ground_truth.push_back(StampedPose::fromIsometry(t, pose));
      run.edvs_ground_truth.push_back(StampedPose::fromIsometry(t, pose * config_.depth_from_edvs));
      ++gt_index;
    }
  };
  emitGroundTruth(t_begin_s);

  const double frame_period_s = 1.0 / config_.depth.frame_rate_hz;
  std::uint64_t frame_index = 0;
  double next_frame_s = t_begin_s;
  auto emitFrames = [&](double up_to_s) {
    while (next_frame_s <= up_to_s) {
      session.movePlanes(moving_planes, next_frame_s);
      const Eigen::Isometry3d frame_rig = interpolatePose(rig_trajectory, next_frame_s).isometry();
      DepthFrame frame = session.renderDepth(frame_rig, next_frame_s, frame_index, leds);
      if (depth_sink) depth_sink(frame);
      ++frame_index;
      next_frame_s = t_begin_s + static_cast<double>(frame_index) * frame_period_s;
    }
  };
  emitFrames(t_begin_s);

  // Largest step: the render rate, and an eighth of any LED's period (its edges are timed by
  // the interpolation between renders).
  double max_step_s = 1.0 / config_.render_rate_hz;
  for (const BlinkingLed& led : leds) max_step_s = std::min(max_step_s, 0.125 / led.frequency_hz);

  const std::vector<std::size_t> probes = stepProbes(width, height);
  const RayGrid& grid = session.edvsGrid();

  EventVector step_events;
  std::vector<std::uint8_t> noise_flags;
  std::vector<TrueDepthEvent> batch;
  double t0 = t_begin_s;
  while (t0 < t_end_s) {
    double t1 = std::min(t0 + max_step_s, t_end_s);
    const Eigen::Isometry3d edvs0 = rig * config_.depth_from_edvs;
    Eigen::Isometry3d next_rig = interpolatePose(rig_trajectory, t1).isometry();
    const Eigen::Isometry3d to_next = (next_rig * config_.depth_from_edvs).inverse() * edvs0;
    const double motion_px = probeMotionPx(edvs, grid, hits_previous, probes, to_next);
    if (motion_px > config_.max_step_motion_px) {
      const double subdivisions = std::min(std::ceil(motion_px / config_.max_step_motion_px), 1e3);
      t1 = t0 + (t1 - t0) / subdivisions;
      next_rig = interpolatePose(rig_trajectory, t1).isometry();
    }
    session.movePlanes(moving_planes, t1);
    session.renderEdvs(next_rig, t1, leds, hits_current, intensity);
    ++run.render_steps;
    step_events.clear();
    noise_flags.clear();
    const std::size_t signal = generator.step(intensity, t1, step_events, &noise_flags);
    run.signal_events += signal;
    run.noise_events += step_events.size() - signal;
    batch.clear();
    batch.reserve(step_events.size());
    for (std::size_t e = 0; e < step_events.size(); ++e) {
      batch.push_back(annotateEvent(step_events[e], noise_flags[e] != 0, t0, t1, hits_previous,
                                    hits_current, width, height));
    }
    if (event_sink && !batch.empty()) event_sink(batch);
    std::swap(hits_previous, hits_current);
    rig = next_rig;
    t0 = t1;
    emitGroundTruth(t0);
    emitFrames(t0);
  }
  if (run.rig_ground_truth.back().t_s < t_end_s) {
    const Eigen::Isometry3d pose = interpolatePose(rig_trajectory, t_end_s).isometry();
    run.rig_ground_truth.push_back(StampedPose::fromIsometry(t_end_s, pose));
    run.edvs_ground_truth.push_back(
        StampedPose::fromIsometry(t_end_s, pose * config_.depth_from_edvs));
  }
  if (config_.simulate_imu) run.imu = simulateImu(rig_trajectory, t_begin_s, t_end_s, config_.imu);
  return run;
}

Eigen::Quaterniond edvsFromImu(const DedvsSimulatorConfig& config) {
  const Eigen::Quaterniond depth_from_edvs(config.depth_from_edvs.linear());
  return (depth_from_edvs.conjugate() * config.imu.body_from_imu).normalized();
}

}  // namespace ebslam
