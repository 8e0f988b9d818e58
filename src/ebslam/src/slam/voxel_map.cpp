#include "ebslam/slam/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

void VoxelMapConfig::validate() const {
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) {
    throw std::invalid_argument("VoxelMapConfig: voxel_size_m must be positive and finite");
  }
  if (voxel_size_m < 1e-4 || voxel_size_m > 10.0) {
    throw std::invalid_argument("VoxelMapConfig: voxel_size_m must be in [1e-4, 10] m, got " +
                                std::to_string(voxel_size_m));
  }
  if (max_memory_bytes != 0 && max_memory_bytes < 2 * ChunkedVoxelMap::kChunkBytes) {
    throw std::invalid_argument(
        "VoxelMapConfig: max_memory_bytes must be 0 (unbounded) or at "
        "least two chunks (" +
        std::to_string(2 * ChunkedVoxelMap::kChunkBytes) + " bytes)");
  }
}

ChunkedVoxelMap::ChunkedVoxelMap(const VoxelMapConfig& config) : config_(config) {
  config_.validate();
  voxel_size_ = config_.voxel_size_m;
  inv_voxel_ = static_cast<float>(1.0 / voxel_size_);
  table_.assign(64, kNoSlot);
  table_mask_ = table_.size() - 1;
  peak_memory_ = memoryBytes();
}

bool ChunkedVoxelMap::voxelOf(const Eigen::Vector3f& p, VoxelIndex& index) const {
  constexpr float kLimit = static_cast<float>(kMaxVoxelCoordinate);
  const Eigen::Vector3f f = p * inv_voxel_;
  if (!(std::abs(f.x()) < kLimit && std::abs(f.y()) < kLimit && std::abs(f.z()) < kLimit)) {
    return false;
  }
  index = VoxelIndex(floorToInt(f.x()), floorToInt(f.y()), floorToInt(f.z()));
  return true;
}

VoxelIndex ChunkedVoxelMap::chunkOrigin(std::uint64_t key) {
  constexpr std::int32_t kOffset = 1 << 20;
  constexpr std::uint64_t kMask = (std::uint64_t{1} << 21) - 1;
  const auto c = [&](int shift) {
    return (static_cast<std::int32_t>((key >> shift) & kMask) - kOffset) * kChunkSide;
  };
  return VoxelIndex(c(0), c(21), c(42));
}

float ChunkedVoxelMap::voxelValue(const VoxelIndex& index) const {
  if ((index.array().abs() > kMaxVoxelCoordinate).any()) return 0.0f;
  const std::int32_t slot =
      findSlot(chunkKey(index.x() >> kChunkBits, index.y() >> kChunkBits, index.z() >> kChunkBits));
  if (slot < 0) return 0.0f;
  return (*chunks_[static_cast<std::size_t>(slot)])[static_cast<std::size_t>(
      localIndex(index.x(), index.y(), index.z()))];
}

void ChunkedVoxelMap::accumulateVoxels(const std::int32_t* ix, const std::int32_t* iy,
                                       const std::int32_t* iz, int n, float* sums) const {
  if (n <= 0) return;
  std::int32_t lox = ix[0], hix = ix[0], loy = iy[0], hiy = iy[0], loz = iz[0], hiz = iz[0];
  for (int i = 1; i < n; ++i) {
    lox = std::min(lox, ix[i]);
    hix = std::max(hix, ix[i]);
    loy = std::min(loy, iy[i]);
    hiy = std::max(hiy, iy[i]);
    loz = std::min(loz, iz[i]);
    hiz = std::max(hiz, iz[i]);
  }
  if ((lox >> kChunkBits) == (hix >> kChunkBits) && (loy >> kChunkBits) == (hiy >> kChunkBits) &&
      (loz >> kChunkBits) == (hiz >> kChunkBits)) {
    const std::int32_t slot =
        findSlot(chunkKey(lox >> kChunkBits, loy >> kChunkBits, loz >> kChunkBits));
    if (slot < 0) return;  // all in one absent chunk: all zero
    const float* c = chunks_[static_cast<std::size_t>(slot)]->data();
    for (int i = 0; i < n; ++i) sums[i] += c[localIndex(ix[i], iy[i], iz[i])];
    return;
  }
  for (int i = 0; i < n; ++i) {
    const std::uint64_t key =
        chunkKey(ix[i] >> kChunkBits, iy[i] >> kChunkBits, iz[i] >> kChunkBits);
    if (key != cached_key_) {
      cached_key_ = key;
      const std::int32_t slot = findSlot(key);
      cached_chunk_ = slot < 0 ? nullptr : chunks_[static_cast<std::size_t>(slot)]->data();
    }
    if (cached_chunk_ != nullptr) sums[i] += cached_chunk_[localIndex(ix[i], iy[i], iz[i])];
  }
}

