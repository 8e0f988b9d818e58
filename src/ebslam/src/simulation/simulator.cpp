#include "ebslam/simulation/simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

namespace ebslam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

// A plane prepared for rendering: its blurred texture and world geometry.
struct PreparedPlane {
  cv::Mat texture;  // CV_32FC1, pre-filtered
  int cols = 0;
  int rows = 0;
  float max_x = 0.0f;  // largest sample coordinate in texel-centre units: cols - 1
  float max_y = 0.0f;
  double extent_u = 0.0;  // extent in texels
  double extent_v = 0.0;
  Eigen::Vector3d origin;  // world
  Eigen::Vector3d axis_u;  // world, unit
  Eigen::Vector3d axis_v;
  Eigen::Vector3d normal;
  double inv_metres_per_texel_u = 0.0;  // texels per metre along axis_u
  double inv_metres_per_texel_v = 0.0;
};

// Per render step: maps a camera ray d (z = 1) to texel coordinates (numerator_u . d / den . d,
// numerator_v . d / den . d) and to its depth along the ray, h / den . d (positive = in front).
struct PlaneProjection {
  Eigen::Vector3d numerator_u;
  Eigen::Vector3d numerator_v;
  Eigen::Vector3d denominator;
  double h = 0.0;
};

PlaneProjection planeProjection(const PreparedPlane& plane, const Eigen::Isometry3d& camera) {
  const Eigen::Matrix3d rt = camera.linear().transpose();
  const Eigen::Vector3d offset = camera.translation() - plane.origin;
  PlaneProjection projection;
  projection.h = plane.normal.dot(-offset);
  projection.denominator = rt * plane.normal;
  // u(d) = a_u . (t - o) + lambda a_u . R d with lambda = h / (n . R d).
  projection.numerator_u =
      (plane.axis_u.dot(offset) * projection.denominator + projection.h * (rt * plane.axis_u)) *
      plane.inv_metres_per_texel_u;
  projection.numerator_v =
      (plane.axis_v.dot(offset) * projection.denominator + projection.h * (rt * plane.axis_v)) *
      plane.inv_metres_per_texel_v;
  return projection;
}

// Bilinear lookup at texel coordinates (u, v); texel (c, r) covers [c, c + 1) x [r, r + 1).
// Coordinates beyond the texture are clamped (repeating textures are tiled to the plane's full
// extent beforehand, which avoids a costly modulo per sample).
inline float sampleTexture(const PreparedPlane& plane, float u, float v) {
  const float x = std::clamp(u - 0.5f, 0.0f, plane.max_x);
  const float y = std::clamp(v - 0.5f, 0.0f, plane.max_y);
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float ax = x - static_cast<float>(x0);
  const float ay = y - static_cast<float>(y0);
  const int x1 = std::min(x0 + 1, plane.cols - 1);
  const float* row0 = plane.texture.ptr<float>(y0);
  const float* row1 = plane.texture.ptr<float>(std::min(y0 + 1, plane.rows - 1));
  const float top = row0[x0] + ax * (row0[x1] - row0[x0]);
  const float bottom = row1[x0] + ax * (row1[x1] - row1[x0]);
  return top + ay * (bottom - top);
}

