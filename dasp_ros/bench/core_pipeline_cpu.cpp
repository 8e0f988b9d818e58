// The core library's CPU time per frame for what Dasp + Sdasp (or Tdasp) compute, on the frames of
// a folder, in one process and one thread: the reference for the ROS overhead of
// dasp_ros/scripts/throughput.py. Frames are decoded before timing.
//   core_pipeline_cpu <folder> [rounds] [tdasp]
#include <dasp/dasp.h>
#include <dasp/rgbd_io.h>
#include <dasp/sdasp.h>
#include <dasp/superpixel_graph.h>
#include <dasp/tdasp.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

namespace {

double cpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <folder> [rounds] [tdasp]\n", argv[0]);
    return 2;
  }
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 2;
  const bool tdasp = argc > 3 && std::string(argv[3]) == "tdasp";
  std::vector<dasp::RgbdFrame> frames;
  for (const dasp::RgbdFramePaths& p : dasp::listRgbdFolder(argv[1])) {
    frames.push_back(dasp::loadRgbdFrame(p));
  }
  if (frames.empty()) return 2;
  dasp::DaspSegmenter segmenter;
  dasp::TemporalDasp temporal;
  const dasp::SdaspConfig sdasp;
  double total = 0.0, dasp_ms = 0.0;
  int count = 0;
  std::size_t checksum = 0;
  for (int r = 0; r < rounds + 1; ++r) {  // round 0 warms up
    for (const dasp::RgbdFrame& frame : frames) {
      const double t0 = cpuMilliseconds();
      if (tdasp) {
        const dasp::TdaspFrame out = temporal.process(frame);
        checksum += out.strand_id.size();
      } else {
        const dasp::Superpixels sp = segmenter.compute(frame);
        const double t1 = cpuMilliseconds();
        const dasp::WeightedGraph graph = dasp::buildSuperpixelGraph(sp);  // Dasp's edges
        const cv::Mat segments = dasp::computeSdasp(sp, sdasp).segments;
        checksum += graph.edges.size() + static_cast<std::size_t>(segments.rows);
        if (r > 0) dasp_ms += t1 - t0;
      }
      if (r > 0) {
        total += cpuMilliseconds() - t0;
        ++count;
      }
    }
  }
  if (tdasp) {
    std::printf("t-DASP core CPU per frame: %.2f ms over %d frames (%zu)\n", total / count, count,
                checksum);
  } else {
    std::printf(
        "DASP + edges + s-DASP core CPU per frame: %.2f ms (DASP alone %.2f ms) over %d "
        "frames (%zu)\n",
        total / count, dasp_ms / count, count, checksum);
  }
  return 0;
}
