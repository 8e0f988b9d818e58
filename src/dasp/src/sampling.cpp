// Seed sampling (thesis §2.3): density pyramid, SPDS alg. 1 and alg. 2, white noise, grid.
#include "dasp/sampling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace dasp {
namespace {

void requireDensity(const cv::Mat& density) {
  if (density.empty()) throw std::invalid_argument("sampling: density is empty");
  if (density.type() != CV_32FC1) throw std::invalid_argument("sampling: density must be CV_32FC1");
  // One pass: NaN, infinity and negative values all fail 0 <= value <= FLT_MAX.
  int unusable = 0;
  for (int row = 0; row < density.rows; ++row) {
    const float* p = density.ptr<float>(row);
    for (int col = 0; col < density.cols; ++col) {
      unusable += (p[col] >= 0.0f) & (p[col] <= std::numeric_limits<float>::max()) ? 0 : 1;
    }
  }
  if (unusable > 0) {
    throw std::invalid_argument("sampling: density must be finite and >= 0 (no NaN or infinity)");
  }
}

// Uniform double in [0, 1) from 53 random bits (portable across standard libraries).
class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : engine_(seed) {}
  double operator()() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

 private:
  std::mt19937_64 engine_;
};

// eq. 2.9
int randomRound(double x, Uniform& uniform) {
  const double lower = std::floor(x);
  return static_cast<int>(lower) + (uniform() < x - lower ? 1 : 0);
}

class SpdsSampler {
 public:
  SpdsSampler(const DensityPyramid& pyramid, Uniform& uniform, std::vector<Seed>& out)
      : pyramid_(pyramid), uniform_(uniform), out_(out) {}

  // Picks a pixel inside node (l, x, y) with probability proportional to rho_0 (eq. 2.8) by
  // descending the pyramid, choosing children by their mass.
  void placeIn(int l, int x, int y) {
    while (l > 0) {
      std::array<double, 4> weights{};
      double total = 0.0;
      for (int e = 0; e < 4; ++e) {
        weights[e] = pyramid_.mass(l - 1, 2 * x + (e & 1), 2 * y + (e >> 1));
        total += weights[e];
      }
      double r = uniform_() * total;
      int chosen = 3;
      for (int e = 0; e < 4; ++e) {
        if (r < weights[e]) {
          chosen = e;
          break;
        }
        r -= weights[e];
      }
      while (weights[chosen] <= 0.0 && chosen > 0) --chosen;  // rounding at the end of the range
      x = 2 * x + (chosen & 1);
      y = 2 * y + (chosen >> 1);
      --l;
    }
    out_.push_back({static_cast<float>(x), static_cast<float>(y)});
  }

  // alg. 1
  void basic(int l, int x, int y) {
    const double mass = pyramid_.mass(l, x, y);
    if (mass <= 0.0) return;
    if (mass <= 1.0) {
      if (uniform_() < mass) placeIn(l, x, y);
      return;
    }
    if (l == 0) {  // a single pixel with more than one expected point
      const int count = randomRound(mass, uniform_);
      for (int i = 0; i < count; ++i) placeIn(0, x, y);
      return;
    }
    for (int e = 0; e < 4; ++e) basic(l - 1, 2 * x + (e & 1), 2 * y + (e >> 1));
  }

  // alg. 2
  void improved(int l, int x, int y) {
    const double mass = pyramid_.mass(l, x, y);
    if (mass <= 0.0) return;
    if (l == 0) {
      const int count = randomRound(mass, uniform_);
      for (int i = 0; i < count; ++i) placeIn(0, x, y);
      return;
    }
    if (mass > 4.0) {
      for (int e = 0; e < 4; ++e) improved(l - 1, 2 * x + (e & 1), 2 * y + (e >> 1));
      return;
    }
    int count = randomRound(mass, uniform_);
    std::array<double, 4> weights{};
    for (int e = 0; e < 4; ++e)
      weights[e] = pyramid_.mass(l - 1, 2 * x + (e & 1), 2 * y + (e >> 1));
    // Choose `count` distinct children by weight (without replacement); only if fewer children
    // than points have mass, children are reused.
    std::array<double, 4> remaining = weights;
    while (count > 0) {
      double total = remaining[0] + remaining[1] + remaining[2] + remaining[3];
      if (total <= 0.0) {
        remaining = weights;
        total = remaining[0] + remaining[1] + remaining[2] + remaining[3];
      }
      double r = uniform_() * total;
      int chosen = -1;
      for (int e = 0; e < 4; ++e) {
        if (remaining[e] <= 0.0) continue;
        chosen = e;
        if (r < remaining[e]) break;
        r -= remaining[e];
      }
      remaining[chosen] = 0.0;
      placeIn(l - 1, 2 * x + (chosen & 1), 2 * y + (chosen >> 1));
      --count;
    }
  }

 private:
  const DensityPyramid& pyramid_;
  Uniform& uniform_;
  std::vector<Seed>& out_;
};

}  // namespace

