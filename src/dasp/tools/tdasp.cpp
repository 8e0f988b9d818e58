// dasp_tdasp: t-DASP video segmentation over labelled RGB-D sequences (folders written by
// dasp_render_sequence: frame<k>_{rgb,depth_mm,label_object}.png and poses.txt), compared with
// s-DASP run independently on every frame with the same superpixel, graph, spectral and
// threshold parameters (threshold = the hysteresis' t_normal, which is also what t-DASP applies
// to strands without history).
//
// Per frame and method: superpixel metrics (count, boundary recall, ASA, undersegmentation error)
// and segment metrics (count, boundary precision/recall/F1 and ASA against the warped human
// labels), and the temporal label consistency to the next frame: the share of valid pixels of
// frame t whose label is found again at the same surface point in frame t+1, the pixels warped
// with frame t's depth and the known relative pose. t-DASP labels are compared as they are
// ("identity"); independent s-DASP labels have no relation between frames, so they are first
// matched one-to-one by largest overlap ("best overlap", also reported for t-DASP). The ground
// truth's own consistency under the same warp is the ceiling.
// Writes <out>/<sequence>.csv (one row per frame and method) and <out>/<sequence>.json (means).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "dasp/delta_density.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/metrics.h"
#include "dasp/rgbd_io.h"
#include "dasp/sampling.h"
#include "dasp/sdasp.h"
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"
#include "dasp/tdasp.h"
#include "dasp/temporal_metrics.h"

namespace {

namespace fs = std::filesystem;

std::vector<Eigen::Isometry3f> readPoses(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::vector<Eigen::Isometry3f> poses;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    int k;
    float tx, ty, tz, qx, qy, qz, qw;
    if (!(f >> k >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) continue;
    if (k != static_cast<int>(poses.size())) throw std::runtime_error("poses.txt out of order");
    Eigen::Isometry3f p = Eigen::Isometry3f::Identity();
    p.linear() = Eigen::Quaternionf(qw, qx, qy, qz).normalized().toRotationMatrix();
    p.translation() = Eigen::Vector3f(tx, ty, tz);
    poses.push_back(p);
  }
  return poses;
}

struct FrameResult {
  std::map<std::string, double> values;
  cv::Mat segments;  // pixel segment labels
};

void addPartitionMetrics(std::map<std::string, double>& v, const std::string& prefix,
                         const cv::Mat& labels, const cv::Mat& truth, const cv::Mat& mask) {
  const auto b = dasp::metrics::boundaryScores(labels, truth, mask);
  v[prefix + "count"] = static_cast<double>(dasp::metrics::countSegments(labels, mask));
  v[prefix + "boundary_recall"] = b.recall;
  v[prefix + "boundary_precision"] = b.precision;
  v[prefix + "boundary_f1"] = b.f1;
  v[prefix + "asa"] = dasp::metrics::achievableSegmentationAccuracy(labels, truth, mask);
}

// Random colour per label (stable over frames for a label).
cv::Mat colourise(const cv::Mat& labels) {
  cv::Mat out(labels.size(), CV_8UC3);
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<int>(y, x);
      const unsigned h = static_cast<unsigned>(l) * 2654435761u;
      out.at<cv::Vec3b>(y, x) =
          l < 0 ? cv::Vec3b(0, 0, 0)
                : cv::Vec3b(64 + (h & 0x7f), 64 + ((h >> 8) & 0x7f), 64 + ((h >> 16) & 0x7f));
    }
  }
  return out;
}

// Share of points that Delta Density Sampling removes or adds when the density did not change
// (the points are an SPDS sample of the same density), per smoothing radius; 5 sampler seeds.
nlohmann::json ddsChurn(const dasp::RgbdFrame& frame, const dasp::DaspConfig& dasp_config) {
  const dasp::PixelFeatures features = dasp::computeFeatures(frame, dasp_config);
  const cv::Mat density = dasp::computeDepthDensity(
      features, dasp::daspRadius(features, dasp_config), dasp_config.experimental.depth_exponent);
  nlohmann::json out = nlohmann::json::object();
  for (const float smoothing : {0.0f, 0.5f, 1.0f, 2.0f, 3.0f}) {
    double churn = 0.0;
    const int runs = 5;
    for (int run = 0; run < runs; ++run) {
      const auto points = dasp::sampleSpds(density, true, 1000 + run);
      dasp::DeltaDensityConfig c;
      c.smoothing_radius_multiple = smoothing;
      const auto r = dasp::deltaDensitySampling(density, points, c, 2000 + run);
      churn += static_cast<double>(r.added + r.removed_by_density + r.removed_invalid) /
               static_cast<double>(points.size()) / runs;
    }
    std::ostringstream key;
    key << smoothing;
    out[key.str()] = churn;
  }
  return out;
}

