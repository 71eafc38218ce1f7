#pragma once
/// \file
/// Seeded drawing of distinct correspondence indices for RANSAC: uniform, or progressive (PROSAC)
/// over correspondences ordered best first.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>

namespace affine_orb::detail {

/// Fills out[first .. count) with indices uniform in [0, bound), distinct from each other and from
/// out[0 .. first) (count − first <= bound). The bounded integers are produced by rejection from the
/// generator's raw 64-bit output (not by std::uniform_int_distribution, whose algorithm differs
/// between standard libraries), so a seed gives the same index sets on every platform.
inline void draw_distinct(std::mt19937_64& engine, int* out, int first, int count, std::uint64_t bound) {
  if (first >= count) return;
  // Largest multiple of bound representable in 64 bits: raw values at or above it would bias x % bound.
  const std::uint64_t max = std::numeric_limits<std::uint64_t>::max();
  const std::uint64_t limit = max - (max % bound + 1) % bound;
  for (int i = first; i < count; ++i) {
    int candidate = 0;
    bool repeated = true;
    while (repeated) {
      std::uint64_t raw = engine();
      while (raw > limit) raw = engine();
      candidate = static_cast<int>(raw % bound);
      repeated = false;
      for (int j = 0; j < i && !repeated; ++j) repeated = out[j] == candidate;
    }
    out[i] = candidate;
  }
}

/// Draws sets of distinct indices in [0, n) from a std::mt19937_64 seeded once at construction
/// (draw_distinct()).
class IndexSampler {
 public:
  /// `n` indices to choose from (n >= 1), generator seeded with `seed`.
  IndexSampler(std::size_t n, std::uint64_t seed) : n_(static_cast<std::uint64_t>(n)), engine_(seed) {}

  /// Fills out[0 .. count) with `count` distinct indices (count <= n), each uniform in [0, n).
  void draw(int* out, int count) { draw_distinct(engine_, out, 0, count, n_); }

 private:
  std::uint64_t n_;
  std::mt19937_64 engine_;
};

/// PROSAC's drawing (Chum & Matas, "Matching with PROSAC – progressive sample consensus", CVPR
/// 2005, Sec. 2.2–2.3) for correspondences ordered best first: sample t is drawn from the first
/// n_t of them, where n_t grows from `sample_size` to n as fast as a uniform RANSAC over the first
/// n_t would have drawn t samples, reaching n after `growth_samples` samples (the paper's T_N).
/// A sample holds the n_t-th correspondence and sample_size − 1 others from the first n_t − 1 while
/// t <= T'_{n_t}, and sample_size from the first n_t after that (once n_t = n, uniform over all).
/// Seeded as IndexSampler, drawn by draw_distinct().
class ProgressiveSampler {
 public:
  /// `n` ordered indices to choose from (n >= sample_size >= 1), the schedule's sample size and
  /// T_N (>= 1), generator seeded with `seed`.
  ProgressiveSampler(std::size_t n, int sample_size, int growth_samples, std::uint64_t seed)
      : n_(n), m_(sample_size), subset_(static_cast<std::size_t>(sample_size)), engine_(seed) {
    // T_m: the samples a uniform RANSAC over all n draws (T_N) that come from the first m alone.
    t_n_ = static_cast<double>(growth_samples);
    for (int i = 0; i < m_; ++i) {
      t_n_ *= static_cast<double>(m_ - i) / static_cast<double>(n_ - static_cast<std::size_t>(i));
    }
  }

  /// Fills out[0 .. count) with `count` distinct indices. Throws std::invalid_argument when count
  /// exceeds the schedule's sample size (the first n_t − 1 might not hold count − 1 of them).
  void draw(int* out, int count) {
    if (count > m_) throw std::invalid_argument("ProgressiveSampler: a draw larger than the sample size");
    ++t_;
    if (t_ >= t_prime_ && subset_ < n_) grow();
    if (t_ <= t_prime_) {
      out[0] = static_cast<int>(subset_ - 1);  // the newest correspondence, the others before it
      draw_distinct(engine_, out, 1, count, subset_ - 1);
    } else {
      draw_distinct(engine_, out, 0, count, subset_);
    }
  }

 private:
  /// n_t + 1: T_{n+1} = T_n (n + 1) / (n + 1 − m), T'_{n+1} = T'_n + ⌈T_{n+1} − T_n⌉.
  void grow() {
    const double next =
        t_n_ * static_cast<double>(subset_ + 1) / static_cast<double>(subset_ + 1 - static_cast<std::size_t>(m_));
    t_prime_ += static_cast<std::uint64_t>(std::ceil(next - t_n_));
    t_n_ = next;
    ++subset_;
  }

  std::size_t n_;
  int m_;
  std::size_t subset_;         ///< n_t
  double t_n_ = 0.0;           ///< T_{n_t}
  std::uint64_t t_prime_ = 1;  ///< T'_{n_t}
  std::uint64_t t_ = 0;        ///< samples drawn
  std::mt19937_64 engine_;
};

}  // namespace affine_orb::detail
