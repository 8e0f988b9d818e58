// Streaming DASP (thesis §5.2.3, alg. 6) with the seed-origin bookkeeping of eq. 5.9.
#include "dasp/streaming_dasp.h"

#include <algorithm>
#include <stdexcept>

#include "dasp/connectivity.h"
#include "dasp/dalic.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp/superpoints.h"

namespace dasp {
namespace {

// SplitMix64 step: decorrelates the per-frame sampler seeds of one stream.
std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t frame) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (frame + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Seeds of a frame and, per seed, the index of the previous centre it continues (-1 = new): a
// fresh sample on the first frame, Delta Density Sampling from the previous centres after it.
struct FrameSeeds {
  std::vector<Seed> seeds;
  std::vector<int> origin;
};

FrameSeeds sampleFrameSeeds(const cv::Mat& density, const std::vector<Seed>& previous_centres,
                            const StreamingDaspConfig& config, std::uint64_t frame_seed,
                            StreamingDaspFrame& out) {
  FrameSeeds s;
  if (previous_centres.empty()) {
    s.seeds = sampleSeeds(density, config.dasp.seeding, frame_seed);
    s.origin.assign(s.seeds.size(), -1);
    out.seeds_added = static_cast<int>(s.seeds.size());
  } else {
    DeltaDensityResult dds =
        deltaDensitySampling(density, previous_centres, config.delta, frame_seed);
    s.seeds = std::move(dds.points);
    s.origin = std::move(dds.origin);
    out.seeds_added = dds.added;
    out.seeds_removed = dds.removed_by_density + dds.removed_invalid;
    out.seeds_kept = static_cast<int>(s.seeds.size()) - dds.added;
  }
  if (s.seeds.empty()) {  // as computeDasp: one superpixel at the density maximum
    cv::Point max_location;
    cv::minMaxLoc(density, nullptr, nullptr, nullptr, &max_location);
    s.seeds.push_back({static_cast<float>(max_location.x), static_cast<float>(max_location.y)});
    s.origin.push_back(-1);
  }
  return s;
}

// The final labels from DALIC's: connectivity enforced, or only empty labels dropped (dense
// indices), as computeDasp does. Returns the label count.
int finalizeLabels(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& density,
                   const DaspConfig& dc, std::size_t cluster_count) {
  if (dc.enforce_connectivity) {
    return enforceConnectivity(labels, valid, density, dc.min_size_fraction);
  }
  int label_count = 0;
  std::vector<int> renumber(cluster_count, -1);
  for (int row = 0; row < labels.rows; ++row) {
    int* l = labels.ptr<int>(row);
    for (int col = 0; col < labels.cols; ++col) {
      if (l[col] < 0) continue;
      int& mapped = renumber[static_cast<std::size_t>(l[col])];
      if (mapped < 0) mapped = label_count++;
      l[col] = mapped;
    }
  }
  return label_count;
}

// Which cluster each final label came from: the cluster holding most of its pixels
// (connectivity enforcement keeps every cluster's largest piece under a new number). When two
// labels claim one cluster (a detached piece heavy enough to stay), the larger one continues it.
struct LabelOrigins {
  std::vector<int> label_cluster;  // per final label: its cluster, or -1
  std::vector<int> cluster_owner;  // per cluster: the final label that continues it, or -1
};

LabelOrigins labelOrigins(const cv::Mat& labels, const cv::Mat& raw_labels, int label_count,
                          std::size_t cluster_count) {
  std::vector<std::vector<std::pair<int, int>>> votes(static_cast<std::size_t>(label_count));
  // (label * 2^31 + cluster, pixel count) per horizontal run of equal pairs, then summed.
  std::vector<std::pair<long long, int>> runs;
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    const int* r = raw_labels.ptr<int>(row);
    for (int col = 0; col < labels.cols; ++col) {
      if (l[col] < 0 || r[col] < 0) continue;
      const long long key = static_cast<long long>(l[col]) * (1LL << 31) + r[col];
      if (col > 0 && !runs.empty() && runs.back().first == key && l[col - 1] == l[col] &&
          r[col - 1] == r[col]) {
        ++runs.back().second;
      } else {
        runs.push_back({key, 1});
      }
    }
  }
  std::sort(runs.begin(), runs.end());
  for (std::size_t i = 0; i < runs.size();) {
    std::size_t j = i;
    int count = 0;
    while (j < runs.size() && runs[j].first == runs[i].first) count += runs[j++].second;
    const int label = static_cast<int>(runs[i].first >> 31);
    const int cluster = static_cast<int>(runs[i].first & ((1LL << 31) - 1));
    votes[static_cast<std::size_t>(label)].push_back({count, cluster});
    i = j;
  }
  LabelOrigins o;
  o.label_cluster.assign(static_cast<std::size_t>(label_count), -1);
  std::vector<int> label_size(static_cast<std::size_t>(label_count), 0);
  for (int l = 0; l < label_count; ++l) {
    const auto& v = votes[static_cast<std::size_t>(l)];
    if (v.empty()) continue;
    const auto best = std::max_element(v.begin(), v.end());
    o.label_cluster[static_cast<std::size_t>(l)] = best->second;
    label_size[static_cast<std::size_t>(l)] = best->first;
  }
  o.cluster_owner.assign(cluster_count, -1);
  for (int l = 0; l < label_count; ++l) {
    const int c = o.label_cluster[static_cast<std::size_t>(l)];
    if (c < 0) continue;
    int& owner = o.cluster_owner[static_cast<std::size_t>(c)];
    if (owner < 0 ||
        label_size[static_cast<std::size_t>(l)] > label_size[static_cast<std::size_t>(owner)]) {
      owner = l;
    }
  }
  return o;
}

}  // namespace

