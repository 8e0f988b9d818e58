#include "sdasp/common.h"

#include <ctime>
#include <stdexcept>

namespace sdasp_tool {

double threadCpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

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

}  // namespace sdasp_tool
