// The internal run and span helpers of the DALIC kernels (src/simd.h) against plain loops, and
// the allocator of the per-pixel arrays they read.
#include "simd.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "dasp/pixel_allocator.h"

namespace dasp::detail {
namespace {

// Rows of random runs (1 to max_run pixels, labels -1 to 5, neighbouring runs may repeat a
// label and then form one longer run).
std::vector<int> randomRow(std::mt19937& rng, int width, int max_run) {
  std::uniform_int_distribution<int> length(1, max_run), label(-1, 5);
  std::vector<int> row;
  while (static_cast<int>(row.size()) < width) row.insert(row.end(), length(rng), label(rng));
  row.resize(static_cast<std::size_t>(width));
  return row;
}

int naiveRunEnd(const std::vector<int>& row, int begin) {
  int end = begin + 1;
  while (end < static_cast<int>(row.size()) && row[end] == row[begin]) ++end;
  return end;
}

TEST(SimdLabelRunEnd, MatchesAScanFromEveryPixel) {
  std::mt19937 rng(7);
  int checked = 0;
  for (const int width : {1, 2, 7, 8, 9, 15, 16, 17, 33, 640}) {
    for (const int max_run : {1, 3, 9, 40, 700}) {
      for (int trial = 0; trial < 20; ++trial) {
        const std::vector<int> row = randomRow(rng, width, max_run);
        for (int begin = 0; begin < width; ++begin) {
          ASSERT_EQ(labelRunEnd(row.data(), begin, width), naiveRunEnd(row, begin))
              << "width " << width << ", begin " << begin;
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 74800);  // every pixel of the 1000 rows
}

TEST(SimdLabelRunEnd, RunsEndingAtEachLaneAndAtTheRowEnd) {
  // A run of 1 .. 20 equal labels followed by a different one, or reaching the row end.
  for (int length = 1; length <= 20; ++length) {
    std::vector<int> row(static_cast<std::size_t>(length), 3);
    EXPECT_EQ(labelRunEnd(row.data(), 0, length), length);
    row.push_back(4);
    row.insert(row.end(), 10, 3);
    EXPECT_EQ(labelRunEnd(row.data(), 0, static_cast<int>(row.size())), length);
  }
}

TEST(SimdCoverSpan, VectorsCoverTheSpanInsideTheRow) {
  for (const bool aligned : {false, true}) {
    for (const int width : {8, 13, 64, 640}) {
      for (int begin = 0; begin < width; ++begin) {
        for (int end = begin + 1; end <= width; ++end) {
          int start = 0, stop = 0;
          const bool ok = aligned ? coverSpanAligned(begin, end, width, start, stop)
                                  : coverSpan(begin, end, width, start, stop);
          const int vectors = (end - begin + kLanes - 1) / kLanes;
          const int aligned_stop = (end + kLanes - 1) / kLanes * kLanes;
          const bool on_grid = aligned && aligned_stop <= width;
          // Only a span wider than the row's whole vectors has no cover (scalar loops run).
          ASSERT_EQ(ok, on_grid || vectors * kLanes <= width) << begin << " " << end;
          if (!ok) continue;
          EXPECT_EQ((stop - start) % kLanes, 0);
          EXPECT_LE(start, begin);
          EXPECT_GE(stop, end);
          EXPECT_GE(start, 0);
          EXPECT_LE(stop, width);
          if (on_grid) {
            EXPECT_EQ(start, begin / kLanes * kLanes);
            EXPECT_EQ(stop, aligned_stop);
          } else {
            EXPECT_EQ(stop - start, vectors * kLanes);  // no vector more than needed
          }
        }
      }
    }
  }
  int start = 0, stop = 0;
  EXPECT_FALSE(coverSpan(0, 3, 5, start, stop));  // rows narrower than a vector: scalar loops
}

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

TEST(PixelAllocator, ArraysStartOnDistinctCacheLinesOfAPage) {
  // Ten images of 640 x 480 floats (exactly 300 pages each), as the features of a frame.
  std::vector<PixelVector<float>> arrays;
  for (int i = 0; i < 10; ++i) arrays.emplace_back(640 * 480, static_cast<float>(i));
  std::set<std::uintptr_t> page_offsets;
  for (int i = 0; i < 10; ++i) {
    const PixelVector<float>& a = arrays[static_cast<std::size_t>(i)];
    EXPECT_EQ(address(a.data()) % 64, 0u) << "array " << i;
    page_offsets.insert(address(a.data()) % 4096);
    EXPECT_EQ(a.front(), static_cast<float>(i));
    EXPECT_EQ(a.back(), static_cast<float>(i));
  }
  EXPECT_EQ(page_offsets.size(), 10u);
  // Copies, growth and small arrays keep the alignment and the contents.
  PixelVector<float> copy = arrays[3];
  EXPECT_EQ(copy, arrays[3]);
  copy.resize(copy.size() + 1000, -1.0f);
  EXPECT_EQ(address(copy.data()) % 64, 0u);
  EXPECT_EQ(copy[640 * 480 - 1], 3.0f);
  EXPECT_EQ(copy.back(), -1.0f);
  const PixelVector<std::uint8_t> small(3, 1);
  EXPECT_EQ(address(small.data()) % 64, 0u);
  EXPECT_EQ(small[2], 1);
}

}  // namespace
}  // namespace dasp::detail
