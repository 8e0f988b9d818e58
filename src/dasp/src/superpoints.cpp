// Connectivity enforcement and the superpoint fit (thesis §3.2.3).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

#include "dasp/stages.h"
#include "point_moments.h"

namespace dasp {
namespace {
constexpr double kPiD = 3.14159265358979323846;
}  // namespace

namespace {

// Union-find over label runs with path halving.
int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

int enforceConnectivity(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                        double min_weight, const cv::Mat& depth, float depth_jump_ratio) {
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
  if (!depth.empty() &&
      (depth.type() != CV_32FC1 || depth.size() != labels.size() || !depth.isContinuous())) {
    throw std::invalid_argument(
        "enforceConnectivity: depth must be a continuous CV_32FC1 of the labels' size");
  }
  if (!depth.empty() && !(depth_jump_ratio > 0.0f)) {
    throw std::invalid_argument("enforceConnectivity: depth_jump_ratio must be positive");
  }
  const int width = labels.cols;
  const int height = labels.rows;
  int* label = labels.ptr<int>();
  // Two neighbouring pixels are connected unless a depth jump lies between them.
  const float* z = depth.empty() ? nullptr : depth.ptr<float>();
  const auto connected = [z, depth_jump_ratio](std::size_t a, std::size_t b) {
    if (z == nullptr) return true;
    const float za = z[a], zb = z[b];
    return std::abs(za - zb) <= depth_jump_ratio * std::min(za, zb);
  };
  const std::uint8_t* ok = valid.empty() ? nullptr : valid.ptr<std::uint8_t>();
  const float* pixel_weight = weight.empty() ? nullptr : weight.ptr<float>();

  // Horizontal runs of equal label over usable pixels; unlabelled usable pixels (-1) form runs
  // too, which are then merged like stray pieces.
  struct Run {
    int row, begin, end, label;
  };
  std::vector<Run> runs;
  runs.reserve(static_cast<std::size_t>(height) * 32);
  std::vector<int> row_first(static_cast<std::size_t>(height) + 1, 0);
  std::vector<int> run_of_pixel(labels.total(), -1);
  for (int row = 0; row < height; ++row) {
    row_first[static_cast<std::size_t>(row)] = static_cast<int>(runs.size());
    const std::size_t base = static_cast<std::size_t>(row) * width;
    int col = 0;
    while (col < width) {
      if (ok != nullptr && !ok[base + col]) {
        ++col;
        continue;
      }
      const int value = label[base + col];
      int end = col + 1;
      while (end < width && (ok == nullptr || ok[base + end]) && label[base + end] == value &&
             connected(base + end - 1, base + end)) {
        ++end;
      }
      const int id = static_cast<int>(runs.size());
      runs.push_back({row, col, end, value});
      std::fill(run_of_pixel.begin() + static_cast<std::ptrdiff_t>(base + col),
                run_of_pixel.begin() + static_cast<std::ptrdiff_t>(base + end), id);
      col = end;
    }
  }
  row_first[static_cast<std::size_t>(height)] = static_cast<int>(runs.size());
  const int run_count = static_cast<int>(runs.size());

  // Connect runs of equal label that overlap in consecutive rows (4-neighbourhood).
  std::vector<int> parent(static_cast<std::size_t>(run_count));
  for (int r = 0; r < run_count; ++r) parent[r] = r;
  for (int row = 1; row < height; ++row) {
    int q = row_first[row - 1];
    const int q_end = row_first[row];
    for (int r = row_first[row]; r < row_first[row + 1]; ++r) {
      while (q < q_end && runs[q].end <= runs[r].begin) ++q;
      for (int p = q; p < q_end && runs[p].begin < runs[r].end; ++p) {
        if (runs[p].label != runs[r].label) continue;
        if (z != nullptr) {
          const std::size_t base = static_cast<std::size_t>(row) * width;
          bool touching = false;
          const int overlap_end = std::min(runs[p].end, runs[r].end);
          for (int x = std::max(runs[p].begin, runs[r].begin); x < overlap_end && !touching; ++x) {
            touching = connected(base + x - width, base + x);
          }
          if (!touching) continue;
        }
        const int a = findRoot(parent, p), b = findRoot(parent, r);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  // Components, their pixel weight and their runs (bucketed by component).
  std::vector<int> component_of_run(static_cast<std::size_t>(run_count));
  std::vector<int> component_of_root(static_cast<std::size_t>(run_count), -1);
  std::vector<int> component_label;
  std::vector<double> component_weight;
  std::vector<int> component_size;
  for (int r = 0; r < run_count; ++r) {
    const int root = findRoot(parent, r);
    int& c = component_of_root[root];
    if (c < 0) {
      c = static_cast<int>(component_label.size());
      component_label.push_back(runs[r].label);
      component_weight.push_back(0.0);
      component_size.push_back(0);
    }
    component_of_run[r] = c;
    const Run& run = runs[r];
    component_size[c] += run.end - run.begin;
    if (pixel_weight == nullptr) {
      component_weight[c] += run.end - run.begin;
    } else {
      const float* w = pixel_weight + static_cast<std::size_t>(run.row) * width;
      float sum = 0.0f;
      for (int x = run.begin; x < run.end; ++x) sum += w[x];
      component_weight[c] += sum;
    }
  }
  const int component_count = static_cast<int>(component_label.size());

  // The largest piece of each label keeps it.
  int max_label = -1;
  for (int value : component_label) max_label = std::max(max_label, value);
  std::vector<int> largest(static_cast<std::size_t>(max_label + 1), -1);
  for (int c = 0; c < component_count; ++c) {
    const int value = component_label[c];
    if (value < 0) continue;
    int& best = largest[static_cast<std::size_t>(value)];
    if (best < 0 || component_size[c] > component_size[best]) best = c;
  }
  constexpr int kUnresolved = -2;
  std::vector<int> final_label(static_cast<std::size_t>(component_count), kUnresolved);
  for (int value = 0; value <= max_label; ++value) {
    const int c = largest[static_cast<std::size_t>(value)];
    if (c >= 0 && component_weight[c] >= min_weight) final_label[c] = value;
  }
  int next_new_label = max_label + 1;

  // Runs of the unresolved components, grouped by component.
  std::vector<int> stray_start(static_cast<std::size_t>(component_count) + 1, 0);
  for (int r = 0; r < run_count; ++r) {
    if (final_label[component_of_run[r]] == kUnresolved) ++stray_start[component_of_run[r] + 1];
  }
  for (int c = 0; c < component_count; ++c) stray_start[c + 1] += stray_start[c];
  std::vector<int> stray_runs(static_cast<std::size_t>(stray_start[component_count]));
  {
    std::vector<int> fill(stray_start.begin(), stray_start.end() - 1);
    for (int r = 0; r < run_count; ++r) {
      const int c = component_of_run[r];
      if (final_label[c] == kUnresolved) stray_runs[fill[c]++] = r;
    }
  }

  // Stray pieces join the resolved neighbour with the longest shared border; repeat while
  // pieces that only touch other stray pieces get resolved through them.
  std::vector<std::pair<int, int>> border;  // (label, border length)
  // Borders across a depth jump count only for pieces that have no other way to a label.
  bool across_jumps = z == nullptr;
  const auto tally = [&](int c, std::size_t from, std::size_t pixel) {
    if (!across_jumps && !connected(from, pixel)) return;
    const int r = run_of_pixel[pixel];
    if (r < 0) return;
    const int other = component_of_run[r];
    if (other == c) return;
    const int value = final_label[other];
    if (value < 0) return;
    auto it = std::find_if(border.begin(), border.end(),
                           [value](const auto& entry) { return entry.first == value; });
    if (it == border.end()) {
      border.push_back({value, 1});
    } else {
      ++it->second;
    }
  };
  bool changed = true;
  while (changed || !across_jumps) {
    if (!changed) across_jumps = true;  // second round: pieces walled in by depth jumps
    changed = false;
    for (int c = 0; c < component_count; ++c) {
      if (final_label[c] != kUnresolved) continue;
      border.clear();
      for (int s = stray_start[c]; s < stray_start[c + 1]; ++s) {
        const Run& run = runs[stray_runs[s]];
        const std::size_t base = static_cast<std::size_t>(run.row) * width;
        if (run.begin > 0) tally(c, base + run.begin, base + run.begin - 1);
        if (run.end < width) tally(c, base + run.end - 1, base + run.end);
        for (int x = run.begin; x < run.end; ++x) {
          if (run.row > 0) tally(c, base + x, base - width + x);
          if (run.row + 1 < height) tally(c, base + x, base + width + x);
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

  // Renumber 0..m-1 in order of first appearance; pixels outside any run become -1.
  std::vector<int> renumber(static_cast<std::size_t>(next_new_label), -1);
  int count = 0;
  std::fill(label, label + labels.total(), -1);
  for (int r = 0; r < run_count; ++r) {
    const int value = final_label[component_of_run[r]];
    if (value < 0) continue;
    int& mapped = renumber[static_cast<std::size_t>(value)];
    if (mapped < 0) mapped = count++;
    const Run& run = runs[r];
    int* row_labels = label + static_cast<std::size_t>(run.row) * width;
    std::fill(row_labels + run.begin, row_labels + run.end, mapped);
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
  // Runs of equal labels are summed in float registers (relative to the label's first point),
  // then added to the double totals.
  const float* rho = density.empty() ? nullptr : density.ptr<float>();
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    const std::size_t base = static_cast<std::size_t>(row) * features.width;
    int col = 0;
    while (col < labels.cols) {
      const int k = l[col];
      int end = col + 1;
      while (end < labels.cols && l[end] == k) ++end;
      if (k >= 0) {
        Sums& s = sums[static_cast<std::size_t>(k)];
        if (depth && s.n == 0.0) {
          s.reference = Eigen::Vector3d(features.x[base + col], features.y[base + col],
                                        features.z[base + col]);
        }
        const double run = end - col;
        s.n += run;
        s.u += 0.5 * run * (col + end - 1);
        s.v += run * row;
        float sr = 0, sg = 0, sb = 0, srho = 0;
        for (int x = col; x < end; ++x) {
          sr += features.r[base + x];
          sg += features.g[base + x];
          sb += features.b[base + x];
          if (rho != nullptr) srho += rho[base + x];
        }
        s.color += Eigen::Vector3d(sr, sg, sb);
        s.density += srho;
        if (depth) {
          const float rx = static_cast<float>(s.reference.x());
          const float ry = static_cast<float>(s.reference.y());
          const float rz = static_cast<float>(s.reference.z());
          const detail::PointMoments m =
              detail::sumPointMoments(features.x.data() + base, features.y.data() + base,
                                      features.z.data() + base, col, end, rx, ry, rz);
          float snx = 0, sny = 0, snz = 0;
          for (int x = col; x < end; ++x) {
            snx += features.nx[base + x];
            sny += features.ny[base + x];
            snz += features.nz[base + x];
          }
          s.position += Eigen::Vector3d(m.sx, m.sy, m.sz);
          Eigen::Matrix3d scatter;
          scatter << m.sxx, m.sxy, m.sxz, m.sxy, m.syy, m.syz, m.sxz, m.syz, m.szz;
          s.scatter += scatter;
          s.normal += Eigen::Vector3d(snx, sny, snz);
        }
      }
      col = end;
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
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(cov);  // closed form: per-superpixel cost must not grow with K
    const Eigen::Vector3d w = solver.eigenvalues().cwiseMax(0.0);  // ascending
    // Plane-fit normal (eq. 3.22) where the points span a plane; for fewer than 3 points or
    // points on a line (second principal variance under 1 % of the first) the mean pixel normal.
    const bool plane = s.n >= 3.0 && w(1) > 0.01 * w(2);
    Eigen::Vector3d normal = plane ? Eigen::Vector3d(solver.eigenvectors().col(0)) : s.normal;
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
