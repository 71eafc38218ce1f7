#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the location-aware ratio test of match_features()
/// and the gated search of match_guided() (matching/affine_matching.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/matcher.hpp"

namespace affine_orb {
namespace detail {

/// Points bucketed into square cells over their bounding box (a counting sort: one index array,
/// no allocation per cell), to visit the points near a position: those within a radius up to
/// `side` lie in the cells that meet the square of that half side around it. Non-finite points are
/// left out.
class PointGrid {
 public:
  /// Buckets `points` into cells of side `side` (> 0), widened to one point per cell on average
  /// where that is larger (a few kilobytes for a thousand points over a large image, instead of
  /// a cell per 2 px) and where the bounding box would need more than kMaxCellsPerSide cells
  /// along a side (far-flung input stays bounded in memory).
  void build(const std::vector<cv::Point2f>& points, double side) {
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
    std::size_t count = 0;  // finite points
    for (const cv::Point2f& p : points) {
      if (!finite(p)) continue;
      x0 = count > 0 ? std::min(x0, static_cast<double>(p.x)) : p.x;
      y0 = count > 0 ? std::min(y0, static_cast<double>(p.y)) : p.y;
      x1 = count > 0 ? std::max(x1, static_cast<double>(p.x)) : p.x;
      y1 = count > 0 ? std::max(y1, static_cast<double>(p.y)) : p.y;
      ++count;
    }
    x0_ = x0;
    y0_ = y0;
    const double per_point = count > 0 ? std::sqrt((x1 - x0) * (y1 - y0) / static_cast<double>(count)) : 0.0;
    side_ = std::max({side, per_point, (x1 - x0) / kMaxCellsPerSide, (y1 - y0) / kMaxCellsPerSide});
    columns_ = count > 0 ? static_cast<int>((x1 - x0) / side_) + 1 : 0;
    rows_ = count > 0 ? static_cast<int>((y1 - y0) / side_) + 1 : 0;
    // Counting sort: cell sizes, their prefix sums (start_), then each point at its cell's cursor.
    start_.assign(static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_) + 1, 0);
    for (const cv::Point2f& p : points) {
      if (finite(p)) ++start_[static_cast<std::size_t>(cell_of(p)) + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    index_.resize(static_cast<std::size_t>(start_.back()));
    std::vector<int> cursor(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!finite(points[i])) continue;
      index_[static_cast<std::size_t>(cursor[static_cast<std::size_t>(cell_of(points[i]))]++)] = static_cast<int>(i);
    }
  }

  /// Calls fn(i) for every point i in the cells that meet the square of half side `radius` around
  /// `p` (rows, then columns, then increasing i within a cell), which holds every point within
  /// `radius` of `p`; nothing for a non-finite `p`. `radius` is at most the side build() was given,
  /// so the square meets at most 3 x 3 cells, and fewer the more build() widened them (a 2 px
  /// duplicate radius mostly meets one).
  template <class Fn>
  void for_each_near(const cv::Point2f& p, double radius, Fn fn) const {
    if (columns_ == 0 || !finite(p)) return;
    const double x_low = std::floor((p.x - radius - x0_) / side_), x_high = std::floor((p.x + radius - x0_) / side_);
    const double y_low = std::floor((p.y - radius - y0_) / side_), y_high = std::floor((p.y + radius - y0_) / side_);
    if (x_high < 0.0 || y_high < 0.0 || x_low > columns_ - 1 || y_low > rows_ - 1) return;
    const int x_first = static_cast<int>(std::max(x_low, 0.0));
    const int x_last = static_cast<int>(std::min(x_high, columns_ - 1.0));
    const int y_first = static_cast<int>(std::max(y_low, 0.0));
    const int y_last = static_cast<int>(std::min(y_high, rows_ - 1.0));
    for (int y = y_first; y <= y_last; ++y) {
      for (int x = x_first; x <= x_last; ++x) {
        const int c = cell(x, y);
        for (int k = start_[static_cast<std::size_t>(c)]; k < start_[static_cast<std::size_t>(c) + 1]; ++k) {
          fn(index_[static_cast<std::size_t>(k)]);
        }
      }
    }
  }

 private:
  static constexpr double kMaxCellsPerSide = 1024.0;

  static bool finite(const cv::Point2f& p) { return std::isfinite(p.x) && std::isfinite(p.y); }
  int cell(int x, int y) const { return y * columns_ + x; }
  /// The cell of a finite point inside the bounding box build() measured.
  int cell_of(const cv::Point2f& p) const {
    return cell(std::min(static_cast<int>((p.x - x0_) / side_), columns_ - 1),
                std::min(static_cast<int>((p.y - y0_) / side_), rows_ - 1));
  }

