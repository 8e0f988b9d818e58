// Row-range parallelism shared by the stages: runs body(begin, end) over [0, n) split into
// fixed chunks, sequentially for threads == 1, with TBB otherwise (0 = all cores). The chunk
// boundaries do not depend on the thread count, so reductions per chunk give the same result
// single- and multi-threaded.
#pragma once

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace dasp::detail {

// The number of chunks forChunks(n, chunk_count, ...) runs.
inline int chunkCount(int n, int chunk_count) { return std::max(1, std::min(chunk_count, n)); }

// First index of chunk c of the `chunks` = chunkCount(n, ...) chunks (c = chunks gives n).
inline int chunkBegin(int n, int chunks, int c) {
  return static_cast<int>(static_cast<long long>(n) * c / chunks);
}

template <typename Body>
void forChunks(int n, int chunk_count, int threads, const Body& body) {
  const int chunks = chunkCount(n, chunk_count);
  const auto chunk_begin = [n, chunks](int c) { return chunkBegin(n, chunks, c); };
  if (threads == 1 || chunks == 1) {
    for (int c = 0; c < chunks; ++c) body(c, chunk_begin(c), chunk_begin(c + 1));
    return;
  }
  const auto run = [&]() {
    tbb::parallel_for(tbb::blocked_range<int>(0, chunks, 1),
                      [&](const tbb::blocked_range<int>& range) {
                        for (int c = range.begin(); c < range.end(); ++c) {
                          body(c, chunk_begin(c), chunk_begin(c + 1));
                        }
                      });
  };
  if (threads <= 0) {
    run();
  } else {
    tbb::task_arena arena(threads);
    arena.execute(run);
  }
}

}  // namespace dasp::detail
