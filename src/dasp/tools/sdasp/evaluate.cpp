#include "sdasp/evaluate.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dasp/metrics.h"
#include "dasp/rgbd_io.h"
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"
#include "peers/lccp.h"
#include "sdasp/common.h"

namespace sdasp_tool {
namespace {

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
  std::vector<dasp::metrics::BoundaryCounts> total;  // summed over frames (ODS)
  dasp::metrics::BoundaryCounts ois_total;           // counts at every frame's own best threshold
  double mean_best_f1 = 0.0;                         // mean over frames of the best F1 of the frame
  int frames = 0;

  void add(const std::vector<dasp::metrics::BoundaryCounts>& frame_curve) {
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

nlohmann::json countsJson(const dasp::metrics::BoundaryCounts& c) {
  return {c.partition_pixels, c.precise_pixels, c.reference_pixels, c.recalled_pixels};
}

struct Times {
  double superpixels = 0.0, graph = 0.0, eigen = 0.0, labelling = 0.0, ucm = 0.0;
};

nlohmann::ordered_json curveJson(const Curve& curve, const std::vector<Times>& times,
                                 const std::vector<double>& frame_best_f1) {
  nlohmann::ordered_json j;
  const std::size_t ods = curve.odsIndex();
  const dasp::metrics::BoundaryCounts& o = curve.total[ods];
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

// Labelled frames of the folder (the first max_frames if > 0).
std::vector<dasp::RgbdFramePaths> labelledFrames(const std::string& folder, int max_frames) {
  std::vector<dasp::RgbdFramePaths> frames = dasp::listRgbdFolder(folder);
  frames.erase(std::remove_if(frames.begin(), frames.end(),
                              [](const dasp::RgbdFramePaths& f) { return f.label.empty(); }),
               frames.end());
  if (max_frames > 0 && static_cast<int>(frames.size()) > max_frames) frames.resize(max_frames);
  if (frames.empty()) throw std::invalid_argument("no frames with labels in " + folder);
  return frames;
}

// threshold_count thresholds evenly spaced in [0, 1], and one just above 1 that merges
// everything but the never-joined boundaries.
std::vector<float> curveThresholds(int threshold_count) {
  if (threshold_count < 2) throw std::invalid_argument("--thresholds must be >= 2");
  std::vector<float> thresholds(static_cast<std::size_t>(threshold_count));
  for (int i = 0; i < threshold_count; ++i) {
    thresholds[i] = static_cast<float>(i) / static_cast<float>(threshold_count - 1);
  }
  thresholds.push_back(std::nextafter(1.0f, 2.0f));
  return thresholds;
}

// The graph and spectral settings of the grid, each a copy of `config`.
std::vector<dasp::SdaspConfig> settingsGrid(const dasp::SdaspConfig& config,
                                            const EvaluateOptions& o) {
  std::vector<dasp::SdaspConfig> grid;
  for (float c : parseList<float>(o.color_weights)) {
    for (float v : parseList<float>(o.position_weights)) {
      for (float n : parseList<float>(o.normal_weights)) {
        for (int k : parseList<int>(o.eigen_counts)) {
          for (int theta : parseList<int>(o.thetas)) {
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
  return grid;
}

struct AdaptiveSetting {
  float scale, quantile, cap;
};

std::vector<AdaptiveSetting> adaptiveGrid(const EvaluateOptions& o) {
  std::vector<AdaptiveSetting> adaptive;
  for (float sc : parseList<float>(o.adaptive_scales)) {
    for (float q : parseList<float>(o.adaptive_quantiles)) {
      for (float cap : parseList<float>(o.adaptive_caps)) adaptive.push_back({sc, q, cap});
    }
  }
  return adaptive;
}

// LCCP at one seed resolution over the frames: a single segmentation per frame, scored as every
// pixel boundary at level 0.
nlohmann::ordered_json evaluateLccp(const std::vector<dasp::RgbdFramePaths>& frames,
                                    float seed_resolution, const EvaluateOptions& o) {
  dasp::peers::LccpConfig lccp;
  lccp.seed_resolution_m = seed_resolution;
  lccp.single_camera_transform = o.lccp_single_camera;
  dasp::metrics::BoundaryCounts total;
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
    dasp::WeightedGraph none;  // labels are compact: 0..n-1
    none.node_count = static_cast<int>(dasp::metrics::countSegments(labels, cv::Mat()));
    const cv::Mat ucm = dasp::ultrametricContourMap(labels, none, mask);
    const dasp::metrics::BoundaryCounts c =
        dasp::metrics::boundaryCurve(ucm, truth, mask, {0.0f}).front();
    total += c;
    frame_f1.push_back(c.f1());
    lccp_counts.push_back(countsJson(c));
  }
  nlohmann::ordered_json r;
  r["method"] = "LCCP";
  r["lccp_seed_resolution_m"] = seed_resolution;
  r["lccp_single_camera_transform"] = o.lccp_single_camera;
  r["mean_supervoxels"] = supervoxels / frames.size();
  r["mean_segments_in_mask"] = segment_count / frames.size();
  r["ods"] = {{"precision", total.precision()}, {"recall", total.recall()}, {"f1", total.f1()}};
  double mean_f1 = 0.0, mean_ms = 0.0;
  for (double v : frame_f1) mean_f1 += v / frame_f1.size();
  for (const Times& t : times) mean_ms += t.superpixels / times.size();
  r["mean_frame_f1"] = mean_f1;
  r["time_ms"] = {{"segmentation_total", mean_ms}};
  r["frame_best_f1"] = frame_f1;
  if (o.per_frame) r["frame_counts"] = lccp_counts;
  std::cout << "LCCP seed " << seed_resolution << " m: F1 " << std::setprecision(4) << total.f1()
            << " (P " << total.precision() << ", R " << total.recall() << "), "
            << std::setprecision(1) << std::fixed << mean_ms << " ms/frame, "
            << supervoxels / frames.size() << " supervoxels" << std::defaultfloat << "\n";
  return r;
}

// The spectral segmentation of one grid setting, accumulated over the frames.
struct SettingScores {
  Curve curve;
  std::vector<Times> times;
  std::vector<double> frame_f1;
  nlohmann::json curve_counts = nlohmann::json::array();
  nlohmann::json adaptive_counts = nlohmann::json::array();
  nlohmann::json adaptive_thresholds = nlohmann::json::array();
  std::vector<dasp::metrics::BoundaryCounts> adaptive_total;
};

// One frame's superpixels under one setting: graph, eigenvectors, cut and UCM (timed), its
// boundary curve and the adaptive cuts' counts.
void scoreFrame(const dasp::Superpixels& sp, double t_superpixels, const cv::Mat& truth,
                const cv::Mat& mask, const dasp::SdaspConfig& setting,
                const std::vector<float>& thresholds, const std::vector<AdaptiveSetting>& adaptive,
                bool per_frame, SettingScores& scores) {
  Times t;
  t.superpixels = t_superpixels;
  double t0 = threadCpuMilliseconds();
  dasp::WeightedGraph ucg = dasp::buildSuperpixelGraph(sp, setting.graph);
  t.graph = threadCpuMilliseconds() - t0;
  t0 = threadCpuMilliseconds();
  const std::vector<float> global = dasp::globalizeEdgeWeights(ucg, setting.spectral);
  for (std::size_t e = 0; e < global.size(); ++e) ucg.edges[e].weight = global[e];
  t.eigen = threadCpuMilliseconds() - t0;
  t0 = threadCpuMilliseconds();
  const float cut = dasp::cutThreshold(ucg, setting);
  const cv::Mat segments = dasp::segmentPixels(sp.labels, dasp::segmentGraph(ucg, cut));
  t.labelling = threadCpuMilliseconds() - t0;
  (void)segments;
  t0 = threadCpuMilliseconds();
  const cv::Mat ucm = dasp::ultrametricContourMap(sp.labels, ucg, mask);
  t.ucm = threadCpuMilliseconds() - t0;
  const std::vector<dasp::metrics::BoundaryCounts> frame_curve =
      dasp::metrics::boundaryCurve(ucm, truth, mask, thresholds);
  scores.curve.thresholds = thresholds;
  scores.curve.add(frame_curve);
  std::vector<float> frame_cuts;
  for (const AdaptiveSetting& a : adaptive) {
    frame_cuts.push_back(dasp::adaptiveCutThreshold(ucg, a.scale, a.quantile, a.cap));
  }
  const std::vector<dasp::metrics::BoundaryCounts> cut_counts =
      dasp::metrics::boundaryCurve(ucm, truth, mask, frame_cuts);
  nlohmann::json frame_adaptive = nlohmann::json::array();
  scores.adaptive_total.resize(adaptive.size());
  for (std::size_t a = 0; a < adaptive.size(); ++a) {
    scores.adaptive_total[a] += cut_counts[a];
    frame_adaptive.push_back(countsJson(cut_counts[a]));
  }
  if (per_frame) {
    nlohmann::json frame_points = nlohmann::json::array();
    for (const dasp::metrics::BoundaryCounts& c : frame_curve)
      frame_points.push_back(countsJson(c));
    scores.curve_counts.push_back(frame_points);
    scores.adaptive_counts.push_back(frame_adaptive);
    scores.adaptive_thresholds.push_back(frame_cuts);
  }
  double best = 0.0;
  for (const auto& c : frame_curve) best = std::max(best, c.f1());
  scores.frame_f1.push_back(best);
  scores.times.push_back(t);
}

// The JSON result of one setting (and its console line).
nlohmann::ordered_json settingResult(const std::string& method, const std::string& kind,
                                     double mean_superpixels, const dasp::SdaspConfig& setting,
                                     const SettingScores& s,
                                     const std::vector<AdaptiveSetting>& adaptive, bool per_frame) {
  nlohmann::ordered_json r;
  r["method"] = method;
  r["superpixels"] = kind;
  r["mean_superpixels"] = mean_superpixels;
  r["weight_color"] = setting.graph.weight_color;
  r["weight_position"] = setting.graph.weight_position;
  r["weight_normal"] = setting.graph.weight_normal;
  r["theta"] = setting.graph.min_border_pairs;
  r["eigenvectors"] = setting.spectral.eigenvector_count;
  const nlohmann::ordered_json c = curveJson(s.curve, s.times, s.frame_f1);
  for (const auto& [key, value] : c.items()) r[key] = value;
  nlohmann::ordered_json cuts = nlohmann::ordered_json::array();
  std::size_t best_adaptive = 0;
  for (std::size_t a = 0; a < adaptive.size(); ++a) {
    const dasp::metrics::BoundaryCounts& counts = s.adaptive_total[a];
    cuts.push_back({{"scale", adaptive[a].scale},
                    {"quantile", adaptive[a].quantile},
                    {"max_threshold", adaptive[a].cap},
                    {"precision", counts.precision()},
                    {"recall", counts.recall()},
                    {"f1", counts.f1()}});
    if (counts.f1() > s.adaptive_total[best_adaptive].f1()) best_adaptive = a;
  }
  r["adaptive"] = cuts;
  if (per_frame) {
    r["frame_counts"] = s.curve_counts;
    r["adaptive_frame_counts"] = s.adaptive_counts;
    r["adaptive_frame_thresholds"] = s.adaptive_thresholds;
  }
  std::cout << std::defaultfloat << std::setprecision(4) << method << " c "
            << setting.graph.weight_color << " v " << setting.graph.weight_position << " n "
            << setting.graph.weight_normal << " k " << setting.spectral.eigenvector_count
            << " theta " << setting.graph.min_border_pairs << ": ODS F1 " << std::setprecision(4)
            << r["ods"]["f1"].get<double>() << " at t = " << r["ods"]["threshold"].get<double>()
            << ", OIS F1 " << r["ois"]["f1"].get<double>() << ", adaptive cut F1 "
            << s.adaptive_total[best_adaptive].f1() << " (scale " << adaptive[best_adaptive].scale
            << ", q " << adaptive[best_adaptive].quantile << ", max " << adaptive[best_adaptive].cap
            << "), " << std::setprecision(1) << std::fixed
            << r["time_ms"]["segmentation_total"].get<double>() << " ms/frame" << std::defaultfloat
            << "\n";
  return r;
}

// A spectral method (sDASP, sSLIC, sSLICvalid) over the frames, every grid setting on the same
// superpixels of a frame: one result per setting.
std::vector<nlohmann::ordered_json> evaluateSpectral(
    const std::string& method, const std::vector<dasp::RgbdFramePaths>& frames,
    const std::vector<dasp::SdaspConfig>& grid, const std::vector<AdaptiveSetting>& adaptive,
    const std::vector<float>& thresholds, int count, std::uint64_t seed, bool per_frame) {
  const std::string kind = method == "sDASP"   ? "DASP"
                           : method == "sSLIC" ? "ASP_RGB"
                           : method == "sSLICvalid"
                               ? "ASP_RGB_VALID"
                               : throw std::invalid_argument("unknown method " + method);
  std::vector<SettingScores> scores(grid.size());
  for (SettingScores& s : scores) s.adaptive_total.resize(adaptive.size());
  double superpixel_total = 0.0;
  for (const dasp::RgbdFramePaths& f : frames) {
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(f);
    const cv::Mat truth = *dasp::loadLabelImage(f);
    const cv::Mat mask = evaluationMask(frame, truth);
    const double t0 = threadCpuMilliseconds();
    const dasp::Superpixels sp = computeSuperpixels(kind, frame, count, seed);
    const double t_superpixels = threadCpuMilliseconds() - t0;
    superpixel_total += static_cast<double>(sp.superpixels.size());
    for (std::size_t g = 0; g < grid.size(); ++g) {
      scoreFrame(sp, t_superpixels, truth, mask, grid[g], thresholds, adaptive, per_frame,
                 scores[g]);
    }
  }
  std::vector<nlohmann::ordered_json> results;
  for (std::size_t g = 0; g < grid.size(); ++g) {
    results.push_back(settingResult(method, kind, superpixel_total / frames.size(), grid[g],
                                    scores[g], adaptive, per_frame));
  }
  return results;
}

}  // namespace

int runEvaluate(const EvaluateOptions& o, const dasp::SdaspConfig& config, int count,
                std::uint64_t seed) {
  const std::vector<dasp::RgbdFramePaths> frames = labelledFrames(o.folder, o.max_frames);
  const std::vector<float> thresholds = curveThresholds(o.threshold_count);
  const std::vector<dasp::SdaspConfig> grid = settingsGrid(config, o);
  const std::vector<AdaptiveSetting> adaptive = adaptiveGrid(o);
  std::vector<std::string> frame_names;
  for (const dasp::RgbdFramePaths& f : frames) frame_names.push_back(f.name);
  const std::vector<std::string> methods = parseList<std::string>(o.methods_text);
  const std::vector<float> seeds = parseList<float>(o.lccp_seeds);

  nlohmann::ordered_json out;
  out["folder"] = o.folder;
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
        out["results"].push_back(evaluateLccp(frames, seed_resolution, o));
      }
      continue;
    }
    for (nlohmann::ordered_json& r :
         evaluateSpectral(method, frames, grid, adaptive, thresholds, count, seed, o.per_frame)) {
      out["results"].push_back(std::move(r));
    }
  }
  std::ofstream file(o.json_path);
  if (!file) throw std::runtime_error("cannot write " + o.json_path);
  file << out.dump(1) << "\n";
  return 0;
}

}  // namespace sdasp_tool