// Renders one camera pose: nearest plane hit per ray, bilinear texture intensity.
class Renderer {
 public:
  Renderer(const SimulatorConfig& config, const Scene& scene, const Eigen::Isometry3d& first_pose)
      : config_(config), background_(static_cast<float>(scene.background_intensity)) {
    const CameraModel& camera = config.camera;
    const int s = config.supersampling;
    samples_per_pixel_ = s * s;
    const std::size_t pixel_count = static_cast<std::size_t>(camera.width) * camera.height;
    rays_.reserve(pixel_count * samples_per_pixel_);
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        for (int sy = 0; sy < s; ++sy) {
          for (int sx = 0; sx < s; ++sx) {
            const Eigen::Vector2d pixel(x - 0.5 + (sx + 0.5) / s, y - 0.5 + (sy + 0.5) / s);
            std::optional<Eigen::Vector3d> ray = camera.backprojectRay(pixel);
            // validate() guarantees invertible distortion over the sensor.
            rays_.push_back(ray ? *ray : Eigen::Vector3d(0.0, 0.0, 1.0));
            ray_x_.push_back(static_cast<float>(rays_.back().x()));
            ray_y_.push_back(static_cast<float>(rays_.back().y()));
          }
        }
      }
    }
    // Blur: optics (blur_sigma_px) plus, without supersampling, the pixel area (box of one
    // pixel, variance 1/12), converted to texels at the plane's distance from the first pose.
    const double sigma_px =
        std::sqrt(config.blur_sigma_px * config.blur_sigma_px + (s == 1 ? 1.0 / 12.0 : 0.0));
    for (const TexturedPlane& plane : scene.planes) {
      PreparedPlane prepared;
      prepared.origin = plane.pose.translation();
      prepared.axis_u = plane.pose.linear().col(0).normalized();
      prepared.axis_v = plane.pose.linear().col(1).normalized();
      prepared.normal = plane.pose.linear().col(2).normalized();
      const double distance =
          std::abs(prepared.normal.dot(first_pose.translation() - prepared.origin));
      const double sigma_texels =
          sigma_px * camera.triggerDistance(std::max(distance, 1e-3)) / plane.metres_per_texel;
      cv::Mat texture = textureFromImage(plane.texture);
      if (sigma_texels > 0.2) {
        const int pad = static_cast<int>(std::ceil(4.0 * sigma_texels)) + 1;
        if (plane.repeat && pad < texture.cols && pad < texture.rows) {
          cv::Mat padded;
          cv::copyMakeBorder(texture, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
          cv::GaussianBlur(padded, padded, cv::Size(), sigma_texels, sigma_texels,
                           cv::BORDER_REFLECT);
          texture = padded(cv::Rect(pad, pad, texture.cols, texture.rows)).clone();
        } else {
          cv::GaussianBlur(texture, texture, cv::Size(), sigma_texels, sigma_texels,
                           cv::BORDER_REPLICATE);
        }
      }
      // Texels much finer than the blurred pixel footprint only cost memory bandwidth:
      // resample to half the sample spacing on the plane (footprint / supersampling).
      const double footprint_m = camera.triggerDistance(std::max(distance, 1e-3));
      const double coarsest_texel_m = 0.5 * footprint_m / s;
      if (coarsest_texel_m > 1.25 * plane.metres_per_texel) {
        const double factor = plane.metres_per_texel / coarsest_texel_m;
        const cv::Size size(std::max(2, static_cast<int>(std::lround(texture.cols * factor))),
                            std::max(2, static_cast<int>(std::lround(texture.rows * factor))));
        cv::resize(texture, texture, size, 0.0, 0.0, cv::INTER_AREA);
      }
      // Effective texel size per axis after resampling (the texture period is kept exactly).
      const cv::Size original = plane.texture.size();
      prepared.inv_metres_per_texel_u = texture.cols / (original.width * plane.metres_per_texel);
      prepared.inv_metres_per_texel_v = texture.rows / (original.height * plane.metres_per_texel);
      prepared.extent_u = plane.size_m.x() * prepared.inv_metres_per_texel_u;
      prepared.extent_v = plane.size_m.y() * prepared.inv_metres_per_texel_v;
      if (plane.repeat) {
        // Tile to the plane's extent plus one texel for the bilinear neighbour.
        const int cols = static_cast<int>(std::ceil(prepared.extent_u)) + 1;
        const int rows = static_cast<int>(std::ceil(prepared.extent_v)) + 1;
        require(static_cast<double>(cols) * rows <= 6.4e7,
                "Scene: a repeating plane's extent exceeds 6.4e7 texels; use coarser texels");
        if (cols > texture.cols || rows > texture.rows) {
          cv::Mat tiled;
          cv::repeat(texture, (rows + texture.rows - 1) / texture.rows,
                     (cols + texture.cols - 1) / texture.cols, tiled);
          texture = tiled;
        }
      } else {
        prepared.extent_u = std::min(prepared.extent_u, static_cast<double>(texture.cols));
        prepared.extent_v = std::min(prepared.extent_v, static_cast<double>(texture.rows));
      }
      prepared.texture = texture;
      prepared.cols = texture.cols;
      prepared.rows = texture.rows;
      prepared.max_x = static_cast<float>(texture.cols - 1);
      prepared.max_y = static_cast<float>(texture.rows - 1);
      planes_.push_back(std::move(prepared));
    }
    projections_.resize(planes_.size());
  }

  // Intensity per pixel (row-major) at camera pose `camera` (camera -> world).
  void render(const Eigen::Isometry3d& camera, std::vector<float>& intensity) {
    for (std::size_t i = 0; i < planes_.size(); ++i) {
      projections_[i] = planeProjection(planes_[i], camera);
    }
    const std::size_t pixel_count = rays_.size() / samples_per_pixel_;
    intensity.resize(pixel_count);
    const float inv_samples = 1.0f / static_cast<float>(samples_per_pixel_);
    if (planes_.size() == 1) {
      // Fast path for the ceiling scenario: plane coordinates of all rays in single precision
      // (vectorisable; texel coordinates stay below 1e4, so float resolves 1e-3 texel), then
      // the texture lookups, averaged over the supersamples of each pixel.
      const PreparedPlane& plane = planes_[0];
      const PlaneProjection& p = projections_[0];
      const float dx = static_cast<float>(p.denominator.x());
      const float dy = static_cast<float>(p.denominator.y());
      const float dz = static_cast<float>(p.denominator.z());
      const float ux = static_cast<float>(p.numerator_u.x());
      const float uy = static_cast<float>(p.numerator_u.y());
      const float uz = static_cast<float>(p.numerator_u.z());
      const float vx = static_cast<float>(p.numerator_v.x());
      const float vy = static_cast<float>(p.numerator_v.y());
      const float vz = static_cast<float>(p.numerator_v.z());
      const float h = static_cast<float>(p.h);
      const std::size_t ray_count = rays_.size();
      texel_u_.resize(ray_count);
      texel_v_.resize(ray_count);
      for (std::size_t i = 0; i < ray_count; ++i) {
        const float x = ray_x_[i];
        const float y = ray_y_[i];
        const float den = dx * x + dy * y + dz;
        const float inv = 1.0f / den;
        const bool in_front = h * den > 0.0f;  // lambda = h / den > 0
        texel_u_[i] = in_front ? (ux * x + uy * y + uz) * inv : -1.0f;
        texel_v_[i] = (vx * x + vy * y + vz) * inv;
      }
      const auto extent_u = static_cast<float>(plane.extent_u);
      const auto extent_v = static_cast<float>(plane.extent_v);
      auto sample = [&](std::size_t ray) {
        const float u = texel_u_[ray];
        const float v = texel_v_[ray];
        return (u >= 0.0f && v >= 0.0f && u <= extent_u && v <= extent_v)
                   ? sampleTexture(plane, u, v)
                   : background_;
      };
      if (samples_per_pixel_ == 1) {
        for (std::size_t i = 0; i < pixel_count; ++i) intensity[i] = sample(i);
      } else {
        const auto spp = static_cast<std::size_t>(samples_per_pixel_);
        for (std::size_t i = 0; i < pixel_count; ++i) {
          float sum = 0.0f;
          for (std::size_t k = 0; k < spp; ++k) sum += sample(i * spp + k);
          intensity[i] = sum * inv_samples;
        }
      }
      return;
    }
    for (std::size_t i = 0; i < pixel_count; ++i) {
      float sum = 0.0f;
      for (int k = 0; k < samples_per_pixel_; ++k) {
        sum += traceRay(rays_[i * samples_per_pixel_ + k]);
      }
      intensity[i] = sum * inv_samples;
    }
  }

  // World point hit by a camera ray d (z = 1) at the last rendered/prepared pose.
  std::optional<Eigen::Vector3d> hitPoint(const Eigen::Isometry3d& camera,
                                          const Eigen::Vector3d& d) {
    double best = kInfinity;
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      const PlaneProjection p = planeProjection(planes_[k], camera);
      const double den = p.denominator.dot(d);
      const double lambda = p.h / den;
      if (!(lambda > 0.0 && lambda < best && std::isfinite(lambda))) continue;
      const double u = p.numerator_u.dot(d) / den;
      const double v = p.numerator_v.dot(d) / den;
      if (u >= 0.0 && v >= 0.0 && u <= planes_[k].extent_u && v <= planes_[k].extent_v) {
        best = lambda;
      }
    }
    if (!std::isfinite(best)) return std::nullopt;
    return camera * (best * d);
  }

 private:
  float traceRay(const Eigen::Vector3d& d) const {
    double best = kInfinity;
    float value = background_;
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      const PlaneProjection& p = projections_[k];
      const double den = p.denominator.dot(d);
      const double lambda = p.h / den;
      if (!(lambda > 0.0 && lambda < best && std::isfinite(lambda))) continue;
      const double inv = 1.0 / den;
      const double u = p.numerator_u.dot(d) * inv;
      const double v = p.numerator_v.dot(d) * inv;
      if (u >= 0.0 && v >= 0.0 && u <= planes_[k].extent_u && v <= planes_[k].extent_v) {
        best = lambda;
        value = sampleTexture(planes_[k], static_cast<float>(u), static_cast<float>(v));
      }
    }
    return value;
  }

  const SimulatorConfig& config_;
  float background_;
  int samples_per_pixel_ = 1;
  std::vector<Eigen::Vector3d> rays_;
  std::vector<float> ray_x_;  // rays_ in single precision (z = 1) for the fast path
  std::vector<float> ray_y_;
  std::vector<float> texel_u_;  // per-pixel texel coordinates, fast path scratch
  std::vector<float> texel_v_;
  std::vector<PreparedPlane> planes_;
  std::vector<PlaneProjection> projections_;
};

}  // namespace

