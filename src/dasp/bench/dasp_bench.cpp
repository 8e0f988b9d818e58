// Benchmarks of every DASP stage at 640x480, K = 1000, 5 iterations, single-threaded and with all
// cores, against OpenCV ximgproc SLIC (10 iterations, region size for K near 1000) on the same
// frame in the same run; prints the time ratio and the peak memory of one frame. Scaling runs
// show the runtime against the pixel count (linear) and against K (flat).
//
// Frame: learn0 of ../shared/data/osd/learn (or $DASP_BENCH_FRAME_DIR/<name>), else a synthetic
// textured two-plane scene of the same size.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc.hpp>

#include "bench_frame.h"
#include "dasp/connectivity.h"
#include "dasp/dalic.h"
#include "dasp/dasp.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp/superpoints.h"

namespace {

using namespace dasp;

constexpr int kCount = 1000;
constexpr int kIterations = 5;

DaspConfig config(int threads) {
  DaspConfig c;
  c.superpixel_count = kCount;
  c.iterations = kIterations;
  c.threads = threads;
  return c;
}

// Frame scaled by factor/4 (colour area-interpolated, depth nearest), intrinsics scaled too.
RgbdFrame scaledFrame(int quarter_factor) {
  const double s = quarter_factor / 4.0;
  RgbdFrame f;
  cv::resize(bench::benchFrame().color, f.color, cv::Size(), s, s, cv::INTER_LINEAR);
  cv::resize(bench::benchFrame().depth, f.depth, cv::Size(), s, s, cv::INTER_NEAREST);
  const Intrinsics k = bench::benchFrame().intrinsics;
  f.intrinsics = {static_cast<float>(k.fx * s), static_cast<float>(k.fy * s),
                  static_cast<float>((k.cx + 0.5) * s - 0.5),
                  static_cast<float>((k.cy + 0.5) * s - 0.5)};
  return f;
}

void BM_Features(benchmark::State& state) {
  const DaspConfig c = config(static_cast<int>(state.range(0)));
  PixelFeatures features;  // kept across frames, as DaspSegmenter does
  for (auto _ : state) {
    computeFeatures(bench::benchFrame(), c, features);
    benchmark::DoNotOptimize(features.valid_count);
  }
}
BENCHMARK(BM_Features)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_Density(benchmark::State& state) {
  const PixelFeatures f = computeFeatures(bench::benchFrame(), config(1));
  for (auto _ : state) {
    const float radius = radiusForCount(f, kCount);
    benchmark::DoNotOptimize(computeDepthDensity(f, radius));
  }
}
BENCHMARK(BM_Density)->Unit(benchmark::kMillisecond);

void BM_Sampling(benchmark::State& state) {
  const PixelFeatures f = computeFeatures(bench::benchFrame(), config(1));
  const cv::Mat density = computeDepthDensity(f, radiusForCount(f, kCount));
  const auto method = static_cast<SeedingMethod>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(sampleSeeds(density, method, 0));
  state.SetLabel(method == SeedingMethod::kSpdsImproved ? "SPDS alg. 2"
                 : method == SeedingMethod::kSpds       ? "SPDS alg. 1"
                 : method == SeedingMethod::kRandom     ? "random"
                                                        : "grid");
}
BENCHMARK(BM_Sampling)
    ->ArgName("method")
    ->Arg(static_cast<int>(SeedingMethod::kSpdsImproved))
    ->Arg(static_cast<int>(SeedingMethod::kSpds))
    ->Arg(static_cast<int>(SeedingMethod::kRandom))
    ->Unit(benchmark::kMillisecond);

struct DalicFixture {
  PixelFeatures features;
  cv::Mat density;
  DalicParams params;
  std::vector<Seed> seeds;
  explicit DalicFixture(int threads, int count = kCount,
                        const RgbdFrame& frame = bench::benchFrame()) {
    DaspConfig c = config(threads);
    c.superpixel_count = count;
    features = computeFeatures(frame, c);
    params = dalicParams(c, MetricKind::kDepthAdaptive, radiusForCount(features, count), count);
    density = computeDepthDensity(features, params.radius_m);
    seeds = sampleSeeds(density, c.seeding, c.seed);
  }
};

// One DALIC iteration (assignment + update), after the initial one.
void BM_DalicIteration(benchmark::State& state) {
  DalicFixture fx(static_cast<int>(state.range(0)));
  Dalic dalic(fx.features, fx.density, fx.params);
  dalic.initialize(fx.seeds);
  dalic.iterate();
  for (auto _ : state) dalic.iterate();
}
BENCHMARK(BM_DalicIteration)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_DalicAssign(benchmark::State& state) {
  DalicFixture fx(static_cast<int>(state.range(0)));
  Dalic dalic(fx.features, fx.density, fx.params);
  dalic.initialize(fx.seeds);
  dalic.iterate();
  for (auto _ : state) dalic.assign();
}
BENCHMARK(BM_DalicAssign)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_ConnectivityAndSuperpointFit(benchmark::State& state) {
  DalicFixture fx(1);
  Dalic dalic(fx.features, fx.density, fx.params);
  dalic.initialize(fx.seeds);
  for (int i = 0; i < kIterations; ++i) dalic.iterate();
  const cv::Mat raw = dalic.labels().clone();
  const cv::Mat valid(fx.features.height, fx.features.width, CV_8UC1, fx.features.valid.data());
  for (auto _ : state) {
    cv::Mat labels = raw.clone();
    enforceConnectivity(labels, valid, fx.density, 0.1);
    benchmark::DoNotOptimize(fitSuperpoints(labels, fx.features, fx.density, fx.params.radius_m));
  }
}
BENCHMARK(BM_ConnectivityAndSuperpointFit)->Unit(benchmark::kMillisecond);

void BM_Dasp(benchmark::State& state) {
  const DaspConfig c = config(static_cast<int>(state.range(0)));
  std::size_t count = 0;
  for (auto _ : state) count = computeDasp(bench::benchFrame(), c).superpixels.size();
  state.counters["superpixels"] = static_cast<double>(count);
}
BENCHMARK(BM_Dasp)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

// A sensor stream: one DaspSegmenter keeps its per-pixel buffers from frame to frame (what the
// ROS node does); the result is the same as computeDasp's.
void BM_DaspStream(benchmark::State& state) {
  const DaspConfig c = config(static_cast<int>(state.range(0)));
  DaspSegmenter segmenter(c);
  std::size_t count = 0;
  for (auto _ : state) count = segmenter.compute(bench::benchFrame()).superpixels.size();
  state.counters["superpixels"] = static_cast<double>(count);
}
BENCHMARK(BM_DaspStream)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_OpenCvSlic(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int previous = cv::getNumThreads();
  cv::setNumThreads(threads == 1 ? 1 : -1);
  int count = 0;
  for (auto _ : state) count = bench::runOpenCvSlic(bench::benchFrame().color);
  cv::setNumThreads(previous);
  state.counters["superpixels"] = count;
}
BENCHMARK(BM_OpenCvSlic)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

// The DASP / SLIC time ratio measured robustly: DASP and OpenCV SLIC (single-threaded) alternate
// frame by frame and each is timed in CPU time of this thread, so that other jobs on a shared
// machine (which inflate wall times and come and go between two separate benchmarks) hit both
// alike.

void BM_DaspVsOpenCvSlic(benchmark::State& state) {
  const int previous = cv::getNumThreads();
  cv::setNumThreads(1);
  const DaspConfig c = config(1);
  double dasp_ms = 0.0, slic_ms = 0.0;
  for (auto _ : state) {
    const double t0 = bench::threadCpuMs();
    benchmark::DoNotOptimize(computeDasp(bench::benchFrame(), c));
    const double t1 = bench::threadCpuMs();
    benchmark::DoNotOptimize(bench::runOpenCvSlic(bench::benchFrame().color));
    const double t2 = bench::threadCpuMs();
    dasp_ms += t1 - t0;
    slic_ms += t2 - t1;
  }
  cv::setNumThreads(previous);
  const double n = static_cast<double>(state.iterations());
  state.counters["dasp_cpu_ms"] = dasp_ms / n;
  state.counters["slic_cpu_ms"] = slic_ms / n;
  state.counters["ratio"] = dasp_ms / slic_ms;
}
BENCHMARK(BM_DaspVsOpenCvSlic)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Runtime against pixel count: the frame scaled by 2/4 .. 8/4 per axis (0.25x .. 4x pixels),
// K scaled with the pixel count so that superpixels keep their pixel size. OpenCV SLIC runs on the
// same scaled frame with the same region size (its superpixels keep their pixel size too), and the
// two alternate frame by frame, timed in CPU time as in BM_DaspVsOpenCvSlic: the peer, whose work
// per pixel does not depend on the frame size, shows how much the time per pixel grows on this
// machine with the frame size alone.
void BM_DaspPixels(benchmark::State& state) {
  const RgbdFrame f = scaledFrame(static_cast<int>(state.range(0)));
  DaspConfig c = config(1);
  c.superpixel_count = static_cast<int>(kCount * state.range(0) * state.range(0) / 16);
  const int previous = cv::getNumThreads();
  cv::setNumThreads(1);
  double dasp_ms = 0.0, slic_ms = 0.0;
  for (auto _ : state) {
    const double t0 = bench::threadCpuMs();
    benchmark::DoNotOptimize(computeDasp(f, c));
    const double t1 = bench::threadCpuMs();
    benchmark::DoNotOptimize(bench::runOpenCvSlic(f.color));
    const double t2 = bench::threadCpuMs();
    dasp_ms += t1 - t0;
    slic_ms += t2 - t1;
  }
  cv::setNumThreads(previous);
  const double n = static_cast<double>(state.iterations());
  state.counters["pixels"] = static_cast<double>(f.color.total());
  state.counters["dasp_cpu_ms"] = dasp_ms / n;
  state.counters["slic_cpu_ms"] = slic_ms / n;
}
BENCHMARK(BM_DaspPixels)
    ->ArgName("quarter_scale")
    ->DenseRange(2, 8, 2)
    ->Unit(benchmark::kMillisecond);

// Runtime against K at 640x480 (expected: flat).
void BM_DaspCount(benchmark::State& state) {
  DaspConfig c = config(1);
  c.superpixel_count = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(computeDasp(bench::benchFrame(), c));
}
// K from 250 to 4000 (superpixels of 1230 to 77 pixels at 640x480).
constexpr int kCounts[] = {250, 500, 1000, 2000, 4000};
void countArgs(benchmark::internal::Benchmark* b) {
  b->ArgName("K");
  for (int k : kCounts) b->Arg(k);
}
BENCHMARK(BM_DaspCount)->Apply(countArgs)->Unit(benchmark::kMillisecond);

// The DASP stages as BM_DaspStagesCount times them, and their counter names.
enum Stage {
  kFeatures,
  kDensity,
  kSampling,
  kInit,
  kAssign,
  kUpdate,
  kConnectivity,
  kFit,
  kStages
};
constexpr const char* kStageNames[kStages] = {"features", "density", "sampling",     "init",
                                              "assign",   "update",  "connectivity", "fit"};

// Row segments of one label in a label image (labels >= 0): the unit of work of the DALIC update,
// connectivity enforcement and the superpoint fit besides the pixels themselves.
int labelRuns(const cv::Mat& labels) {
  int runs = 0;
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) runs += row[x] >= 0 && (x == 0 || row[x] != row[x - 1]);
  }
  return runs;
}

