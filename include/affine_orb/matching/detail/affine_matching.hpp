#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the location-aware ratio test of match_features()
/// (matching/affine_matching.hpp).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/matcher.hpp"

namespace affine_orb {
namespace detail {

/// Global matching with the location-aware ratio test of AffineMatchOptions::ratio_exclusion_radius
/// (`exclusion_radius`, pixels of image b).
/// knn2() gives the best neighbour j1 and the runner-up; when the runner-up lies within the radius
/// of j1 (a duplicate of the same point), the train set is scanned again for the nearest descriptor
/// outside the radius.
template <int Bits>
std::vector<Match> match_excluding_duplicates(const Features<Bits>& a, const Features<Bits>& b, const MatcherOptions& m,
                                              double exclusion_radius) {
  const std::vector<KnnMatch> forward = knn2(a.descriptors, b.descriptors);
  std::vector<KnnMatch> backward;
  if (m.cross_check) backward = knn2(b.descriptors, a.descriptors);
  const double r2 = exclusion_radius * exclusion_radius;
  auto near = [&](int j, int k) {
    const cv::Point2f& p = b.keypoints[static_cast<std::size_t>(j)].pt;
    const cv::Point2f& q = b.keypoints[static_cast<std::size_t>(k)].pt;
    return (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) <= r2;
  };
  std::vector<Match> matches;
  for (const KnnMatch& k : forward) {
    if (k.count == 0 || k.best.distance > m.max_distance) continue;
    KnnMatch test = k;
    if (k.count == 2 && near(k.best.train, k.second.train)) {
      test.count = 1;
      test.second = Neighbour{};
      const auto& q = a.descriptors[static_cast<std::size_t>(k.query)];
      for (std::size_t j = 0; j < b.size(); ++j) {
        if (near(k.best.train, static_cast<int>(j))) continue;
        const int d = hamming_distance(q, b.descriptors[j]);
        if (d < test.second.distance) {
          test.second = {static_cast<int>(j), d};
          test.count = 2;
        }
      }
    }
    if (!passes_ratio_test(test, m.ratio)) continue;
    if (m.cross_check && backward[static_cast<std::size_t>(k.best.train)].best.train != k.query) continue;
    matches.push_back({k.query, k.best.train, k.best.distance});
  }
  return matches;
}

}  // namespace detail
}  // namespace affine_orb
