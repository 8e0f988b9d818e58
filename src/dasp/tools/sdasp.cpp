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
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"
#include "peers/lccp.h"

namespace {

double threadCpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// Superpixels for the segmentation: DASP (s-DASP) or colour-only ASP_RGB (s-SLIC) over the whole
// image, or ASP_RGB_VALID: ASP_RGB with the pixels without depth unlabelled, so that the graph
// covers the same pixels as DASP's (the depth values themselves are still not used).
dasp::Superpixels computeSuperpixels(const std::string& kind, const dasp::RgbdFrame& frame,
                                     int count, std::uint64_t seed) {
  if (kind == "ASP_RGB_VALID") {
    dasp::Superpixels sp = computeSuperpixels("ASP_RGB", frame, count, seed);
    sp.labels.setTo(-1, frame.depth == 0);
    return sp;
  }
  if (kind == "DASP") {
    dasp::DaspConfig config;
    config.superpixel_count = count;
    config.seed = seed;
    return dasp::computeDasp(frame, config);
  }
  if (kind == "ASP_RGB") {
    dasp::AspConfig config;
    config.superpixel_count = count;
    config.seed = seed;
    return dasp::computeAspRgb(frame.color, config);
  }
  throw std::invalid_argument("superpixels must be DASP, ASP_RGB or ASP_RGB_VALID, not " + kind);
}

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

template <typename T>
std::vector<T> parseList(const std::string& text) {
  std::vector<T> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (item.empty()) continue;
    std::istringstream parse(item);
    T value{};
    if (!(parse >> value)) throw std::invalid_argument("cannot parse list item '" + item + "'");
    values.push_back(value);
  }
  if (values.empty()) throw std::invalid_argument("empty list '" + text + "'");
  return values;
}

cv::Mat evaluationMask(const dasp::RgbdFrame& frame, const cv::Mat& truth) {
  return (truth > 0) & (frame.depth > 0);
}

struct Curve {
  std::vector<float> thresholds;
  std::vector<dasp::BoundaryCounts> total;  // summed over frames (ODS)
  dasp::BoundaryCounts ois_total;           // counts at every frame's own best threshold
  double mean_best_f1 = 0.0;                // mean over frames of the best F1 of the frame
  int frames = 0;

  void add(const std::vector<dasp::BoundaryCounts>& frame_curve) {
    if (total.empty()) total.resize(frame_curve.size());
    std::size_t best = 0;
    for (std::size_t i = 0; i < frame_curve.size(); ++i) {
      total[i] += frame_curve[i];
      if (frame_curve[i].f1() > frame_curve[best].f1()) best = i;
    }
    ois_total += frame_curve[best];
    mean_best_f1 += frame_curve[best].f1();
    ++frames;
  }
  std::size_t odsIndex() const {
    std::size_t best = 0;
    for (std::size_t i = 0; i < total.size(); ++i) {
      if (total[i].f1() > total[best].f1()) best = i;
    }
    return best;
  }
};

nlohmann::json countsJson(const dasp::BoundaryCounts& c) {
  return {c.partition_pixels, c.precise_pixels, c.reference_pixels, c.recalled_pixels};
}

struct Times {
  double superpixels = 0.0, graph = 0.0, eigen = 0.0, labelling = 0.0, ucm = 0.0;
};

