#include "ebslam/slam/fast_normal_generator.h"

#include <cmath>
#include <cstddef>
#include <vector>

namespace ebslam {

namespace {

constexpr int kNormalTableBits = FastNormalGenerator::kTableBits;
constexpr std::size_t kNormalTableSize = std::size_t{1} << kNormalTableBits;

double inverseNormalCdf(double p) {
  // Bisection on Phi(x) = 0.5 erfc(-x / sqrt 2): robust in the far tails, run once per table.
  double lo = -10.0;
  double hi = 10.0;
  for (int it = 0; it < 64; ++it) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

const std::vector<float>& normalTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kNormalTableSize);
    for (std::size_t i = 0; i < kNormalTableSize; ++i) {
      t[i] = static_cast<float>(
          inverseNormalCdf((static_cast<double>(i) + 0.5) / static_cast<double>(kNormalTableSize)));
    }
    return t;
  }();
  return table;
}

std::uint64_t splitMix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

FastNormalGenerator::FastNormalGenerator(std::uint64_t seed) {
  for (auto& s : state_) s = splitMix64(seed);
  table_ = normalTable().data();  // built once, outside any timed loop
}

}  // namespace ebslam
