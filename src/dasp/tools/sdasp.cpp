// dasp_sdasp: s-DASP image segmentation (thesis ch. 4).
//   segment:  one RGB-D frame -> segments picture, ultrametric contour map picture, labels.
//   evaluate: a folder of frames with object labels (../shared/data/osd/learn layout) ->
//             boundary precision/recall curves, ODS and OIS F1 and time per frame of s-DASP
//             (DASP superpixels), s-SLIC (the same segmentation on ASP_RGB superpixels) and PCL's
//             LCCP, as JSON. Parameter lists (comma separated) run a grid on the same superpixels;
//             the adaptive cut (dasp::adaptiveCutThreshold) is scored for a grid of its
//             parameters too, and --per-frame writes every frame's counts (for cross-validation,
//             sdasp_crossval.py).
// Mask per frame: object label > 0 and depth > 0; boundary F1 at 2 px (dasp/metrics.h).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <exception>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "dasp/dasp.h"
#include "dasp/metrics.h"
#include "dasp/rgbd_io.h"
#include "dasp/sdasp.h"
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"
#include "peers/lccp.h"
#include "sdasp/common.h"
#include "sdasp/evaluate.h"

namespace {

using sdasp_tool::computeSuperpixels;
using sdasp_tool::EvaluateOptions;
using sdasp_tool::threadCpuMilliseconds;

cv::Vec3b segmentColor(int segment) {
  // Deterministic well-spread false colours (golden-ratio hue steps).
  const double hue = std::fmod(segment * 0.618033988749895, 1.0) * 180.0;
  cv::Mat hsv(1, 1, CV_8UC3,
              cv::Scalar(hue, 160 + (segment * 37) % 96, 150 + (segment * 53) % 106));
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr.at<cv::Vec3b>(0, 0);
}

// Segments in false colours; unlabelled pixels black.
cv::Mat segmentsPicture(const cv::Mat& segments) {
  cv::Mat out(segments.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      const int s = segments.at<int>(y, x);
      if (s >= 0) out.at<cv::Vec3b>(y, x) = segmentColor(s);
    }
  }
  return out;
}

// UCM as dark strokes on white: grey = 255 (1 - sqrt(min(level, 1))), the square root so that the
// weaker object boundaries (levels about 0.1) stay visible; never-merged boundaries black.
cv::Mat ucmPicture(const cv::Mat& ucm) {
  cv::Mat out(ucm.size(), CV_8UC1, cv::Scalar(255));
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      const float level = ucm.at<float>(y, x);
      if (level < 0.0f) continue;
      out.at<std::uint8_t>(y, x) =
          cv::saturate_cast<std::uint8_t>(255.0f * (1.0f - std::sqrt(std::min(level, 1.0f))));
    }
  }
  return out;
}

// Pictures are written at `scale` of the frame size (area interpolation; nearest for labels).
void writePicture(const std::string& path, const cv::Mat& picture, double scale) {
  cv::Mat out = picture;
  if (scale != 1.0) cv::resize(picture, out, cv::Size(), scale, scale, cv::INTER_AREA);
  if (!cv::imwrite(path, out)) throw std::runtime_error("cannot write " + path);
}

int runSegment(const dasp::RgbdFramePaths& paths, const dasp::Intrinsics& intrinsics,
               const std::string& superpixels_kind, int count, std::uint64_t seed,
               const dasp::SdaspConfig& config, const std::string& segments_path,
               const std::string& ucm_path, const std::string& labels_path,
               const std::string& superpixels_path, const std::string& overlay_path, double scale) {
  const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths, intrinsics);
  double t0 = threadCpuMilliseconds();
  const dasp::Superpixels sp = computeSuperpixels(superpixels_kind, frame, count, seed);
  const double t_superpixels = threadCpuMilliseconds() - t0;
  t0 = threadCpuMilliseconds();
  const dasp::WeightedGraph ucg = dasp::ultrametricContourGraph(sp, config);
  const double t_ucg = threadCpuMilliseconds() - t0;
  t0 = threadCpuMilliseconds();
  const float threshold = dasp::cutThreshold(ucg, config);
  const cv::Mat segments = dasp::segmentPixels(sp.labels, dasp::segmentGraph(ucg, threshold));
  const double t_label = threadCpuMilliseconds() - t0;
  std::cout << superpixels_kind << ": " << sp.superpixels.size() << " superpixels, "
            << ucg.edges.size() << " edges, " << dasp::metrics::countSegments(segments, cv::Mat())
            << " segments at threshold " << threshold
            << (config.cut == dasp::CutRule::kAdaptive ? " (adaptive)" : " (global)") << "; "
            << std::fixed << std::setprecision(1) << t_superpixels << " ms superpixels + " << t_ucg
            << " ms graph and eigen + " << t_label << " ms labelling (thread CPU)\n";
  if (!segments_path.empty()) writePicture(segments_path, segmentsPicture(segments), scale);
  if (!ucm_path.empty()) {
    writePicture(ucm_path, ucmPicture(dasp::ultrametricContourMap(sp.labels, ucg)), scale);
  }
  if (!superpixels_path.empty()) {
    cv::Mat picture = frame.color.clone();
    picture.setTo(cv::Scalar(0, 0, 255), dasp::metrics::boundaryMap(sp.labels, cv::Mat()));
    writePicture(superpixels_path, picture, scale);
  }
  if (!overlay_path.empty()) {
    cv::Mat picture = frame.color.clone();
    cv::Mat boundary = dasp::metrics::boundaryMap(segments, cv::Mat());
    cv::dilate(boundary, boundary, cv::Mat());  // 3 px strokes, visible at half size
    picture.setTo(cv::Scalar(0, 0, 255), boundary);
    writePicture(overlay_path, picture, scale);
  }
  if (!labels_path.empty()) {
    cv::Mat image;
    segments.convertTo(image, CV_16U, 1.0, 1.0);  // label + 1, 0 = unlabelled
    if (!cv::imwrite(labels_path, image)) throw std::runtime_error("cannot write " + labels_path);
  }
  return 0;
}

