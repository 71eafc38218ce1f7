#pragma once
/// \file
/// The a-contrario support test of a geometric model: how many models as well supported as this
/// one would arise by chance among correspondences that are all wrong. Under the null hypothesis
/// each image-2 point is uniform over the image, independent of its image-1 point, so a wrong
/// correspondence falls within a model's inlier bound with a small probability p; a model fitted to
/// a minimal sample of s and supported by k of n correspondences is then expected among all the
/// models one could test
///   NFA = (n − s) · C(n, k) · C(k, s) · p^(k − s)
/// times (Moisan & Stival, "A probabilistic criterion to detect rigid point matches between two
/// images and estimate the fundamental matrix", IJCV 57(3), 2004; Moisan, Moulon & Monasse,
/// "Automatic homographic registration of a pair of images, with a contrario elimination of
/// outliers", IPOL 2, 2012). A model with NFA ≤ 1 is meaningful: chance explains it less than once.
/// Unlike a bound on the inlier share, the test grows with the evidence, so a correct model
/// supported by a few percent of many correspondences (a day/night pair) passes it, while a chance
/// consensus among a few wrong ones does not.

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"

namespace affine_orb {

/// log10 of the number of false alarms of a model supported by `inliers` of `correspondences`,
/// fitted to minimal samples of `sample_size`, when a wrong correspondence is an inlier with
/// probability `inlier_probability`: log10[(n − s) C(n, k) C(k, s) p^(k − s)]. +infinity when
/// k < s or n ≤ s (no model is testable). Throws std::invalid_argument unless 0 ≤ k ≤ n,
/// s ≥ 1 and 0 < p ≤ 1.
inline double log10_false_alarms(int correspondences, int inliers, int sample_size, double inlier_probability) {
  detail::require(inliers >= 0 && inliers <= correspondences,
                  "log10_false_alarms: inliers must be in [0, correspondences]");
  detail::require(sample_size >= 1, "log10_false_alarms: sample_size must be at least 1");
  detail::require_range(inlier_probability, {0.0, 1.0, true}, "log10_false_alarms: inlier_probability");
  if (inliers < sample_size || correspondences <= sample_size) return std::numeric_limits<double>::infinity();
  // log10 C(a, b) as a sum of b ratios: exact to rounding, and no lgamma (which writes the global
  // signgam in glibc).
  const auto log10_choose = [](int a, int b) {
    b = std::min(b, a - b);
    double sum = 0.0;
    for (int i = 1; i <= b; ++i) sum += std::log10(static_cast<double>(a - b + i) / i);
    return sum;
  };
  return std::log10(static_cast<double>(correspondences - sample_size)) + log10_choose(correspondences, inliers) +
         log10_choose(inliers, sample_size) + (inliers - sample_size) * std::log10(inlier_probability);
}

/// The probability that a point uniform over an image of `size` falls within `radius` pixels of a
/// given point (a homography's transfer error): π r² / area, at most 1. Throws
/// std::invalid_argument for a radius that is not positive and finite or an empty size.
inline double point_inlier_probability(double radius, cv::Size size) {
  detail::require_range(radius, detail::kPositive, "point_inlier_probability: radius");
  detail::require(size.area() > 0, "point_inlier_probability: the image size must not be empty");
  constexpr double kPi = 3.14159265358979323846;
  return std::min(1.0, kPi * radius * radius / static_cast<double>(size.area()));
}

/// The probability that a point uniform over an image of `size` falls within `distance` pixels of
/// a given line through it (an epipolar line): at most the band of width 2 d along the image's
/// diagonal D over the area, 2 d D / area, at most 1 (Moisan & Stival 2004). Throws
/// std::invalid_argument as point_inlier_probability().
inline double line_inlier_probability(double distance, cv::Size size) {
  detail::require_range(distance, detail::kPositive, "line_inlier_probability: distance");
  detail::require(size.area() > 0, "line_inlier_probability: the image size must not be empty");
  const double diagonal = std::hypot(static_cast<double>(size.width), static_cast<double>(size.height));
  return std::min(1.0, 2.0 * distance * diagonal / static_cast<double>(size.area()));
}

}  // namespace affine_orb