DensityPyramid::DensityPyramid(const cv::Mat& density) {
  requireDensity(density);
  cv::Mat base;
  density.convertTo(base, CV_64F);
  level_.push_back(base);
  while (level_.back().rows > 1 || level_.back().cols > 1) {
    const cv::Mat& fine = level_.back();
    cv::Mat coarse((fine.rows + 1) / 2, (fine.cols + 1) / 2, CV_64F);
    const int pairs = fine.cols / 2;  // full 2x2 blocks per row pair; an odd column is added last
    for (int row = 0; row < coarse.rows; ++row) {
      const double* top = fine.ptr<double>(2 * row);
      const double* bottom = 2 * row + 1 < fine.rows ? fine.ptr<double>(2 * row + 1) : nullptr;
      double* dst = coarse.ptr<double>(row);
      // Summed in the order top left, top right, bottom left, bottom right.
      for (int col = 0; col < pairs; ++col) dst[col] = top[2 * col] + top[2 * col + 1];
      if (fine.cols % 2 != 0) dst[pairs] = top[fine.cols - 1];
      if (bottom != nullptr) {
        for (int col = 0; col < pairs; ++col) {
          dst[col] = dst[col] + bottom[2 * col] + bottom[2 * col + 1];
        }
        if (fine.cols % 2 != 0) dst[pairs] += bottom[fine.cols - 1];
      }
    }
    level_.push_back(coarse);
  }
}

double DensityPyramid::mass(int l, int x, int y) const {
  const cv::Mat& m = level_[static_cast<std::size_t>(l)];
  if (x < 0 || y < 0 || x >= m.cols || y >= m.rows) return 0.0;
  return m.at<double>(y, x);
}

std::vector<Seed> sampleSpds(const cv::Mat& density, bool improved, std::uint64_t seed) {
  const DensityPyramid pyramid(density);
  Uniform uniform(seed);
  std::vector<Seed> seeds;
  seeds.reserve(static_cast<std::size_t>(pyramid.mass(pyramid.levels() - 1, 0, 0) * 1.2) + 16);
  SpdsSampler sampler(pyramid, uniform, seeds);
  if (improved) {
    sampler.improved(pyramid.levels() - 1, 0, 0);
  } else {
    sampler.basic(pyramid.levels() - 1, 0, 0);
  }
  return seeds;
}

std::vector<Seed> sampleRandom(const cv::Mat& density, std::uint64_t seed) {
  requireDensity(density);
  std::vector<double> cumulative(static_cast<std::size_t>(density.total()));
  double sum = 0.0;
  for (int row = 0; row < density.rows; ++row) {
    const float* p = density.ptr<float>(row);
    for (int col = 0; col < density.cols; ++col) {
      sum += p[col];
      cumulative[static_cast<std::size_t>(row) * density.cols + col] = sum;
    }
  }
  const long long count = std::llround(sum);
  std::vector<Seed> seeds;
  if (count <= 0) return seeds;
  seeds.reserve(static_cast<std::size_t>(count));
  Uniform uniform(seed);
  for (long long i = 0; i < count; ++i) {
    const double target = uniform() * sum;
    auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
    if (it == cumulative.end()) --it;
    const long long index = it - cumulative.begin();
    seeds.push_back(
        {static_cast<float>(index % density.cols), static_cast<float>(index / density.cols)});
  }
  return seeds;
}

std::vector<Seed> sampleGrid(const cv::Mat& density) {
  requireDensity(density);
  double sum = 0.0;
  long long positive = 0;
  for (int row = 0; row < density.rows; ++row) {
    const float* p = density.ptr<float>(row);
    for (int col = 0; col < density.cols; ++col) {
      sum += p[col];
      positive += p[col] > 0.0f ? 1 : 0;
    }
  }
  std::vector<Seed> seeds;
  if (positive == 0 || sum <= 0.0) return seeds;
  const double spacing = 1.0 / std::sqrt(sum / static_cast<double>(positive));
  const int cols = std::max(1, static_cast<int>(std::lround(density.cols / spacing)));
  const int rows = std::max(1, static_cast<int>(std::lround(density.rows / spacing)));
  const double step_x = static_cast<double>(density.cols) / cols;
  const double step_y = static_cast<double>(density.rows) / rows;
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      const int x = std::min(density.cols - 1, static_cast<int>((i + 0.5) * step_x));
      const int y = std::min(density.rows - 1, static_cast<int>((j + 0.5) * step_y));
      if (density.at<float>(y, x) > 0.0f) {
        seeds.push_back({static_cast<float>(x), static_cast<float>(y)});
      }
    }
  }
  return seeds;
}

std::vector<Seed> sampleSeeds(const cv::Mat& density, SeedingMethod method, std::uint64_t seed) {
  switch (method) {
    case SeedingMethod::kSpds:
      return sampleSpds(density, false, seed);
    case SeedingMethod::kSpdsImproved:
      return sampleSpds(density, true, seed);
    case SeedingMethod::kRandom:
      return sampleRandom(density, seed);
    case SeedingMethod::kGrid:
      return sampleGrid(density);
  }
  throw std::invalid_argument("sampleSeeds: unknown seeding method");
}

}  // namespace dasp
