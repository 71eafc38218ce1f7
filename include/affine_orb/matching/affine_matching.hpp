#pragma once
/// \file
/// Matching of two affine feature sets (docs/algorithm.md §4): every simulated view of one image against every
/// view of the other, as ASIFT does, then removal of the duplicate correspondences that several
/// view pairs find for the same scene point.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/detail/affine_matching.hpp"
#include "affine_orb/matching/matcher.hpp"

namespace affine_orb {

/// How two affine feature sets are matched.
struct AffineMatchOptions {
  /// Nearest-neighbour acceptance (ratio test, cross-check, maximum distance).
  MatcherOptions matcher;
  /// Radius in pixels of image 2 within which train keypoints count as the same scene point for
  /// the ratio test: the second neighbour d2 is the nearest train descriptor whose keypoint lies
  /// farther than this from the best neighbour's keypoint. Affine views describe one scene point
  /// several times with nearly equal descriptors; without the exclusion a ratio test over all of
  /// them rejects its true match. 4 px covers the spread of one corner mapped back from several
  /// views. 0: every other descriptor competes (the plain ratio test). In [0, 1000];
  /// bench/eval_viewpoint measures matching with it.
  double ratio_exclusion_radius = 4.0;
  /// Match each view of image 1 against each view of image 2 separately (ASIFT's scheme) instead of
  /// one search over all descriptors; ratio_exclusion_radius does not apply then. Per view pair the
  /// ratio test sees few competitors, which finds more correct matches at a much lower precision.
  bool per_view_pairs = false;
  /// Two correspondences are duplicates when their points are within this distance in image 1 and
  /// in image 2 (pixels, in [0, 1000]); the one with the smaller Hamming distance is kept. docs/algorithm.md §4
  /// says "within a pixel or two": 2.
  double duplicate_radius = 2.0;

  void check() const {
    matcher.check();
    detail::require_range(ratio_exclusion_radius, {0, 1000}, "AffineMatchOptions::ratio_exclusion_radius");
    detail::require_range(duplicate_radius, {0, 1000}, "AffineMatchOptions::duplicate_radius");
  }
};

/// How match_guided() matches keypoints of image 1 near their predicted positions in image 2.
struct GuidedMatchOptions {
  /// Radius, pixels of image 2, around a keypoint's predicted position within which keypoints of
  /// image 2 are its candidates. It has to cover the prediction's error: a homography that puts
  /// image 1's corners 5–15 px off ground truth (the imprecise stage-0 models of
  /// bench/eval_two_view) is off by less inside the image, so 10 px catches most of the true
  /// partners there. In (0, 1000].
  double gate_radius = 10.0;
  /// Lowe's ratio test among the gated candidates (MatcherOptions::ratio's definition; the
  /// runner-up excludes the best's duplicates as in AffineMatchOptions::ratio_exclusion_radius).
  /// With few competitors in the gate the test is weak, so 0.8 as Lowe's global value; finite and
  /// > 0.
  float ratio = 0.8f;
  /// Gated candidates within this distance of the best one's keypoint (pixels of image 2) do not
  /// count as its runner-up: affine views describe one scene point several times (4 px as
  /// AffineMatchOptions::ratio_exclusion_radius). In [0, 1000].
  double ratio_exclusion_radius = 4.0;
  /// Largest accepted Hamming distance, bits: a lone candidate passes the ratio test, so the
  /// distance bounds it. 100 as ORB-SLAM's search by projection (ORBmatcher::TH_HIGH; Mur-Artal &
  /// Tardós, ORB-SLAM2, IEEE T-RO 33(5), 2017). >= 0.
  int max_distance = 100;
  /// Duplicate removal radius, pixels (remove_duplicate_matches(); AffineMatchOptions'). In
  /// [0, 1000].
  double duplicate_radius = 2.0;

