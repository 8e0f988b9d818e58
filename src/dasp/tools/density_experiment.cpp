// The Adaptive Superpixels experiment of thesis fig. 2.11: relative density error E_rel
// (eq. 2.15) of the superpixel centres against the number of DALIC iterations, for white-noise
// (random) seeding and Simplified Poisson Disc Sampling (alg. 1 and alg. 2), averaged over a set
// of synthetic density functions (in the spirit of fig. 2.13) and several seeds.
//
// Usage: dasp_density_experiment [--out results.csv] [--iterations 10] [--size 256]
//                                [--points 500] [--seeds 3]
// Prints the mean error per method and iteration and writes every measurement as CSV
// (density,method,seed,iteration,points,relative_density_error).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dalic.h"
#include "dasp/features.h"
#include "dasp/metrics.h"
#include "dasp/sampling.h"

namespace {

using dasp::SeedingMethod;

struct DensityFunction {
  std::string name;
  std::function<double(double, double)> value;  // of normalised coordinates in [0, 1]^2
};

std::vector<DensityFunction> densityFunctions() {
  constexpr double kPi = 3.14159265358979323846;
  const auto gauss = [](double x, double y, double cx, double cy, double s) {
    return std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2.0 * s * s));
  };
  return {
      {"constant", [](double, double) { return 1.0; }},
      {"ramp", [](double x, double) { return 0.2 + x; }},
      {"diagonal", [](double x, double y) { return 0.1 + (x + y) * (x + y); }},
      {"blob", [=](double x, double y) { return 0.1 + gauss(x, y, 0.4, 0.6, 0.15); }},
      {"two_blobs",
       [=](double x, double y) {
         return 0.05 + gauss(x, y, 0.25, 0.3, 0.1) + 0.6 * gauss(x, y, 0.7, 0.7, 0.12);
       }},
      {"ring",
       [=](double x, double y) {
         const double r = std::hypot(x - 0.5, y - 0.5);
         return 0.1 + std::exp(-(r - 0.3) * (r - 0.3) / (2.0 * 0.05 * 0.05));
       }},
      {"stripes", [=](double x, double) { return 1.1 + std::sin(6.0 * kPi * x); }},
      {"checker",
       [=](double x, double y) { return 1.2 + std::sin(4.0 * kPi * x) * std::sin(4.0 * kPi * y); }},
      {"step", [](double x, double) { return 0.25 + 1.0 / (1.0 + std::exp(-(x - 0.5) / 0.03)); }},
      {"fovea", [](double x, double y) { return 1.0 / (0.05 + std::hypot(x - 0.6, y - 0.45)); }},
  };
}

cv::Mat sampleDensity(const DensityFunction& function, int size, int points) {
  cv::Mat density(size, size, CV_32FC1);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      density.at<float>(y, x) =
          static_cast<float>(function.value((x + 0.5) / size, (y + 0.5) / size));
    }
  }
  density *= points / cv::sum(density)[0];  // density of weight `points` (def. 2)
  return density;
}

std::vector<cv::Point2d> toPoints(const std::vector<dasp::Cluster>& clusters) {
  std::vector<cv::Point2d> points;
  points.reserve(clusters.size());
  for (const dasp::Cluster& c : clusters) points.emplace_back(c.u, c.v);
  return points;
}

std::vector<cv::Point2d> toPoints(const std::vector<dasp::Seed>& seeds) {
  std::vector<cv::Point2d> points;
  points.reserve(seeds.size());
  for (const dasp::Seed& s : seeds) points.emplace_back(s.u, s.v);
  return points;
}