void Scene::validate() const {
  require(std::isfinite(background_intensity) && background_intensity >= 0.0,
          "Scene: background_intensity must be finite and >= 0");
  for (std::size_t i = 0; i < planes.size(); ++i) {
    try {
      planes[i].validate();
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument("Scene plane " + std::to_string(i) + ": " + error.what());
    }
  }
}

void TexturedPlane::validate() const {
  require(!texture.empty(), "TexturedPlane: texture is empty");
  require(texture.channels() == 1 || texture.channels() == 3,
          "TexturedPlane: texture must have 1 or 3 channels");
  require(std::isfinite(metres_per_texel) && metres_per_texel > 0.0,
          "TexturedPlane: metres_per_texel must be positive");
  require(size_m.allFinite() && size_m.x() > 0.0 && size_m.y() > 0.0,
          "TexturedPlane: size_m must be positive");
  require(pose.matrix().allFinite(), "TexturedPlane: pose is not finite");
  const Eigen::Matrix3d r = pose.linear();
  require((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-6,
          "TexturedPlane: pose rotation is not orthonormal");
}

cv::Mat textureFromImage(const cv::Mat& image) {
  require(!image.empty(), "textureFromImage: image is empty");
  require(image.channels() == 1 || image.channels() == 3 || image.channels() == 4,
          "textureFromImage: image must have 1, 3 or 4 channels");
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  } else {
    grey = image;
  }
  cv::Mat result;
  switch (grey.depth()) {
    case CV_8U:
      grey.convertTo(result, CV_32F, 1.0 / 255.0);
      break;
    case CV_16U:
      grey.convertTo(result, CV_32F, 1.0 / 65535.0);
      break;
    case CV_32F:
    case CV_64F:
      grey.convertTo(result, CV_32F);
      break;
    default:
      throw std::invalid_argument("textureFromImage: unsupported pixel depth");
  }
  cv::patchNaNs(result, 0.0);
  cv::max(result, 0.0, result);
  return result;
}

