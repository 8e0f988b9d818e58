// Connectivity enforcement and the superpoint fit (thesis §3.2.3).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

#include "dasp/stages.h"

namespace dasp {
namespace {
constexpr double kPiD = 3.14159265358979323846;
}  // namespace

int enforceConnectivity(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                        double min_weight) {
  if (labels.type() != CV_32SC1 || !labels.isContinuous()) {
    throw std::invalid_argument("enforceConnectivity: labels must be a continuous CV_32SC1");
  }
  if (!valid.empty() &&
      (valid.type() != CV_8UC1 || valid.size() != labels.size() || !valid.isContinuous())) {
    throw std::invalid_argument(
        "enforceConnectivity: valid must be a continuous CV_8UC1 of the labels' size");
  }
  if (!weight.empty() &&
      (weight.type() != CV_32FC1 || weight.size() != labels.size() || !weight.isContinuous())) {
    throw std::invalid_argument(
        "enforceConnectivity: weight must be a continuous CV_32FC1 of the labels' size");
  }
  const int width = labels.cols;
  const int height = labels.rows;
  const std::size_t n = labels.total();
  const float* pixel_weight = weight.empty() ? nullptr : weight.ptr<float>();
  int* label = labels.ptr<int>();
  const std::uint8_t* ok = valid.empty() ? nullptr : valid.ptr<std::uint8_t>();
  const auto usable = [&](std::size_t i) { return ok == nullptr || ok[i] != 0; };

  // Connected components (4-neighbourhood) of equal label over usable pixels; unlabelled usable
  // pixels (-1) form components too, which are then merged like stray pieces.
  std::vector<int> component(n, -1);
  std::vector<int> pixels;  // pixel indices grouped by component
  pixels.reserve(n);
  std::vector<int> start;  // component c: pixels[start[c] .. start[c + 1])
  std::vector<int> component_label;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (component[seed] >= 0 || !usable(seed)) continue;
    const int c = static_cast<int>(start.size());
    const int value = label[seed];
    start.push_back(static_cast<int>(pixels.size()));
    component_label.push_back(value);
    component[seed] = c;
    pixels.push_back(static_cast<int>(seed));
    for (std::size_t head = static_cast<std::size_t>(start.back()); head < pixels.size(); ++head) {
      const int i = pixels[head];
      const int x = i % width;
      const int y = i / width;
      const int neighbours[4] = {x > 0 ? i - 1 : -1, x + 1 < width ? i + 1 : -1,
                                 y > 0 ? i - width : -1, y + 1 < height ? i + width : -1};
      for (int j : neighbours) {
        if (j < 0) continue;
        const auto uj = static_cast<std::size_t>(j);
        if (component[uj] >= 0 || !usable(uj) || label[uj] != value) continue;
        component[uj] = c;
        pixels.push_back(j);
      }
    }
  }
  const int component_count = static_cast<int>(start.size());
  start.push_back(static_cast<int>(pixels.size()));
  const auto size_of = [&](int c) { return start[c + 1] - start[c]; };
  std::vector<double> component_weight(static_cast<std::size_t>(component_count), 0.0);
  for (int c = 0; c < component_count; ++c) {
    if (pixel_weight == nullptr) {
      component_weight[c] = size_of(c);
      continue;
    }
    double sum = 0.0;
    for (int p = start[c]; p < start[c + 1]; ++p) sum += pixel_weight[pixels[p]];
    component_weight[c] = sum;
  }

  // The largest piece of each label keeps it.
  int max_label = -1;
  for (int value : component_label) max_label = std::max(max_label, value);
  std::vector<int> largest(static_cast<std::size_t>(max_label + 1), -1);
  for (int c = 0; c < component_count; ++c) {
    const int value = component_label[c];
    if (value < 0) continue;
    int& best = largest[static_cast<std::size_t>(value)];
    if (best < 0 || size_of(c) > size_of(best)) best = c;
  }
  constexpr int kUnresolved = -2;
  std::vector<int> final_label(static_cast<std::size_t>(component_count), kUnresolved);
  for (int value = 0; value <= max_label; ++value) {
    const int c = largest[static_cast<std::size_t>(value)];
    if (c >= 0 && component_weight[c] >= min_weight) final_label[c] = value;
  }
  int next_new_label = max_label + 1;

  // Stray pieces join the resolved neighbour with the longest shared border; repeat while
  // pieces that only touch other stray pieces get resolved through them.
  std::vector<std::pair<int, int>> border;  // (label, border length)
  bool changed = true;
  while (changed) {
    changed = false;
    for (int c = 0; c < component_count; ++c) {
      if (final_label[c] != kUnresolved) continue;
      border.clear();
      for (int p = start[c]; p < start[c + 1]; ++p) {
        const int i = pixels[p];
        const int x = i % width;
        const int y = i / width;
        const int neighbours[4] = {x > 0 ? i - 1 : -1, x + 1 < width ? i + 1 : -1,
                                   y > 0 ? i - width : -1, y + 1 < height ? i + width : -1};
        for (int j : neighbours) {
          if (j < 0) continue;
          const int other = component[static_cast<std::size_t>(j)];
          if (other < 0 || other == c) continue;
          const int value = final_label[other];
          if (value < 0) continue;
          auto it = std::find_if(border.begin(), border.end(),
                                 [value](const auto& entry) { return entry.first == value; });
          if (it == border.end()) {
            border.push_back({value, 1});
          } else {
            ++it->second;
          }
        }
      }
      if (border.empty()) continue;
      auto best = border.begin();
      for (auto it = border.begin(); it != border.end(); ++it) {
        if (it->second > best->second || (it->second == best->second && it->first < best->first)) {
          best = it;
        }
      }
      final_label[c] = best->first;
      changed = true;
    }
  }
  // Islands that touch no label (e.g. surrounded by invalid depth).
  for (int c = 0; c < component_count; ++c) {
    if (final_label[c] != kUnresolved) continue;
    final_label[c] = component_weight[c] >= min_weight ? next_new_label++ : -1;
  }

