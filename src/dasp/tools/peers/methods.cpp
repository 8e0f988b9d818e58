#include "peers/methods.h"

#include <time.h>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "dasp/density.h"
#include "dasp/metrics.h"
#include "dasp/superpoints.h"
#include "peers/peers.h"

namespace dasp {
namespace peers {
namespace {

double threadCpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// The settings of the DASP family (DaspConfig or AspConfig) that every one of them takes from the
// options.
template <class Config>
Config daspFamilyConfig(const MethodOptions& options) {
  Config config;
  config.superpixel_count = options.superpixel_count;
  config.iterations = options.iterations;
  config.seed = options.seed;
  config.threads = options.threads;
  return config;
}

// DASP or ASP_RGBD (the RGB-D members of the DASP family).
Superpixels runRgbdFamily(Method method, const RgbdFrame& frame, const MethodOptions& options) {
  DaspConfig config = daspFamilyConfig<DaspConfig>(options);
  config.depth_jump_ratio = options.depth_jump_ratio;
  config.experimental = options.experimental;
  if (method == Method::kDasp) return computeDasp(frame, config);
  config.experimental.depth_exponent = DaspExperimental{}.depth_exponent;  // DASP's only
  return computeAspRgbd(frame, config);
}

}  // namespace

Method parseMethod(const std::string& name) {
  std::string upper = name;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  for (Method m : allMethods()) {
    if (methodName(m) == upper) return m;
  }
  throw std::invalid_argument("unknown method '" + name +
                              "' (expected DASP, ASP_RGB, ASP_RGBD, SLIC, SEEDS or VCCS)");
}

std::string methodName(Method method) {
  switch (method) {
    case Method::kDasp:
      return "DASP";
    case Method::kAspRgb:
      return "ASP_RGB";
    case Method::kAspRgbd:
      return "ASP_RGBD";
    case Method::kSlic:
      return "SLIC";
    case Method::kSeeds:
      return "SEEDS";
    case Method::kVccs:
      return "VCCS";
  }
  return "?";
}

std::vector<Method> allMethods() {
  return {Method::kDasp, Method::kAspRgb, Method::kAspRgbd,
          Method::kSlic, Method::kSeeds,  Method::kVccs};
}

MethodResult runMethod(Method method, const RgbdFrame& frame, const MethodOptions& options) {
  MethodResult result;
  int run_count = 1;  // VCCS reruns to match the count: the time reported is per run
  const double cpu_start = threadCpuMilliseconds();
  const auto start = std::chrono::steady_clock::now();
  switch (method) {
    case Method::kDasp:
    case Method::kAspRgbd:
    case Method::kAspRgb: {
      Superpixels s = method == Method::kAspRgb
                          ? computeAspRgb(frame.color, daspFamilyConfig<AspConfig>(options))
                          : runRgbdFamily(method, frame, options);
      result.labels = std::move(s.labels);
      result.superpixels = std::move(s.superpixels);
      break;
    }
    case Method::kSlic: {
      SlicConfig config;
      config.superpixel_count = options.superpixel_count;
      config.iterations = options.slic_iterations;
      result.labels = computeOpenCvSlic(frame.color, config);
      break;
    }
    case Method::kSeeds: {
      SeedsConfig config;
      config.superpixel_count = options.superpixel_count;
      result.labels = computeOpenCvSeeds(frame.color, config);
      break;
    }
    case Method::kVccs: {
      VccsConfig config;
      config.superpixel_count = options.superpixel_count;
      config.seed_scale = options.vccs_seed_scale;
      int runs = 1;
      result.labels = computeVccs(frame, config, &runs);
      run_count = runs;
      break;
    }
  }
  result.wall_milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() /
      run_count;
  result.cpu_milliseconds = (threadCpuMilliseconds() - cpu_start) / run_count;
  return result;
}

std::vector<Superpixel> describeSuperpixels(const cv::Mat& labels, const PixelFeatures& features) {
  cv::Mat compact = labels.clone();
  const int count = compactLabels(compact);
  if (count == 0) return {};
  if (!features.hasDepth()) return fitSuperpoints(compact, features, cv::Mat(), 0.0f);
  const float radius = radiusForCount(features, count);
  return fitSuperpoints(compact, features, computeDepthDensity(features, radius), radius);
}

FrameReference makeFrameReference(const RgbdFrame& frame, const cv::Mat& ground_truth,
                                  const PixelFeatures& features) {
  FrameReference ref;
  if (ground_truth.size() != frame.color.size()) {
    throw std::invalid_argument("ground truth size differs from the frame");
  }
  ground_truth.convertTo(ref.ground_truth, CV_32S);
  ref.mask = (ref.ground_truth > 0) & (frame.depth > 0);
  cv::Mat rgb;
  cv::cvtColor(frame.color, rgb, cv::COLOR_BGR2RGB);
  rgb.convertTo(ref.color, CV_32FC3);
  const cv::Size size = frame.color.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ref.depth_mm.create(size, CV_32FC1);
  ref.depth_m.create(size, CV_32FC1);
  ref.position_mm.create(size, CV_32FC3);
  ref.normals.create(size, CV_32FC3);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * size.width + x;
      const bool valid = features.valid[i] != 0;
      const bool has_normal =
          valid && (features.nx[i] != 0.0f || features.ny[i] != 0.0f || features.nz[i] != 0.0f);
      ref.depth_m.at<float>(y, x) = valid ? features.z[i] : nan;
      ref.depth_mm.at<float>(y, x) = valid ? 1000.0f * features.z[i] : nan;
      ref.position_mm.at<cv::Vec3f>(y, x) =
          valid
              ? cv::Vec3f(1000.0f * features.x[i], 1000.0f * features.y[i], 1000.0f * features.z[i])
              : cv::Vec3f(nan, nan, nan);
      ref.normals.at<cv::Vec3f>(y, x) =
          has_normal ? cv::Vec3f(features.nx[i], features.ny[i], features.nz[i])
                     : cv::Vec3f(nan, nan, nan);
    }
  }
  ref.focal_px = 0.5 * (frame.intrinsics.fx + frame.intrinsics.fy);
  return ref;
}

