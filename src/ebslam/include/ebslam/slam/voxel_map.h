#pragma once

// Sparse voxel grid of dense chunks for EB-SLAM-3D's occurrence map (thesis 8.3, "Map data
// structure"): 8^3 float voxels per chunk (2 KiB) in an open-addressing hash map keyed by the
// chunk's integer coordinates; unbounded extent, memory grows with the surface seen; an optional
// memory bound evicts the least recently written chunk. Voxel (i, j, k) covers
// [i v, (i+1) v) x [j v, (j+1) v) x [k v, (k+1) v) in the map frame, v the voxel edge length [m].
// Details (why 8^3, not the thesis' 32^3): docs/ebslam_core.md#voxel-map

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace ebslam {

struct VoxelMapConfig {
  double voxel_size_m = 0.01;  ///< voxel edge length [m] (thesis 8.4 default set: 1 cm)
  /// Bound on the memory of chunks plus index [bytes]; 0 = unbounded. When a new chunk would
  /// exceed it, the least recently written chunk is evicted (its voxels read as 0 again).
  std::size_t max_memory_bytes = 0;
  /// Throws std::invalid_argument naming the offending parameter (voxel size not positive and
  /// finite, or a bound below the size of two chunks).
  void validate() const;
};

/// Integer voxel coordinates.
using VoxelIndex = Eigen::Vector3i;

class ChunkedVoxelMap {
 public:
  static constexpr int kChunkBits = 3;
  static constexpr int kChunkSide = 1 << kChunkBits;  ///< voxels per chunk edge (8)
  static constexpr int kChunkVoxels = kChunkSide * kChunkSide * kChunkSide;
  static constexpr std::size_t kChunkBytes = sizeof(float) * kChunkVoxels;
  /// Largest |voxel coordinate| stored; points beyond read as 0 and are not written.
  static constexpr std::int32_t kMaxVoxelCoordinate = (1 << (20 + kChunkBits)) - 1;

  /// Throws std::invalid_argument for an invalid config.
  explicit ChunkedVoxelMap(const VoxelMapConfig& config = {});

  double voxelSize() const { return voxel_size_; }
  const VoxelMapConfig& config() const { return config_; }

  /// Voxel containing point p [m]; false (index untouched) for a non-finite point or one beyond
  /// kMaxVoxelCoordinate.
  bool voxelOf(const Eigen::Vector3f& p, VoxelIndex& index) const;
  /// Centre of a voxel [m].
  Eigen::Vector3f voxelCentre(const VoxelIndex& index) const {
    return ((index.cast<float>().array() + 0.5f) * static_cast<float>(voxel_size_)).matrix();
  }

  /// Value of the voxel containing p; 0 where no chunk exists or p is invalid. Inline: this is
  /// the particle filter's inner loop. Remembers the last chunk read (not thread-safe).
  float value(float x, float y, float z) const {
    const float fx = x * inv_voxel_, fy = y * inv_voxel_, fz = z * inv_voxel_;
    constexpr float kLimit = static_cast<float>(kMaxVoxelCoordinate);
    // Written so that NaN fails the test.
    if (!(std::abs(fx) < kLimit && std::abs(fy) < kLimit && std::abs(fz) < kLimit)) return 0.0f;
    const std::int32_t ix = floorToInt(fx), iy = floorToInt(fy), iz = floorToInt(fz);
    const std::uint64_t key = chunkKey(ix >> kChunkBits, iy >> kChunkBits, iz >> kChunkBits);
    if (key != cached_key_) {
      cached_key_ = key;
      const std::int32_t slot = findSlot(key);
      cached_chunk_ = slot < 0 ? nullptr : chunks_[static_cast<std::size_t>(slot)]->data();
    }
    if (cached_chunk_ == nullptr) return 0.0f;
    return cached_chunk_[localIndex(ix, iy, iz)];
  }
  float value(const Eigen::Vector3f& p) const { return value(p.x(), p.y(), p.z()); }
  /// sums[i] += voxelValue((ix[i], iy[i], iz[i])) for i < n (indices within
  /// +-kMaxVoxelCoordinate), faster than n lookups when the voxels are close together (the
  /// particles' views of one event): when all fall into one chunk, that chunk is found once.
  void accumulateVoxels(const std::int32_t* ix, const std::int32_t* iy, const std::int32_t* iz,
                        int n, float* sums) const;
  /// Value of a voxel; 0 where no chunk exists.
  float voxelValue(const VoxelIndex& index) const;

  /// Adds w to a voxel, creating its chunk (and evicting under the memory bound). Returns false
  /// (nothing written) for an index beyond kMaxVoxelCoordinate.
  bool add(const VoxelIndex& index, float w);
  /// Adds `weight` spread as an isotropic Gaussian of standard deviation sigma_m [m] centred at
  /// p (eq. 8.9): the voxels of the box of radius r = ceil(2 sigma / v - 0.5) voxels around p's
  /// voxel get N(centre | p, sigma), normalised over the box so that the weights sum to
  /// `weight`. With sigma below a quarter voxel (r = 0) this is p's voxel alone. Returns false
  /// (nothing written) for a non-finite p or sigma < 0, or p outside the coordinate range. The box
  /// radius is capped at kMaxSplatRadius voxels.
  bool addGaussian(const Eigen::Vector3f& p, float sigma_m, float weight);
  static constexpr int kMaxSplatRadius = 3;

  /// Number of allocated chunks, memory of chunks plus index [bytes], chunks evicted so far.
  std::size_t chunkCount() const { return chunk_count_; }
  std::size_t memoryBytes() const;
  std::size_t peakMemoryBytes() const { return peak_memory_; }
  std::uint64_t evictedChunks() const { return evicted_; }
  /// Removes every chunk (memory is kept for reuse; evictedChunks() is kept).
  void clear();

  /// Calls f(index, value) for every voxel with value > threshold, chunk by chunk (order
  /// unspecified).
  template <typename F>
  void forEachVoxel(float threshold, F&& f) const {
    for (std::size_t s = 0; s < chunks_.size(); ++s) {
      if (slot_key_[s] == kEmptyKey) continue;
      const VoxelIndex base = chunkOrigin(slot_key_[s]);
      const float* c = chunks_[s]->data();
      for (int k = 0; k < kChunkVoxels; ++k) {
        if (c[k] > threshold) {
          f(VoxelIndex(base.x() + (k & (kChunkSide - 1)),
                       base.y() + ((k >> kChunkBits) & (kChunkSide - 1)),
                       base.z() + (k >> (2 * kChunkBits))),
            c[k]);
        }
      }
    }
  }

 private:
  using Chunk = std::array<float, kChunkVoxels>;
  static constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};
  static constexpr std::uint32_t kNoSlot = ~std::uint32_t{0};

  static std::int32_t floorToInt(float v) {
    const auto i = static_cast<std::int32_t>(v);
    return i - (static_cast<float>(i) > v ? 1 : 0);
  }
  static std::uint64_t chunkKey(std::int32_t cx, std::int32_t cy, std::int32_t cz) {
    constexpr std::int32_t kOffset = 1 << 20;
    constexpr std::uint64_t kMask = (std::uint64_t{1} << 21) - 1;
    return (static_cast<std::uint64_t>(cx + kOffset) & kMask) |
           ((static_cast<std::uint64_t>(cy + kOffset) & kMask) << 21) |
           ((static_cast<std::uint64_t>(cz + kOffset) & kMask) << 42);
  }
  static VoxelIndex chunkOrigin(std::uint64_t key);
  static int localIndex(std::int32_t ix, std::int32_t iy, std::int32_t iz) {
    constexpr std::int32_t m = kChunkSide - 1;
    return (ix & m) | ((iy & m) << kChunkBits) | ((iz & m) << (2 * kChunkBits));
  }
  static std::size_t hashKey(std::uint64_t key) {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return static_cast<std::size_t>(key);
  }
  /// Slot of a chunk, -1 if absent.
  std::int32_t findSlot(std::uint64_t key) const {
    std::size_t h = hashKey(key) & table_mask_;
    while (true) {
      const std::uint32_t slot = table_[h];
      if (slot == kNoSlot) return -1;
      if (slot_key_[slot] == key) return static_cast<std::int32_t>(slot);
      h = (h + 1) & table_mask_;
    }
  }
  /// Pointer to a chunk's voxels, created if needed.
  float* chunkFor(std::uint64_t key);
  void insertIntoTable(std::uint64_t key, std::uint32_t slot);
  void eraseFromTable(std::uint64_t key);
  void growTable();
  void evictOldest();
  void unlinkLru(std::uint32_t slot);
  void pushLruFront(std::uint32_t slot);
  std::size_t maxChunks() const;

  VoxelMapConfig config_;
  double voxel_size_ = 0.01;
  float inv_voxel_ = 100.0f;
  std::vector<std::unique_ptr<Chunk>> chunks_;  // by slot; reused after eviction or clear()
  std::vector<std::uint64_t> slot_key_;         // key of each slot, kEmptyKey when free
  // Recency list of the occupied slots (doubly linked through slot indices, kNoSlot ends it):
  // head = most recently written, tail = the next to evict.
  std::vector<std::uint32_t> lru_prev_, lru_next_;
  std::uint32_t lru_head_ = kNoSlot, lru_tail_ = kNoSlot;
  std::vector<std::uint32_t> free_slots_;
  std::vector<std::uint32_t> table_;  // open addressing, linear probing, power-of-two size
  std::size_t table_mask_ = 0;
  std::size_t chunk_count_ = 0;
  std::size_t peak_memory_ = 0;
  std::uint64_t evicted_ = 0;
  mutable std::uint64_t cached_key_ = kEmptyKey;
  mutable const float* cached_chunk_ = nullptr;
};

}  // namespace ebslam
