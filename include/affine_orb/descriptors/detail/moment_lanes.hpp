#pragma once
/// \file
/// The intensity-centroid moments of Rbrief's orientation over the disc of CentroidDisc, in chunks
/// of columns: eight pixels widened to 16-bit lanes, multiplied by 16-bit weights and summed
/// pairwise into four 32-bit lanes, with SSE2's multiply-add or NEON's widening
/// multiply-accumulate; 32 at a time with AVX2's 8-bit multiply-add, chosen at run time. One loop
/// over the 128-bit operations serves SSE2 and NEON; every path gives the scalar reference's
/// integers (tests/test_rbrief.cpp, under qemu-user for NEON).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "affine_orb/core/detail/simd.hpp"

#if AFFINE_ORB_SIMD128
namespace affine_orb::detail {

#if AFFINE_ORB_NEON
struct MomentLanes {
  using Words = int16x8_t;  ///< eight signed 16-bit lanes
  using Sums = int32x4_t;   ///< four signed 32-bit lanes
  static Sums zero() { return vdupq_n_s32(0); }
  /// The eight bytes at p, zero-extended.
  static Words load8(const std::uint8_t* p) { return vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p))); }
  static Words load(const std::array<std::int16_t, 8>& w) { return vld1q_s16(w.data()); }
  static Words add(Words a, Words b) { return vaddq_s16(a, b); }
  static Words subtract(Words a, Words b) { return vsubq_s16(a, b); }
  /// sum + the products a·w, lanes 2i and 2i+1 into lane i (each product below 2^15 here).
  static Sums multiply_add(Sums sum, Words a, Words w) {
    return vmlal_high_s16(vmlal_s16(sum, vget_low_s16(a), vget_low_s16(w)), a, w);
  }
  static std::int64_t total(Sums s) { return vaddlvq_s32(s); }
};
#else
struct MomentLanes {
  using Words = __m128i;
  using Sums = __m128i;
  static Sums zero() { return _mm_setzero_si128(); }
  static Words load8(const std::uint8_t* p) {
    return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128());
  }
  static Words load(const std::array<std::int16_t, 8>& w) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(w.data()));
  }
  static Words add(Words a, Words b) { return _mm_add_epi16(a, b); }
  static Words subtract(Words a, Words b) { return _mm_sub_epi16(a, b); }
  static Sums multiply_add(Sums sum, Words a, Words w) { return _mm_add_epi32(sum, _mm_madd_epi16(a, w)); }
  static std::int64_t total(Sums s) {
    alignas(16) std::int32_t lanes[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(lanes), s);
    return static_cast<std::int64_t>(lanes[0]) + lanes[1] + lanes[2] + lanes[3];
  }
};
#endif

/// The disc of CentroidDisc in chunks of N columns (r + 1 = half_widths.size()): a disc narrower
/// than N in one chunk, columns −N/2 .. N/2 − 1; a wider one in chunks from column −r, x[j] ..
/// x[j] + N − 1, the last one ending at r and overlapping the one before. For chunk j and row v,
/// the weight u of column u inside the disc and not in an earlier chunk (else 0), and the weight v
/// of the same columns, as `Weight`.
template <int N, class Weight = std::int16_t>
struct DiscChunks {
  int radius = 0;
  std::vector<int> x;
  std::vector<std::array<Weight, N>> u;  ///< [v·chunks + j]
  std::vector<std::array<Weight, N>> v;  ///< [v·chunks + j]
};

/// DiscChunks of the disc whose row v spans columns −half_widths[v] .. half_widths[v].
template <int N, class Weight = std::int16_t>
DiscChunks<N, Weight> disc_chunks(const std::vector<int>& half_widths) {
  DiscChunks<N, Weight> d;
  const int r = static_cast<int>(half_widths.size()) - 1;
  d.radius = r;
  if (2 * r + 1 <= N) {
    d.x.push_back(-N / 2);
  } else {
    for (int x = -r;; x = std::min(x + N, r - (N - 1))) {
      d.x.push_back(x);
      if (x + N > r) break;
    }
  }
  const std::size_t chunks = d.x.size();
  d.u.assign((static_cast<std::size_t>(r) + 1) * chunks, {});
  d.v.assign(d.u.size(), {});
  for (int v = 0; v <= r; ++v) {
    const int half = half_widths[static_cast<std::size_t>(v)];
    for (std::size_t j = 0; j < chunks; ++j) {
      for (int i = 0; i < N; ++i) {
        const int u = d.x[j] + i;
        const bool earlier = j > 0 && u < d.x[j - 1] + N;
        if (std::abs(u) > half || earlier) continue;
        d.u[static_cast<std::size_t>(v) * chunks + j][static_cast<std::size_t>(i)] = static_cast<Weight>(u);
        d.v[static_cast<std::size_t>(v) * chunks + j][static_cast<std::size_t>(i)] = static_cast<Weight>(v);
      }
    }
  }
  return d;
}

/// The moments m01 = Σ v·I and m10 = Σ u·I of a disc.
struct CentroidMoments {
  std::int64_t m01 = 0;
  std::int64_t m10 = 0;
};