const std::vector<std::string>& metricNames() {
  static const std::vector<std::string> names = {"requested_k",
                                                 "superpixels",
                                                 "superpixels_in_mask",
                                                 "count_ratio",
                                                 "boundary_recall",
                                                 "boundary_precision",
                                                 "boundary_f1",
                                                 "ue_np",
                                                 "use_thesis",
                                                 "asa",
                                                 "cq",
                                                 "disconnected_fraction",
                                                 "co_ipq",
                                                 "ipq_3d",
                                                 "ce_color",
                                                 "ce_depth_mm",
                                                 "ce_position_mm",
                                                 "ce_normal",
                                                 "ev_color",
                                                 "ev_depth",
                                                 "ev_position",
                                                 "ev_normal",
                                                 "ude_relative",
                                                 "unlabelled_in_mask"};
  return names;
}

std::map<std::string, double> evaluateLabels(const cv::Mat& labels, const FrameReference& ref,
                                             int requested_count) {
  using namespace dasp::metrics;
  std::map<std::string, double> m;
  const cv::Mat& mask = ref.mask;
  m["requested_k"] = requested_count;
  // Delivered count and connectivity over the whole image: properties of the method's output.
  const ConnectivityScores whole = connectivity(labels, cv::Mat());
  m["superpixels"] = static_cast<double>(whole.segments);
  m["count_ratio"] = static_cast<double>(whole.segments) / requested_count;
  m["cq"] = whole.quotient;
  m["disconnected_fraction"] =
      whole.segments > 0 ? static_cast<double>(whole.disconnected_segments) / whole.segments : 0.0;
  m["superpixels_in_mask"] = static_cast<double>(countSegments(labels, mask));
  const BoundaryScores b = boundaryScores(labels, ref.ground_truth, mask, 2);
  m["boundary_recall"] = b.recall;
  m["boundary_precision"] = b.precision;
  m["boundary_f1"] = b.f1;
  m["ue_np"] = undersegmentationErrorNp(labels, ref.ground_truth, mask);
  m["use_thesis"] = undersegmentationErrorThesis(labels, ref.ground_truth, mask, 0.05);
  m["asa"] = achievableSegmentationAccuracy(labels, ref.ground_truth, mask);
  m["co_ipq"] = isoperimetricQuotient(labels, mask);
  m["ipq_3d"] = isoperimetricQuotient3d(labels, mask, ref.depth_m, ref.normals, ref.focal_px);
  const CompressionScores color = compressionScores(labels, mask, ref.color);
  const CompressionScores depth = compressionScores(labels, mask, ref.depth_mm);
  const CompressionScores position = compressionScores(labels, mask, ref.position_mm);
  const CompressionScores normal =
      compressionScores(labels, mask, ref.normals, FeatureMean::kUnitVector);
  m["ce_color"] = color.compression_error;
  m["ce_depth_mm"] = depth.compression_error;
  m["ce_position_mm"] = position.compression_error;
  m["ce_normal"] = normal.compression_error;
  m["ev_color"] = color.explained_variation;
  m["ev_depth"] = depth.explained_variation;
  m["ev_position"] = position.explained_variation;
  m["ev_normal"] = normal.explained_variation;
  m["ude_relative"] = uniformDistributionError(labels, mask).relative_rms;
  const int in_mask = cv::countNonZero(mask);
  const int unlabelled = cv::countNonZero((labels < 0) & mask);
  m["unlabelled_in_mask"] = in_mask > 0 ? static_cast<double>(unlabelled) / in_mask : 0.0;
  return m;
}

}  // namespace peers
}  // namespace dasp
