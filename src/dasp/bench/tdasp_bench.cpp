// Benchmarks of t-DASP at 640x480, 1000 superpixels per frame, single-threaded: one t-DASP frame
// in steady state (strand graph full), its Delta Density Sampling step, and one independent
// s-DASP frame (DASP + ultrametric contour graph + threshold) for comparison.
//
// Before the benchmarks it runs a long stream (default 1000 frames, --stream_frames=N) and
// prints the per-frame thread CPU time of the first and the last 100 frames, the strand count,
// and the resident memory after 100 frames and at the end, to show that cost and memory per
// frame stay flat on an endless stream (the strand graph is reduced to max_strands).
//
// Stream: learn0 of ../shared/data/osd/learn (or $DASP_BENCH_FRAME_DIR) moved by a periodic
// sub-pixel image translation (period 40 frames, amplitude 8 px horizontally, 4 px vertically),
// with fresh Kinect-like depth noise and colour noise every frame (seeded); a synthetic
// two-plane scene if the data is absent.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_frame.h"
#include "dasp/delta_density.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp/sdasp.h"
#include "dasp/segmentation.h"
#include "dasp/tdasp.h"

namespace {

using namespace dasp;

constexpr int kCount = 1000;
constexpr double kPi = 3.14159265358979323846;

// Frame k of the endless stream (see the file comment).
RgbdFrame streamFrame(std::int64_t k) {
  const RgbdFrame& base = bench::benchFrame();
  const double phase = 2.0 * kPi * static_cast<double>(k % 40) / 40.0;
  const cv::Matx23d shift(1, 0, 8.0 * std::sin(phase), 0, 1, 4.0 * std::sin(2.0 * phase));
  RgbdFrame f;
  f.intrinsics = base.intrinsics;
  cv::warpAffine(base.color, f.color, shift, base.color.size(), cv::INTER_LINEAR,
                 cv::BORDER_CONSTANT);
  cv::warpAffine(base.depth, f.depth, shift, base.depth.size(), cv::INTER_NEAREST,
                 cv::BORDER_CONSTANT);
  std::mt19937_64 rng(static_cast<std::uint64_t>(k) + 1);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int y = 0; y < f.depth.rows; ++y) {
    std::uint16_t* d = f.depth.ptr<std::uint16_t>(y);
    cv::Vec3b* c = f.color.ptr<cv::Vec3b>(y);
    for (int x = 0; x < f.depth.cols; ++x) {
      for (int ch = 0; ch < 3; ++ch) {
        c[x][ch] = cv::saturate_cast<std::uint8_t>(c[x][ch] + 2.0 * normal(rng));
      }
      if (d[x] == 0) continue;
      const double z = d[x] / 1000.0;
      const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
      d[x] = static_cast<std::uint16_t>(
          std::clamp(std::lround((z + sigma * normal(rng)) * 1000.0), 1L, 65535L));
    }
  }
  return f;
}

TdaspConfig tdaspConfig() {
  TdaspConfig c;
  c.superpixels.dasp.superpixel_count = kCount;
  c.superpixels.dasp.threads = 1;
  return c;
}

long currentRssKb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

void BM_TdaspFrame(benchmark::State& state) {
  TemporalDasp tdasp(tdaspConfig());
  std::int64_t k = 0;
  for (; k < 60; ++k) tdasp.process(streamFrame(k));  // fill the strand graph
  std::vector<RgbdFrame> frames;
  for (int i = 0; i < 40; ++i) frames.push_back(streamFrame(k + i));
  std::size_t i = 0;
  for (auto _ : state) {
    TdaspFrame out = tdasp.process(frames[i++ % frames.size()]);
    benchmark::DoNotOptimize(out.segment_labels.data);
  }
}
BENCHMARK(BM_TdaspFrame)->Unit(benchmark::kMillisecond)->MinTime(5.0);

void BM_SdaspFrame(benchmark::State& state) {
  const RgbdFrame f = streamFrame(0);
  DaspConfig dc = tdaspConfig().superpixels.dasp;
  for (auto _ : state) {
    const Superpixels sp = computeDasp(f, dc);
    const WeightedGraph ucg = ultrametricContourGraph(sp);
    const cv::Mat segments =
        segmentPixels(sp.labels, segmentGraph(ucg, cutThreshold(ucg, SdaspConfig{})));
    benchmark::DoNotOptimize(segments.data);
  }
}
BENCHMARK(BM_SdaspFrame)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_DeltaDensitySampling(benchmark::State& state) {
  const RgbdFrame f0 = streamFrame(0), f1 = streamFrame(1);
  const DaspConfig dc = tdaspConfig().superpixels.dasp;
  const Superpixels previous = computeDasp(f0, dc);
  std::vector<Seed> centres;
  for (const Superpixel& s : previous.superpixels) centres.push_back({s.u, s.v});
  const PixelFeatures features = computeFeatures(f1, dc);
  const cv::Mat density = computeDepthDensity(features, radiusForCount(features, kCount));
  std::uint64_t seed = 0;
  for (auto _ : state) {
    const DeltaDensityResult r = deltaDensitySampling(density, centres, {}, seed++);
    benchmark::DoNotOptimize(r.points.data());
  }
}
BENCHMARK(BM_DeltaDensitySampling)->Unit(benchmark::kMillisecond);