std::size_t ChunkedVoxelMap::memoryBytes() const {
  // Allocated chunks (including free slots kept for reuse) plus the per-slot bookkeeping and the
  // hash table.
  return chunks_.size() *
             (kChunkBytes + sizeof(std::unique_ptr<Chunk>) + 2 * sizeof(std::uint64_t)) +
         table_.size() * sizeof(std::uint32_t) + free_slots_.capacity() * sizeof(std::uint32_t);
}

std::size_t ChunkedVoxelMap::maxChunks() const {
  if (config_.max_memory_bytes == 0) return ~std::size_t{0};
  // Per chunk: its voxels, its bookkeeping and at most two hash-table entries (load <= 1/2).
  const std::size_t per_chunk = kChunkBytes + sizeof(std::unique_ptr<Chunk>) +
                                2 * sizeof(std::uint64_t) + 3 * sizeof(std::uint32_t);
  return std::max<std::size_t>(2, config_.max_memory_bytes / per_chunk);
}

bool ChunkedVoxelMap::add(const VoxelIndex& index, float w) {
  if ((index.array().abs() > kMaxVoxelCoordinate).any()) return false;
  float* chunk =
      chunkFor(chunkKey(index.x() >> kChunkBits, index.y() >> kChunkBits, index.z() >> kChunkBits));
  chunk[localIndex(index.x(), index.y(), index.z())] += w;
  return true;
}

bool ChunkedVoxelMap::addGaussian(const Eigen::Vector3f& p, float sigma_m, float weight) {
  VoxelIndex centre;
  if (!(sigma_m >= 0.0f) || !std::isfinite(sigma_m) || !voxelOf(p, centre)) return false;
  const int r =
      std::min(kMaxSplatRadius, static_cast<int>(std::ceil(2.0f * sigma_m * inv_voxel_ - 0.5f)));
  if (r <= 0) return add(centre, weight);
  if ((centre.array().abs() + r > kMaxVoxelCoordinate).any()) return false;
  const int side = 2 * r + 1;
  float weights[(2 * kMaxSplatRadius + 1) * (2 * kMaxSplatRadius + 1) * (2 * kMaxSplatRadius + 1)];
  const float inv_two_var = 1.0f / (2.0f * sigma_m * sigma_m);
  const auto v = static_cast<float>(voxel_size_);
  // Separable: the Gaussian of the offset to each voxel centre per axis.
  float gx[2 * kMaxSplatRadius + 1], gy[2 * kMaxSplatRadius + 1], gz[2 * kMaxSplatRadius + 1];
  for (int d = -r; d <= r; ++d) {
    const auto axis = [&](float pc, int c) {
      const float off = (static_cast<float>(c + d) + 0.5f) * v - pc;
      return std::exp(-off * off * inv_two_var);
    };
    gx[d + r] = axis(p.x(), centre.x());
    gy[d + r] = axis(p.y(), centre.y());
    gz[d + r] = axis(p.z(), centre.z());
  }
  float total = 0.0f;
  for (int z = 0; z < side; ++z) {
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        const float w = gx[x] * gy[y] * gz[z];
        weights[(z * side + y) * side + x] = w;
        total += w;
      }
    }
  }
  if (!(total > 0.0f)) return add(centre, weight);
  const float scale = weight / total;
  for (int z = 0; z < side; ++z) {
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        add(VoxelIndex(centre.x() + x - r, centre.y() + y - r, centre.z() + z - r),
            weights[(z * side + y) * side + x] * scale);
      }
    }
  }
  return true;
}

void ChunkedVoxelMap::unlinkLru(std::uint32_t slot) {
  const std::uint32_t prev = lru_prev_[slot], next = lru_next_[slot];
  if (prev != kNoSlot) {
    lru_next_[prev] = next;
  } else {
    lru_head_ = next;
  }
  if (next != kNoSlot) {
    lru_prev_[next] = prev;
  } else {
    lru_tail_ = prev;
  }
}