nlohmann::ordered_json curveJson(const Curve& curve, const std::vector<Times>& times,
                                 const std::vector<double>& frame_best_f1) {
  nlohmann::ordered_json j;
  const std::size_t ods = curve.odsIndex();
  const dasp::BoundaryCounts& o = curve.total[ods];
  j["ods"] = {{"threshold", curve.thresholds[ods]},
              {"precision", o.precision()},
              {"recall", o.recall()},
              {"f1", o.f1()}};
  j["ois"] = {{"precision", curve.ois_total.precision()},
              {"recall", curve.ois_total.recall()},
              {"f1", curve.ois_total.f1()},
              {"mean_frame_best_f1", curve.mean_best_f1 / std::max(1, curve.frames)}};
  nlohmann::ordered_json points = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < curve.total.size(); ++i) {
    points.push_back({curve.thresholds[i], curve.total[i].precision(), curve.total[i].recall(),
                      curve.total[i].f1()});
  }
  j["curve_threshold_precision_recall_f1"] = points;
  Times mean;
  for (const Times& t : times) {
    mean.superpixels += t.superpixels / times.size();
    mean.graph += t.graph / times.size();
    mean.eigen += t.eigen / times.size();
    mean.ucm += t.ucm / times.size();
    mean.labelling += t.labelling / times.size();
  }
  j["time_ms"] = {
      {"superpixels", mean.superpixels},
      {"graph", mean.graph},
      {"eigen", mean.eigen},
      {"labelling", mean.labelling},
      {"segmentation_total", mean.superpixels + mean.graph + mean.eigen + mean.labelling},
      {"ucm_image", mean.ucm}};
  j["frame_best_f1"] = frame_best_f1;
  return j;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "s-DASP image segmentation (thesis ch. 4): segment one frame, or evaluate boundary "
      "precision/recall, ODS/OIS F1 and time on a folder against s-SLIC and PCL LCCP."};
  app.require_subcommand(1);
  dasp::SdaspConfig config;
  int count = 1000;
  std::uint64_t seed = 0;
  std::string normalization = "max";

  auto add_common = [&](CLI::App* sub) {
    sub->add_option("-k,--count", count, "number of superpixels K")->capture_default_str();
    sub->add_option("--seed", seed, "random seed of the superpixels")->capture_default_str();
  };

  // segment
  CLI::App* segment = app.add_subcommand("segment", "s-DASP segmentation of one frame");
  dasp::RgbdFramePaths paths;
  dasp::Intrinsics intrinsics;
  std::string superpixels_kind = "DASP";
  std::string cut_rule = "adaptive";
  std::string segments_path, ucm_path, labels_path, superpixels_path, overlay_path;
  segment->add_option("--color", paths.color, "8-bit colour PNG")
      ->required()
      ->check(CLI::ExistingFile);
  segment->add_option("--depth", paths.depth, "16-bit depth PNG in millimetres")
      ->required()
      ->check(CLI::ExistingFile);
  segment
      ->add_option("--superpixels", superpixels_kind,
                   "DASP (s-DASP), ASP_RGB (s-SLIC) or ASP_RGB_VALID")
      ->capture_default_str();
  segment
      ->add_option("-t,--threshold", config.threshold,
                   "global cut threshold on the normalised UCG weights (edges below it merge)")
      ->capture_default_str();
  segment->add_option("--cut", cut_rule, "cut rule: adaptive (per frame) or global (--threshold)")
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
  segment->add_option("--segments", segments_path, "output PNG: segments in false colours");
  segment->add_option("--ucm", ucm_path, "output PNG: ultrametric contour map (dark = strong)");
  segment->add_option("--superpixel-overlay", superpixels_path,
                      "output PNG: superpixel boundaries over the colour image");
  segment->add_option("--segment-overlay", overlay_path,
                      "output PNG: segment boundaries (red) over the colour image");
  segment->add_option("--labels", labels_path, "output 16-bit PNG: segment + 1, 0 = unlabelled");
  double picture_scale = 1.0;
  segment->add_option("--picture-scale", picture_scale, "size of the pictures (1 = frame size)")
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
  add_common(segment);

  // lccp
  CLI::App* lccp_cmd = app.add_subcommand("lccp", "PCL LCCP segmentation of one frame (peer)");
  dasp::peers::LccpConfig lccp_config;
  lccp_cmd->add_option("--color", paths.color, "8-bit colour PNG")
      ->required()
      ->check(CLI::ExistingFile);
  lccp_cmd->add_option("--depth", paths.depth, "16-bit depth PNG in millimetres")
      ->required()
      ->check(CLI::ExistingFile);
  lccp_cmd
      ->add_option("--lccp-seed-resolution", lccp_config.seed_resolution_m,
                   "supervoxel seed resolution in metres")
      ->capture_default_str();
  lccp_cmd->add_flag("--lccp-single-camera-transform", lccp_config.single_camera_transform,
                     "depth-dependent voxel grid (PCL example switch -tvoxel)");
  lccp_cmd->add_option("--segments", segments_path, "output PNG: segments in false colours");
  lccp_cmd->add_option("--picture-scale", picture_scale, "size of the pictures")
      ->capture_default_str();

  // evaluate
  CLI::App* evaluate = app.add_subcommand("evaluate", "PR curves, ODS/OIS F1 and times");
  std::string folder, json_path, methods_text = "sDASP,sSLIC,LCCP";
  int threshold_count = 201;
  int max_frames = 0;
  std::string color_weights = std::to_string(config.graph.weight_color);
  std::string position_weights = std::to_string(config.graph.weight_position);
  std::string normal_weights = std::to_string(config.graph.weight_normal);
  std::string eigen_counts = std::to_string(config.spectral.eigenvector_count);
  std::string thetas = std::to_string(config.graph.min_border_pairs);
  std::string lccp_seeds = "0.015,0.02,0.03";
  std::string adaptive_scales = std::to_string(config.adaptive_scale);
  std::string adaptive_quantiles = std::to_string(config.adaptive_quantile);
  std::string adaptive_caps = std::to_string(config.adaptive_max_threshold);
  bool per_frame = false;
  evaluate->add_option("--folder", folder, "folder of <name>_rgb/_depth_mm/_label_object.png")
      ->required()
      ->check(CLI::ExistingDirectory);
  evaluate->add_option("--json", json_path, "output JSON with curves, ODS, OIS, times")->required();
  evaluate
      ->add_option("--methods", methods_text,
                   "comma list of sDASP, sSLIC, sSLICvalid (ASP_RGB on depth-valid pixels), LCCP")
      ->capture_default_str();
  evaluate
      ->add_option("--thresholds", threshold_count,
                   "number of thresholds evenly spaced in [0, 1] (curve points)")
      ->capture_default_str();
  evaluate->add_option("--frames", max_frames, "use only the first N frames (0 = all)");
  evaluate->add_option("--color-weight", color_weights, "lambda_c, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--position-weight", position_weights, "lambda_v, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--normal-weight", normal_weights, "lambda_n, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--eigenvectors", eigen_counts, "k, comma list = grid")
      ->capture_default_str();
  evaluate->add_option("--theta", thetas, "Theta (min border pairs), comma list = grid")
      ->capture_default_str();
  evaluate
      ->add_option("--lccp-seed-resolutions", lccp_seeds,
                   "LCCP supervoxel seed resolutions in metres (one run each)")
      ->capture_default_str();
  evaluate->add_option("--adaptive-scale", adaptive_scales, "adaptive cut scale, comma list")
      ->capture_default_str();
  evaluate->add_option("--adaptive-quantile", adaptive_quantiles, "adaptive cut quantile, list")
      ->capture_default_str();
  evaluate->add_option("--adaptive-max-threshold", adaptive_caps, "adaptive cut upper bound, list")
      ->capture_default_str();
  evaluate->add_flag("--per-frame", per_frame,
                     "write every frame's boundary counts (curve and adaptive cuts)");
  bool lccp_single_camera = false;
  evaluate->add_flag("--lccp-single-camera-transform", lccp_single_camera,
                     "LCCP: depth-dependent voxel grid (PCL example switch -tvoxel)");
  add_common(evaluate);
  CLI11_PARSE(app, argc, argv);

  try {
    if (segment->parsed()) {
      paths.name = paths.color;
      config.cut = cut_rule == "global" ? dasp::CutRule::kGlobal : dasp::CutRule::kAdaptive;
      return runSegment(paths, intrinsics, superpixels_kind, count, seed, config, segments_path,
                        ucm_path, labels_path, superpixels_path, overlay_path, picture_scale);
    }
    if (lccp_cmd->parsed()) {
      paths.name = paths.color;
      const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths, intrinsics);
      int supervoxels = 0;
      const double t0 = threadCpuMilliseconds();
      const cv::Mat labels = dasp::peers::computeLccp(frame, lccp_config, &supervoxels);
      std::cout << "LCCP: " << supervoxels << " supervoxels, "
                << dasp::metrics::countSegments(labels, cv::Mat()) << " segments, " << std::fixed
                << std::setprecision(1) << threadCpuMilliseconds() - t0 << " ms (thread CPU)\n";
      if (!segments_path.empty())
        writePicture(segments_path, segmentsPicture(labels), picture_scale);
      return 0;
    }
    std::vector<dasp::RgbdFramePaths> frames = dasp::listRgbdFolder(folder);
    frames.erase(std::remove_if(frames.begin(), frames.end(),
                                [](const dasp::RgbdFramePaths& f) { return f.label.empty(); }),
                 frames.end());
    if (max_frames > 0 && static_cast<int>(frames.size()) > max_frames) frames.resize(max_frames);
    if (frames.empty()) throw std::invalid_argument("no frames with labels in " + folder);
    if (threshold_count < 2) throw std::invalid_argument("--thresholds must be >= 2");
    std::vector<float> thresholds(static_cast<std::size_t>(threshold_count));
    for (int i = 0; i < threshold_count; ++i) {
      thresholds[i] = static_cast<float>(i) / static_cast<float>(threshold_count - 1);
    }
    // A threshold just above 1 merges everything but the never-joined boundaries.
    thresholds.push_back(std::nextafter(1.0f, 2.0f));

    std::vector<dasp::SdaspConfig> grid;
    for (float c : parseList<float>(color_weights)) {
      for (float v : parseList<float>(position_weights)) {
        for (float n : parseList<float>(normal_weights)) {
          for (int k : parseList<int>(eigen_counts)) {
            for (int theta : parseList<int>(thetas)) {
              dasp::SdaspConfig g = config;
              g.graph.weight_color = c;
              g.graph.weight_position = v;
              g.graph.weight_normal = n;
              g.graph.min_border_pairs = theta;
              g.spectral.eigenvector_count = k;
              grid.push_back(g);
            }
          }
        }
      }
    }
    struct AdaptiveSetting {
      float scale, quantile, cap;
    };
    std::vector<AdaptiveSetting> adaptive;
    for (float sc : parseList<float>(adaptive_scales)) {
      for (float q : parseList<float>(adaptive_quantiles)) {
        for (float cap : parseList<float>(adaptive_caps)) adaptive.push_back({sc, q, cap});
      }
    }
    std::vector<std::string> frame_names;
    for (const dasp::RgbdFramePaths& f : frames) {
      frame_names.push_back(f.name);
    }
    const std::vector<std::string> methods = parseList<std::string>(methods_text);
    const std::vector<float> seeds = parseList<float>(lccp_seeds);

    nlohmann::ordered_json out;
    out["folder"] = folder;
    out["frames"] = frames.size();
    out["superpixel_count"] = count;
    out["seed"] = seed;
    out["mask"] = "object label > 0 and depth > 0";
    out["boundary_tolerance_px"] = dasp::metrics::kDefaultBoundaryTolerancePx;
    out["time"] = "thread CPU time per frame, single-threaded, milliseconds";
    out["frame_files"] = frame_names;
    out["thresholds"] = thresholds;
    out["counts"] = "[partition, precise, reference, recalled] boundary pixels";
    out["results"] = nlohmann::ordered_json::array();

    for (const std::string& method : methods) {
      if (method == "LCCP") {
        for (float seed_resolution : seeds) {
          dasp::peers::LccpConfig lccp;
          lccp.seed_resolution_m = seed_resolution;
          lccp.single_camera_transform = lccp_single_camera;
          dasp::BoundaryCounts total;
          std::vector<Times> times;
          std::vector<double> frame_f1;
          nlohmann::json lccp_counts = nlohmann::json::array();
          double supervoxels = 0.0, segment_count = 0.0;
          for (const dasp::RgbdFramePaths& f : frames) {
            const dasp::RgbdFrame frame = dasp::loadRgbdFrame(f);
            const cv::Mat truth = *dasp::loadLabelImage(f);
            const cv::Mat mask = evaluationMask(frame, truth);
            int supervoxel_count = 0;
            const double t0 = threadCpuMilliseconds();
            const cv::Mat labels = dasp::peers::computeLccp(frame, lccp, &supervoxel_count);
            Times t;
            t.superpixels = threadCpuMilliseconds() - t0;
            times.push_back(t);
            supervoxels += supervoxel_count;
            segment_count += static_cast<double>(dasp::metrics::countSegments(labels, mask));
            // The curve of a single segmentation: every pixel boundary at level 0.
            dasp::WeightedGraph none;  // labels are compact: 0..n-1
            none.node_count = static_cast<int>(dasp::metrics::countSegments(labels, cv::Mat()));
            const cv::Mat ucm = dasp::ultrametricContourMap(labels, none, mask);
            const dasp::BoundaryCounts c = dasp::boundaryCurve(ucm, truth, mask, {0.0f}).front();
            total += c;
            frame_f1.push_back(c.f1());
            lccp_counts.push_back(countsJson(c));
          }
          nlohmann::ordered_json r;
          r["method"] = "LCCP";
          r["lccp_seed_resolution_m"] = seed_resolution;
          r["lccp_single_camera_transform"] = lccp_single_camera;
          r["mean_supervoxels"] = supervoxels / frames.size();
          r["mean_segments_in_mask"] = segment_count / frames.size();
          r["ods"] = {
              {"precision", total.precision()}, {"recall", total.recall()}, {"f1", total.f1()}};
          double mean_f1 = 0.0, mean_ms = 0.0;
          for (double v : frame_f1) mean_f1 += v / frame_f1.size();
          for (const Times& t : times) mean_ms += t.superpixels / times.size();
          r["mean_frame_f1"] = mean_f1;
          r["time_ms"] = {{"segmentation_total", mean_ms}};
          r["frame_best_f1"] = frame_f1;
          if (per_frame) r["frame_counts"] = lccp_counts;
          std::cout << "LCCP seed " << seed_resolution << " m: F1 " << std::setprecision(4)
                    << total.f1() << " (P " << total.precision() << ", R " << total.recall()
                    << "), " << std::setprecision(1) << std::fixed << mean_ms << " ms/frame, "
                    << supervoxels / frames.size() << " supervoxels" << std::defaultfloat << "\n";
          out["results"].push_back(r);
        }
        continue;
      }
      const std::string kind = method == "sDASP"   ? "DASP"
                               : method == "sSLIC" ? "ASP_RGB"
                               : method == "sSLICvalid"
                                   ? "ASP_RGB_VALID"
                                   : throw std::invalid_argument("unknown method " + method);
      std::vector<Curve> curves(grid.size());
      std::vector<std::vector<Times>> times(grid.size());
      std::vector<std::vector<double>> frame_f1(grid.size());
      std::vector<nlohmann::json> curve_counts(grid.size(), nlohmann::json::array());
      std::vector<nlohmann::json> adaptive_counts(grid.size(), nlohmann::json::array());
      std::vector<nlohmann::json> adaptive_thresholds(grid.size(), nlohmann::json::array());
      std::vector<std::vector<dasp::BoundaryCounts>> adaptive_total(
          grid.size(), std::vector<dasp::BoundaryCounts>(adaptive.size()));
      double superpixel_total = 0.0;
      for (const dasp::RgbdFramePaths& f : frames) {
        const dasp::RgbdFrame frame = dasp::loadRgbdFrame(f);
        const cv::Mat truth = *dasp::loadLabelImage(f);
        const cv::Mat mask = evaluationMask(frame, truth);
        double t0 = threadCpuMilliseconds();
        const dasp::Superpixels sp = computeSuperpixels(kind, frame, count, seed);
        const double t_superpixels = threadCpuMilliseconds() - t0;
        superpixel_total += static_cast<double>(sp.superpixels.size());
        for (std::size_t g = 0; g < grid.size(); ++g) {
          Times t;
          t.superpixels = t_superpixels;
          t0 = threadCpuMilliseconds();
          dasp::WeightedGraph ucg = dasp::buildSuperpixelGraph(sp, grid[g].graph);
          t.graph = threadCpuMilliseconds() - t0;
          t0 = threadCpuMilliseconds();
          const std::vector<float> global = dasp::globalizeEdgeWeights(ucg, grid[g].spectral);
          for (std::size_t e = 0; e < global.size(); ++e) ucg.edges[e].weight = global[e];
          t.eigen = threadCpuMilliseconds() - t0;
          t0 = threadCpuMilliseconds();
          const float cut = dasp::cutThreshold(ucg, grid[g]);
          const cv::Mat segments = dasp::segmentPixels(sp.labels, dasp::segmentGraph(ucg, cut));
          t.labelling = threadCpuMilliseconds() - t0;
          (void)segments;
          t0 = threadCpuMilliseconds();
          const cv::Mat ucm = dasp::ultrametricContourMap(sp.labels, ucg, mask);
          t.ucm = threadCpuMilliseconds() - t0;
          const std::vector<dasp::BoundaryCounts> frame_curve =
              dasp::boundaryCurve(ucm, truth, mask, thresholds);
          curves[g].thresholds = thresholds;
          curves[g].add(frame_curve);
          std::vector<float> frame_cuts;
          for (const AdaptiveSetting& a : adaptive) {
            frame_cuts.push_back(dasp::adaptiveCutThreshold(ucg, a.scale, a.quantile, a.cap));
          }
          const std::vector<dasp::BoundaryCounts> cut_counts =
              dasp::boundaryCurve(ucm, truth, mask, frame_cuts);
          nlohmann::json frame_adaptive = nlohmann::json::array();
          for (std::size_t a = 0; a < adaptive.size(); ++a) {
            adaptive_total[g][a] += cut_counts[a];
            frame_adaptive.push_back(countsJson(cut_counts[a]));
          }
          if (per_frame) {
            nlohmann::json frame_points = nlohmann::json::array();
            for (const dasp::BoundaryCounts& c : frame_curve) frame_points.push_back(countsJson(c));
            curve_counts[g].push_back(frame_points);
            adaptive_counts[g].push_back(frame_adaptive);
            adaptive_thresholds[g].push_back(frame_cuts);
          }
          double best = 0.0;
          for (const auto& c : frame_curve) best = std::max(best, c.f1());
          frame_f1[g].push_back(best);
          times[g].push_back(t);
        }
      }
      for (std::size_t g = 0; g < grid.size(); ++g) {
        nlohmann::ordered_json r;
        r["method"] = method;
        r["superpixels"] = kind;
        r["mean_superpixels"] = superpixel_total / frames.size();
        r["weight_color"] = grid[g].graph.weight_color;
        r["weight_position"] = grid[g].graph.weight_position;
        r["weight_normal"] = grid[g].graph.weight_normal;
        r["theta"] = grid[g].graph.min_border_pairs;
        r["eigenvectors"] = grid[g].spectral.eigenvector_count;
        const nlohmann::ordered_json c = curveJson(curves[g], times[g], frame_f1[g]);
        for (const auto& [key, value] : c.items()) r[key] = value;
        nlohmann::ordered_json cuts = nlohmann::ordered_json::array();
        std::size_t best_adaptive = 0;
        for (std::size_t a = 0; a < adaptive.size(); ++a) {
          const dasp::BoundaryCounts& c = adaptive_total[g][a];
          cuts.push_back({{"scale", adaptive[a].scale},
                          {"quantile", adaptive[a].quantile},
                          {"max_threshold", adaptive[a].cap},
                          {"precision", c.precision()},
                          {"recall", c.recall()},
                          {"f1", c.f1()}});
          if (c.f1() > adaptive_total[g][best_adaptive].f1()) best_adaptive = a;
        }
        r["adaptive"] = cuts;
        if (per_frame) {
          r["frame_counts"] = curve_counts[g];
          r["adaptive_frame_counts"] = adaptive_counts[g];
          r["adaptive_frame_thresholds"] = adaptive_thresholds[g];
        }
        std::cout << std::defaultfloat << std::setprecision(4) << method << " c "
                  << grid[g].graph.weight_color << " v " << grid[g].graph.weight_position << " n "
                  << grid[g].graph.weight_normal << " k " << grid[g].spectral.eigenvector_count
                  << " theta " << grid[g].graph.min_border_pairs << ": ODS F1 "
                  << std::setprecision(4) << r["ods"]["f1"].get<double>()
                  << " at t = " << r["ods"]["threshold"].get<double>() << ", OIS F1 "
                  << r["ois"]["f1"].get<double>() << ", adaptive cut F1 "
                  << adaptive_total[g][best_adaptive].f1() << " (scale "
                  << adaptive[best_adaptive].scale << ", q " << adaptive[best_adaptive].quantile
                  << ", max " << adaptive[best_adaptive].cap << "), " << std::setprecision(1)
                  << std::fixed << r["time_ms"]["segmentation_total"].get<double>() << " ms/frame"
                  << std::defaultfloat << "\n";
        out["results"].push_back(r);
      }
    }
    std::ofstream file(json_path);
    if (!file) throw std::runtime_error("cannot write " + json_path);
    file << out.dump(1) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "dasp_sdasp: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
