#pragma once
/// \file
/// The BRISK sampling pattern (Leutenegger, Chli and Siegwart, "BRISK: Binary Robust Invariant
/// Scalable Keypoints", ICCV 2011, section 3.2), generated from its definition: concentric rings of
/// points, a Gaussian smoothing σ per ring, and the short and long point pairs. Used by brisk.hpp.

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace affine_orb::detail {

/// Ring radii of the published BRISK pattern, in units that pattern_scale turns into level pixels
/// (BRISK reference implementation, ICCV 2011: radii 0, 2.9, 4.9, 7.4, 10.8).
inline constexpr std::array<double, 5> kBriskRingRadii = {0.0, 2.9, 4.9, 7.4, 10.8};
/// Number of points on each ring of the published pattern (same source): 1 + 10 + 14 + 15 + 20 = 60.
inline constexpr std::array<int, 5> kBriskRingPoints = {1, 10, 14, 15, 20};
/// Number of ring points in total.
inline constexpr int kBriskPointCount = 60;

/// One point of the unrotated pattern: position in level pixels relative to the keypoint
/// (x right, y down), its ring and its index on the ring.
struct BriskPatternPoint {
  double x = 0.0;
  double y = 0.0;
  int ring = 0;
  int index_on_ring = 0;
};

/// A point pair (i < j, indices into BriskPattern::points) and its length in level pixels.
struct BriskPair {
  int i = 0;
  int j = 0;
  double distance = 0.0;
};

/// The pattern for one set of parameters.
struct BriskPattern {
  /// Ring radii in level pixels (published radii × pattern scale).
  std::array<double, 5> ring_radius{};
  /// Gaussian σ of the smoothing of each ring's points, level pixels.
  std::array<double, 5> ring_sigma{};
  /// Side in pixels of the box that approximates each ring's Gaussian (see brisk_box_side()).
  std::array<int, 5> ring_box{};
  /// The 60 points, ring by ring (ring 0 = the centre), on ring k at angles 2π·j/n_k, j = 0 … n_k − 1.
  std::vector<BriskPatternPoint> points;
  /// Pairs shorter than δ_max, in the order i = 0 … N−1, then j = i+1 … N−1 (bit order).
  std::vector<BriskPair> short_pairs;
  /// Pairs longer than δ_min, same order.
  std::vector<BriskPair> long_pairs;
  /// Number of pairs considered, N(N−1)/2.
  int pair_count = 0;
};

/// Side of the box filter that stands in for a Gaussian of standard deviation `sigma` (pixels): the
/// odd integer nearest to √(12σ² + 1), because a box of n pixels has the variance (n² − 1)/12 of the
/// Gaussian it replaces. Odd, so that the box is centred on a pixel; at least 1.
inline int brisk_box_side(double sigma) {
  const double exact = std::sqrt(12.0 * sigma * sigma + 1.0);
  const int side = 2 * static_cast<int>(std::floor((exact - 1.0) / 2.0 + 0.5)) + 1;
  return side < 1 ? 1 : side;
}

/// Generates the pattern.
/// - pattern_scale: multiplies kBriskRingRadii into level pixels;
/// - sigma_factor: σ_k = sigma_factor · r_k · sin(π / n_k) for the rings k ≥ 1 (r_k in level pixels);
/// - centre_sigma: σ of the centre point, level pixels;
/// - max_short, min_long: δ_max and δ_min in level pixels; a pair is short when its length is
///   < max_short and long when its length is > min_long.
inline BriskPattern make_brisk_pattern(double pattern_scale, double sigma_factor, double centre_sigma, double max_short,
                                       double min_long) {
  BriskPattern pattern;
  for (std::size_t k = 0; k < kBriskRingRadii.size(); ++k) {
    const double radius = pattern_scale * kBriskRingRadii[k];
    const int count = kBriskRingPoints[k];
    pattern.ring_radius[k] = radius;
    pattern.ring_sigma[k] = k == 0 ? centre_sigma : sigma_factor * radius * std::sin(CV_PI / count);
    pattern.ring_box[k] = brisk_box_side(pattern.ring_sigma[k]);
    for (int j = 0; j < count; ++j) {
      const double alpha = 2.0 * CV_PI * j / count;
      pattern.points.push_back({radius * std::cos(alpha), radius * std::sin(alpha), static_cast<int>(k), j});
    }
  }
  const int n = static_cast<int>(pattern.points.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const auto& a = pattern.points[static_cast<std::size_t>(i)];
      const auto& b = pattern.points[static_cast<std::size_t>(j)];
      const double distance = std::hypot(b.x - a.x, b.y - a.y);
      ++pattern.pair_count;
      if (distance < max_short) pattern.short_pairs.push_back({i, j, distance});
      if (distance > min_long) pattern.long_pairs.push_back({i, j, distance});
    }
  }
  return pattern;
}

}  // namespace affine_orb::detail