/// The moments of the disc `d` around the pixel at `center` (rows `step` bytes apart), eight
/// columns at a time: per row pair ±v, u·(I(u, v) + I(u, −v)) and v·(I(u, v) − I(u, −v)) (|u|,
/// |v| <= 64, each product below 2^15), exactly the integers of the scalar loop. Reads the disc's
/// chunks: for a disc narrower than 8, columns −4 .. 3.
inline CentroidMoments centroid_moments_128(const std::uint8_t* center, std::size_t step, const DiscChunks<8>& d) {
  const std::size_t chunks = d.x.size();
  using L = MomentLanes;
  L::Sums m10 = L::zero();
  L::Sums m01 = L::zero();
  for (std::size_t j = 0; j < chunks; ++j) m10 = L::multiply_add(m10, L::load8(center + d.x[j]), L::load(d.u[j]));
  for (int v = 1; v <= d.radius; ++v) {
    const std::uint8_t* below = center + static_cast<std::ptrdiff_t>(v) * static_cast<std::ptrdiff_t>(step);
    const std::uint8_t* above = center - static_cast<std::ptrdiff_t>(v) * static_cast<std::ptrdiff_t>(step);
    for (std::size_t j = 0; j < chunks; ++j) {
      const std::size_t k = static_cast<std::size_t>(v) * chunks + j;
      const L::Words b = L::load8(below + d.x[j]);
      const L::Words a = L::load8(above + d.x[j]);
      m10 = L::multiply_add(m10, L::add(a, b), L::load(d.u[k]));
      m01 = L::multiply_add(m01, L::subtract(b, a), L::load(d.v[k]));
    }
  }
  return {L::total(m01), L::total(m10)};
}

/// Largest disc radius of centroid_moments_avx2(): its 16-bit sums of two rows' products,
/// 2·2·255·r, stay below 2^15.
inline constexpr int kCentroidAvx2MaxRadius = 32;

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// m10 += u·(I_b + I_a), m01 += v·(I_b − I_a) for the 32 columns at `below` and `above` with the
/// weights `u` and `w` (the body of centroid_moments_avx2()).
inline void add_row_pair_avx2(const std::uint8_t* below, const std::uint8_t* above, const std::int8_t* u,
                              const std::int8_t* w, __m256i& m10, __m256i& m01) {
  const __m256i ones = _mm256_set1_epi16(1);
  const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(below));
  const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(above));
  const __m256i wu = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(u));
  const __m256i wv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w));
  const __m256i s10 = _mm256_add_epi16(_mm256_maddubs_epi16(b, wu), _mm256_maddubs_epi16(a, wu));
  const __m256i s01 = _mm256_sub_epi16(_mm256_maddubs_epi16(b, wv), _mm256_maddubs_epi16(a, wv));
  m10 = _mm256_add_epi32(m10, _mm256_madd_epi16(s10, ones));
  m01 = _mm256_add_epi32(m01, _mm256_madd_epi16(s01, ones));
}

/// centroid_moments_128() 32 columns at a time, for radii up to kCentroidAvx2MaxRadius: the
/// pixels multiplied by 8-bit weights and summed pairwise into 16-bit lanes (vpmaddubsw, exact
/// here), the row pair ±v added (u) or subtracted (v) and summed into 32-bit lanes, the same
/// integers. ORB's radius 15 is one chunk a row. Reads the disc's chunks: for a disc narrower
/// than 32, columns −16 .. 15.
inline CentroidMoments centroid_moments_avx2(const std::uint8_t* center, std::size_t step,
                                             const DiscChunks<32, std::int8_t>& d) {
  const std::size_t chunks = d.x.size();
  const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(step);
  __m256i m10 = _mm256_setzero_si256();
  __m256i m01 = _mm256_setzero_si256();
  // Row 0 (v = 0) adds to m10 only.
  for (std::size_t j = 0; j < chunks; ++j) {
    const __m256i i0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(center + d.x[j]));
    const __m256i u = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d.u[j].data()));
    m10 = _mm256_add_epi32(m10, _mm256_madd_epi16(_mm256_maddubs_epi16(i0, u), _mm256_set1_epi16(1)));
  }
  // One chunk a row (radius < 16, ORB's included): no chunk loop and no index arithmetic, the
  // pointers step by a row; the general loop below gives the same sums with more instructions.
  if (chunks == 1) {
    const std::uint8_t* below = center + d.x[0] + row;
    const std::uint8_t* above = center + d.x[0] - row;
    for (int v = 1; v <= d.radius; ++v, below += row, above -= row) {
      add_row_pair_avx2(below, above, d.u[static_cast<std::size_t>(v)].data(), d.v[static_cast<std::size_t>(v)].data(),
                        m10, m01);
    }
  } else {
    for (int v = 1; v <= d.radius; ++v) {
      for (std::size_t j = 0; j < chunks; ++j) {
        const std::size_t k = static_cast<std::size_t>(v) * chunks + j;
        add_row_pair_avx2(center + v * row + d.x[j], center - v * row + d.x[j], d.u[k].data(), d.v[k].data(), m10, m01);
      }
    }
  }
  alignas(32) std::int32_t lanes10[8];
  alignas(32) std::int32_t lanes01[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes10), m10);
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes01), m01);
  CentroidMoments moments;
  for (int i = 0; i < 8; ++i) {
    moments.m10 += lanes10[i];
    moments.m01 += lanes01[i];
  }
  return moments;
}
AFFINE_ORB_TARGET_AVX2_END
#endif

}  // namespace affine_orb::detail
#endif