void SimulatorConfig::validate() const {
  camera.validate();
  events.validate();
  require(std::isfinite(render_rate_hz) && render_rate_hz > 0.0,
          "SimulatorConfig: render_rate_hz must be positive");
  require(std::isfinite(max_step_motion_px) && max_step_motion_px > 0.0,
          "SimulatorConfig: max_step_motion_px must be positive");
  require(std::isfinite(blur_sigma_px) && blur_sigma_px >= 0.0,
          "SimulatorConfig: blur_sigma_px must be >= 0");
  require(supersampling >= 1 && supersampling <= 8, "SimulatorConfig: supersampling in [1, 8]");
  require(std::isfinite(ground_truth_rate_hz) && ground_truth_rate_hz > 0.0,
          "SimulatorConfig: ground_truth_rate_hz must be positive");
}

EventSimulator::EventSimulator(const SimulatorConfig& config) : config_(config) {
  config_.validate();
}

cv::Mat EventSimulator::renderIntensity(const Scene& scene,
                                        const Eigen::Isometry3d& camera_pose) const {
  scene.validate();
  require(camera_pose.matrix().allFinite(), "renderIntensity: camera pose is not finite");
  Renderer renderer(config_, scene, camera_pose);
  std::vector<float> intensity;
  renderer.render(camera_pose, intensity);
  cv::Mat image(config_.camera.height, config_.camera.width, CV_32FC1);
  std::copy(intensity.begin(), intensity.end(), image.ptr<float>(0));
  return image;
}

