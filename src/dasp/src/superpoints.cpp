// Connectivity enforcement and the superpoint fit (thesis §3.2.3).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

#include "dasp/stages.h"
#include "run_sums.h"
#include "simd.h"

namespace dasp {
namespace {
constexpr double kPiD = 3.14159265358979323846;

// Sum of p[begin, end).
float runSum(const float* p, int begin, int end) {
  float s = 0.0f;
  for (int i = begin; i < end; ++i) s += p[i];
  return s;
}

struct FitTotals {
  double n = 0, u = 0, v = 0, density = 0;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // first point, for precision
};

// Runs of equal labels are summed in float registers (relative to the label's first point),
// then added to the double totals. Returns the largest label seen.
template <bool kDepth, bool kRho>
DASP_ALWAYS_INLINE int accumulateFit(const cv::Mat& labels, const PixelFeatures& features,
                                     const float* rho, std::vector<FitTotals>& sums) {
  const int width = labels.cols;
  int max_label = -1;
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    const std::size_t base = static_cast<std::size_t>(row) * features.width;
    const detail::FeatureRow f = detail::featureRow(features, row);
    const float* rho_row = kRho ? rho + base : nullptr;
    int col = 0;
    while (col < width) {
      const int k = l[col];
      const int end = detail::labelRunEnd(l, col, width);
      if (k >= 0) {
        if (k > max_label) {
          max_label = k;
          if (static_cast<std::size_t>(k) >= sums.size()) {
            sums.resize(std::max(static_cast<std::size_t>(k) + 1, 2 * sums.size()));
          }
        }
        FitTotals& s = sums[static_cast<std::size_t>(k)];
        if (kDepth && s.n == 0.0) s.reference = Eigen::Vector3d(f.x[col], f.y[col], f.z[col]);
        const double run = end - col;
        s.n += run;
        s.u += 0.5 * run * (col + end - 1);
        s.v += run * row;
        float m[detail::kRunSums] = {};
        detail::addRunSums<kRho, kDepth, kDepth>(
            f, rho_row, width, col, end, static_cast<float>(s.reference.x()),
            static_cast<float>(s.reference.y()), static_cast<float>(s.reference.z()), m);
        s.color += Eigen::Vector3d(m[detail::kSumR], m[detail::kSumG], m[detail::kSumB]);
        s.density += m[detail::kSumDensity];
        if constexpr (kDepth) {
          const float* moments = m + detail::kSumX;  // x, y, z, xx, xy, xz, yy, yz, zz
          s.position += Eigen::Vector3d(moments[0], moments[1], moments[2]);
          double* c = s.scatter.data();  // symmetric: column-major = row-major
          c[0] += moments[3];
          c[1] += moments[4];
          c[2] += moments[5];
          c[3] += moments[4];
          c[4] += moments[6];
          c[5] += moments[7];
          c[6] += moments[5];
          c[7] += moments[7];
          c[8] += moments[8];
          s.normal += Eigen::Vector3d(m[detail::kSumNx], m[detail::kSumNy], m[detail::kSumNz]);
        }
      }
      col = end;
    }
  }
  return max_label;
}

// The fit's accumulation for each kind of input, built for the vector units of the CPU.
DASP_VECTOR_CLONES int accumulateFitAny(const cv::Mat& labels, const PixelFeatures& features,
                                        const float* rho, std::vector<FitTotals>& sums) {
  if (features.hasDepth()) {
    return rho != nullptr ? accumulateFit<true, true>(labels, features, rho, sums)
                          : accumulateFit<true, false>(labels, features, rho, sums);
  }
  return rho != nullptr ? accumulateFit<false, true>(labels, features, rho, sums)
                        : accumulateFit<false, false>(labels, features, rho, sums);
}

// Union-find over label runs with path halving.
int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Two neighbouring pixels are connected unless a depth jump lies between them.
inline bool depthConnected(float za, float zb, float ratio) {
  return std::abs(za - zb) <= ratio * std::min(za, zb);
}

// Per-pixel run flags of one row: bit 0 = a run starts here (the pixel is not in the run of its
// left neighbour: first column, other label, unusable left neighbour or depth jump), bit 1 = the
// pixel is not usable. flags[width .. width + 7] = 1 (sentinels for the scans).
template <bool kValid, bool kDepth>
DASP_ALWAYS_INLINE void rowFlags(const int* __restrict l, const std::uint8_t* __restrict ok,
                                 const float* __restrict z, float ratio, int width,
                                 std::uint8_t* __restrict flags) {
  flags[0] = static_cast<std::uint8_t>(1 | (kValid && !ok[0] ? 2 : 0));
  for (int x = 1; x < width; ++x) {
    bool start = l[x] != l[x - 1];
    if constexpr (kValid) start |= ok[x - 1] == 0;
    if constexpr (kDepth) start |= !depthConnected(z[x - 1], z[x], ratio);
    int f = start ? 1 : 0;
    if constexpr (kValid) f |= ok[x] == 0 ? 2 : 0;
    flags[x] = static_cast<std::uint8_t>(f);
  }
  std::memset(flags + width, 1, 8);
}

DASP_VECTOR_CLONES void rowFlagsAny(const int* l, const std::uint8_t* ok, const float* z,
                                    float ratio, int width, std::uint8_t* flags) {
  if (ok != nullptr) {
    if (z != nullptr) {
      rowFlags<true, true>(l, ok, z, ratio, width, flags);
    } else {
      rowFlags<true, false>(l, ok, z, ratio, width, flags);
    }
  } else if (z != nullptr) {
    rowFlags<false, true>(l, ok, z, ratio, width, flags);
  } else {
    rowFlags<false, false>(l, ok, z, ratio, width, flags);
  }
}

// Scans of the run flags, eight at a time: the next pixel that starts a run or is unusable
// (flags != 0; the sentinels stop it), and the next usable pixel (bit 1 clear) before width.
inline int nextNonZero(const std::uint8_t* flags, int x) {
#if defined(__GNUC__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  for (;; x += 8) {
    std::uint64_t w;
    std::memcpy(&w, flags + x, 8);
    if (w != 0) return x + __builtin_ctzll(w) / 8;
  }
#else
  while (flags[x] == 0) ++x;
  return x;
#endif
}
inline int nextUsable(const std::uint8_t* flags, int x, int width) {
#if defined(__GNUC__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  while (x + 8 <= width) {
    std::uint64_t w;
    std::memcpy(&w, flags + x, 8);
    const std::uint64_t usable = ~w & 0x0202020202020202ull;
    if (usable != 0) return x + __builtin_ctzll(usable) / 8;
    x += 8;
  }
