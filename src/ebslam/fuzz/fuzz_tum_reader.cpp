// libFuzzer target for readTumTrajectory: any file content either gives a valid trajectory
// (finite, strictly increasing time, unit quaternions) or a std::runtime_error. Built by
// run_fuzz.sh, not by the normal build.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "ebslam/events/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/dev/shm/ebslam_fuzz_tum_" + std::to_string(::getpid());
  static const int registered = std::atexit([] { std::remove(path.c_str()); });
  (void)registered;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
  std::fclose(file);
  try {
    const ebslam::Trajectory trajectory = ebslam::readTumTrajectory(path);
    ebslam::validateTrajectory(trajectory);  // throws std::invalid_argument => abort below
    if (!trajectory.empty()) {
      const double mid = 0.5 * (trajectory.front().t_s + trajectory.back().t_s);
      const ebslam::StampedPose p = ebslam::interpolatePose(trajectory, mid);
      if (!p.position.allFinite() || !p.orientation.coeffs().allFinite()) std::abort();
    }
  } catch (const std::runtime_error&) {
    // malformed input, reported with file:line: the expected outcome for most inputs
  } catch (...) {
    std::abort();
  }
  return 0;
}
