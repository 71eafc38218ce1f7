#pragma once
/// \file
/// Internals (namespace detail, not part of the API) of matching/matcher.hpp: the bit-sliced k = 2
/// search.
///
/// How the k = 2 search is fast: the train descriptors are transposed into bit planes, so that one
/// machine word (or SIMD register) holds the same bit of 64 (128, 256) train descriptors, one per
/// bit "lane". XOR-ing plane b with bit b of the query (all ones or all zeros) gives, in every lane,
/// whether that bit differs; a carry-save adder tree then adds these planes up lane by lane into a
/// binary counter kept as bit planes too, i.e. it computes the Hamming distances of one query to a
/// whole block of train descriptors at once, with about six logic instructions per descriptor bit
/// and block. A bit-serial comparison of the counter with the current second-best distance tells
/// which lanes (usually none) can enter the two best; only those are looked at one by one.
///
/// The search runs on 256-bit lanes (AVX2, chosen at run time as the extraction kernels are, see
/// core/detail/simd.hpp) where the CPU has AVX2, on 128-bit lanes elsewhere. Both give the same
/// results.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/detail/popcount.hpp"
#include "affine_orb/matching/knn_match.hpp"

namespace affine_orb {
namespace detail {

/// The bit-lane vectors of the k = 2 search: GCC/Clang vectors of 64-bit words as wide as an
/// integer SIMD register, 16 bytes (SSE2 on every x86-64, NEON on AArch64, pairs of plain words on
/// targets without SIMD) and, where the AVX2 kernels are compiled (AFFINE_ORB_KNN2_LANES256), 32
/// bytes; other compilers use a plain 64-bit word. Every lane type gives the same results (the tests
/// compare each with a naive search).
#if defined(__GNUC__)
typedef std::uint64_t LaneVector128 __attribute__((vector_size(16), may_alias));
#else
using LaneVector128 = std::uint64_t;
#endif

#if AFFINE_ORB_AVX2 && defined(__GNUC__)
/// 1 when knn2() may use 256-bit lanes: where the AVX2 kernels are compiled, on a CPU that has
/// AVX2 (cpu_has_avx2(), asked per call).
#define AFFINE_ORB_KNN2_LANES256 1
typedef std::uint64_t LaneVector256 __attribute__((vector_size(32), may_alias));
#else
#define AFFINE_ORB_KNN2_LANES256 0
#endif

/// 64-bit words in a lane vector V (std::uint64_t or a GCC/Clang vector of them).
template <class V>
inline constexpr int kLaneWords = static_cast<int>(sizeof(V) / sizeof(std::uint64_t));

/// Releases what lane_array() allocates.
template <class V>
struct LaneArrayDelete {
  void operator()(V* p) const noexcept { ::operator delete (p, std::align_val_t{sizeof(V)}); }
};

/// `n` lane vectors V, uninitialised, aligned to sizeof(V). A std::vector<V> would not do for the
/// 256-bit lanes: GCC drops a vector typedef's attributes in a template argument and allocates the
/// vector at the 16-byte alignment of the target outside an AVX2 region, while the AVX2 code loads
/// it with aligned 32-byte moves.
template <class V>
using LaneArray = std::unique_ptr<V[], LaneArrayDelete<V>>;

template <class V>
LaneArray<V> lane_array(std::size_t n) {
  return LaneArray<V>(static_cast<V*>(::operator new (n * sizeof(V), std::align_val_t{sizeof(V)})));
}

/// Transposes a 64x64 bit matrix in place: afterwards bit c of m[r] is what bit r of m[c] was.
/// Block-swap method: exchange the two off-diagonal 32x32 blocks, then the off-diagonal 16x16
/// blocks inside each 32x32 block, and so on down to single bits (H. S. Warren, Hacker's Delight,
/// 2nd ed., 2012, section 7-3).
inline void transpose_bits64(std::array<std::uint64_t, 64>& m) noexcept {
  std::uint64_t mask = 0x00000000ffffffffULL;  // the low j bits of every 2j-bit group
  for (int j = 32; j != 0; j >>= 1, mask ^= mask << j) {
    for (int r = 0; r < 64; ++r) {
      if ((r & j) != 0) continue;
      const std::uint64_t t = ((m[r] >> j) ^ m[r + j]) & mask;
      m[r] ^= t << j;
      m[r + j] ^= t;
    }
  }
}

/// Number of binary digits of x >= 0.
constexpr int bit_width(int x) noexcept { return x == 0 ? 0 : 1 + bit_width(x / 2); }

/// Bit planes of a lane-wise counter of up to Bits: six for the carry-save tree over 64 planes,
/// then enough for the number of 64-bit words (the counter reaches Bits + 1 < 2^planes).
template <int Bits>
inline constexpr int kCountPlanes = 6 + bit_width(Bits / 64);

/// (distance, train index) packed so that comparing keys compares distance first, then index.
inline std::uint64_t neighbour_key(int distance, std::size_t train) noexcept {
  return (static_cast<std::uint64_t>(distance) << 32) | static_cast<std::uint64_t>(train);
}

inline constexpr std::uint64_t kNoKey = std::numeric_limits<std::uint64_t>::max();

/// Inserts a key into the two smallest so far (best < second; kNoKey where none yet).
inline void keep_two_smallest(std::uint64_t key, std::uint64_t& best, std::uint64_t& second) noexcept {
  if (key < second) {
    if (key < best) {
      second = best;
      best = key;
    } else {
      second = key;
    }
  }
}

/// knn2()'s result before the search: one entry per query, count = min(2, train_count).
inline std::vector<KnnMatch> knn2_frame(std::size_t query_count, std::size_t train_count) {
  constexpr std::size_t kMaxCount = static_cast<std::size_t>(std::numeric_limits<int>::max());
  require(query_count <= kMaxCount && train_count <= kMaxCount,
          "knn2: more than INT_MAX descriptors (indices are int)");
  std::vector<KnnMatch> result(query_count);
  for (std::size_t i = 0; i < query_count; ++i) {
    result[i].query = static_cast<int>(i);
    result[i].count = static_cast<int>(train_count < 2 ? train_count : 2);
  }
  return result;
}

/// Stores the two smallest keys (kNoKey: none) of neighbour_key() as neighbours.
inline void set_neighbours(KnnMatch& m, std::uint64_t best, std::uint64_t second) noexcept {
  if (best != kNoKey) m.best = {static_cast<int>(best & 0xffffffffU), static_cast<int>(best >> 32)};
  if (second != kNoKey) m.second = {static_cast<int>(second & 0xffffffffU), static_cast<int>(second >> 32)};
}

// The bit-sliced search over each lane type: 128-bit lanes here, 256-bit lanes compiled for AVX2.
namespace bitsliced128 {
#include "affine_orb/matching/detail/knn2_lanes.inc"
}  // namespace bitsliced128

#if AFFINE_ORB_KNN2_LANES256
AFFINE_ORB_TARGET_AVX2_BEGIN
namespace bitsliced256 {
#include "affine_orb/matching/detail/knn2_lanes.inc"
}  // namespace bitsliced256
AFFINE_ORB_TARGET_AVX2_END
#endif

}  // namespace detail
}  // namespace affine_orb