#endif
  while (x < width && (flags[x] & 2) != 0) ++x;
  return x;
}

struct Run {
  int row, begin, end, label;
};

// Working memory of enforceConnectivity, O(runs) (a frame has some 20 000 runs). A thread_local
// copy measured no faster on a stream of frames, so it is allocated per call.
struct ConnectivityScratch {
  std::vector<Run> runs;
  std::vector<float> run_weight;
  std::vector<int> row_first, parent, component_of_run, component_of_root;
  std::vector<std::uint8_t> flags;
};

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
  const float* z = depth.empty() ? nullptr : depth.ptr<float>();
  const auto connected = [z, depth_jump_ratio](std::size_t a, std::size_t b) {
    return depthConnected(z[a], z[b], depth_jump_ratio);
  };
  const std::uint8_t* ok = valid.empty() ? nullptr : valid.ptr<std::uint8_t>();
  const float* pixel_weight = weight.empty() ? nullptr : weight.ptr<float>();

  ConnectivityScratch w;

  // Horizontal runs of equal label over usable pixels; unlabelled usable pixels (-1) form runs
  // too, which are then merged like stray pieces. The run flags of a row come from one
  // vectorised pass; the runs are read off them eight flags at a time.
  std::vector<Run>& runs = w.runs;
  std::vector<float>& run_weight = w.run_weight;
  std::vector<int>& row_first = w.row_first;
  runs.reserve(static_cast<std::size_t>(height) * 48);
  if (pixel_weight != nullptr) run_weight.reserve(runs.capacity());
  row_first.assign(static_cast<std::size_t>(height) + 1, 0);
  w.flags.resize(static_cast<std::size_t>(width) + 8);
  std::uint8_t* flags = w.flags.data();
  for (int row = 0; row < height; ++row) {
    row_first[static_cast<std::size_t>(row)] = static_cast<int>(runs.size());
    const std::size_t base = static_cast<std::size_t>(row) * width;
    if (width == 0) continue;
    rowFlagsAny(label + base, ok == nullptr ? nullptr : ok + base,
                z == nullptr ? nullptr : z + base, depth_jump_ratio, width, flags);
    int col = 0;
    while (col < width) {
      if ((flags[col] & 2) != 0) {
        col = nextUsable(flags, col + 1, width);
        continue;
      }
      const int end = nextNonZero(flags, col + 1);
      runs.push_back({row, col, end, label[base + col]});
      if (pixel_weight != nullptr) run_weight.push_back(runSum(pixel_weight + base, col, end));
      col = end;
    }
  }
  row_first[static_cast<std::size_t>(height)] = static_cast<int>(runs.size());
  const int run_count = static_cast<int>(runs.size());

  // Connect runs of equal label that overlap in consecutive rows (4-neighbourhood).
  std::vector<int>& parent = w.parent;
  parent.resize(static_cast<std::size_t>(run_count));
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
  std::vector<int>& component_of_run = w.component_of_run;
  std::vector<int>& component_of_root = w.component_of_root;
  component_of_run.resize(static_cast<std::size_t>(run_count));
  component_of_root.assign(static_cast<std::size_t>(run_count), -1);
  std::vector<int> component_label;
  std::vector<double> component_weight;
  std::vector<int> component_size;
  for (int r = 0; r < run_count; ++r) {
    // Roots are the smallest run of their component, so parent[r] < r is already final.
    const int root = parent[r] == r ? r : parent[r] = parent[parent[r]];
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
      component_weight[c] += run_weight[r];
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
  // pieces that only touch other stray pieces get resolved through them. The neighbours of a
  // run are found among the runs of its own and the adjacent rows (pixels in no run are
  // unusable and count for nothing).
  std::vector<std::pair<int, int>> border;  // (label, border length)
  // Borders across a depth jump count only for pieces that have no other way to a label.
  bool across_jumps = z == nullptr;
  // Adds `length` border pixels of piece c with run `other_run`.
  const auto tally = [&](int c, int other_run, int length) {
    const int other = component_of_run[other_run];
    if (other == c) return;
    const int value = final_label[other];
    if (value < 0) return;
    auto it = std::find_if(border.begin(), border.end(),
                           [value](const auto& entry) { return entry.first == value; });
    if (it == border.end()) {
      border.push_back({value, length});
    } else {
      it->second += length;
    }
  };
  // The border of run r (piece c) with the runs of row `other_row` above or below.
  const auto tally_row = [&](int c, const Run& run, int other_row) {
    const int first = row_first[other_row], last = row_first[other_row + 1];
    int p =
        static_cast<int>(std::partition_point(runs.begin() + first, runs.begin() + last,
                                              [&run](const Run& o) { return o.end <= run.begin; }) -
                         runs.begin());
    for (; p < last && runs[p].begin < run.end; ++p) {
      const int begin = std::max(runs[p].begin, run.begin);
      const int end = std::min(runs[p].end, run.end);
      int length = end - begin;
      if (!across_jumps) {
        const std::size_t base = static_cast<std::size_t>(run.row) * width;
        const std::size_t other_base = static_cast<std::size_t>(other_row) * width;
        length = 0;
        for (int x = begin; x < end; ++x) length += connected(base + x, other_base + x) ? 1 : 0;
      }
      if (length > 0) tally(c, p, length);
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
        const int r = stray_runs[s];
        const Run& run = runs[r];
        const std::size_t base = static_cast<std::size_t>(run.row) * width;
        if (r > row_first[run.row] && runs[r - 1].end == run.begin &&
            (across_jumps || connected(base + run.begin, base + run.begin - 1))) {
          tally(c, r - 1, 1);
        }
        if (r + 1 < row_first[run.row + 1] && runs[r + 1].begin == run.end &&
            (across_jumps || connected(base + run.end - 1, base + run.end))) {
          tally(c, r + 1, 1);
        }
        if (run.row > 0) tally_row(c, run, run.row - 1);
        if (run.row + 1 < height) tally_row(c, run, run.row + 1);
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

  // Renumber 0..m-1 in order of first appearance; pixels outside any run become -1. One pass
  // over each row: the gaps between its runs, then each run.
  std::vector<int> renumber(static_cast<std::size_t>(next_new_label), -1);
  int count = 0;
  for (int row = 0; row < height; ++row) {
    int* row_labels = label + static_cast<std::size_t>(row) * width;
    int x = 0;
    for (int r = row_first[row]; r < row_first[row + 1]; ++r) {
      const Run& run = runs[r];
      std::fill(row_labels + x, row_labels + run.begin, -1);
      int value = final_label[component_of_run[r]];
      if (value >= 0) {
        int& mapped = renumber[static_cast<std::size_t>(value)];
        if (mapped < 0) mapped = count++;
        value = mapped;
      }
      std::fill(row_labels + run.begin, row_labels + run.end, value);
      x = run.end;
    }
    std::fill(row_labels + x, row_labels + width, -1);
  }
  return count;
}

std::vector<Superpixel> fitSuperpoints(const cv::Mat& labels, const PixelFeatures& features,
                                       const cv::Mat& density, float radius_m,
                                       float depth_exponent) {
  if (labels.type() != CV_32SC1 || labels.cols != features.width ||
      labels.rows != features.height) {
    throw std::invalid_argument("fitSuperpoints: labels must be CV_32SC1 of the features' size");
  }
  if (!density.empty() && (density.type() != CV_32FC1 || density.size() != labels.size())) {
    throw std::invalid_argument("fitSuperpoints: density must be CV_32FC1 of the labels' size");
  }
  const bool depth = features.hasDepth();
  const float* rho = density.empty() ? nullptr : density.ptr<float>();
  // One pass over the labels: the label count is the largest label seen plus one.
  std::vector<FitTotals> sums(1024);
  const int max_label = accumulateFitAny(labels, features, rho, sums);
  sums.resize(static_cast<std::size_t>(max_label + 1));
  std::vector<Superpixel> out(sums.size());
  for (std::size_t k = 0; k < sums.size(); ++k) {
    const FitTotals& s = sums[k];
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
    sp.radius_m = radiusAtDepth(radius_m, sp.position.z(), depth_exponent);
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