  /// Throws std::invalid_argument for a value outside its range.
  void check() const {
    detail::require_range(gate_radius, {0, 1000, true}, "GuidedMatchOptions::gate_radius");
    detail::require_range(ratio, detail::kPositive, "GuidedMatchOptions::ratio");
    detail::require_range(ratio_exclusion_radius, {0, 1000}, "GuidedMatchOptions::ratio_exclusion_radius");
    detail::require_range(max_distance, detail::kNonNegative, "GuidedMatchOptions::max_distance");
    detail::require_range(duplicate_radius, {0, 1000}, "GuidedMatchOptions::duplicate_radius");
  }
};

/// Drops duplicate correspondences: visiting matches by increasing distance (ties: smaller query,
/// then smaller train index), a match is dropped when an already kept one has its image-1 point
/// and its image-2 point both closer than `radius` pixels (strictly) to this match's points.
/// `points1[m.query]` and `points2[m.train]` are the matched positions. Returns the kept matches
/// sorted by query index, then train index.
inline std::vector<Match> remove_duplicate_matches(std::vector<Match> matches, const std::vector<cv::Point2f>& points1,
                                                   const std::vector<cv::Point2f>& points2, double radius) {
  detail::require_range(radius, detail::kNonNegative, "remove_duplicate_matches: radius");
  std::sort(matches.begin(), matches.end(), [](const Match& a, const Match& b) {
    return a.distance < b.distance ||
           (a.distance == b.distance && (a.query < b.query || (a.query == b.query && a.train < b.train)));
  });
  std::vector<Match> kept;
  if (radius == 0.0) {
    kept = std::move(matches);
  } else {
    // Every match's image-1 point in a grid of cells of side `radius`; a match is compared with the
    // kept ones among its neighbours there.
    std::vector<cv::Point2f> first(matches.size());
    for (std::size_t i = 0; i < matches.size(); ++i) first[i] = points1[static_cast<std::size_t>(matches[i].query)];
    detail::PointGrid grid;
    grid.build(first, radius);
    std::vector<std::uint8_t> is_kept(matches.size(), 0);
    const double r2 = radius * radius;
    for (std::size_t i = 0; i < matches.size(); ++i) {
      const cv::Point2f& p = first[i];
      const cv::Point2f& q = points2[static_cast<std::size_t>(matches[i].train)];
      bool duplicate = false;
      grid.for_each_near(p, radius, [&](int k) {
        if (duplicate || !is_kept[static_cast<std::size_t>(k)]) return;
        const cv::Point2f& kp = first[static_cast<std::size_t>(k)];
        const cv::Point2f& kq = points2[static_cast<std::size_t>(matches[static_cast<std::size_t>(k)].train)];
        const double d1 = (kp.x - p.x) * (kp.x - p.x) + (kp.y - p.y) * (kp.y - p.y);
        const double d2 = (kq.x - q.x) * (kq.x - q.x) + (kq.y - q.y) * (kq.y - q.y);
        duplicate = d1 < r2 && d2 < r2;
      });
      if (duplicate) continue;
      is_kept[i] = 1;
      kept.push_back(matches[i]);
    }
  }
  std::sort(kept.begin(), kept.end(), [](const Match& a, const Match& b) {
    return a.query < b.query || (a.query == b.query && a.train < b.train);
  });
  return kept;
}

/// Matches two feature sets from Extractor::extract() (docs/algorithm.md §4). Match::query indexes `a`,
/// Match::train indexes `b`.
/// - Default: one search over all descriptors with the location-aware ratio test
///   (AffineMatchOptions::ratio_exclusion_radius), max distance and optional cross-check.
/// - per_view_pairs: each view of `a` against each view of `b` (Features::views; an empty views
///   vector means one view) with match() and MatcherOptions as they are.
/// Either way the union is freed of duplicates by remove_duplicate_matches(). Sets of different
/// descriptor widths cannot be mixed (the template parameter differs). Empty sets give no matches.
template <int Bits>
std::vector<Match> match_features(const Features<Bits>& a, const Features<Bits>& b,
                                  const AffineMatchOptions& options = {});

namespace detail {

/// match_features() with the knn2() searches of its default path kept in `searches`, which holds
/// those of the sets' first features (detail::KnnSearches): TwoViewMatcher's stages append
/// features to the same two sets, and each stage searches only the pairs the previous ones did not.
template <int Bits>
std::vector<Match> match_growing_features(const Features<Bits>& a, const Features<Bits>& b,
                                          const AffineMatchOptions& options, KnnSearches& searches) {
  options.check();
  detail::require(a.descriptors.size() == a.keypoints.size() && b.descriptors.size() == b.keypoints.size(),
                  "match_features: keypoints and descriptors differ in number");
  detail::require((a.views.empty() || a.views.size() == a.size()) && (b.views.empty() || b.views.size() == b.size()),
                  "match_features: views must be empty or one per keypoint");
  if (a.empty() || b.empty()) return {};

  std::vector<Match> all;
  if (!options.per_view_pairs) {
    all = match_excluding_duplicates(a, b, options.matcher, options.ratio_exclusion_radius, searches);
  } else {
    // Indices of each view's keypoints.
    auto group = [](const Features<Bits>& f) {
      std::vector<std::vector<int>> by_view;
      for (std::size_t i = 0; i < f.size(); ++i) {
        const int v = f.views.empty() ? 0 : f.views[i];
        detail::require(v >= 0, "match_features: negative view index");
        if (static_cast<std::size_t>(v) >= by_view.size()) by_view.resize(static_cast<std::size_t>(v) + 1);
        by_view[static_cast<std::size_t>(v)].push_back(static_cast<int>(i));
      }
      return by_view;
    };
    const std::vector<std::vector<int>> views_a = group(a);
    const std::vector<std::vector<int>> views_b = group(b);
    std::vector<BinaryDescriptor<Bits>> query;
    std::vector<BinaryDescriptor<Bits>> train;
    for (const std::vector<int>& ia : views_a) {
      if (ia.empty()) continue;
      query.clear();
      for (int i : ia) query.push_back(a.descriptors[static_cast<std::size_t>(i)]);
      for (const std::vector<int>& ib : views_b) {
        if (ib.empty()) continue;
        train.clear();
        for (int j : ib) train.push_back(b.descriptors[static_cast<std::size_t>(j)]);
        for (const Match& m : match(query, train, options.matcher)) {
          all.push_back({ia[static_cast<std::size_t>(m.query)], ib[static_cast<std::size_t>(m.train)], m.distance});
        }
      }
    }
  }
  return remove_duplicate_matches(std::move(all), positions(a.keypoints), positions(b.keypoints),
                                  options.duplicate_radius);
}

}  // namespace detail

template <int Bits>
std::vector<Match> match_features(const Features<Bits>& a, const Features<Bits>& b, const AffineMatchOptions& options) {
  detail::KnnSearches searches;
  return detail::match_growing_features(a, b, options, searches);
}

/// Guided matching: every keypoint i of `a` whose predicted position `predicted[i]` (pixels of
/// image 2, e.g. x2 ~ H x1 under a verified homography) is finite is matched against the keypoints
/// of `b` within options.gate_radius of that position only: the nearest descriptor among them,
/// accepted by the ratio test among them (runner-up outside ratio_exclusion_radius of the best)
/// and max_distance; then remove_duplicate_matches(). Match::query indexes `a`, Match::train `b`;
/// sorted by query index. Throws std::invalid_argument for invalid options, keypoints and
/// descriptors differing in number, or a `predicted` list that is not one per keypoint of `a`.
template <int Bits>
std::vector<Match> match_guided(const Features<Bits>& a, const Features<Bits>& b,
                                const std::vector<cv::Point2f>& predicted, const GuidedMatchOptions& options = {}) {
  options.check();
  detail::require(a.descriptors.size() == a.keypoints.size() && b.descriptors.size() == b.keypoints.size(),
                  "match_guided: keypoints and descriptors differ in number");
  detail::require(predicted.size() == a.size(), "match_guided: one predicted position per keypoint of a needed");
  if (a.empty() || b.empty()) return {};
  std::vector<Match> all = detail::match_gated(a, b, predicted, options.gate_radius, options.ratio,
                                               options.ratio_exclusion_radius, options.max_distance);
  return remove_duplicate_matches(std::move(all), detail::positions(a.keypoints), detail::positions(b.keypoints),
                                  options.duplicate_radius);
}

}  // namespace affine_orb
