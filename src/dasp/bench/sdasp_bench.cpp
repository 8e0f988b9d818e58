// Benchmarks of s-DASP (thesis ch. 4) at 640x480 with K = 1000 DASP superpixels, single-threaded:
// superpixel graph, eigen solve (globalisation), labelling at one threshold, the pixel UCM, and
// DASP + s-DASP together against OpenCV ximgproc SLIC on the same frame in the same run; prints the
// ratio (CPU time, robust on a shared machine) and the thesis' 250 ms per frame for comparison.
//
// Frame: learn0 of ../shared/data/osd/learn (or $DASP_BENCH_FRAME_DIR/<name>), else a synthetic
// textured two-plane scene of the same size.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc.hpp>

#include "bench_frame.h"
#include "dasp/dasp.h"
#include "dasp/sdasp.h"
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"

namespace {

using namespace dasp;

constexpr int kCount = 1000;

DaspConfig daspConfig() {
  DaspConfig c;
  c.superpixel_count = kCount;
  c.threads = 1;
  return c;
}

const Superpixels& superpixels() {
  static const Superpixels s = computeDasp(bench::benchFrame(), daspConfig());
  return s;
}

const WeightedGraph& similarityGraph() {
  static const WeightedGraph g = buildSuperpixelGraph(superpixels());
  return g;
}

const WeightedGraph& contourGraph() {
  static const WeightedGraph g = ultrametricContourGraph(superpixels());
  return g;
}

void BM_SdaspGraph(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(buildSuperpixelGraph(superpixels()));
  state.counters["nodes"] = similarityGraph().node_count;
  state.counters["edges"] = static_cast<double>(similarityGraph().edges.size());
}
BENCHMARK(BM_SdaspGraph)->Unit(benchmark::kMillisecond);

void BM_SdaspEigenSolve(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(globalizeEdgeWeights(similarityGraph()));
  state.counters["k"] = SpectralConfig{}.eigenvector_count;
}
BENCHMARK(BM_SdaspEigenSolve)->Unit(benchmark::kMillisecond);

// Union-find labelling of the graph and the pixel segment image at the default threshold.
void BM_SdaspLabelling(benchmark::State& state) {
  const SdaspConfig defaults;
  const float threshold = defaults.threshold;
  std::size_t segments = 0;
  for (auto _ : state) {
    const std::vector<int> nodes = segmentGraph(contourGraph(), threshold);
    benchmark::DoNotOptimize(segmentPixels(superpixels().labels, nodes));
    segments = static_cast<std::size_t>(*std::max_element(nodes.begin(), nodes.end()) + 1);
  }
  state.counters["segments"] = static_cast<double>(segments);
}
BENCHMARK(BM_SdaspLabelling)->Unit(benchmark::kMillisecond);

// The whole threshold sweep at 101 levels (node labels only).
void BM_SdaspSweep101(benchmark::State& state) {
  std::vector<float> thresholds(101);
  for (int i = 0; i <= 100; ++i) thresholds[i] = 0.01f * i;
  for (auto _ : state) benchmark::DoNotOptimize(segmentGraphSweep(contourGraph(), thresholds));
}
BENCHMARK(BM_SdaspSweep101)->Unit(benchmark::kMillisecond);

void BM_SdaspUcmImage(benchmark::State& state) {
  for (auto _ : state) {
    benchmark::DoNotOptimize(ultrametricContourMap(superpixels().labels, contourGraph()));
  }
}
BENCHMARK(BM_SdaspUcmImage)->Unit(benchmark::kMillisecond);

// s-DASP after the superpixels: graph, eigen solve, cut threshold (the default adaptive rule),
// labelling.
void BM_Sdasp(benchmark::State& state) {
  const SdaspConfig config;
  for (auto _ : state) {
    const WeightedGraph ucg = ultrametricContourGraph(superpixels(), config);
    benchmark::DoNotOptimize(
        segmentPixels(superpixels().labels, segmentGraph(ucg, cutThreshold(ucg, config))));
  }
}
BENCHMARK(BM_Sdasp)->Unit(benchmark::kMillisecond);

// The same with the one global threshold (the s-DASP of before the per-frame cut).
void BM_SdaspGlobalCut(benchmark::State& state) {
  SdaspConfig config;
  config.cut = CutRule::kGlobal;
  for (auto _ : state) {
    const WeightedGraph ucg = ultrametricContourGraph(superpixels(), config);
    benchmark::DoNotOptimize(
        segmentPixels(superpixels().labels, segmentGraph(ucg, config.threshold)));
  }
}
BENCHMARK(BM_SdaspGlobalCut)->Unit(benchmark::kMillisecond);

// DASP + s-DASP from the RGB-D frame to the segment image.
void BM_DaspPlusSdasp(benchmark::State& state) {
  const SdaspConfig config;
  for (auto _ : state) {
    const Superpixels s = computeDasp(bench::benchFrame(), daspConfig());
    const WeightedGraph ucg = ultrametricContourGraph(s, config);
    benchmark::DoNotOptimize(segmentPixels(s.labels, segmentGraph(ucg, cutThreshold(ucg, config))));
  }
}
BENCHMARK(BM_DaspPlusSdasp)->Unit(benchmark::kMillisecond);

void BM_OpenCvSlic(benchmark::State& state) {
  const int previous = cv::getNumThreads();
  cv::setNumThreads(1);
  int count = 0;
  for (auto _ : state) count = bench::runOpenCvSlic(bench::benchFrame().color);
  cv::setNumThreads(previous);
  state.counters["superpixels"] = count;
}
BENCHMARK(BM_OpenCvSlic)->Unit(benchmark::kMillisecond);

// Records the mean CPU time per run name, to print the ratios at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      // One run: its time; with --benchmark_repetitions: the median (BM_x_median).
      if (run.run_type == Run::RT_Iteration && run.iterations > 0) {
        cpu_ms.emplace(run.benchmark_name(), run.GetAdjustedCPUTime());
      } else if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        cpu_ms[run.run_name.function_name] = run.GetAdjustedCPUTime();
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> cpu_ms;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::printf("K = %d: %zu DASP superpixels, %zu graph edges\n", kCount,
              superpixels().superpixels.size(), similarityGraph().edges.size());
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto find = [&](const std::string& name) {
    const auto it = reporter.cpu_ms.find(name);
    return it == reporter.cpu_ms.end() ? -1.0 : it->second;
  };
  const double total = find("BM_DaspPlusSdasp"), slic = find("BM_OpenCvSlic");
  const double sdasp = find("BM_Sdasp"), global_cut = find("BM_SdaspGlobalCut");
  if (sdasp > 0 && global_cut > 0) {
    std::printf("ratio s-DASP adaptive cut / global cut, single-threaded CPU time: %.3f\n",
                sdasp / global_cut);
  }
  if (total > 0 && slic > 0) {
    std::printf(
        "ratio DASP + s-DASP / OpenCV SLIC, single-threaded CPU time: %.3f (%.2f ms / %.2f ms)\n",
        total / slic, total, slic);
  }
  if (total > 0) {
    std::printf(
        "DASP + s-DASP: %.2f ms a frame (s-DASP alone %.2f ms) = %.3f x the thesis' 250 ms\n",
        total, sdasp, total / 250.0);
  }
  benchmark::Shutdown();
  return 0;
}