struct Window {
  double mean = 0.0, median = 0.0, p95 = 0.0;
};

Window summarise(std::vector<double> v) {
  Window w;
  if (v.empty()) return w;
  for (const double x : v) w.mean += x / static_cast<double>(v.size());
  std::sort(v.begin(), v.end());
  w.median = v[v.size() / 2];
  w.p95 = v[std::min(v.size() - 1, static_cast<std::size_t>(0.95 * v.size()))];
  return w;
}

// The long-stream run: per-frame CPU time, strand count and memory.
void runStream(int frames, const std::string& csv_path) {
  TemporalDasp tdasp(tdaspConfig());
  std::vector<double> cpu_ms(static_cast<std::size_t>(frames));
  std::vector<int> strands(static_cast<std::size_t>(frames));
  long rss_after_100 = 0, max_rss_after_100 = 0;
  std::FILE* csv = csv_path.empty() ? nullptr : std::fopen(csv_path.c_str(), "w");
  if (csv != nullptr)
    std::fprintf(csv, "frame,cpu_ms,wall_ms,strands,strand_edges,segments,rss_kb\n");
  for (int k = 0; k < frames; ++k) {
    const RgbdFrame f = streamFrame(k);
    const double start = bench::threadCpuMs();
    const TdaspFrame out = tdasp.process(f);
    cpu_ms[static_cast<std::size_t>(k)] = bench::threadCpuMs() - start;
    strands[static_cast<std::size_t>(k)] = out.strand_count;
    if (k == 99) {
      rss_after_100 = currentRssKb();
      max_rss_after_100 = bench::maxRssKb();
    }
    if (csv != nullptr) {
      std::fprintf(csv, "%d,%.3f,%.3f,%d,%d,%d,%ld\n", k, cpu_ms[static_cast<std::size_t>(k)],
                   out.timings.total_ms, out.strand_count, out.strand_edge_count,
                   out.labelling.component_count, currentRssKb());
    }
  }
  if (csv != nullptr) std::fclose(csv);
  const int window = std::min(100, frames / 2);
  const Window first = summarise(std::vector<double>(cpu_ms.begin(), cpu_ms.begin() + window));
  const Window last = summarise(std::vector<double>(cpu_ms.end() - window, cpu_ms.end()));
  std::printf("stream of %d frames, %d superpixels, max_strands %d, single-threaded CPU time:\n",
              frames, kCount, tdaspConfig().strands.max_strands);
  std::printf("  first %d frames: mean %.1f ms, median %.1f ms, p95 %.1f ms per frame\n", window,
              first.mean, first.median, first.p95);
  std::printf("  last  %d frames: mean %.1f ms, median %.1f ms, p95 %.1f ms per frame\n", window,
              last.mean, last.median, last.p95);
  std::printf("  ratio last / first (mean): %.3f\n", last.mean / first.mean);
  // Per block of 100 frames: the cost grows while the strand graph fills up to max_strands, then
  // stays flat.
  for (int begin = 0; begin + 100 <= frames; begin += 100) {
    const Window block =
        summarise(std::vector<double>(cpu_ms.begin() + begin, cpu_ms.begin() + begin + 100));
    std::printf("  frames %4d-%4d: mean %.1f ms, median %.1f ms; strands at the end %d\n", begin,
                begin + 99, block.mean, block.median,
                strands[static_cast<std::size_t>(begin + 99)]);
  }
  std::printf("  strands: %d after 100 frames, %d at the end (max over the stream %d)\n",
              strands[static_cast<std::size_t>(std::min(99, frames - 1))], strands.back(),
              *std::max_element(strands.begin(), strands.end()));
  if (frames >= 100) {
    std::printf(
        "  memory: resident %.1f MB after 100 frames, %.1f MB at the end; peak (max RSS) %.1f MB "
        "after 100 frames, %.1f MB at the end\n",
        rss_after_100 / 1024.0, currentRssKb() / 1024.0, max_rss_after_100 / 1024.0,
        bench::maxRssKb() / 1024.0);
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int stream_frames = 1000;
  std::string stream_csv;
  // Own flags first (Google Benchmark rejects unknown ones).
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--stream_frames=", 16) == 0) {
      stream_frames = std::atoi(argv[i] + 16);
    } else if (std::strncmp(argv[i], "--stream_csv=", 13) == 0) {
      stream_csv = argv[i] + 13;
    } else {
      rest.push_back(argv[i]);
    }
  }
  int rest_argc = static_cast<int>(rest.size());
  benchmark::Initialize(&rest_argc, rest.data());
  if (stream_frames > 0) runStream(stream_frames, stream_csv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
