// Vectorisation helpers of the per-pixel loops (internal to the dasp library): load-time
// selection of AVX-512 / AVX2 / baseline builds of a function, GCC vector extensions, eight
// floats at a time, and the runtime check of functions written with AVX-512 intrinsics.
#pragma once

#include <atomic>

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define DASP_ALWAYS_INLINE inline __attribute__((always_inline))
// For lambdas (after the parameter list). A lambda is a function of its own, built for the
// baseline even inside a DASP_VECTOR_CLONES function; a clone that calls one taking or returning
// Vec8f expects the vector in a register where the baseline passes it in memory (at -O0, where
// nothing else is inlined, that crashed). Inlined, no call and no vector ABI remain.
#define DASP_LAMBDA_ALWAYS_INLINE __attribute__((always_inline))
// The function is built for x86-64-v4 (AVX-512), x86-64-v3 (AVX2, FMA) and the baseline, and the
// best one for the CPU is chosen when the library is loaded: Debian builds for the baseline.
#define DASP_VECTOR_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
// A function written with AVX-512F intrinsics: built for AVX-512F whatever the build's baseline,
// and called only where avx512Available() says that the processor and the OS run it.
#define DASP_AVX512_FUNCTIONS 1
#define DASP_AVX512_FUNCTION __attribute__((target("avx512f")))
#else
#define DASP_ALWAYS_INLINE inline
#define DASP_LAMBDA_ALWAYS_INLINE
#define DASP_VECTOR_CLONES
#define DASP_AVX512_FUNCTIONS 0
#endif

namespace dasp::detail {

constexpr int kLanes = 8;  // floats per vector

#if DASP_AVX512_FUNCTIONS
/// Whether the AVX-512 loops may run (default true). Tests turn it off to check the eight-lane
/// loops on processors with AVX-512 too.
inline std::atomic<bool>& avx512Allowed() {
  static std::atomic<bool> allowed{true};
  return allowed;
}

/// True if the AVX-512 loops may run: the processor supports AVX-512F, the OS saves its
/// registers (both checked once), and avx512Allowed().
inline bool avx512Available() {
  static const bool supported = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") != 0;
  }();
  return supported && avx512Allowed().load(std::memory_order_relaxed);
}
#endif

#if defined(__GNUC__) && !defined(__clang__)
#define DASP_VECTOR_EXTENSIONS 1
#else
#define DASP_VECTOR_EXTENSIONS 0  // the scalar loops run
#endif

#if DASP_VECTOR_EXTENSIONS
// Eight floats / ints: AVX2 or AVX-512 registers in those builds, two SSE registers in the
// baseline one. Functions and lambdas taking or returning them are always inlined
// (DASP_ALWAYS_INLINE, DASP_LAMBDA_ALWAYS_INLINE), also at -O0: no call passes a vector, so the
// clones built for another ISA never disagree on its ABI, and the build turns GCC's -Wpsabi
// note off for this reason.
typedef float Vec8f __attribute__((vector_size(32)));
typedef int Vec8i __attribute__((vector_size(32)));
template <typename Vec, typename T>
DASP_ALWAYS_INLINE Vec loadVec(const T* p) {  // unaligned
  Vec v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
template <typename Vec, typename T>
DASP_ALWAYS_INLINE void storeVec(T* p, const Vec& v) {  // unaligned
  __builtin_memcpy(p, &v, sizeof v);
}
#endif

/// Whole vectors covering columns [begin, end) of a row of `width` pixels, shifted left at the
/// right image border: [start, stop), the caller masks out the lanes outside [begin, end). A
/// scalar remainder loop would cost as much as the vector part on the short spans and runs of
/// superpixels. False if the row is narrower than the vectors (then the scalar loops run).
DASP_ALWAYS_INLINE bool coverSpan(int begin, int end, int width, int& start, int& stop) {
  const int vectors = (end - begin + kLanes - 1) / kLanes;
  if (vectors * kLanes > width) return false;
  start = begin < width - vectors * kLanes ? begin : width - vectors * kLanes;
  stop = start + vectors * kLanes;
  return true;
}

/// Like coverSpan, but the vectors start at multiples of kLanes columns wherever the row allows:
/// a loop that stores to the row (the assignment's distances and labels) then loads exactly what
/// an earlier span stored, or nothing of it, and the store can be forwarded. Unaligned, the load
/// of a span overlapping its neighbour's last store in part stalls until that store is written.
DASP_ALWAYS_INLINE bool coverSpanAligned(int begin, int end, int width, int& start, int& stop) {
  start = begin & ~(kLanes - 1);
  stop = (end + kLanes - 1) & ~(kLanes - 1);
  if (stop <= width) return true;
  return coverSpan(begin, end, width, start, stop);
}

/// End (one past the last pixel) of the run of equal labels that starts at `begin` in a row of
/// `width` labels. Superpixel runs are about 10 to 40 pixels long: eight labels are compared at a
/// time, and the first differing one is found from the bit mask of the comparisons, not by a
/// scalar loop whose exit (after 0 to 7 steps) the branch predictor cannot guess.
DASP_ALWAYS_INLINE int labelRunEnd(const int* labels, int begin, int width) {
  const int k = labels[begin];
  int end = begin + 1;
#if defined(__GNUC__)  // GCC and Clang: __builtin_ctz
  while (end + kLanes <= width) {
    unsigned differ = 0;  // bit j: labels[end + j] != k (compiled to one vector compare)
    for (int j = 0; j < kLanes; ++j) {
      differ |= static_cast<unsigned>(labels[end + j] != k) << j;
    }
    if (differ != 0) return end + __builtin_ctz(differ);
    end += kLanes;
  }
#endif
  while (end < width && labels[end] == k) ++end;
  return end;
}

}  // namespace dasp::detail