// t-DASP on the next frame of its sequence.
FrameResult runTdasp(dasp::TemporalDasp& tdasp, const dasp::RgbdFrame& frame, const cv::Mat& truth,
                     const cv::Mat& mask) {
  FrameResult t;
  const auto t_frame = tdasp.process(frame);
  t.segments = t_frame.segment_labels;
  t.values["time_ms"] = t_frame.timings.total_ms;
  t.values["superpixel_ms"] = t_frame.timings.superpixels_ms;
  t.values["graph_ms"] = t_frame.timings.graph_ms;
  t.values["spectral_ms"] = t_frame.timings.spectral_ms;
  t.values["labelling_ms"] = t_frame.timings.labelling_ms;
  t.values["strands"] = t_frame.strand_count;
  t.values["strand_edges"] = t_frame.strand_edge_count;
  t.values["seeds_kept"] = t_frame.superpixels.seeds_kept;
  t.values["seeds_added"] = t_frame.superpixels.seeds_added;
  t.values["seeds_removed"] = t_frame.superpixels.seeds_removed;
  t.values["strands_continued"] = tdasp.strandGraph().continuedLastFrame();
  addPartitionMetrics(t.values, "sp_", t_frame.superpixels.superpixels.labels, truth, mask);
  addPartitionMetrics(t.values, "seg_", t.segments, truth, mask);
  return t;
}

// s-DASP on one frame with t-DASP's parameters (threshold = the hysteresis' t_normal).
FrameResult runSdasp(const dasp::TdaspConfig& config, const dasp::RgbdFrame& frame,
                     const cv::Mat& truth, const cv::Mat& mask) {
  FrameResult s;
  const auto start = std::chrono::steady_clock::now();
  const dasp::Superpixels sp = dasp::computeDasp(frame, config.superpixels.dasp);
  dasp::SdaspConfig sdasp_config;
  sdasp_config.graph = config.strands.graph;
  sdasp_config.spectral = config.spectral;
  sdasp_config.threshold = config.hysteresis.normal;
  const dasp::WeightedGraph ucg = dasp::ultrametricContourGraph(sp, sdasp_config);
  s.segments = dasp::segmentPixels(sp.labels, dasp::segmentGraph(ucg, sdasp_config.threshold));
  s.values["time_ms"] =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  addPartitionMetrics(s.values, "sp_", sp.labels, truth, mask);
  addPartitionMetrics(s.values, "seg_", s.segments, truth, mask);
  return s;
}

// A sequence's frames as the metrics need them.
struct SequenceFrames {
  std::vector<cv::Mat> depths, truths, masks;
  std::vector<Eigen::Isometry3f> poses;
};

// Temporal consistency of frame k to k+1, for both methods and the ground truth.
void addConsistency(const SequenceFrames& seq, const dasp::Intrinsics& intrinsics,
                    std::vector<FrameResult>& t_results, std::vector<FrameResult>& s_results) {
  using dasp::metrics::LabelMatching;
  for (std::size_t k = 0; k + 1 < seq.depths.size(); ++k) {
    const Eigen::Isometry3f next_from_current = seq.poses[k + 1].inverse() * seq.poses[k];
    auto consistency = [&](const cv::Mat& a, const cv::Mat& b, LabelMatching m) {
      // Only pixels with a ground-truth label are compared (the evaluation mask).
      cv::Mat a_masked = a.clone(), b_masked = b.clone();
      a_masked.setTo(-1, seq.masks[k] == 0);
      b_masked.setTo(-1, seq.masks[k + 1] == 0);
      return dasp::metrics::temporalLabelConsistency(a_masked, seq.depths[k], b_masked,
                                                     seq.depths[k + 1], intrinsics,
                                                     next_from_current, m)
          .consistency;
    };
    for (std::vector<FrameResult>* results : {&t_results, &s_results}) {
      FrameResult& r = (*results)[k];
      const cv::Mat& next = (*results)[k + 1].segments;
      r.values["consistency_identity"] = consistency(r.segments, next, LabelMatching::kIdentity);
      r.values["consistency_best_overlap"] =
          consistency(r.segments, next, LabelMatching::kBestOverlap);
    }
    const double truth_consistency =
        consistency(seq.truths[k], seq.truths[k + 1], LabelMatching::kIdentity);
    t_results[k].values["consistency_truth"] = truth_consistency;
    s_results[k].values["consistency_truth"] = truth_consistency;
  }
}

