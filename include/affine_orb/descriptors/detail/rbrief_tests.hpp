#pragma once
/// \file
/// The 256 intensity tests of rBRIEF (rbrief.hpp) on the smoothed level: with the rotated test
/// points as byte offsets from the keypoint's pixel (rotated_offsets.hpp; test i's points at
/// offset[2i] and offset[2i + 1]), bit i is 1 iff I(offset[2i]) < I(offset[2i + 1]). The scalar
/// reference, SSE2 or NEON gathering the samples into byte arrays and comparing 16 tests at a
/// time, and AVX2 (chosen at run time) inserting them into registers and comparing 32 at a time,
/// give the same bits.

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "affine_orb/core/detail/simd.hpp"

namespace affine_orb::detail {

/// Number of tests, and of bits of the descriptor.
inline constexpr int kRbriefTests = 256;

/// Sets the bits of the tests on the pixels at center + offset[k] into words (zeroed by the
/// caller): the scalar reference.
inline void rbrief_tests_scalar(const std::uint8_t* center, const std::int32_t* offset, std::uint64_t* words) {
  for (int i = 0; i < kRbriefTests; ++i) {
    const int ia = center[offset[2 * i]];
    const int ib = center[offset[2 * i + 1]];
    words[i / 64] |= static_cast<std::uint64_t>(ia < ib) << (i % 64);
  }
}

#if AFFINE_ORB_SIMD128
/// rbrief_tests_scalar() with the two samples of every test gathered into byte arrays, then
/// compared 16 tests at a time (SSE2 or NEON), the same bits.
inline void rbrief_tests_128(const std::uint8_t* center, const std::int32_t* offset, std::uint64_t* words) {
  alignas(16) std::array<std::uint8_t, kRbriefTests> first;
  alignas(16) std::array<std::uint8_t, kRbriefTests> second;
  // Unrolled: the loads and stores are all its work, so a loop's count and branch per test
  // would be a third of its instructions.
  AFFINE_ORB_UNROLL
  for (std::size_t i = 0; i < static_cast<std::size_t>(kRbriefTests); ++i) {
    first[i] = center[offset[2 * i]];
    second[i] = center[offset[2 * i + 1]];
  }
  for (int i = 0; i < kRbriefTests; i += 16) {
#if defined(__SSE2__)
    // I_a < I_b iff the saturated difference I_b − I_a is non-zero.
    const __m128i va = _mm_load_si128(reinterpret_cast<const __m128i*>(first.data() + i));
    const __m128i vb = _mm_load_si128(reinterpret_cast<const __m128i*>(second.data() + i));
    const int not_less = _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(vb, va), _mm_setzero_si128()));
    const std::uint64_t bits = static_cast<std::uint64_t>(~not_less & 0xFFFF);
#else
    const uint8x16_t less = vcltq_u8(vld1q_u8(first.data() + i), vld1q_u8(second.data() + i));
    const std::uint64_t bits = top_bits_neon(less);
#endif
    words[static_cast<std::size_t>(i / 64)] |= bits << (i % 64);
  }
}
#endif

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// The first (`side` 0) or second (1) samples of tests first .. first + 15, each loaded straight
/// into its lane (vpinsrb from memory: no byte array to store and load again).
template <std::size_t... K>
inline __m128i rbrief_samples_avx2(const std::uint8_t* center, const std::int32_t* offset, int first, int side,
                                   std::index_sequence<K...>) {
  __m128i v = _mm_setzero_si128();
  ((v = _mm_insert_epi8(v, center[offset[2 * (first + static_cast<int>(K)) + side]], static_cast<int>(K))), ...);
  return v;
}

/// rbrief_tests_scalar() 32 tests at a time: the samples inserted into two 16-lane halves per side,
/// compared as in rbrief_tests_128(), the same bits.
inline void rbrief_tests_avx2(const std::uint8_t* center, const std::int32_t* offset, std::uint64_t* words) {
  constexpr auto kLanes = std::make_index_sequence<16>{};
  for (int i = 0; i < kRbriefTests; i += 32) {
    const __m256i a = _mm256_set_m128i(rbrief_samples_avx2(center, offset, i + 16, 0, kLanes),
                                       rbrief_samples_avx2(center, offset, i, 0, kLanes));
    const __m256i b = _mm256_set_m128i(rbrief_samples_avx2(center, offset, i + 16, 1, kLanes),
                                       rbrief_samples_avx2(center, offset, i, 1, kLanes));
    const int not_less = _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_subs_epu8(b, a), _mm256_setzero_si256()));
    words[static_cast<std::size_t>(i / 64)] |= static_cast<std::uint64_t>(~static_cast<std::uint32_t>(not_less))
                                               << (i % 64);
  }
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// rbrief_tests_scalar() on the widest path the CPU has (AVX2, SSE2 or NEON, else the scalar
/// reference).
inline void rbrief_tests(const std::uint8_t* center, const std::int32_t* offset, std::uint64_t* words) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    rbrief_tests_avx2(center, offset, words);
    return;
  }
#endif
#if AFFINE_ORB_SIMD128
  rbrief_tests_128(center, offset, words);
#else
  rbrief_tests_scalar(center, offset, words);
#endif
}

}  // namespace affine_orb::detail