// The DASP stages one by one (the steps computeDasp takes, buffers kept across frames as in
// DaspSegmenter) on `frame` with K = count, each timed in thread CPU time; the counters are ms per
// frame, and "runs" the label runs of DALIC's last labels.
void timeStages(benchmark::State& state, const RgbdFrame& frame, int count) {
  DaspConfig c = config(1);
  c.superpixel_count = count;
  DalicFixture fx(1, c.superpixel_count, frame);  // buffers and parameters; refilled every frame
  Dalic dalic(fx.features, fx.density, fx.params);
  const cv::Mat valid(fx.features.height, fx.features.width, CV_8UC1, fx.features.valid.data());
  const cv::Mat depth(fx.features.height, fx.features.width, CV_32FC1, fx.features.z.data());
  double ms[kStages] = {};
  for (auto _ : state) {
    double t = bench::threadCpuMs();
    const auto lap = [&t, &ms](Stage stage) {
      const double now = bench::threadCpuMs();
      ms[stage] += now - t;
      t = now;
    };
    computeFeatures(frame, c, fx.features);
    lap(kFeatures);
    computeDepthDensity(fx.features, radiusForCount(fx.features, c.superpixel_count), fx.density);
    lap(kDensity);
    const std::vector<Seed> seeds = sampleSeeds(fx.density, c.seeding, c.seed);
    lap(kSampling);
    dalic.reset(fx.params);
    dalic.initialize(seeds);
    lap(kInit);
    for (int it = 0; it < c.iterations; ++it) {
      dalic.assign();
      lap(kAssign);
      if (it + 1 < c.iterations) dalic.update();
      lap(kUpdate);
    }
    cv::Mat labels = dalic.labels().clone();
    enforceConnectivity(labels, valid, fx.density, c.min_size_fraction, depth, c.depth_jump_ratio);
    lap(kConnectivity);
    benchmark::DoNotOptimize(fitSuperpoints(labels, fx.features, fx.density, fx.params.radius_m));
    lap(kFit);
  }
  const double n = static_cast<double>(state.iterations());
  for (int stage = 0; stage < kStages; ++stage) state.counters[kStageNames[stage]] = ms[stage] / n;
  state.counters["runs"] = labelRuns(dalic.labels());  // the same every frame
}

