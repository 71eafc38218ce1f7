#pragma once
/// \file
/// Bit counting for Hamming distances: a 64-bit population count that compiles to the hardware
/// instruction where the target has one, and a portable fallback that is always available (and is
/// what the tests compare the hardware path against).

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

/// 1 when popcount64() compiles to a hardware instruction: POPCNT on x86 (enabled by -mpopcnt,
/// -msse4.2 or -march=native), CNT on AArch64 (always present). On other targets GCC's
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

/// Index of the lowest set bit of a non-zero `x` (0 ... 63): the set bits below it, counted.
inline int lowest_set_bit(std::uint64_t x) noexcept { return popcount64((x & (0 - x)) - 1); }

/// popcount(a ^ b) summed over the N words, unrolled at compile time.
template <std::size_t N, std::size_t... I>
int popcount_xor_words(const std::array<std::uint64_t, N>& a, const std::array<std::uint64_t, N>& b,
                       std::index_sequence<I...>) noexcept {
  return (0 + ... + popcount64(a[I] ^ b[I]));
}

}  // namespace affine_orb::detail