SimulationResult EventSimulator::simulate(const Scene& scene, const Trajectory& camera_trajectory,
                                          double t_begin_s, double t_end_s) const {
  SimulationResult collected;
  EventVector events;
  std::vector<std::uint8_t> labels;
  collected =
      simulateLabelled(scene, camera_trajectory, t_begin_s, t_end_s,
                       [&](const EventVector& step, const std::vector<std::uint8_t>& is_noise) {
                         events.insert(events.end(), step.begin(), step.end());
                         labels.insert(labels.end(), is_noise.begin(), is_noise.end());
                       });
  collected.events = std::move(events);
  collected.noise_labels = std::move(labels);
  return collected;
}

SimulationResult EventSimulator::simulate(const Scene& scene, const Trajectory& camera_trajectory,
                                          double t_begin_s, double t_end_s,
                                          const EventSink& sink) const {
  require(static_cast<bool>(sink), "simulate: no event sink");
  return simulateLabelled(
      scene, camera_trajectory, t_begin_s, t_end_s,
      [&sink](const EventVector& events, const std::vector<std::uint8_t>&) { sink(events); });
}

struct EventStream::State {
  State(const SimulatorConfig& c, const Scene& scene, const Eigen::Isometry3d& start_pose,
        double t_s)
      : config(c),
        renderer(config, scene, start_pose),
        generator(config.events, config.camera.width, config.camera.height),
        pose(start_pose),
        t(t_s) {}

  SimulatorConfig config;
  Renderer renderer;
  EventGenerator generator;
  Eigen::Isometry3d pose;
  double t = 0.0;
  std::vector<float> intensity;
  std::vector<Eigen::Vector3d> probe_rays;  // sensor corners and centre: step-size control
  EventVector step_events;
  std::vector<std::uint8_t> step_labels;
  std::size_t signal_events = 0;
  std::size_t noise_events = 0;
  std::size_t render_steps = 0;
};