// `segment` and `lccp`: one frame, its pictures and labels.
struct SegmentOptions {
  dasp::RgbdFramePaths paths;
  dasp::Intrinsics intrinsics;
  std::string superpixels_kind = "DASP";
  std::string cut_rule = "adaptive";
  std::string segments_path, ucm_path, labels_path, superpixels_path, overlay_path;
  double picture_scale = 1.0;
  dasp::peers::LccpConfig lccp;
};

CLI::App* addSegmentCommand(CLI::App& app, SegmentOptions& o, dasp::SdaspConfig& config) {
  CLI::App* segment = app.add_subcommand("segment", "s-DASP segmentation of one frame");
  segment->add_option("--color", o.paths.color, "8-bit colour PNG")
      ->required()
      ->check(CLI::ExistingFile);
  segment->add_option("--depth", o.paths.depth, "16-bit depth PNG in millimetres")
      ->required()
      ->check(CLI::ExistingFile);
  segment
      ->add_option("--superpixels", o.superpixels_kind,
                   "DASP (s-DASP), ASP_RGB (s-SLIC) or ASP_RGB_VALID")
      ->capture_default_str();
  segment
      ->add_option("-t,--threshold", config.threshold,
                   "global cut threshold on the normalised UCG weights (edges below it merge)")
      ->capture_default_str();
  segment->add_option("--cut", o.cut_rule, "cut rule: adaptive (per frame) or global (--threshold)")
      ->check(CLI::IsMember({"adaptive", "global"}))
      ->capture_default_str();
  segment->add_option("--adaptive-scale", config.adaptive_scale, "adaptive cut: scale")
      ->capture_default_str();
  segment->add_option("--adaptive-quantile", config.adaptive_quantile, "adaptive cut: quantile")
      ->capture_default_str();
  segment
      ->add_option("--adaptive-max-threshold", config.adaptive_max_threshold,
                   "adaptive cut: largest threshold")
      ->capture_default_str();
  segment->add_option("--segments", o.segments_path, "output PNG: segments in false colours");
  segment->add_option("--ucm", o.ucm_path, "output PNG: ultrametric contour map (dark = strong)");
  segment->add_option("--superpixel-overlay", o.superpixels_path,
                      "output PNG: superpixel boundaries over the colour image");
  segment->add_option("--segment-overlay", o.overlay_path,
                      "output PNG: segment boundaries (red) over the colour image");
  segment->add_option("--labels", o.labels_path, "output 16-bit PNG: segment + 1, 0 = unlabelled");
  segment->add_option("--picture-scale", o.picture_scale, "size of the pictures (1 = frame size)")
      ->capture_default_str();
  segment->add_option("--color-weight", config.graph.weight_color, "lambda_c")
      ->capture_default_str();
  segment->add_option("--position-weight", config.graph.weight_position, "lambda_v")
      ->capture_default_str();
  segment->add_option("--normal-weight", config.graph.weight_normal, "lambda_n")
      ->capture_default_str();
  segment->add_option("--eigenvectors", config.spectral.eigenvector_count, "k")
      ->capture_default_str();
  segment->add_option("--theta", config.graph.min_border_pairs, "Theta (min border pairs)")
      ->capture_default_str();
  return segment;
}

CLI::App* addLccpCommand(CLI::App& app, SegmentOptions& o) {
  CLI::App* lccp_cmd = app.add_subcommand("lccp", "PCL LCCP segmentation of one frame (peer)");
  lccp_cmd->add_option("--color", o.paths.color, "8-bit colour PNG")
      ->required()
      ->check(CLI::ExistingFile);
  lccp_cmd->add_option("--depth", o.paths.depth, "16-bit depth PNG in millimetres")
      ->required()
      ->check(CLI::ExistingFile);
  lccp_cmd
      ->add_option("--lccp-seed-resolution", o.lccp.seed_resolution_m,
                   "supervoxel seed resolution in metres")
      ->capture_default_str();
  lccp_cmd->add_flag("--lccp-single-camera-transform", o.lccp.single_camera_transform,
                     "depth-dependent voxel grid (PCL example switch -tvoxel)");
  lccp_cmd->add_option("--segments", o.segments_path, "output PNG: segments in false colours");
  lccp_cmd->add_option("--picture-scale", o.picture_scale, "size of the pictures")
      ->capture_default_str();
  return lccp_cmd;
}