  double x0_ = 0.0, y0_ = 0.0, side_ = 1.0;
  int columns_ = 0, rows_ = 0;
  std::vector<int> start_;  ///< per cell, the first entry of index_; one more entry at the end
  std::vector<int> index_;  ///< point indices, cell by cell
};

/// The keypoints' positions, pixels, in their order.
inline std::vector<cv::Point2f> positions(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<cv::Point2f> out;
  out.reserve(keypoints.size());
  for (const cv::KeyPoint& k : keypoints) out.push_back(k.pt);
  return out;
}

/// `into`'s two nearest neighbours merged with `more`'s, whose train indices all exceed `into`'s:
/// the two nearest of both by distance, ties broken by the smaller train index, as knn2() does.
inline void merge_neighbours(KnnMatch& into, const KnnMatch& more) {
  const Neighbour left[2] = {into.best, into.second};
  const Neighbour right[2] = {more.best, more.second};
  int i = 0, j = 0;
  Neighbour merged[2];
  const int count = std::min(2, into.count + more.count);
  for (int k = 0; k < count; ++k) {
    // A tie goes to `into`: its train indices are the smaller ones.
    const bool take_left = j >= more.count || (i < into.count && left[i].distance <= right[j].distance);
    merged[k] = take_left ? left[i++] : right[j++];
  }
  into.count = count;
  into.best = count > 0 ? merged[0] : Neighbour{};
  into.second = count > 1 ? merged[1] : Neighbour{};
}

/// knn2(query, train), given `known` = knn2(query[0, known.size()), train[0, known_train)): those
/// queries are searched on train[known_train, end) alone and their neighbours merged with the known
/// ones; the later queries are searched on every train descriptor. The same result as knn2() on the
/// whole sets, which it costs only for the pairs `known` lacks.
template <std::size_t Words>
std::vector<KnnMatch> extend_knn2(std::vector<KnnMatch> known, std::size_t known_train,
                                  const std::vector<std::array<std::uint64_t, Words>>& query,
                                  const std::vector<std::array<std::uint64_t, Words>>& train) {
  using Descriptors = std::vector<std::array<std::uint64_t, Words>>;
  require(known.size() <= query.size() && known_train <= train.size(), "extend_knn2: known sets larger than the sets");
  if (known.empty()) return knn2(query, train);
  const auto known_query = static_cast<std::ptrdiff_t>(known.size());
  if (known_train < train.size()) {
    const Descriptors old_query(query.begin(), query.begin() + known_query);
    const Descriptors new_train(train.begin() + static_cast<std::ptrdiff_t>(known_train), train.end());
    std::vector<KnnMatch> more = knn2(old_query, new_train);
    for (std::size_t i = 0; i < known.size(); ++i) {
      more[i].best.train += static_cast<int>(known_train);
      more[i].second.train += static_cast<int>(known_train);
      merge_neighbours(known[i], more[i]);
    }
  }
  if (known.size() < query.size()) {
    const std::vector<KnnMatch> rest = knn2(Descriptors(query.begin() + known_query, query.end()), train);
    for (KnnMatch k : rest) {
      k.query += static_cast<int>(known_query);
      known.push_back(k);
    }
  }
  return known;
}

/// The knn2() searches of match_excluding_duplicates() on two feature sets, kept so that the same
/// sets with more features appended (the stages of TwoViewMatcher) search only the new pairs.
/// forward.size() is the number of a's features they cover.
struct KnnSearches {
  std::size_t size_b = 0;          ///< features of b they cover
  std::vector<KnnMatch> forward;   ///< a[0, forward.size()) against b[0, size_b)
  std::vector<KnnMatch> backward;  ///< b against a[0, forward.size()) (with MatcherOptions::cross_check)
};

/// The rescan of match_excluding_duplicates() for a query whose two nearest train descriptors are
/// duplicates of one point: whether `best` passes the ratio test against the nearest descriptor of
/// b whose keypoint is not near() best's. The scan stops at the first such descriptor that fails
/// it (a nearer one would fail it too), so the answer is that of a whole scan.
template <int Bits, class Near>
bool rescan_passes(const BinaryDescriptor<Bits>& query, const Features<Bits>& b, const Neighbour& best, float ratio,
                   const Near& near, std::vector<int>& distances) {
  constexpr std::size_t kChunk = 256;
  distances.resize(kChunk);
  for (std::size_t start = 0; start < b.size(); start += kChunk) {
    const std::size_t n = std::min(kChunk, b.size() - start);
    hamming_row(query, b.descriptors.data() + start, n, distances.data());
    for (std::size_t j = 0; j < n; ++j) {
      // The distance first: it rules out most j, and costs less than the radius test.
      const int d = distances[j];
      if (static_cast<double>(best.distance) >= static_cast<double>(ratio) * d &&
          !near(best.train, static_cast<int>(start + j))) {
        return false;
      }
    }
  }
  return true;
}

/// Global matching with the location-aware ratio test of AffineMatchOptions::ratio_exclusion_radius
/// (`exclusion_radius`, pixels of image b).
/// knn2() gives the best neighbour j1 and the runner-up; when the runner-up lies within the radius
/// of j1 (a duplicate of the same point), the train set is scanned again for the nearest descriptor
/// outside the radius. `searches` holds the searches of the sets' first features (a and b may
/// only have grown since) and is extended to all of them.
template <int Bits>
std::vector<Match> match_excluding_duplicates(const Features<Bits>& a, const Features<Bits>& b, const MatcherOptions& m,
                                              double exclusion_radius, KnnSearches& searches) {
  if (m.cross_check) {
    searches.backward =
        extend_knn2(std::move(searches.backward), searches.forward.size(), b.descriptors, a.descriptors);
  }
  searches.forward = extend_knn2(std::move(searches.forward), searches.size_b, a.descriptors, b.descriptors);
  searches.size_b = b.size();
  const std::vector<KnnMatch>& forward = searches.forward;
  const std::vector<KnnMatch>& backward = searches.backward;
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
    if (k.count == 2 && near(k.best.train, k.second.train)) {
      if (!rescan_passes(a.descriptors[static_cast<std::size_t>(k.query)], b, k.best, m.ratio, near, distances)) {
        continue;
      }
    } else if (!passes_ratio_test(k, m.ratio)) {
      continue;
    }
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
  PointGrid grid;
  grid.build(positions(b.keypoints), gate_radius);
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
    grid.for_each_near(p, gate_radius, [&](int j) {
      if (squared(p, b.keypoints[static_cast<std::size_t>(j)].pt) > gate2) return;
      candidates.push_back({j, hamming_distance(a.descriptors[i], b.descriptors[static_cast<std::size_t>(j)])});
    });
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
