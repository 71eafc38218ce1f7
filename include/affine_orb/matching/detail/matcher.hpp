#pragma once
/// \file
/// Internals (namespace detail, not part of the API) of matching/matcher.hpp: the bit-sliced and
/// VPOPCNTDQ k = 2 searches.
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
/// Where the target has AVX-512 VPOPCNTDQ (AFFINE_ORB_KNN2_VPOPCNTDQ, chosen at compile time) a
/// plain XOR + VPOPCNTQ search over eight queries per register replaces it. Both give the same
/// results; the default x86-64 build (SSE2 only) uses the bit-sliced search.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#if defined(__AVX512F__) && defined(__AVX512VPOPCNTDQ__)
#include <immintrin.h>
/// 1 when knn2() uses the AVX-512 VPOPCNTDQ search (the target has it, e.g. -march=native on Ice
/// Lake or Zen 4 and later), 0 when it uses the bit-sliced search.
#define AFFINE_ORB_KNN2_VPOPCNTDQ 1
#else
#define AFFINE_ORB_KNN2_VPOPCNTDQ 0
#endif

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/detail/popcount.hpp"

namespace affine_orb {
namespace detail {

/// One neighbour of a query descriptor: index into the train descriptors and distance in bits. The
/// defaults mark an entry that holds no neighbour (distance larger than any real one).
struct Neighbour {
  int train = 0;
  int distance = std::numeric_limits<int>::max();
};

/// The two nearest train descriptors of one query descriptor, ties broken by the smaller train
/// index. `count` = min(2, number of train descriptors) says how many of `best`, `second` are real;
/// the others keep Neighbour's defaults.
struct KnnMatch {
  int query = 0;
  int count = 0;
  Neighbour best;
  Neighbour second;
};

/// The bit-lane vector of the k = 2 search, chosen at compile time: a GCC/Clang vector of 64-bit
/// words as wide as the target's integer SIMD registers (32 bytes with AVX2, 16 bytes otherwise:
/// SSE2 on every x86-64, NEON on AArch64, and pairs of plain words on targets without SIMD), a plain
/// 64-bit word with other compilers. Every lane type gives the same results (tests check both).
#if defined(__GNUC__)
#if defined(__AVX2__)
typedef std::uint64_t LaneVector __attribute__((vector_size(32), may_alias));
#else
typedef std::uint64_t LaneVector __attribute__((vector_size(16), may_alias));
#endif
#else
using LaneVector = std::uint64_t;
#endif

/// 64-bit words in a lane vector V (std::uint64_t or a GCC/Clang vector of them).
template <class V>
inline constexpr int kLaneWords = static_cast<int>(sizeof(V) / sizeof(std::uint64_t));

/// Word i of V; lane l of V is bit l % 64 of word l / 64.
template <class V>
std::uint64_t lane_word(const V& v, int i) noexcept {
  std::uint64_t w = 0;
  std::memcpy(&w, reinterpret_cast<const unsigned char*>(&v) + sizeof(w) * static_cast<std::size_t>(i), sizeof(w));
  return w;
}

template <class V>
void set_lane_word(V& v, int i, std::uint64_t w) noexcept {
  std::memcpy(reinterpret_cast<unsigned char*>(&v) + sizeof(w) * static_cast<std::size_t>(i), &w, sizeof(w));
}

/// Every word of the vector set to `w`.
template <class V>
V lane_broadcast(std::uint64_t w) noexcept {
  V v{};
  for (int i = 0; i < kLaneWords<V>; ++i) set_lane_word(v, i, w);
  return v;
}

template <class V>
bool lane_any(const V& v) noexcept {
  std::uint64_t any = 0;
  for (int i = 0; i < kLaneWords<V>; ++i) any |= lane_word(v, i);
  return any != 0;
}

/// Index of the lowest set lane of a non-zero vector.
template <class V>
int first_lane(const V& v) noexcept {
  int i = 0;
  while (lane_word(v, i) == 0) ++i;
  return 64 * i + lowest_set_bit(lane_word(v, i));
}

template <class V>
void clear_lane(V& v, int lane) noexcept {
  set_lane_word(v, lane / 64, lane_word(v, lane / 64) & ~(std::uint64_t{1} << (lane % 64)));
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

/// The descriptors as bit planes, kLaneWords<V>·64 descriptors per block: plane b of block k,
/// planes[k·Bits + b], holds in lane l bit b of descriptor k·lanes + l. Lanes past the last
/// descriptor are zero.
template <int Bits, class V>
std::vector<V> bit_planes(const std::vector<BinaryDescriptor<Bits>>& descriptors) {
  constexpr std::size_t kLanes = 64 * kLaneWords<V>;
  const std::size_t n = descriptors.size();
  const std::size_t blocks = (n + kLanes - 1) / kLanes;
  std::vector<V> planes(blocks * Bits, lane_broadcast<V>(0));
  std::array<std::uint64_t, 64> square{};
  for (std::size_t block = 0; block < blocks; ++block) {
    for (int word = 0; word < kLaneWords<V>; ++word) {
      const std::size_t first = block * kLanes + 64 * static_cast<std::size_t>(word);
      if (first >= n) break;
      for (int w = 0; w < Bits / 64; ++w) {
        for (std::size_t r = 0; r < 64; ++r) square[r] = first + r < n ? descriptors[first + r][w] : 0;
        transpose_bits64(square);
        for (int b = 0; b < 64; ++b) set_lane_word(planes[block * Bits + 64 * w + b], word, square[b]);
      }
    }
  }
  return planes;
}

/// Number of binary digits of x >= 0.
constexpr int bit_width(int x) noexcept { return x == 0 ? 0 : 1 + bit_width(x / 2); }

/// Bit planes of a lane-wise counter of up to Bits: six for the carry-save tree over 64 planes,
/// then enough for the number of 64-bit words (the counter reaches Bits + 1 < 2^planes).
template <int Bits>
inline constexpr int kCountPlanes = 6 + bit_width(Bits / 64);

/// Full adder per lane: adds planes a and b into `sum` (weight 1) and returns the carry plane
/// (weight 2).
template <class V>
V carry_save_add(V& sum, V a, V b) noexcept {
  const V u = sum ^ a;
  const V carry = (sum & a) | (u & b);
  sum = u ^ b;
  return carry;
}

/// Adds the 2^K planes t[i] ^ q[i] lane-wise to the binary counter acc[0..K-1] (acc[k] holds bit k
/// of each lane's count) and returns the carry of weight 2^K: a carry-save adder tree, one full
/// adder per plane (the Harley-Seal scheme of W. Muła, N. Kurz, D. Lemire, "Faster population
/// counts using AVX2 instructions", The Computer Journal 61(1), 2018, applied per lane).
template <int K, class V>
V add_planes(const V* t, const V* q, V* acc) noexcept {
  if constexpr (K == 1) {
    return carry_save_add(acc[0], t[0] ^ q[0], t[1] ^ q[1]);
  } else {
    const V low = add_planes<K - 1>(t, q, acc);
    const V high = add_planes<K - 1>(t + (1 << (K - 1)), q + (1 << (K - 1)), acc);
    return carry_save_add(acc[K - 1], low, high);
  }
}

/// Lane-wise Hamming distances of one query (its bits as all-ones/all-zero planes `query_planes`)
/// to one block of train planes, as a binary counter, least significant plane first.
template <int Bits, class V>
std::array<V, kCountPlanes<Bits>> block_distances(const V* train_planes, const V* query_planes) noexcept {
  std::array<V, kCountPlanes<Bits>> count{};
  for (int w = 0; w < Bits / 64; ++w) {
    V carry = add_planes<6>(train_planes + 64 * w, query_planes + 64 * w, count.data());
    for (int k = 6; k < kCountPlanes<Bits>; ++k) {
      const V sum = count[k] ^ carry;
      carry = count[k] & carry;
      count[k] = sum;
    }
  }
  return count;
}

/// Lanes whose counter is < threshold (0 <= threshold < 2^P): a bit-serial comparison from the
/// least significant plane up.
template <class V, std::size_t P>
V lanes_below(const std::array<V, P>& count, int threshold) noexcept {
  V at_least = lane_broadcast<V>(~std::uint64_t{0});  // counter >= threshold on the bits seen so far
  for (std::size_t k = 0; k < P; ++k) {
    at_least = ((threshold >> k) & 1) != 0 ? (count[k] & at_least) : (count[k] | at_least);
  }
  return ~at_least;
}

/// The smallest counter among the lanes of the non-empty `set`, found bit-serially from the most
/// significant plane down; `set` is narrowed to the lanes that hold it.
template <class V, std::size_t P>
int narrow_to_minimum(const std::array<V, P>& count, V& set) noexcept {
  int minimum = 0;
  for (std::size_t k = P; k-- > 0;) {
    const V zero_here = set & ~count[k];
    if (lane_any(zero_here)) {
      set = zero_here;
    } else {
      minimum |= 1 << k;
    }
  }
  return minimum;
}

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

/// knn2() with an explicit lane vector type V (std::uint64_t or a GCC/Clang vector of them).
template <class V, std::size_t Words>
std::vector<KnnMatch> knn2_bitsliced(const std::vector<std::array<std::uint64_t, Words>>& query,
                                     const std::vector<std::array<std::uint64_t, Words>>& train) {
  static_assert(Words > 0, "a descriptor has at least one 64-bit word");
  constexpr int Bits = static_cast<int>(64 * Words);
  constexpr std::size_t kLanes = 64 * kLaneWords<V>;
  const std::size_t n = train.size();
  std::vector<KnnMatch> result = knn2_frame(query.size(), n);
  if (query.empty() || n == 0) return result;

  const std::vector<V> planes = bit_planes<Bits, V>(train);
  const std::size_t blocks = planes.size() / Bits;
  V last_block_lanes = lane_broadcast<V>(0);  // the lanes of the last block that hold a descriptor
  for (std::size_t lane = 0; lane < n - (blocks - 1) * kLanes; ++lane) {
    const int word = static_cast<int>(lane / 64);
    set_lane_word(last_block_lanes, word, lane_word(last_block_lanes, word) | (std::uint64_t{1} << (lane % 64)));
  }

  std::vector<V> query_planes(Bits);
  for (std::size_t i = 0; i < query.size(); ++i) {
    for (int b = 0; b < Bits; ++b) {
      query_planes[b] = lane_broadcast<V>(0 - ((query[i][b / 64] >> (b % 64)) & 1));
    }
    std::uint64_t best = kNoKey;
    std::uint64_t second = kNoKey;
    for (std::size_t block = 0; block < blocks; ++block) {
      const auto count = block_distances<Bits, V>(planes.data() + block * Bits, query_planes.data());
      const int threshold = second == kNoKey ? Bits + 1 : static_cast<int>(second >> 32);
      V candidates = lanes_below(count, threshold);
      if (block + 1 == blocks) candidates = candidates & last_block_lanes;
      // Only the block's two smallest (distance, index) can enter the two best.
      for (int found = 0; found < 2 && lane_any(candidates); ++found) {
        V nearest = candidates;
        const int distance = narrow_to_minimum(count, nearest);
        const int lane = first_lane(nearest);
        keep_two_smallest(neighbour_key(distance, block * kLanes + lane), best, second);
        clear_lane(nearest, lane);
        if (lane_any(nearest)) {  // a tie: the next lane at the same distance is the block's second
          keep_two_smallest(neighbour_key(distance, block * kLanes + first_lane(nearest)), best, second);
          break;
        }
        clear_lane(candidates, lane);
      }
    }
    set_neighbours(result[i], best, second);
  }
  return result;
}

#if AFFINE_ORB_KNN2_VPOPCNTDQ
/// knn2() with AVX-512 VPOPCNTDQ: eight queries per 512-bit register, one per 64-bit lane, and two
/// such groups at a time. Each train descriptor is broadcast word by word, XOR-ed with the queries
/// and counted with VPOPCNTQ; the two best are kept per lane as neighbour_key()s with unsigned
/// 64-bit min/max, updated only when some lane beats its current second-best distance.
template <std::size_t Words>
std::vector<KnnMatch> knn2_vpopcntdq(const std::vector<std::array<std::uint64_t, Words>>& query,
                                     const std::vector<std::array<std::uint64_t, Words>>& train) {
  static_assert(Words > 0, "a descriptor has at least one 64-bit word");
  const std::size_t nq = query.size();
  const std::size_t nt = train.size();
  std::vector<KnnMatch> result = knn2_frame(nq, nt);
  if (nq == 0 || nt == 0) return result;
  // Word w of query 8g + l at [(g · Words + w) · 8 + l]; the last group is padded with the last query.
  const std::size_t groups = (nq + 7) / 8;
  std::vector<std::uint64_t> lanes(groups * Words * 8);
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t w = 0; w < Words; ++w) {
      for (std::size_t l = 0; l < 8; ++l) lanes[(g * Words + w) * 8 + l] = query[std::min(nq - 1, 8 * g + l)][w];
    }
  }
  // Shifts and min/max use the zero-masked forms with every lane selected: the same instructions,
  // but GCC 12's unmasked intrinsics trip -Wmaybe-uninitialized on their undefined pass-through.
  constexpr __mmask8 kAll = 0xff;
  const __m512i none = _mm512_set1_epi64(-1);
  for (std::size_t g = 0; g < groups; g += 2) {
    const std::size_t h = g + 1 < groups ? g + 1 : g;  // the second group (the first again at the end)
    __m512i qa[Words];
    __m512i qb[Words];
    for (std::size_t w = 0; w < Words; ++w) {
      qa[w] = _mm512_loadu_si512(lanes.data() + (g * Words + w) * 8);
      qb[w] = _mm512_loadu_si512(lanes.data() + (h * Words + w) * 8);
    }
    __m512i best_a = none;
    __m512i second_a = none;
    __m512i best_b = none;
    __m512i second_b = none;
    __m512i limit_a = _mm512_maskz_srli_epi64(kAll, none, 32);  // second-best distances
    __m512i limit_b = limit_a;
    for (std::size_t j = 0; j < nt; ++j) {
      __m512i da = _mm512_setzero_si512();
      __m512i db = _mm512_setzero_si512();
      for (std::size_t w = 0; w < Words; ++w) {
        const __m512i t = _mm512_set1_epi64(static_cast<long long>(train[j][w]));
        da = _mm512_add_epi64(da, _mm512_popcnt_epi64(_mm512_xor_si512(qa[w], t)));
        db = _mm512_add_epi64(db, _mm512_popcnt_epi64(_mm512_xor_si512(qb[w], t)));
      }
      if ((_mm512_cmplt_epu64_mask(da, limit_a) | _mm512_cmplt_epu64_mask(db, limit_b)) == 0) continue;
      const __m512i index = _mm512_set1_epi64(static_cast<long long>(j));
      const __m512i key_a = _mm512_or_si512(_mm512_maskz_slli_epi64(kAll, da, 32), index);
      const __m512i key_b = _mm512_or_si512(_mm512_maskz_slli_epi64(kAll, db, 32), index);
      second_a = _mm512_maskz_min_epu64(kAll, second_a, _mm512_maskz_max_epu64(kAll, best_a, key_a));
      best_a = _mm512_maskz_min_epu64(kAll, best_a, key_a);
      second_b = _mm512_maskz_min_epu64(kAll, second_b, _mm512_maskz_max_epu64(kAll, best_b, key_b));
      best_b = _mm512_maskz_min_epu64(kAll, best_b, key_b);
      limit_a = _mm512_maskz_srli_epi64(kAll, second_a, 32);
      limit_b = _mm512_maskz_srli_epi64(kAll, second_b, 32);
    }
    std::uint64_t keys[4][8];
    _mm512_storeu_si512(keys[0], best_a);
    _mm512_storeu_si512(keys[1], second_a);
    _mm512_storeu_si512(keys[2], best_b);
    _mm512_storeu_si512(keys[3], second_b);
    for (std::size_t l = 0; l < 8; ++l) {
      if (8 * g + l < nq) set_neighbours(result[8 * g + l], keys[0][l], keys[1][l]);
      if (8 * h + l < nq) set_neighbours(result[8 * h + l], keys[2][l], keys[3][l]);
    }
  }
  return result;
}
#endif

}  // namespace detail
}  // namespace affine_orb
