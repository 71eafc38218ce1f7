#pragma once
/// \file
/// Seeded drawing of distinct correspondence indices for RANSAC.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>

namespace affine_orb::detail {

/// Draws sets of distinct indices in [0, n) from a std::mt19937_64 seeded once at construction.
///
/// The bounded integers are produced by rejection from the generator's raw 64-bit output (not by
/// std::uniform_int_distribution, whose algorithm differs between standard libraries), so a seed
/// gives the same index sets on every platform.
class IndexSampler {
 public:
  /// `n` indices to choose from (n >= 1), generator seeded with `seed`.
  IndexSampler(std::size_t n, std::uint64_t seed) : n_(static_cast<std::uint64_t>(n)), engine_(seed) {
    // Largest multiple of n representable in 64 bits: raw values at or above it would bias x % n.
    const std::uint64_t max = std::numeric_limits<std::uint64_t>::max();
    limit_ = max - (max % n_ + 1) % n_;
  }

  /// Fills out[0 .. count) with `count` distinct indices (count <= n), each uniform in [0, n).
  void draw(int* out, int count) {
    for (int i = 0; i < count; ++i) {
      int candidate = 0;
      bool repeated = true;
      while (repeated) {
        candidate = static_cast<int>(uniform());
        repeated = false;
        for (int j = 0; j < i; ++j) {
          if (out[j] == candidate) {
            repeated = true;
            break;
          }
        }
      }
      out[i] = candidate;
    }
  }

 private:
  std::uint64_t uniform() {
    std::uint64_t raw = engine_();
    while (raw > limit_) raw = engine_();
    return raw % n_;
  }

  std::uint64_t n_;
  std::uint64_t limit_ = 0;
  std::mt19937_64 engine_;
};

}  // namespace affine_orb::detail