CLI::App* addEvaluateCommand(CLI::App& app, EvaluateOptions& o) {
  CLI::App* evaluate = app.add_subcommand("evaluate", "PR curves, ODS/OIS F1 and times");
  evaluate->add_option("--folder", o.folder, "folder of <name>_rgb/_depth_mm/_label_object.png")
      ->required()
      ->check(CLI::ExistingDirectory);
  evaluate->add_option("--json", o.json_path, "output JSON with curves, ODS, OIS, times")
      ->required();
  evaluate
      ->add_option("--methods", o.methods_text,
                   "comma list of sDASP, sSLIC, sSLICvalid (ASP_RGB on depth-valid pixels), LCCP")
      ->capture_default_str();
  evaluate
      ->add_option("--thresholds", o.threshold_count,
                   "number of thresholds evenly spaced in [0, 1] (curve points)")
      ->capture_default_str();
  evaluate->add_option("--frames", o.max_frames, "use only the first N frames (0 = all)");
  evaluate->add_option("--color-weight", o.color_weights, "lambda_c, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--position-weight", o.position_weights, "lambda_v, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--normal-weight", o.normal_weights, "lambda_n, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--eigenvectors", o.eigen_counts, "k, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--theta", o.thetas, "Theta (min border pairs), comma list = grid")
      ->capture_default_str();
  evaluate
      ->add_option("--lccp-seed-resolutions", o.lccp_seeds,
                   "LCCP supervoxel seed resolutions in metres (one run each)")
      ->capture_default_str();
  evaluate->add_option("--adaptive-scale", o.adaptive_scales, "adaptive cut scale, comma list")
      ->capture_default_str();
  evaluate->add_option("--adaptive-quantile", o.adaptive_quantiles, "adaptive cut quantile, list")
      ->capture_default_str();
  evaluate
      ->add_option("--adaptive-max-threshold", o.adaptive_caps, "adaptive cut upper bound, list")
      ->capture_default_str();
  evaluate->add_flag("--per-frame", o.per_frame,
                     "write every frame's boundary counts (curve and adaptive cuts)");
  evaluate->add_flag("--lccp-single-camera-transform", o.lccp_single_camera,
                     "LCCP: depth-dependent voxel grid (PCL example switch -tvoxel)");
  return evaluate;
}

int runLccp(const SegmentOptions& o) {
  const dasp::RgbdFrame frame = dasp::loadRgbdFrame(o.paths, o.intrinsics);
  int supervoxels = 0;
  const double t0 = threadCpuMilliseconds();
  const cv::Mat labels = dasp::peers::computeLccp(frame, o.lccp, &supervoxels);
  std::cout << "LCCP: " << supervoxels << " supervoxels, "
            << dasp::metrics::countSegments(labels, cv::Mat()) << " segments, " << std::fixed
            << std::setprecision(1) << threadCpuMilliseconds() - t0 << " ms (thread CPU)\n";
  if (!o.segments_path.empty()) {
    writePicture(o.segments_path, segmentsPicture(labels), o.picture_scale);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "s-DASP image segmentation (thesis ch. 4): segment one frame, or evaluate boundary "
      "precision/recall, ODS/OIS F1 and time on a folder against s-SLIC and PCL LCCP."};
  app.require_subcommand(1);
  dasp::SdaspConfig config;
  int count = 1000;
  std::uint64_t seed = 0;
  auto add_common = [&](CLI::App* sub) {
    sub->add_option("-k,--count", count, "number of superpixels K")->capture_default_str();
    sub->add_option("--seed", seed, "random seed of the superpixels")->capture_default_str();
  };
  SegmentOptions segment_options;
  EvaluateOptions evaluate_options(config);
  CLI::App* segment = addSegmentCommand(app, segment_options, config);
  add_common(segment);
  CLI::App* lccp_cmd = addLccpCommand(app, segment_options);
  CLI::App* evaluate = addEvaluateCommand(app, evaluate_options);
  add_common(evaluate);
  CLI11_PARSE(app, argc, argv);

  try {
    SegmentOptions& o = segment_options;
    if (segment->parsed()) {
      o.paths.name = o.paths.color;
      config.cut = o.cut_rule == "global" ? dasp::CutRule::kGlobal : dasp::CutRule::kAdaptive;
      return runSegment(o.paths, o.intrinsics, o.superpixels_kind, count, seed, config,
                        o.segments_path, o.ucm_path, o.labels_path, o.superpixels_path,
                        o.overlay_path, o.picture_scale);
    }
    if (lccp_cmd->parsed()) {
      o.paths.name = o.paths.color;
      return runLccp(o);
    }
    return sdasp_tool::runEvaluate(evaluate_options, config, count, seed);
  } catch (const std::exception& e) {
    std::cerr << "dasp_sdasp: " << e.what() << "\n";
    return 1;
  }
}
