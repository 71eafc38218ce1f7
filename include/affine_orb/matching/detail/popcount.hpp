#pragma once
/// \file
/// Bit counting for Hamming distances: a 64-bit population count that compiles to the hardware
/// instruction where the target has one, and a portable fallback that is always available (and is
/// what the tests compare the hardware path against).

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "affine_orb/core/detail/simd.hpp"

/// 1 when popcount64() compiles to a hardware instruction: POPCNT on x86 (enabled by -mpopcnt,
/// -msse4.2 or -march=native), CNT on AArch64 (always present). Without it on x86-64, hamming_row()
/// still uses POPCNT where the CPU has it, chosen at run time. On other targets GCC's
/// __builtin_popcountll may become a call into libgcc, which is slower than the inline portable
/// version, so that one is used instead.
#if defined(__GNUC__) && (defined(__POPCNT__) || defined(__aarch64__))
#define AFFINE_ORB_HARDWARE_POPCOUNT 1
#else
#define AFFINE_ORB_HARDWARE_POPCOUNT 0
#endif

namespace affine_orb::detail {

/// Number of set bits of `x` without any special instruction: the classic parallel ("SWAR") sum of
/// bit fields, 2-bit then 4-bit then 8-bit partial counts, the bytes added by one multiplication
/// (H. S. Warren, Hacker's Delight, 2nd ed., 2012, section 5-1).
constexpr int popcount64_portable(std::uint64_t x) noexcept {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
}

/// Number of set bits of `x`; the hardware instruction when AFFINE_ORB_HARDWARE_POPCOUNT is 1.
inline int popcount64(std::uint64_t x) noexcept {
#if AFFINE_ORB_HARDWARE_POPCOUNT
  return __builtin_popcountll(x);
#else
  return popcount64_portable(x);
#endif
}

/// Index of the lowest set bit of a non-zero `x` (0 ... 63): the trailing-zero count instruction
/// with GCC and Clang (BSF on every x86-64, RBIT + CLZ on AArch64), elsewhere the set bits below it,
/// counted.
inline int lowest_set_bit(std::uint64_t x) noexcept {
#if defined(__GNUC__)
  return __builtin_ctzll(x);
#else
  return popcount64((x & (0 - x)) - 1);
#endif
}

/// popcount(a ^ b) summed over the N words, unrolled at compile time.
template <std::size_t N, std::size_t... I>
int popcount_xor_words(const std::array<std::uint64_t, N>& a, const std::array<std::uint64_t, N>& b,
                       std::index_sequence<I...>) noexcept {
  return (0 + ... + popcount64(a[I] ^ b[I]));
}

/// out[j] = popcount(q ^ train[j]) summed over the words, j in [0, n), with popcount64().
template <std::size_t N>
void hamming_row_generic(const std::array<std::uint64_t, N>& q, const std::array<std::uint64_t, N>* train,
                         std::size_t n, int* out) noexcept {
  for (std::size_t j = 0; j < n; ++j) out[j] = popcount_xor_words(q, train[j], std::make_index_sequence<N>{});
}

#if AFFINE_ORB_AVX2_RUNTIME
AFFINE_ORB_TARGET_AVX2_BEGIN
/// hamming_row_generic() with the POPCNT instruction, compiled for it whatever the build flags;
/// call only where cpu_has_avx2() (which checks POPCNT too).
template <std::size_t N>
void hamming_row_popcnt(const std::array<std::uint64_t, N>& q, const std::array<std::uint64_t, N>* train, std::size_t n,
                        int* out) noexcept {
  for (std::size_t j = 0; j < n; ++j) {
    int d = 0;
    for (std::size_t w = 0; w < N; ++w) d += __builtin_popcountll(q[w] ^ train[j][w]);
    out[j] = d;
  }
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// Hamming distances of one descriptor to a row of them: out[j] = popcount(q ^ train[j]), j in
/// [0, n). Where popcount64() is the portable count (x86-64 without -mpopcnt) and the CPU has
/// POPCNT, the instruction is chosen at run time, once per row.
template <std::size_t N>
void hamming_row(const std::array<std::uint64_t, N>& q, const std::array<std::uint64_t, N>* train, std::size_t n,
                 int* out) noexcept {
#if AFFINE_ORB_AVX2_RUNTIME
  if (cpu_has_avx2()) {
    hamming_row_popcnt(q, train, n, out);
    return;
  }
#endif
  hamming_row_generic(q, train, n, out);
}

}  // namespace affine_orb::detail
