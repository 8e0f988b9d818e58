// t-DASP video segmentation pipeline (thesis ch. 5).
#include "dasp/tdasp.h"

#include <chrono>
#include <limits>
#include <stdexcept>

namespace dasp {
namespace {

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

TemporalDasp::TemporalDasp(const TdaspConfig& config)
    : config_(config), superpixels_(config.superpixels), strands_(config.strands) {
  const HysteresisConfig& h = config.hysteresis;
  if (!(h.force <= h.normal && h.normal <= h.grant)) {
    throw std::invalid_argument(
        "TemporalDasp: hysteresis thresholds need force <= normal <= grant");
  }
}

TdaspFrame TemporalDasp::process(const RgbdFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  TdaspFrame out;
  auto stage = std::chrono::steady_clock::now();
  out.superpixels = superpixels_.process(frame);
  out.timings.superpixels_ms = msSince(stage);

  stage = std::chrono::steady_clock::now();
  const WeightedGraph superpixel_graph =
      buildSuperpixelGraph(out.superpixels.superpixels, config_.strands.graph);
  const std::vector<int> strand_index = strands_.addFrame(out.superpixels, superpixel_graph);
  const WeightedGraph strand_graph = strands_.graph();
  out.timings.graph_ms = msSince(stage);

  stage = std::chrono::steady_clock::now();
  WeightedGraph boundary = strand_graph;  // eq. 5.16 on the reduced strand graph
  const std::vector<float> global = globalizeEdgeWeights(strand_graph, config_.spectral);
  for (std::size_t e = 0; e < boundary.edges.size(); ++e) boundary.edges[e].weight = global[e];
  out.timings.spectral_ms = msSince(stage);

  stage = std::chrono::steady_clock::now();
  const std::vector<Strand>& strands = strands_.strands();
  std::vector<std::int64_t> supervised(strands.size());
  std::vector<double> node_size(strands.size());
  for (std::size_t i = 0; i < strands.size(); ++i) {
    // Supervised: the strand was in the graph of the previous frame and got a label there.
    supervised[i] = strands[i].segment_label;
    node_size[i] = static_cast<double>(strands[i].length());
  }
  out.labelling =
      hysteresisSegmentation(boundary, supervised, node_size, config_.hysteresis, next_label_);
  for (std::size_t i = 0; i < strands.size(); ++i) {
    strands_.setSegmentLabel(static_cast<int>(i), out.labelling.labels[i]);
  }
  const std::size_t n = strand_index.size();
  out.strand_id.resize(n);
  out.segment_label.resize(n);
  std::vector<int> pixel_label(n);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = static_cast<std::size_t>(strand_index[j]);
    out.strand_id[j] = strands[i].id;
    out.segment_label[j] = out.labelling.labels[i];
    if (out.segment_label[j] > std::numeric_limits<int>::max()) {
      throw std::overflow_error("TemporalDasp: segment labels exceed the label image range");
    }
    pixel_label[j] = static_cast<int>(out.segment_label[j]);
  }
  const cv::Mat& labels = out.superpixels.superpixels.labels;
  out.segment_labels.create(labels.size(), CV_32SC1);
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    int* s = out.segment_labels.ptr<int>(row);
    for (int col = 0; col < labels.cols; ++col) {
      s[col] = l[col] >= 0 ? pixel_label[static_cast<std::size_t>(l[col])] : -1;
    }
  }
  out.strand_count = static_cast<int>(strands.size());
  out.strand_edge_count = static_cast<int>(strand_graph.edges.size());
  out.timings.labelling_ms = msSince(stage);
  out.timings.total_ms = msSince(start);
  return out;
}

}  // namespace dasp
