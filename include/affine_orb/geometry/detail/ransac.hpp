#pragma once
/// \file
/// Internals (namespace detail, not part of the API): early-exit scoring of a model, the adaptive iteration count and
/// the detection of an estimator's optional refine(), behind geometry/ransac.hpp.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/detail/ransac_sampler.hpp"

namespace affine_orb {
namespace detail {

template <class E, class = void>
struct HasRefine : std::false_type {};
template <class E>
struct HasRefine<E, std::void_t<decltype(std::declval<const E&>().refine(
                        std::declval<const typename E::Model&>(), std::declval<const std::vector<std::uint8_t>&>()))>>
    : std::true_type {};

/// Correspondences scored between two checks of the early exit in score_model(): short enough to
/// stop soon after a model falls behind, long enough for the compiler to keep the scoring loop
/// free of the check.
inline constexpr std::size_t kScoreBlock = 32;

/// Scores `model` on every correspondence into `mask`; stops (returning nullopt) as soon as the
/// score cannot exceed `to_beat` any more. Returns {score, inlier count} otherwise.
template <class Estimator>
std::optional<std::pair<double, int>> score_model(const Estimator& estimator, const typename Estimator::Model& model,
                                                  double to_beat, std::vector<std::uint8_t>& mask) {
  const std::size_t n = estimator.size();
  const double best_term = estimator.max_point_score();
  double total = 0.0;
  int count = 0;
  for (std::size_t begin = 0; begin < n; begin += kScoreBlock) {
    const std::size_t end = std::min(n, begin + kScoreBlock);
    for (std::size_t i = begin; i < end; ++i) {
      const auto s = estimator.score(model, i);
      total += s.value;
      mask[i] = s.inlier ? 1 : 0;
      count += s.inlier ? 1 : 0;
    }
    if (total + best_term * static_cast<double>(n - end) <= to_beat) return std::nullopt;
  }
  return std::make_pair(total, count);
}

/// Samples needed so that one is outlier-free with probability `confidence`, for inlier ratio
/// `inlier_ratio` and sample size `sample_size` (Hartley & Zisserman eq. 4.18), capped at `cap`.
inline int adaptive_iterations(double inlier_ratio, int sample_size, double confidence, int cap) {
  if (inlier_ratio >= 1.0) return 0;
  const double all_inliers = std::pow(inlier_ratio, sample_size);
  if (!(all_inliers > 0.0)) return cap;
  const double needed = std::log1p(-confidence) / std::log1p(-all_inliers);
  if (!(needed < static_cast<double>(cap))) return cap;
  return static_cast<int>(std::ceil(needed));
}

}  // namespace detail
}  // namespace affine_orb
