#pragma once
/// \file
/// The 128-bit SIMD instruction set the kernels compile for, chosen at compile time:
/// AFFINE_ORB_SIMD128 is 1 with SSE2 (every x86-64) and with NEON on AArch64 (always present), 0
/// elsewhere, where the scalar references run; AFFINE_ORB_NEON is 1 when that set is NEON. The kernels written once
/// over 16 lanes of bytes (FAST scores, non-maximum suppression, rBRIEF's tests) use these; each instruction set's
/// kernel equals the scalar reference byte for byte (the tests compare them, under qemu-user for
/// AArch64: tests/cross_aarch64.sh).

#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#define AFFINE_ORB_SIMD128 1
#define AFFINE_ORB_NEON 0
#elif defined(__ARM_NEON) && defined(__aarch64__)
#include <arm_neon.h>
#define AFFINE_ORB_SIMD128 1
#define AFFINE_ORB_NEON 1
#else
#define AFFINE_ORB_SIMD128 0
#define AFFINE_ORB_NEON 0
#endif

#if defined(__GNUC__) || defined(__clang__)
#define AFFINE_ORB_UNROLL _Pragma("GCC unroll 16")
#else
#define AFFINE_ORB_UNROLL
#endif

#if AFFINE_ORB_NEON
namespace affine_orb::detail {

/// Bit i of the result set where lane i of `v` has its top bit set: SSE2's movemask on NEON (each
/// lane's top bit spread over the lane, masked with its bit weight, the two halves summed).
inline unsigned top_bits_neon(uint8x16_t v) {
  static constexpr std::uint8_t kWeight[16] = {1, 2, 4, 8, 16, 32, 64, 128, 1, 2, 4, 8, 16, 32, 64, 128};
  const uint8x16_t bits = vandq_u8(vreinterpretq_u8_s8(vshrq_n_s8(vreinterpretq_s8_u8(v), 7)), vld1q_u8(kWeight));
  return static_cast<unsigned>(vaddv_u8(vget_low_u8(bits))) |
         (static_cast<unsigned>(vaddv_u8(vget_high_u8(bits))) << 8);
}

}  // namespace affine_orb::detail
#endif