void ChunkedVoxelMap::pushLruFront(std::uint32_t slot) {
  lru_prev_[slot] = kNoSlot;
  lru_next_[slot] = lru_head_;
  if (lru_head_ != kNoSlot) lru_prev_[lru_head_] = slot;
  lru_head_ = slot;
  if (lru_tail_ == kNoSlot) lru_tail_ = slot;
}

float* ChunkedVoxelMap::chunkFor(std::uint64_t key) {
  const std::int32_t found = findSlot(key);
  if (found >= 0) {
    const auto slot = static_cast<std::uint32_t>(found);
    if (slot != lru_head_) {
      unlinkLru(slot);
      pushLruFront(slot);
    }
    return chunks_[slot]->data();
  }
  if (chunk_count_ >= maxChunks()) evictOldest();
  std::uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
    chunks_[slot]->fill(0.0f);
  } else {
    slot = static_cast<std::uint32_t>(chunks_.size());
    chunks_.push_back(std::make_unique<Chunk>());
    chunks_.back()->fill(0.0f);
    slot_key_.push_back(kEmptyKey);
    lru_prev_.push_back(kNoSlot);
    lru_next_.push_back(kNoSlot);
  }
  slot_key_[slot] = key;
  pushLruFront(slot);
  ++chunk_count_;
  if (2 * (chunk_count_ + 1) > table_.size()) growTable();
  insertIntoTable(key, slot);
  cached_key_ = kEmptyKey;  // the cache may hold this chunk as absent
  peak_memory_ = std::max(peak_memory_, memoryBytes());
  return chunks_[slot]->data();
}

void ChunkedVoxelMap::insertIntoTable(std::uint64_t key, std::uint32_t slot) {
  std::size_t h = hashKey(key) & table_mask_;
  while (table_[h] != kNoSlot) h = (h + 1) & table_mask_;
  table_[h] = slot;
}

void ChunkedVoxelMap::eraseFromTable(std::uint64_t key) {
  std::size_t h = hashKey(key) & table_mask_;
  while (slot_key_[table_[h]] != key) h = (h + 1) & table_mask_;
  // Backward-shift deletion keeps every probe sequence unbroken without tombstones.
  std::size_t hole = h;
  std::size_t next = (hole + 1) & table_mask_;
  while (table_[next] != kNoSlot) {
    const std::size_t home = hashKey(slot_key_[table_[next]]) & table_mask_;
    // Move the entry into the hole unless its home lies cyclically in (hole, next].
    const bool home_after_hole =
        hole <= next ? (home > hole && home <= next) : (home > hole || home <= next);
    if (!home_after_hole) {
      table_[hole] = table_[next];
      hole = next;
    }
    next = (next + 1) & table_mask_;
  }
  table_[hole] = kNoSlot;
}

void ChunkedVoxelMap::growTable() {
  table_.assign(table_.size() * 2, kNoSlot);
  table_mask_ = table_.size() - 1;
  for (std::size_t s = 0; s < slot_key_.size(); ++s) {
    if (slot_key_[s] != kEmptyKey) insertIntoTable(slot_key_[s], static_cast<std::uint32_t>(s));
  }
}

void ChunkedVoxelMap::evictOldest() {
  // O(1): the tail of the recency list (the previous linear scan cost a pass over every chunk
  // per new chunk once the bound was reached).
  const std::uint32_t oldest = lru_tail_;
  if (oldest == kNoSlot) return;
  unlinkLru(oldest);
  eraseFromTable(slot_key_[oldest]);
  slot_key_[oldest] = kEmptyKey;
  free_slots_.push_back(oldest);
  --chunk_count_;
  ++evicted_;
  cached_key_ = kEmptyKey;
}

void ChunkedVoxelMap::clear() {
  for (std::size_t s = 0; s < slot_key_.size(); ++s) {
    if (slot_key_[s] == kEmptyKey) continue;
    slot_key_[s] = kEmptyKey;
    free_slots_.push_back(static_cast<std::uint32_t>(s));
  }
  std::fill(table_.begin(), table_.end(), kNoSlot);
  lru_head_ = lru_tail_ = kNoSlot;
  chunk_count_ = 0;
  cached_key_ = kEmptyKey;
}

}  // namespace ebslam
