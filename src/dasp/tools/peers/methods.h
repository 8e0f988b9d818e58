// Uniform access to every superpixel method the tools compare (DASP, ASP_RGB, ASP_RGBD and the
// peers), and the per-frame metric set of the evaluation. Part of dasp_peers (tools only).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/features.h"
#include "peers/peers.h"

namespace dasp {
namespace peers {

enum class Method { kDasp, kAspRgb, kAspRgbd, kSlic, kSeeds, kVccs };

/// Names as used on the command line and in result files: DASP, ASP_RGB, ASP_RGBD, SLIC, SEEDS,
/// VCCS (case-insensitive when parsing). parseMethod throws std::invalid_argument otherwise.
Method parseMethod(const std::string& name);
std::string methodName(Method method);
std::vector<Method> allMethods();

struct MethodOptions {
  int superpixel_count = 1000;  ///< K requested from every method.
  int iterations = 5;           ///< DALIC iterations for DASP / ASP_RGB / ASP_RGBD (thesis: 5).
  int slic_iterations = 10;     ///< OpenCV SLIC iterations (OpenCV default).
  std::uint64_t seed = 0;       ///< Random seed of the DASP family.
  int threads = 1;              ///< Threads inside DASP / ASP (1 = single core, 0 = all).
  float vccs_seed_scale = VccsConfig{}.seed_scale;         ///< See VccsConfig::seed_scale.
  float depth_jump_ratio = DaspConfig{}.depth_jump_ratio;  ///< DASP depth jump (dasp.h).
  /// DASP's ablation knobs (dasp.h); ASP_RGBD takes all but depth_exponent.
  DaspExperimental experimental;
};

/// Runs one method on a frame. labels: CV_32SC1, 0..n-1, -1 = unlabelled. `superpixels` is
/// filled by the DASP family only (their own superpoint list).
struct MethodResult {
  cv::Mat labels;
  std::vector<Superpixel> superpixels;
  /// Time of the method call alone (no I/O, no metrics): CPU time of the calling thread, which
  /// equals the single-core run time and does not grow when other processes load the machine
  /// (valid as a run time only when the method runs single-threaded), and wall time.
  double cpu_milliseconds = 0.0;
  double wall_milliseconds = 0.0;
};
MethodResult runMethod(Method method, const RgbdFrame& frame, const MethodOptions& options);

/// Superpoint list for any label image (labels -1..n-1) from the frame's features: the
/// superpoint fit of dasp/superpoints.h with the depth-adaptive density for n superpixels.
std::vector<Superpixel> describeSuperpixels(const cv::Mat& labels, const PixelFeatures& features);

/// Inputs of the metrics that do not depend on the method, computed once per frame.
struct FrameReference {
  cv::Mat ground_truth;  ///< CV_32SC1 object labels
  cv::Mat mask;          ///< CV_8UC1: ground truth > 0 and depth > 0
  cv::Mat color;         ///< CV_32FC3 RGB in 0..255
  cv::Mat depth_mm;      ///< CV_32FC1 millimetres, NaN where invalid
  cv::Mat depth_m;       ///< CV_32FC1 metres, NaN where invalid
  cv::Mat position_mm;   ///< CV_32FC3 3D point in millimetres, NaN where invalid
  cv::Mat normals;       ///< CV_32FC3 unit normals, NaN where invalid
  double focal_px = 525.0;
};
FrameReference makeFrameReference(const RgbdFrame& frame, const cv::Mat& ground_truth,
                                  const PixelFeatures& features);

/// Names of the per-frame metrics in output order (columns of the CSV files).
const std::vector<std::string>& metricNames();
/// All metrics of one label image, keyed by metricNames().
std::map<std::string, double> evaluateLabels(const cv::Mat& labels, const FrameReference& ref,
                                             int requested_count);

}  // namespace peers
}  // namespace dasp
