#pragma once
/// \file
/// The instruction sets the kernels use and how the widest one is chosen.
///
/// 128 bits, at compile time: AFFINE_ORB_SIMD128 is 1 with SSE2 (every x86-64) and with NEON on
/// AArch64 (always present), 0 elsewhere, where the scalar references run; AFFINE_ORB_NEON is 1 when
/// that set is NEON. The kernels written once over 16 lanes of bytes (FAST scores, non-maximum
/// suppression, rBRIEF's tests) use these; each instruction set's kernel equals the scalar reference
/// byte for byte (the tests compare them, under qemu-user for AArch64: tests/cross_aarch64.sh).
///
/// 256 bits (AVX2), at run time: AFFINE_ORB_AVX2 is 1 where the AVX2 kernels are compiled, i.e.
/// where the target has AVX2 (-march=native on such a CPU, AFFINE_ORB_NATIVE) and on every x86-64
/// with GCC or Clang. There they are compiled whatever the build flags, each between
/// AFFINE_ORB_TARGET_AVX2_BEGIN and AFFINE_ORB_TARGET_AVX2_END (a region whose functions GCC and
/// Clang compile for AVX2 and POPCNT), and a kernel's dispatcher calls the AVX2 one when
/// cpu_has_avx2() is true: the default build runs AVX2 on CPUs that have it and SSE2 on the others.
/// Only AVX2 kernels go inside a region (a generic inline function compiled for AVX2 there could be
/// the copy the linker keeps and then run on a CPU without it), and a dispatcher decides per row or
/// per block, not per pixel. Where the target has AVX2 at compile time the regions are empty and
/// cpu_has_avx2() is the constant true.

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

#if defined(__AVX2__) && (defined(__POPCNT__) || !defined(__GNUC__))
#include <immintrin.h>
#define AFFINE_ORB_AVX2 1
#define AFFINE_ORB_AVX2_RUNTIME 0
#define AFFINE_ORB_TARGET_AVX2_BEGIN
#define AFFINE_ORB_TARGET_AVX2_END
#elif defined(__x86_64__) && defined(__clang__)
#include <immintrin.h>
#define AFFINE_ORB_AVX2 1
#define AFFINE_ORB_AVX2_RUNTIME 1
#define AFFINE_ORB_TARGET_AVX2_BEGIN \
  _Pragma("clang attribute push(__attribute__((target(\"avx2,popcnt\"))), apply_to = function)")
#define AFFINE_ORB_TARGET_AVX2_END _Pragma("clang attribute pop")
#elif defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define AFFINE_ORB_AVX2 1
#define AFFINE_ORB_AVX2_RUNTIME 1
// GCC checks the ABI of a 256-bit argument or result (-Wpsabi) of a lambda or template in the
// region where it instantiates it, after the region, and would warn of a change that cannot happen:
// such functions are called only from the region.
#define AFFINE_ORB_TARGET_AVX2_BEGIN                                                                \
  _Pragma("GCC push_options") _Pragma("GCC target(\"avx2,popcnt\")") _Pragma("GCC diagnostic push") \
      _Pragma("GCC diagnostic ignored \"-Wpsabi\"")
#define AFFINE_ORB_TARGET_AVX2_END _Pragma("GCC diagnostic pop") _Pragma("GCC pop_options")
#else
#define AFFINE_ORB_AVX2 0
#define AFFINE_ORB_AVX2_RUNTIME 0
#endif

namespace affine_orb::detail {

/// True when the AVX2 kernels are compiled and the CPU running the program has AVX2 and POPCNT
/// (and the operating system saves the 256-bit registers: __builtin_cpu_supports checks it). Asked
/// once and kept in a function-local constant.
inline bool cpu_has_avx2() noexcept {
#if AFFINE_ORB_AVX2_RUNTIME
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  }();
  return has;
#else
  return AFFINE_ORB_AVX2 != 0;
#endif
}

/// The widest instruction set the kernels use on this CPU: "avx2", "sse2", "neon" or "scalar".
inline const char* simd_path() noexcept {
  if (cpu_has_avx2()) return "avx2";
#if AFFINE_ORB_NEON
  return "neon";
#elif AFFINE_ORB_SIMD128
  return "sse2";
#else
  return "scalar";
#endif
}

}  // namespace affine_orb::detail

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
