#pragma once
/// \file
/// The lane operations of the intensity-centroid moments (Rbrief's orientation): eight pixels
/// widened to 16-bit lanes, multiplied by 16-bit weights and summed pairwise into four 32-bit lanes,
/// with SSE2's multiply-add or NEON's widening multiply-accumulate. One loop over these operations
/// serves both instruction sets; both give the scalar reference's integers (tests/test_rbrief.cpp,
/// under qemu-user for NEON).

#include <array>
#include <cstdint>

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

}  // namespace affine_orb::detail
#endif