EventStream::EventStream(const SimulatorConfig& config, const Scene& scene,
                         const Eigen::Isometry3d& start_pose, double t_s) {
  config.validate();
  scene.validate();
  require(start_pose.matrix().allFinite() && std::isfinite(t_s),
          "EventStream: start pose and time must be finite");
  state_ = std::make_unique<State>(config, scene, start_pose, t_s);
  State& st = *state_;
  const CameraModel& camera = st.config.camera;
  st.renderer.render(st.pose, st.intensity);
  st.generator.start(st.intensity, t_s);

  const std::vector<Eigen::Vector2d> probe_pixels = {{0.0, 0.0},
                                                     {camera.width - 1.0, 0.0},
                                                     {0.0, camera.height - 1.0},
                                                     {camera.width - 1.0, camera.height - 1.0},
                                                     camera.principal_point};
  for (const Eigen::Vector2d& pixel : probe_pixels) {
    if (std::optional<Eigen::Vector3d> ray = camera.backprojectRay(pixel)) {
      st.probe_rays.push_back(*ray);
    }
  }
}

EventStream::~EventStream() = default;
EventStream::EventStream(EventStream&&) noexcept = default;
EventStream& EventStream::operator=(EventStream&&) noexcept = default;

double EventStream::time() const { return state_->t; }
const Eigen::Isometry3d& EventStream::pose() const { return state_->pose; }
std::size_t EventStream::signalEvents() const { return state_->signal_events; }
std::size_t EventStream::noiseEvents() const { return state_->noise_events; }
std::size_t EventStream::renderSteps() const { return state_->render_steps; }

void EventStream::moveTo(const Eigen::Isometry3d& pose, double t_end_s, EventVector& events,
                         std::vector<std::uint8_t>* noise_labels) {
  require(pose.matrix().allFinite(), "EventStream::moveTo: pose is not finite");
  const Eigen::Isometry3d from = state_->pose;
  const double t_from = state_->t;
  const Eigen::Quaterniond q_from(from.linear());
  const Eigen::Quaterniond q_to(pose.linear());
  advance(
      t_end_s,
      [&](double t) {
        const double a = std::clamp((t - t_from) / (t_end_s - t_from), 0.0, 1.0);
        Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
        p.linear() = q_from.slerp(a, q_to).toRotationMatrix();
        p.translation() = (1.0 - a) * from.translation() + a * pose.translation();
        return p;
      },
      [&](const EventVector& step, const std::vector<std::uint8_t>& is_noise, double) {
        events.insert(events.end(), step.begin(), step.end());
        if (noise_labels != nullptr) {
          noise_labels->insert(noise_labels->end(), is_noise.begin(), is_noise.end());
        }
      },
      noise_labels != nullptr);
}

