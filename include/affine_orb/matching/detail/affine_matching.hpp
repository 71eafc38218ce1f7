#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the location-aware ratio test of match_features()
/// and the gated search of match_guided() (matching/affine_matching.hpp).

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

/// The keypoints' positions, pixels, in their order.
inline std::vector<cv::Point2f> positions(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<cv::Point2f> out;
  out.reserve(keypoints.size());
  for (const cv::KeyPoint& k : keypoints) out.push_back(k.pt);
  return out;
}

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
  std::vector<int> distances;
  for (const KnnMatch& k : forward) {
    if (k.count == 0 || k.best.distance > m.max_distance) continue;
    KnnMatch test = k;
    if (k.count == 2 && near(k.best.train, k.second.train)) {
      test.count = 1;
      test.second = Neighbour{};
      distances.resize(b.size());
      hamming_row(a.descriptors[static_cast<std::size_t>(k.query)], b.descriptors.data(), b.size(), distances.data());
      for (std::size_t j = 0; j < b.size(); ++j) {
        if (near(k.best.train, static_cast<int>(j))) continue;
        const int d = distances[j];
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

/// The gated search of match_guided(): per keypoint i of `a` with a finite `predicted[i]` (pixels
/// of image b), the candidates are b's keypoints within `gate_radius` of it (grid of cells of that
/// side over b's keypoints); the best is the nearest descriptor among them (ties: smaller index),
/// the runner-up the nearest among those farther than `exclusion_radius` from the best's keypoint.
/// Returns the matches whose best has at most `max_distance` bits and passes the ratio test.
template <int Bits>
std::vector<Match> match_gated(const Features<Bits>& a, const Features<Bits>& b,
                               const std::vector<cv::Point2f>& predicted, double gate_radius, float ratio,
                               double exclusion_radius, int max_distance) {
  std::unordered_map<long long, std::vector<int>> grid;
  const auto key = [](long long cx, long long cy) { return cx * 2000003LL + cy; };
  const auto cell = [gate_radius](float v) { return static_cast<long long>(std::floor(v / gate_radius)); };
  for (std::size_t j = 0; j < b.size(); ++j) {
    const cv::Point2f& q = b.keypoints[j].pt;
    grid[key(cell(q.x), cell(q.y))].push_back(static_cast<int>(j));
  }
  const auto squared = [](const cv::Point2f& p, const cv::Point2f& q) {
    return static_cast<double>(p.x - q.x) * (p.x - q.x) + static_cast<double>(p.y - q.y) * (p.y - q.y);
  };
  const double gate2 = gate_radius * gate_radius;
  const double exclusion2 = exclusion_radius * exclusion_radius;
  std::vector<Neighbour> candidates;
  std::vector<Match> matches;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const cv::Point2f& p = predicted[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || std::abs(p.x) > 1e7f || std::abs(p.y) > 1e7f) continue;
    candidates.clear();
    const long long cx = cell(p.x), cy = cell(p.y);
    for (long long dy = -1; dy <= 1; ++dy) {
      for (long long dx = -1; dx <= 1; ++dx) {
        const auto it = grid.find(key(cx + dx, cy + dy));
        if (it == grid.end()) continue;
        for (const int j : it->second) {
          if (squared(p, b.keypoints[static_cast<std::size_t>(j)].pt) > gate2) continue;
          candidates.push_back({j, hamming_distance(a.descriptors[i], b.descriptors[static_cast<std::size_t>(j)])});
        }
      }
    }
    KnnMatch test;
    test.query = static_cast<int>(i);
    for (const Neighbour& c : candidates) {
      if (c.distance < test.best.distance || (c.distance == test.best.distance && c.train < test.best.train)) {
        test.best = c;
        test.count = 1;
      }
    }
    if (test.count == 0 || test.best.distance > max_distance) continue;
    const cv::Point2f& best = b.keypoints[static_cast<std::size_t>(test.best.train)].pt;
    for (const Neighbour& c : candidates) {
      if (squared(best, b.keypoints[static_cast<std::size_t>(c.train)].pt) <= exclusion2) continue;
      if (c.distance < test.second.distance) {
        test.second = c;
        test.count = 2;
      }
    }
    if (!passes_ratio_test(test, ratio)) continue;
    matches.push_back({test.query, test.best.train, test.best.distance});
  }
  return matches;
}

}  // namespace detail
}  // namespace affine_orb