// <out>/<name>.csv (a row per frame and method); the means go into `summary` under the
// methods' names.
void writeResults(const fs::path& out_dir, const std::string& name,
                  const std::vector<FrameResult>& t_results,
                  const std::vector<FrameResult>& s_results, nlohmann::json& summary) {
  std::ofstream csv(out_dir / (name + ".csv"));
  std::vector<std::string> keys;
  for (const auto& r : {t_results, s_results}) {
    for (const auto& fr : r) {
      for (const auto& [key, value] : fr.values) {
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  csv << "sequence,method,frame";
  for (const auto& key : keys) csv << ',' << key;
  csv << '\n';
  for (const auto& [method, results] :
       {std::pair<std::string, const std::vector<FrameResult>*>{"tdasp", &t_results},
        {"sdasp", &s_results}}) {
    std::map<std::string, std::pair<double, int>> sums;
    for (std::size_t k = 0; k < results->size(); ++k) {
      const auto& values = (*results)[k].values;
      csv << name << ',' << method << ',' << k;
      for (const auto& key : keys) {
        const auto it = values.find(key);
        csv << ',';
        if (it != values.end()) {
          csv << std::setprecision(8) << it->second;
          sums[key].first += it->second;
          ++sums[key].second;
        }
      }
      csv << '\n';
    }
    for (const auto& [key, sum] : sums) summary[method][key] = sum.first / sum.second;
  }
}

void printSummary(const std::string& name, const nlohmann::json& summary) {
  std::cout << std::fixed << std::setprecision(3) << name << ": consistency t-DASP identity "
            << summary["tdasp"]["consistency_identity"].get<double>() << " (best overlap "
            << summary["tdasp"]["consistency_best_overlap"].get<double>()
            << "), s-DASP best overlap "
            << summary["sdasp"]["consistency_best_overlap"].get<double>() << ", truth "
            << summary["tdasp"]["consistency_truth"].get<double>() << "; segment F1 t-DASP "
            << summary["tdasp"]["seg_boundary_f1"].get<double>() << " s-DASP "
            << summary["sdasp"]["seg_boundary_f1"].get<double>() << "; segments t-DASP "
            << summary["tdasp"]["seg_count"].get<double>() << " s-DASP "
            << summary["sdasp"]["seg_count"].get<double>() << "; ms/frame t-DASP "
            << summary["tdasp"]["time_ms"].get<double>() << " s-DASP "
            << summary["sdasp"]["time_ms"].get<double>() << '\n';
}

// One sequence folder: both methods on every frame, the metrics, <out>/<name>.{csv,json}.
void evaluateSequence(const std::string& folder, const dasp::TdaspConfig& config,
                      const fs::path& out_dir, const std::string& image_dir) {
  const dasp::Intrinsics intrinsics;
  const std::string name = fs::path(folder).filename().string();
  const auto frames = dasp::listRgbdFolder(folder);
  SequenceFrames seq;
  seq.poses = readPoses(fs::path(folder) / "poses.txt");
  if (frames.size() != seq.poses.size() || frames.empty()) {
    throw std::runtime_error(folder + ": frame and pose counts differ");
  }
  dasp::TemporalDasp tdasp(config);
  const nlohmann::json churn =
      ddsChurn(dasp::loadRgbdFrame(frames.front(), intrinsics), config.superpixels.dasp);
  std::vector<FrameResult> t_results, s_results;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(frames[k], intrinsics);
    const cv::Mat truth = *dasp::loadLabelImage(frames[k]);
    const cv::Mat mask = (truth > 0) & (frame.depth > 0);
    seq.depths.push_back(frame.depth);
    seq.truths.push_back(truth);
    seq.masks.push_back(mask);
    t_results.push_back(runTdasp(tdasp, frame, truth, mask));
    s_results.push_back(runSdasp(config, frame, truth, mask));
    if (!image_dir.empty()) {
      fs::create_directories(fs::path(image_dir) / name);
      const std::string base = (fs::path(image_dir) / name / frames[k].name).string();
      cv::imwrite(base + "_tdasp.png", colourise(t_results.back().segments));
      cv::imwrite(base + "_sdasp.png", colourise(s_results.back().segments));
    }
  }
  addConsistency(seq, intrinsics, t_results, s_results);
  nlohmann::json summary;
  summary["sequence"] = name;
  summary["frames"] = frames.size();
  summary["superpixels"] = config.superpixels.dasp.superpixel_count;
  summary["seed"] = config.superpixels.dasp.seed;
  summary["dds_churn_static"] = churn;
  writeResults(out_dir, name, t_results, s_results, summary);
  std::ofstream(out_dir / (name + ".json")) << summary.dump(2) << '\n';
  printSummary(name, summary);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"t-DASP over labelled RGB-D sequences, compared with independent s-DASP"};
  std::vector<std::string> sequences;
  std::string out_dir = "tdasp_eval";
  std::string image_dir;
  dasp::TdaspConfig config;
  int superpixel_count = config.superpixels.dasp.superpixel_count;
  std::uint64_t seed = 0;
  app.add_option("sequences", sequences, "sequence folders (dasp_render_sequence output)")
      ->required();
  app.add_option("--out", out_dir, "output folder for CSV/JSON")->capture_default_str();
  app.add_option("--images", image_dir, "also write segment pictures of every frame here");
  app.add_option("-k,--superpixels", superpixel_count, "superpixels per frame")
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the superpixel sampling")->capture_default_str();
  app.add_option("--max-strands", config.strands.max_strands, "strands kept in the graph")
      ->capture_default_str();
  app.add_option("--t-force", config.hysteresis.force)->capture_default_str();
  app.add_option("--t-normal", config.hysteresis.normal, "also the s-DASP threshold")
      ->capture_default_str();
  app.add_option("--t-grant", config.hysteresis.grant)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    config.superpixels.dasp.superpixel_count = superpixel_count;
    config.superpixels.dasp.seed = seed;
    fs::create_directories(out_dir);
    for (const std::string& folder : sequences) {
      evaluateSequence(folder, config, out_dir, image_dir);
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
