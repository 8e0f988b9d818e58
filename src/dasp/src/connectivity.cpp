// Connectivity enforcement (not in the thesis): docs/dasp_core.md#connectivity-enforcement
#include "dasp/connectivity.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

#include "simd.h"

namespace dasp {
namespace {

// Sum of p[begin, end).
float runSum(const float* p, int begin, int end) {
  float s = 0.0f;
  for (int i = begin; i < end; ++i) s += p[i];
  return s;
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

void checkConnectivityInputs(const cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                             const cv::Mat& depth, float depth_jump_ratio) {
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
}

// enforceConnectivity in its steps: horizontal runs of equal label, runs linked into 4-connected
// components, the largest piece of each label keeps it, stray pieces join a neighbour, labels
// renumbered. Working memory O(runs) (a frame has some 20 000 runs); a thread_local copy
// measured no faster on a stream of frames, so it is allocated per call.
class ConnectivityPass {
 public:
  ConnectivityPass(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight, double min_weight,
                   const cv::Mat& depth, float depth_jump_ratio)
      : width_(labels.cols),
        height_(labels.rows),
        label_(labels.ptr<int>()),
        ok_(valid.empty() ? nullptr : valid.ptr<std::uint8_t>()),
        pixel_weight_(weight.empty() ? nullptr : weight.ptr<float>()),
        z_(depth.empty() ? nullptr : depth.ptr<float>()),
        depth_jump_ratio_(depth_jump_ratio),
        min_weight_(min_weight) {}

  int run() {
    findRuns();
    linkRuns();
    buildComponents();
    keepLargestPieces();
    groupStrayRuns();
    resolveStrayPieces();
    labelIslands();
    return writeLabels();
  }

 private:
  static constexpr int kUnresolved = -2;

  bool connected(std::size_t a, std::size_t b) const {
    return depthConnected(z_[a], z_[b], depth_jump_ratio_);
  }

  // Horizontal runs of equal label over usable pixels; unlabelled usable pixels (-1) form runs
  // too, which are then merged like stray pieces. The run flags of a row come from one
  // vectorised pass; the runs are read off them eight flags at a time.
  void findRuns() {
    runs_.reserve(static_cast<std::size_t>(height_) * 48);
    if (pixel_weight_ != nullptr) run_weight_.reserve(runs_.capacity());
    row_first_.assign(static_cast<std::size_t>(height_) + 1, 0);
    std::vector<std::uint8_t> flag_row(static_cast<std::size_t>(width_) + 8);
    std::uint8_t* flags = flag_row.data();
    for (int row = 0; row < height_; ++row) {
      row_first_[static_cast<std::size_t>(row)] = static_cast<int>(runs_.size());
      const std::size_t base = static_cast<std::size_t>(row) * width_;
      if (width_ == 0) continue;
      rowFlagsAny(label_ + base, ok_ == nullptr ? nullptr : ok_ + base,
                  z_ == nullptr ? nullptr : z_ + base, depth_jump_ratio_, width_, flags);
      int col = 0;
      while (col < width_) {
        if ((flags[col] & 2) != 0) {
          col = nextUsable(flags, col + 1, width_);
          continue;
        }
        const int end = nextNonZero(flags, col + 1);
        runs_.push_back({row, col, end, label_[base + col]});
        if (pixel_weight_ != nullptr) {
          run_weight_.push_back(runSum(pixel_weight_ + base, col, end));
        }
        col = end;
      }
    }
    row_first_[static_cast<std::size_t>(height_)] = static_cast<int>(runs_.size());
    run_count_ = static_cast<int>(runs_.size());
  }

  // Connects runs of equal label that overlap in consecutive rows (4-neighbourhood).
  void linkRuns() {
    std::vector<int>& parent = parent_;
    const std::vector<Run>& runs = runs_;
    parent.resize(static_cast<std::size_t>(run_count_));
    for (int r = 0; r < run_count_; ++r) parent[r] = r;
    for (int row = 1; row < height_; ++row) {
      int q = row_first_[row - 1];
      const int q_end = row_first_[row];
      for (int r = row_first_[row]; r < row_first_[row + 1]; ++r) {
        while (q < q_end && runs[q].end <= runs[r].begin) ++q;
        for (int p = q; p < q_end && runs[p].begin < runs[r].end; ++p) {
          if (runs[p].label != runs[r].label) continue;
          if (z_ != nullptr) {
            const std::size_t base = static_cast<std::size_t>(row) * width_;
            bool touching = false;
            const int overlap_end = std::min(runs[p].end, runs[r].end);
            for (int x = std::max(runs[p].begin, runs[r].begin); x < overlap_end && !touching;
                 ++x) {
              touching = connected(base + x - width_, base + x);
            }
            if (!touching) continue;
          }
          const int a = findRoot(parent, p), b = findRoot(parent, r);
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
      }
    }
  }

  // Components, their pixel weight and size.
  void buildComponents() {
    std::vector<int>& parent = parent_;
    component_of_run_.resize(static_cast<std::size_t>(run_count_));
    std::vector<int> component_of_root(static_cast<std::size_t>(run_count_), -1);
    for (int r = 0; r < run_count_; ++r) {
      // Roots are the smallest run of their component, so parent[r] < r is already final.
      const int root = parent[r] == r ? r : parent[r] = parent[parent[r]];
      int& c = component_of_root[root];
      if (c < 0) {
        c = static_cast<int>(component_label_.size());
        component_label_.push_back(runs_[r].label);
        component_weight_.push_back(0.0);
        component_size_.push_back(0);
      }
      component_of_run_[r] = c;
      const Run& run = runs_[r];
      component_size_[c] += run.end - run.begin;
      if (pixel_weight_ == nullptr) {
        component_weight_[c] += run.end - run.begin;
      } else {
        component_weight_[c] += run_weight_[r];
      }
    }
    component_count_ = static_cast<int>(component_label_.size());
  }

  // The largest piece of each label keeps it if heavy enough; every other piece is unresolved.
  void keepLargestPieces() {
    int max_label = -1;
    for (int value : component_label_) max_label = std::max(max_label, value);
    std::vector<int> largest(static_cast<std::size_t>(max_label + 1), -1);
    for (int c = 0; c < component_count_; ++c) {
      const int value = component_label_[c];
      if (value < 0) continue;
      int& best = largest[static_cast<std::size_t>(value)];
      if (best < 0 || component_size_[c] > component_size_[best]) best = c;
    }
    final_label_.assign(static_cast<std::size_t>(component_count_), kUnresolved);
    for (int value = 0; value <= max_label; ++value) {
      const int c = largest[static_cast<std::size_t>(value)];
      if (c >= 0 && component_weight_[c] >= min_weight_) final_label_[c] = value;
    }
    next_new_label_ = max_label + 1;
  }

  // Runs of the unresolved components, grouped by component.
  void groupStrayRuns() {
    stray_start_.assign(static_cast<std::size_t>(component_count_) + 1, 0);
    for (int r = 0; r < run_count_; ++r) {
      if (final_label_[component_of_run_[r]] == kUnresolved)
        ++stray_start_[component_of_run_[r] + 1];
    }
    for (int c = 0; c < component_count_; ++c) stray_start_[c + 1] += stray_start_[c];
    stray_runs_.resize(static_cast<std::size_t>(stray_start_[component_count_]));
    std::vector<int> fill(stray_start_.begin(), stray_start_.end() - 1);
    for (int r = 0; r < run_count_; ++r) {
      const int c = component_of_run_[r];
      if (final_label_[c] == kUnresolved) stray_runs_[fill[c]++] = r;
    }
  }

  // Adds `length` border pixels of piece c with run `other_run`.
  void tally(int c, int other_run, int length) {
    const int other = component_of_run_[other_run];
    if (other == c) return;
    const int value = final_label_[other];
    if (value < 0) return;
    auto it = std::find_if(border_.begin(), border_.end(),
                           [value](const auto& entry) { return entry.first == value; });
    if (it == border_.end()) {
      border_.push_back({value, length});
    } else {
      it->second += length;
    }
  }

  // The border of run `run` (piece c) with the runs of row `other_row` above or below.
  void tallyRow(int c, const Run& run, int other_row) {
    const int first = row_first_[other_row], last = row_first_[other_row + 1];
    int p =
        static_cast<int>(std::partition_point(runs_.begin() + first, runs_.begin() + last,
                                              [&run](const Run& o) { return o.end <= run.begin; }) -
                         runs_.begin());
    for (; p < last && runs_[p].begin < run.end; ++p) {
      const int begin = std::max(runs_[p].begin, run.begin);
      const int end = std::min(runs_[p].end, run.end);
      int length = end - begin;
      if (!across_jumps_) {
        const std::size_t base = static_cast<std::size_t>(run.row) * width_;
        const std::size_t other_base = static_cast<std::size_t>(other_row) * width_;
        length = 0;
        for (int x = begin; x < end; ++x) length += connected(base + x, other_base + x) ? 1 : 0;
      }
      if (length > 0) tally(c, p, length);
    }
  }

  // The label of the resolved neighbour that stray piece c shares the longest border with
  // (the smaller label on a tie), or kUnresolved. Neighbours are found among the runs of its
  // own and the adjacent rows (pixels in no run are unusable and count for nothing).
  int bestNeighbour(int c) {
    border_.clear();
    for (int s = stray_start_[c]; s < stray_start_[c + 1]; ++s) {
      const int r = stray_runs_[s];
      const Run& run = runs_[r];
      const std::size_t base = static_cast<std::size_t>(run.row) * width_;
      if (r > row_first_[run.row] && runs_[r - 1].end == run.begin &&
          (across_jumps_ || connected(base + run.begin, base + run.begin - 1))) {
        tally(c, r - 1, 1);
      }
      if (r + 1 < row_first_[run.row + 1] && runs_[r + 1].begin == run.end &&
          (across_jumps_ || connected(base + run.end - 1, base + run.end))) {
        tally(c, r + 1, 1);
      }
      if (run.row > 0) tallyRow(c, run, run.row - 1);
      if (run.row + 1 < height_) tallyRow(c, run, run.row + 1);
    }
    if (border_.empty()) return kUnresolved;
    auto best = border_.begin();
    for (auto it = border_.begin(); it != border_.end(); ++it) {
      if (it->second > best->second || (it->second == best->second && it->first < best->first)) {
        best = it;
      }
    }
    return best->first;
  }

  // Stray pieces join their best neighbour; repeat while pieces that only touch other stray
  // pieces get resolved through them. Borders across a depth jump count only for pieces that
  // have no other way to a label (a second round).
  void resolveStrayPieces() {
    across_jumps_ = z_ == nullptr;
    bool changed = true;
    while (changed || !across_jumps_) {
      if (!changed) across_jumps_ = true;
      changed = false;
      for (int c = 0; c < component_count_; ++c) {
        if (final_label_[c] != kUnresolved) continue;
        const int value = bestNeighbour(c);
        if (value == kUnresolved) continue;
        final_label_[c] = value;
        changed = true;
      }
    }
  }

  // Islands that touch no label (e.g. surrounded by invalid depth).
  void labelIslands() {
    for (int c = 0; c < component_count_; ++c) {
      if (final_label_[c] != kUnresolved) continue;
      final_label_[c] = component_weight_[c] >= min_weight_ ? next_new_label_++ : -1;
    }
  }

  // Renumbers 0..m-1 in order of first appearance; pixels outside any run become -1. One pass
  // over each row: the gaps between its runs, then each run. Returns m.
  int writeLabels() {
    std::vector<int> renumber(static_cast<std::size_t>(next_new_label_), -1);
    int count = 0;
    for (int row = 0; row < height_; ++row) {
      int* row_labels = label_ + static_cast<std::size_t>(row) * width_;
      int x = 0;
      for (int r = row_first_[row]; r < row_first_[row + 1]; ++r) {
        const Run& run = runs_[r];
        std::fill(row_labels + x, row_labels + run.begin, -1);
        int value = final_label_[component_of_run_[r]];
        if (value >= 0) {
          int& mapped = renumber[static_cast<std::size_t>(value)];
          if (mapped < 0) mapped = count++;
          value = mapped;
        }
        std::fill(row_labels + run.begin, row_labels + run.end, value);
        x = run.end;
      }
      std::fill(row_labels + x, row_labels + width_, -1);
    }
    return count;
  }

  const int width_, height_;
  int* const label_;
  const std::uint8_t* const ok_;
  const float* const pixel_weight_;
  const float* const z_;
  const float depth_jump_ratio_;
  const double min_weight_;

  std::vector<Run> runs_;
  std::vector<float> run_weight_;
  std::vector<int> row_first_, parent_, component_of_run_;
  int run_count_ = 0;
  std::vector<int> component_label_, component_size_;
  std::vector<double> component_weight_;
  int component_count_ = 0;
  std::vector<int> final_label_;  // per component: label, -1, or kUnresolved
  int next_new_label_ = 0;
  std::vector<int> stray_start_, stray_runs_;
  std::vector<std::pair<int, int>> border_;  // (label, border length) of one stray piece
  bool across_jumps_ = false;
};

}  // namespace

int enforceConnectivity(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                        double min_weight, const cv::Mat& depth, float depth_jump_ratio) {
  checkConnectivityInputs(labels, valid, weight, depth, depth_jump_ratio);
  return ConnectivityPass(labels, valid, weight, min_weight, depth, depth_jump_ratio).run();
}

}  // namespace dasp
