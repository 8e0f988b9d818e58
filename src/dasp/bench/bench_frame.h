// The frame every dasp benchmark runs on: learn0 of ../shared/data/osd/learn (or of
// $DASP_BENCH_FRAME_DIR), else a synthetic textured two-plane scene of the same size (640x480);
// the peer every bench compares against, OpenCV ximgproc SLIC; and the CPU time and memory
// readings the benches share.
#pragma once

#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc.hpp>

#include "dasp/dasp.h"

namespace dasp::bench {

inline RgbdFrame loadBenchFrame() {
  namespace fs = std::filesystem;
  fs::path folder = fs::path(__FILE__).parent_path() / "../../../../shared/data/osd/learn";
  if (const char* env = std::getenv("DASP_BENCH_FRAME_DIR")) folder = env;
  RgbdFrame frame;
  frame.intrinsics = {525.0f, 525.0f, 319.5f, 239.5f};
  if (fs::exists(folder / "learn0_rgb.png")) {
    frame.color = cv::imread((folder / "learn0_rgb.png").string(), cv::IMREAD_COLOR);
    frame.depth = cv::imread((folder / "learn0_depth_mm.png").string(), cv::IMREAD_UNCHANGED);
    std::printf("frame: %s/learn0\n", folder.string().c_str());
    return frame;
  }
  std::printf("frame: synthetic (no data at %s)\n", folder.string().c_str());
  frame.color = cv::Mat(480, 640, CV_8UC3);
  cv::randu(frame.color, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::GaussianBlur(frame.color, frame.color, cv::Size(0, 0), 4.0);
  frame.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(2000));
  frame.depth(cv::Rect(160, 120, 320, 240)).setTo(1200);
  return frame;
}

/// The bench frame, loaded once per process.
inline const RgbdFrame& benchFrame() {
  static const RgbdFrame frame = loadBenchFrame();
  return frame;
}

/// Region size of OpenCV SLIC for K near 1000 at 640x480: 640x480 / 18^2 = 948 grid cells, SLIC
/// returns about 970.
constexpr int kSlicRegionSize = 18;

/// OpenCV ximgproc SLIC as the benchmarks run it: CIELab conversion included, 10 iterations
/// (OpenCV's default). Returns the number of superpixels.
inline int runOpenCvSlic(const cv::Mat& bgr, int region_size = kSlicRegionSize) {
  cv::Mat lab;
  cv::cvtColor(bgr, lab, cv::COLOR_BGR2Lab);
  auto slic = cv::ximgproc::createSuperpixelSLIC(lab, cv::ximgproc::SLIC, region_size);
  slic->iterate(10);
  cv::Mat labels;
  slic->getLabels(labels);
  return slic->getNumberOfSuperpixels();
}

/// CPU time of the calling thread, milliseconds: other jobs on a shared machine do not inflate
/// it the way they inflate wall time.
inline double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/// Peak resident set size of the process so far, KiB.
inline long maxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

}  // namespace dasp::bench