void EventStream::advance(double t_end_s, const PoseAt& pose_at, const StepSink& sink,
                          bool with_labels) {
  State& st = *state_;
  require(std::isfinite(t_end_s) && t_end_s > st.t,
          "EventStream::advance: the end time must be finite and after time()");
  require(static_cast<bool>(pose_at) && static_cast<bool>(sink),
          "EventStream::advance: no pose function or sink");
  const CameraModel& camera = st.config.camera;
  const double base_step_s = 1.0 / st.config.render_rate_hz;
  const auto poseAt = [&pose_at](double t) {
    const Eigen::Isometry3d p = pose_at(t);
    require(p.matrix().allFinite(), "EventStream::advance: pose_at returned a non-finite pose");
    return p;
  };

  double t0 = st.t;
  while (t0 < t_end_s) {
    double t1 = std::min(t0 + base_step_s, t_end_s);
    Eigen::Isometry3d next_pose = poseAt(t1);
    // Largest image motion of a probe point between the two poses [pixels].
    double motion_px = 0.0;
    for (const Eigen::Vector3d& probe : st.probe_rays) {
      const std::optional<Eigen::Vector3d> world = st.renderer.hitPoint(st.pose, probe);
      const Eigen::Vector2d start = *camera.project(probe);  // probe.z() = 1
      if (!world) {
        // No plane: fall back to the rotation alone (points at infinity).
        const Eigen::Vector3d direction =
            next_pose.linear().transpose() * (st.pose.linear() * probe);
        if (const std::optional<Eigen::Vector2d> end = camera.project(direction)) {
          motion_px = std::max(motion_px, (*end - start).norm());
        }
        continue;
      }
      const Eigen::Vector3d in_next = next_pose.inverse() * *world;
      if (const std::optional<Eigen::Vector2d> end = camera.project(in_next)) {
        motion_px = std::max(motion_px, (*end - start).norm());
      } else {
        motion_px = kInfinity;
      }
    }
    if (motion_px > st.config.max_step_motion_px) {
      const double subdivisions =
          std::isfinite(motion_px) ? std::ceil(motion_px / st.config.max_step_motion_px) : 64.0;
      t1 = t0 + (t1 - t0) / std::min(subdivisions, 1e4);
      next_pose = poseAt(t1);
    }

    st.renderer.render(next_pose, st.intensity);
    ++st.render_steps;
    st.step_events.clear();
    st.step_labels.clear();
    const std::size_t signal = st.generator.step(st.intensity, t1, st.step_events,
                                                 with_labels ? &st.step_labels : nullptr);
    st.signal_events += signal;
    st.noise_events += st.step_events.size() - signal;
    st.pose = next_pose;
    st.t = t1;
    t0 = t1;
    sink(st.step_events, st.step_labels, t1);
  }
}

SimulationResult EventSimulator::simulateLabelled(const Scene& scene,
                                                  const Trajectory& camera_trajectory,
                                                  double t_begin_s, double t_end_s,
                                                  const LabelledEventSink& sink) const {
  scene.validate();
  require(camera_trajectory.size() >= 2, "simulate: the trajectory needs at least two poses");
  validateTrajectory(camera_trajectory, "simulate: camera trajectory");
  require(std::isfinite(t_begin_s) && std::isfinite(t_end_s) && t_begin_s < t_end_s,
          "simulate: the time range must be finite and non-empty");
  require(t_begin_s >= camera_trajectory.front().t_s && t_end_s <= camera_trajectory.back().t_s,
          "simulate: the time range lies outside the trajectory");
  require(static_cast<bool>(sink), "simulate: no event sink");

  EventStream stream(config_, scene, interpolatePose(camera_trajectory, t_begin_s).isometry(),
                     t_begin_s);
  SimulationResult result;
  const double gt_step_s = 1.0 / config_.ground_truth_rate_hz;
  std::size_t gt_index = 0;
  // Ground truth at t_begin + k / ground_truth_rate_hz up to `up_to_s`.
  auto emitGroundTruth = [&](double up_to_s) {
    for (double t = t_begin_s + gt_index * gt_step_s; t <= up_to_s;
         t = t_begin_s + gt_index * gt_step_s) {
      result.ground_truth.push_back(interpolatePose(camera_trajectory, t));
      ++gt_index;
    }
  };
  emitGroundTruth(t_begin_s);
  stream.advance(
      t_end_s,
      [&camera_trajectory](double t) { return interpolatePose(camera_trajectory, t).isometry(); },
      [&](const EventVector& events, const std::vector<std::uint8_t>& is_noise, double t1) {
        if (!events.empty()) sink(events, is_noise);
        emitGroundTruth(t1);
      });
  result.signal_events = stream.signalEvents();
  result.noise_events = stream.noiseEvents();
  result.render_steps = stream.renderSteps();
  if (result.ground_truth.empty() || result.ground_truth.back().t_s < t_end_s) {
    result.ground_truth.push_back(interpolatePose(camera_trajectory, t_end_s));
  }
  return result;
}

}  // namespace ebslam
