// Allocator of the per-pixel arrays of the library (PixelFeatures, DALIC's distances and labels).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

namespace dasp {

/// Starts every array at a 64-byte boundary, and consecutive arrays at different 64-byte lines
/// of a 4 KiB page. Why: the per-pixel loops read and write about ten arrays at the same index,
/// sixteen floats (one cache line) at a time with AVX-512. The C library aligns large blocks to
/// 16 bytes only, so such a load would span two cache lines; and it places same-sized blocks at
/// the same offset within a page (a 640x480 float image is exactly 300 pages), so the same
/// index of every array maps to one L1 cache set, and a load can wait for an earlier store to
/// another array at the same page offset (4 KiB aliasing). Costs up to one page per array.
template <typename T>
struct PixelAllocator {
  using value_type = T;
  PixelAllocator() noexcept = default;
  template <typename U>
  PixelAllocator(const PixelAllocator<U>&) noexcept {}  // implicit, as allocators convert

  /// Throws std::bad_array_new_length or std::bad_alloc like std::allocator.
  T* allocate(std::size_t n) {
    constexpr std::size_t kPage = 4096, kLine = 64, kLines = kPage / kLine;
    static std::atomic<unsigned> next_line{0};
    // Lines 1 .. kLines - 1 of the first page: the word before the data keeps the block's start.
    const std::size_t offset =
        kLine * (1 + next_line.fetch_add(1, std::memory_order_relaxed) % (kLines - 1));
    if (n > (SIZE_MAX - offset - kPage) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = (offset + n * sizeof(T) + kPage - 1) / kPage * kPage;
    void* block = std::aligned_alloc(kPage, bytes);
    if (block == nullptr) throw std::bad_alloc();
    void* data = static_cast<unsigned char*>(block) + offset;
    static_cast<void**>(data)[-1] = block;
    return static_cast<T*>(data);
  }
  void deallocate(T* p, std::size_t) noexcept {
    std::free(static_cast<void**>(static_cast<void*>(p))[-1]);
  }
};

template <typename T, typename U>
bool operator==(const PixelAllocator<T>&, const PixelAllocator<U>&) noexcept {
  return true;  // stateless: any instance frees what another allocated
}
template <typename T, typename U>
bool operator!=(const PixelAllocator<T>&, const PixelAllocator<U>&) noexcept {
  return false;
}

/// A per-pixel array (a std::vector with PixelAllocator).
template <typename T>
using PixelVector = std::vector<T, PixelAllocator<T>>;

}  // namespace dasp