// Where the growth with K comes from: the stages against K at 640x480.
void BM_DaspStagesCount(benchmark::State& state) {
  timeStages(state, bench::benchFrame(), static_cast<int>(state.range(0)));
}
BENCHMARK(BM_DaspStagesCount)->Apply(countArgs)->Unit(benchmark::kMillisecond);

// Where the growth of the time per pixel comes from: the stages against the pixel count (the
// frames and K of BM_DaspPixels).
void BM_DaspStagesPixels(benchmark::State& state) {
  const int quarter_scale = static_cast<int>(state.range(0));
  timeStages(state, scaledFrame(quarter_scale), kCount * quarter_scale * quarter_scale / 16);
}
BENCHMARK(BM_DaspStagesPixels)
    ->ArgName("quarter_scale")
    ->DenseRange(2, 8, 2)
    ->Unit(benchmark::kMillisecond);

// The peer against K: OpenCV SLIC (10 iterations) with the region size for about K superpixels.
void BM_OpenCvSlicCount(benchmark::State& state) {
  const int previous = cv::getNumThreads();
  cv::setNumThreads(1);
  const int region = static_cast<int>(std::lround(
      std::sqrt(static_cast<double>(bench::benchFrame().color.total()) / state.range(0))));
  int count = 0;
  for (auto _ : state) count = bench::runOpenCvSlic(bench::benchFrame().color, region);
  cv::setNumThreads(previous);
  state.counters["superpixels"] = count;
}
BENCHMARK(BM_OpenCvSlicCount)->Apply(countArgs)->Unit(benchmark::kMillisecond);