  // Renumber 0..m-1 in order of first appearance.
  std::vector<int> renumber(static_cast<std::size_t>(next_new_label), -1);
  int count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int c = component[i];
    if (c < 0) {
      label[i] = -1;
      continue;
    }
    const int value = final_label[c];
    if (value < 0) {
      label[i] = -1;
      continue;
    }
    int& mapped = renumber[static_cast<std::size_t>(value)];
    if (mapped < 0) mapped = count++;
    label[i] = mapped;
  }
  return count;
}

std::vector<Superpixel> fitSuperpoints(const cv::Mat& labels, const PixelFeatures& features,
                                       const cv::Mat& density, float radius_m) {
  if (labels.type() != CV_32SC1 || labels.cols != features.width ||
      labels.rows != features.height) {
    throw std::invalid_argument("fitSuperpoints: labels must be CV_32SC1 of the features' size");
  }
  if (!density.empty() && (density.type() != CV_32FC1 || density.size() != labels.size())) {
    throw std::invalid_argument("fitSuperpoints: density must be CV_32FC1 of the labels' size");
  }
  double max_value = -1.0;
  cv::minMaxLoc(labels, nullptr, &max_value);
  const int count = static_cast<int>(max_value) + 1;
  struct Sums {
    double n = 0, u = 0, v = 0, density = 0;
    Eigen::Vector3d color = Eigen::Vector3d::Zero();
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // first point, for precision
  };
  std::vector<Sums> sums(static_cast<std::size_t>(std::max(0, count)));
  const bool depth = features.hasDepth();
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    for (int col = 0; col < labels.cols; ++col) {
      if (l[col] < 0) continue;
      const std::size_t i = static_cast<std::size_t>(row) * features.width + col;
      Sums& s = sums[static_cast<std::size_t>(l[col])];
      s.n += 1.0;
      s.u += col;
      s.v += row;
      s.color += Eigen::Vector3d(features.r[i], features.g[i], features.b[i]);
      if (!density.empty()) s.density += density.at<float>(row, col);
      if (depth) {
        const Eigen::Vector3d p(features.x[i], features.y[i], features.z[i]);
        if (s.n == 1.0) s.reference = p;
        const Eigen::Vector3d q = p - s.reference;
        s.position += q;
        s.scatter += q * q.transpose();
        s.normal += Eigen::Vector3d(features.nx[i], features.ny[i], features.nz[i]);
      }
    }
  }
  std::vector<Superpixel> out(sums.size());
  for (std::size_t k = 0; k < sums.size(); ++k) {
    const Sums& s = sums[k];
    Superpixel& sp = out[k];
    sp.id = static_cast<int>(k);
    sp.radius_m = radius_m;
    if (s.n <= 0.0) continue;
    sp.pixel_count = static_cast<int>(s.n);
    sp.u = static_cast<float>(s.u / s.n);
    sp.v = static_cast<float>(s.v / s.n);
    sp.color = (s.color / s.n).cast<float>();
    sp.density = static_cast<float>(s.density / s.n);
    if (!depth) continue;
    const Eigen::Vector3d mean = s.position / s.n;
    sp.position = (s.reference + mean).cast<float>();
    const Eigen::Matrix3d cov = s.scatter / s.n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
    const Eigen::Vector3d w = solver.eigenvalues().cwiseMax(0.0);  // ascending
    Eigen::Vector3d normal = s.n >= 3.0 ? Eigen::Vector3d(solver.eigenvectors().col(0)) : s.normal;
    if (!(normal.norm() > 0.0)) normal = -Eigen::Vector3d::UnitZ();
    normal.normalize();
    if (normal.dot(sp.position.cast<double>()) > 0.0) normal = -normal;
    sp.normal = normal.cast<float>();
    // 2-sigma ellipsoid axes (d, b, a) = 2 (sqrt w1, sqrt w2, sqrt w3).
    const double d = 2.0 * std::sqrt(w(0));
    const double b = 2.0 * std::sqrt(w(1));
    const double a = 2.0 * std::sqrt(w(2));
    sp.thickness = static_cast<float>(2.0 * d);
    sp.eccentricity =
        a > 0.0 ? static_cast<float>(std::sqrt(std::max(0.0, 1.0 - b * b / (a * a)))) : 0.0f;
    sp.flatness =
        a > 0.0 ? static_cast<float>(std::sqrt(std::max(0.0, 1.0 - d * d / (a * a)))) : 0.0f;
    sp.area_m2 = static_cast<float>(kPiD * a * b);
  }
  return out;
}

}  // namespace dasp