StreamingDasp::StreamingDasp(const StreamingDaspConfig& config) : config_(config) {
  if (config.delta.sampling == SeedingMethod::kGrid) {
    throw std::invalid_argument("StreamingDasp: delta sampling must not be kGrid");
  }
}

void StreamingDasp::reset() {
  frame_index_ = 0;
  previous_centres_.clear();
  previous_track_ids_.clear();
}

StreamingDaspFrame StreamingDasp::process(const RgbdFrame& frame) {
  const DaspConfig& dc = config_.dasp;
  const PixelFeatures features = computeFeatures(frame, dc);  // validates
  const float radius = daspRadius(features, dc);
  const cv::Mat density = computeDepthDensity(features, radius, dc.experimental.depth_exponent);
  const std::uint64_t frame_seed = mixSeed(dc.seed, static_cast<std::uint64_t>(frame_index_));

  StreamingDaspFrame out;
  out.frame_index = frame_index_;
  const FrameSeeds seeds = sampleFrameSeeds(density, previous_centres_, config_, frame_seed, out);

  const DalicParams params =
      dalicParams(dc, MetricKind::kDepthAdaptive, radius,
                  dc.size_mode == SizeMode::kCount ? dc.superpixel_count : 0);
  Dalic dalic(features, density, params);
  dalic.initialize(seeds.seeds);
  for (int it = 0; it < dc.iterations; ++it) {
    dalic.assign();
    if (it + 1 < dc.iterations) dalic.update();
  }
  const std::vector<Cluster>& clusters = dalic.clusters();  // label k of assign() = cluster k
  const cv::Mat raw_labels = dalic.labels().clone();
  cv::Mat labels = raw_labels.clone();
  const cv::Mat valid(features.height, features.width, CV_8UC1,
                      const_cast<std::uint8_t*>(features.valid.data()));
  const int label_count = finalizeLabels(labels, valid, density, dc, clusters.size());
  const LabelOrigins origins = labelOrigins(labels, raw_labels, label_count, clusters.size());

  out.superpixels.labels = labels;
  out.superpixels.superpixels =
      fitSuperpoints(labels, features, density, radius, dc.experimental.depth_exponent);
  const std::size_t n = out.superpixels.superpixels.size();
  out.predecessor.assign(n, -1);
  out.track_id.assign(n, -1);
  for (std::size_t j = 0; j < n; ++j) {
    const int c = j < origins.label_cluster.size() ? origins.label_cluster[j] : -1;
    if (c >= 0 && origins.cluster_owner[static_cast<std::size_t>(c)] == static_cast<int>(j)) {
      const int seed_index = clusters[static_cast<std::size_t>(c)].origin;
      if (seed_index >= 0) out.predecessor[j] = seeds.origin[static_cast<std::size_t>(seed_index)];
    }
    const int p = out.predecessor[j];
    out.track_id[j] = p >= 0 ? previous_track_ids_[static_cast<std::size_t>(p)] : next_track_id_++;
  }

  previous_centres_.clear();
  previous_centres_.reserve(n);
  for (const Superpixel& s : out.superpixels.superpixels) previous_centres_.push_back({s.u, s.v});
  previous_track_ids_ = out.track_id;
  ++frame_index_;
  return out;
}

}  // namespace dasp