// Records the real time per run name (the median when repeated), to print the DASP / SLIC ratios
// at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.run_type == Run::RT_Iteration && run.iterations > 0) {
        times_ms[run.benchmark_name()] = run.GetAdjustedRealTime();
        for (const auto& [name, counter] : run.counters) {
          counters[run.benchmark_name() + "." + name] = counter.value;
        }
      } else if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        times_ms[run.run_name.str()] = run.GetAdjustedRealTime();  // with --benchmark_repetitions
        for (const auto& [name, counter] : run.counters) {
          counters[run.run_name.str() + "." + name] = counter.value;
        }
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times_ms;
  std::map<std::string, double> counters;  // "<run>.<counter>"
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  // Peak memory of one frame: resident set before and after the first DASP run.
  const RgbdFrame& f = bench::benchFrame();
  const long before_kb = bench::maxRssKb();
  const Superpixels first = computeDasp(f, config(1));
  const long after_kb = bench::maxRssKb();
  std::printf(
      "peak memory: max RSS %.1f MB before the first frame, %.1f MB after it (+%.1f MB "
      "for one %dx%d DASP frame, %zu superpixels)\n",
      before_kb / 1024.0, after_kb / 1024.0, (after_kb - before_kb) / 1024.0, f.color.cols,
      f.color.rows, first.superpixels.size());
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto find = [&](const std::string& name) {
    const auto it = reporter.times_ms.find(name);
    return it == reporter.times_ms.end() ? -1.0 : it->second;
  };
  const double dasp1 = find("BM_Dasp/threads:1"), slic1 = find("BM_OpenCvSlic/threads:1");
  const double dasp0 = find("BM_Dasp/threads:0"), slic0 = find("BM_OpenCvSlic/threads:0");
  if (dasp1 > 0 && slic1 > 0) {
    std::printf(
        "ratio DASP / OpenCV SLIC, single-threaded, separate benchmarks (wall time, sensitive to "
        "other jobs): %.3f (%.2f ms / %.2f ms)\n",
        dasp1 / slic1, dasp1, slic1);
  }
  // The run name carries the benchmark's options ("BM_DaspVsOpenCvSlic/min_time:...").
  const auto counter = [&](const std::string& name) {
    for (const auto& [key, value] : reporter.counters) {
      if (key.rfind("BM_DaspVsOpenCvSlic", 0) == 0 && key.size() > name.size() &&
          key.compare(key.size() - name.size(), name.size(), name) == 0) {
        return value;
      }
    }
    return -1.0;
  };
  if (counter(".ratio") > 0) {
    std::printf(
        "ratio DASP / OpenCV SLIC, single-threaded, alternating frames, CPU time: %.3f (%.2f ms / "
        "%.2f ms)\n",
        counter(".ratio"), counter(".dasp_cpu_ms"), counter(".slic_cpu_ms"));
  }
  const double stream1 = find("BM_DaspStream/threads:1");
  const double stream0 = find("BM_DaspStream/threads:0");
  if (stream1 > 0 && slic1 > 0) {
    std::printf(
        "ratio DASP stream (buffers kept across frames) / OpenCV SLIC, single-threaded, separate "
        "benchmarks: %.3f (%.2f ms / %.2f ms)\n",
        stream1 / slic1, stream1, slic1);
  }
  if (stream0 > 0 && slic0 > 0) {
    std::printf("ratio DASP stream / OpenCV SLIC, all cores: %.3f (%.2f ms / %.2f ms)\n",
                stream0 / slic0, stream0, slic0);
  }
  if (dasp1 > 0 && slic0 > 0) {
    std::printf("ratio DASP single-threaded / OpenCV SLIC default threads: %.3f\n", dasp1 / slic0);
  }
  if (dasp0 > 0 && slic0 > 0) {
    std::printf("ratio DASP / OpenCV SLIC, all cores: %.3f (%.2f ms / %.2f ms)\n", dasp0 / slic0,
                dasp0, slic0);
  }
  // Runtime against K and against the pixel count, relative to K = 1000 and to full size.
  const double dasp_k1000 = find("BM_DaspCount/K:1000"),
               slic_k1000 = find("BM_OpenCvSlicCount/K:1000");
  if (dasp_k1000 > 0) {
    std::printf("runtime against K (single-threaded, relative to K = 1000):\n");
    for (int k : kCounts) {
      const double dasp_k = find("BM_DaspCount/K:" + std::to_string(k));
      const double slic_k = find("BM_OpenCvSlicCount/K:" + std::to_string(k));
      if (dasp_k <= 0) continue;
      std::printf("  K = %4d: DASP %6.2f ms (x%.2f)", k, dasp_k, dasp_k / dasp_k1000);
      if (slic_k > 0 && slic_k1000 > 0) {
        std::printf(", OpenCV SLIC %7.2f ms (x%.2f), DASP / SLIC %.3f", slic_k, slic_k / slic_k1000,
                    dasp_k / slic_k);
      }
      std::printf("\n");
    }
  }
  // The stages against K (CPU ms per frame; assign and update summed over the iterations) and
  // the label runs: the counters of BM_DaspStagesCount.
  const auto stageCounter = [&](int k, const std::string& name) {
    const auto it =
        reporter.counters.find("BM_DaspStagesCount/K:" + std::to_string(k) + "." + name);
    return it == reporter.counters.end() ? -1.0 : it->second;
  };
  if (stageCounter(1000, "assign") > 0) {
    std::printf("DASP stages against K (single-threaded, CPU ms per frame; label runs):\n       ");
    for (const char* stage : kStageNames) std::printf(" %12s", stage);
    std::printf(" %12s\n", "label runs");
    for (int k : kCounts) {
      if (stageCounter(k, "assign") < 0) continue;
      std::printf("  K = %4d", k);
      for (const char* stage : kStageNames) std::printf(" %12.2f", stageCounter(k, stage));
      std::printf(" %12.0f\n", stageCounter(k, "runs"));
    }
  }
  // Runtime against the pixel count: the counters of BM_DaspPixels (CPU time, DASP and OpenCV
  // SLIC alternating on the same scaled frame), relative to 640x480.
  const auto pixelCounter = [&](const std::string& bench, int quarter_scale,
                                const std::string& name) {
    const auto it = reporter.counters.find(
        bench + "/quarter_scale:" + std::to_string(quarter_scale) + "." + name);
    return it == reporter.counters.end() ? -1.0 : it->second;
  };
  const double dasp_full = pixelCounter("BM_DaspPixels", 4, "dasp_cpu_ms");
  const double slic_full = pixelCounter("BM_DaspPixels", 4, "slic_cpu_ms");
  if (dasp_full > 0 && slic_full > 0) {
    std::printf(
        "runtime against pixel count (K scaled with it; CPU time, DASP and OpenCV SLIC alternating "
        "on the same frame; relative to 640x480):\n");
    for (int q : {2, 4, 6, 8}) {
      const double dasp_t = pixelCounter("BM_DaspPixels", q, "dasp_cpu_ms");
      const double slic_t = pixelCounter("BM_DaspPixels", q, "slic_cpu_ms");
      if (dasp_t <= 0 || slic_t <= 0) continue;
      const double pixels = q * q / 16.0;
      std::printf(
          "  %.2fx the pixels: %7.2f ms, time x%.2f, time per pixel x%.2f; OpenCV SLIC %7.2f ms, "
          "time per pixel x%.2f; DASP / SLIC %.3f\n",
          pixels, dasp_t, dasp_t / dasp_full, dasp_t / dasp_full / pixels, slic_t,
          slic_t / slic_full / pixels, dasp_t / slic_t);
    }
  }
  // The stages against the pixel count, CPU ms per 640x480 worth of pixels (the same figure at
  // every size for a stage whose time grows linearly): the counters of BM_DaspStagesPixels.
  if (pixelCounter("BM_DaspStagesPixels", 4, "assign") > 0) {
    std::printf(
        "DASP stages against pixel count (single-threaded, CPU ms per 640x480 worth of pixels; "
        "label runs per 640x480):\n                 ");
    for (const char* stage : kStageNames) std::printf(" %12s", stage);
    std::printf(" %12s\n", "label runs");
    for (int q : {2, 4, 6, 8}) {
      if (pixelCounter("BM_DaspStagesPixels", q, "assign") < 0) continue;
      const double pixels = q * q / 16.0;
      std::printf("  %.2fx the pixels", pixels);
      for (const char* stage : kStageNames) {
        std::printf(" %12.2f", pixelCounter("BM_DaspStagesPixels", q, stage) / pixels);
      }
      std::printf(" %12.0f\n", pixelCounter("BM_DaspStagesPixels", q, "runs") / pixels);
    }
  }
  benchmark::Shutdown();
  return 0;
}