int run(int argc, char** argv) {
  std::string out_path = "density_experiment.csv";
  int iterations = 10, size = 256, points = 500, seeds = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + arg);
      return argv[++i];
    };
    if (arg == "--out") {
      out_path = next();
    } else if (arg == "--iterations") {
      iterations = std::stoi(next());
    } else if (arg == "--size") {
      size = std::stoi(next());
    } else if (arg == "--points") {
      points = std::stoi(next());
    } else if (arg == "--seeds") {
      seeds = std::stoi(next());
    } else {
      std::fprintf(stderr,
                   "usage: %s [--out file.csv] [--iterations N] [--size S] [--points P] "
                   "[--seeds n]\n",
                   argv[0]);
      return arg == "--help" || arg == "-h" ? 0 : 2;
    }
  }
  if (iterations < 0 || size < 8 || points < 1 || points > size * size || seeds < 1) {
    throw std::invalid_argument(
        "need iterations >= 0, size >= 8, 1 <= points <= size^2, seeds >= 1");
  }
  const std::vector<std::pair<std::string, SeedingMethod>> methods = {
      {"random", SeedingMethod::kRandom},
      {"spds_alg1", SeedingMethod::kSpds},
      {"spds_alg2", SeedingMethod::kSpdsImproved}};
  std::ofstream csv(out_path);
  if (!csv) throw std::runtime_error("cannot write " + out_path);
  csv << "density,method,seed,iteration,points,relative_density_error\n";
  // Colour carries no information here: DALIC is driven by the density-adaptive compactness
  // term alone (def. 7 with d_F = 0), as in the thesis' evaluation of the distribution.
  const dasp::PixelFeatures features =
      dasp::computeColorFeatures(cv::Mat(size, size, CV_8UC3, cv::Scalar::all(128)));
  std::map<std::string, std::vector<double>> mean;  // method -> per iteration
  for (const auto& entry : methods) mean[entry.first].assign(iterations + 1, 0.0);
  const std::vector<DensityFunction> functions = densityFunctions();
  const double runs = static_cast<double>(functions.size()) * seeds;
  for (const DensityFunction& function : functions) {
    const cv::Mat density = sampleDensity(function, size, points);
    for (const auto& [method_name, method] : methods) {
      for (int seed = 0; seed < seeds; ++seed) {
        const std::vector<dasp::Seed> initial =
            dasp::sampleSeeds(density, method, static_cast<std::uint64_t>(seed));
        dasp::DalicParams params;
        params.metric = dasp::MetricKind::kColor2D;
        params.weight_color = 0.0f;
        params.weight_spatial = 1.0f;
        params.window_multiple = 2.0f;
        params.min_size_fraction = 0.0f;
        params.target_count = 0;
        dasp::Dalic dalic(features, density, params);
        dalic.initialize(initial);
        for (int it = 0; it <= iterations; ++it) {
          if (it > 0) dalic.iterate();
          const std::vector<cv::Point2d> current =
              it == 0 ? toPoints(initial) : toPoints(dalic.clusters());
          const double error = dasp::metrics::relativeDensityError(density, current);
          mean[method_name][static_cast<std::size_t>(it)] += error / runs;
          csv << function.name << ',' << method_name << ',' << seed << ',' << it << ','
              << current.size() << ',' << error << '\n';
        }
      }
    }
  }
  std::printf(
      "mean relative density error E_rel (eq. 2.15) over %zu densities x %d seeds, "
      "%dx%d, %d points\n",
      functions.size(), seeds, size, size, points);
  std::printf("%-10s", "iteration");
  for (const auto& entry : methods) std::printf(" %12s", entry.first.c_str());
  std::printf("\n");
  for (int it = 0; it <= iterations; ++it) {
    std::printf("%-10d", it);
    for (const auto& entry : methods) {
      std::printf(" %12.4f", mean[entry.first][static_cast<std::size_t>(it)]);
    }
    std::printf("\n");
  }
  const double spds_end = mean["spds_alg2"].back(), random_end = mean["random"].back();
  std::printf("after %d iterations: SPDS (alg. 2) %.4f vs random %.4f -> SPDS ends %s\n",
              iterations, spds_end, random_end, spds_end < random_end ? "lower" : "NOT lower");
  std::printf("wrote %s\n", out_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
