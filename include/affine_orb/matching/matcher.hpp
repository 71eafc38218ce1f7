#pragma once
/// \file
/// Brute-force Hamming matching of binary descriptors (docs/algorithm.md §4): the nearest and second-nearest
/// train descriptor of every query descriptor, Lowe's ratio test, a maximum distance and an optional
/// cross-check. The results are exactly those of plain nested loops over all pairs; ties between
/// equal distances always go to the smaller index.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/detail/matcher.hpp"
#include "affine_orb/matching/detail/popcount.hpp"
#include "affine_orb/matching/knn_match.hpp"

namespace affine_orb {

/// Hamming distance in bits between two descriptors (BinaryDescriptor<64 · Words>): popcount(a XOR
/// b), word by word, unrolled on the compile-time word count. Uses the POPCNT instruction where the
/// target has it (see AFFINE_ORB_HARDWARE_POPCOUNT in detail/popcount.hpp), a portable bit count
/// otherwise.
template <std::size_t Words>
int hamming_distance(const std::array<std::uint64_t, Words>& a, const std::array<std::uint64_t, Words>& b) noexcept {
  static_assert(Words > 0, "a descriptor has at least one 64-bit word");
  return detail::popcount_xor_words(a, b, std::make_index_sequence<Words>{});
}

/// Which nearest neighbours match() accepts. Distances are Hamming distances in bits.
struct MatcherOptions {
  /// Lowe's ratio test (D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
  /// IJCV 60(2), 2004, section 7.1, where 0.8 rejects 90% of the false matches and under 5% of the
  /// correct ones). With j1 the nearest train descriptor of query i at distance d1, and d2 the
  /// smallest distance over the other train descriptors (d2 = d1 when two of them tie), the match
  /// i -> j1 passes iff d1 < ratio · d2, a strict inequality evaluated exactly for the float value
  /// of `ratio` (in double precision, exact for distances below 2^29). So a ratio <= 1 rejects ties
  /// (d1 = d2), ratio = 1 means "strictly closer than the second", a ratio > 1 also accepts ties,
  /// except d1 = d2 = 0, which no ratio accepts. With a single train descriptor the test passes.
  /// Must be finite and > 0. bench/eval_viewpoint matches every method at 0.8.
  float ratio = 0.8f;
  /// Mutual nearest neighbours: keep i -> j1 only when query i is also the nearest query descriptor
  /// of train descriptor j1 (smallest distance, ties to the smallest query index). Runs the search a
  /// second time in the reverse direction.
  bool cross_check = false;
  /// Keep only matches with d1 <= max_distance (bits), >= 0. The default is no limit: the ratio
  /// test decides.
  int max_distance = std::numeric_limits<int>::max();

  /// Throws std::invalid_argument for a ratio that is not finite and > 0 or a negative
  /// max_distance.
  void check() const {
    detail::require_range(ratio, detail::kPositive, "MatcherOptions: ratio");
    detail::require_range(max_distance, detail::kNonNegative, "MatcherOptions: max_distance");
  }
};

/// An accepted correspondence: indices into the query and train descriptor vectors (or matrix
/// rows), and their Hamming distance in bits.
struct Match {
  int query = 0;
  int train = 0;
  int distance = 0;
};

/// The positions of matched keypoints, pixels: points1[i] is the query keypoint's and points2[i]
/// the train keypoint's position of match i (image 1 and image 2 of a pair).
struct MatchedPoints {
  std::vector<cv::Point2f> points1;
  std::vector<cv::Point2f> points2;
};

/// Fills `out` (its buffers reused, for callers that match frame after frame) with the positions
/// of `matches`' keypoints: Match::query indexes keypoints1, Match::train keypoints2. Throws
/// std::invalid_argument for an index outside its list.
inline void matched_points(const std::vector<cv::KeyPoint>& keypoints1, const std::vector<cv::KeyPoint>& keypoints2,
                           const std::vector<Match>& matches, MatchedPoints& out) {
  out.points1.clear();
  out.points2.clear();
  for (const Match& m : matches) {
    detail::require(m.query >= 0 && static_cast<std::size_t>(m.query) < keypoints1.size() && m.train >= 0 &&
                        static_cast<std::size_t>(m.train) < keypoints2.size(),
                    "matched_points: a match indexes past its keypoints");
    out.points1.push_back(keypoints1[static_cast<std::size_t>(m.query)].pt);
    out.points2.push_back(keypoints2[static_cast<std::size_t>(m.train)].pt);
  }
}

/// The positions of `matches`' keypoints (see the overload that fills a MatchedPoints).
inline MatchedPoints matched_points(const std::vector<cv::KeyPoint>& keypoints1,
                                    const std::vector<cv::KeyPoint>& keypoints2, const std::vector<Match>& matches) {
  MatchedPoints out;
  matched_points(keypoints1, keypoints2, matches, out);
  return out;
}

/// Lowe's ratio test on a knn2() result, exactly as MatcherOptions::ratio defines it: false without
/// neighbours, true with a single one, else best.distance < ratio · second.distance.
inline bool passes_ratio_test(const KnnMatch& m, float ratio) noexcept {
  if (m.count == 0) return false;
  if (m.count == 1) return true;
  return static_cast<double>(m.best.distance) < static_cast<double>(ratio) * m.second.distance;
}

/// For every query descriptor, its nearest and second-nearest train descriptor by Hamming distance,
/// ties broken by the smaller train index. Descriptors are BinaryDescriptor<64 · Words> (the word
/// count is deduced). result[i].query == i; result.size() == query.size(); with an empty train set
/// every count is 0.
template <std::size_t Words>
std::vector<KnnMatch> knn2(const std::vector<std::array<std::uint64_t, Words>>& query,
                           const std::vector<std::array<std::uint64_t, Words>>& train) {
#if AFFINE_ORB_KNN2_LANES256
  if (detail::cpu_has_avx2()) return detail::bitsliced256::knn2_bitsliced<detail::LaneVector256>(query, train);
#endif
  return detail::bitsliced128::knn2_bitsliced<detail::LaneVector128>(query, train);
}

/// Nearest-neighbour matches of query to train that pass the tests of `options` (ratio, maximum
/// distance, optional cross-check), sorted by query index, at most one per query. Empty when either
/// set is empty. Throws std::invalid_argument for invalid options.
template <std::size_t Words>
std::vector<Match> match(const std::vector<std::array<std::uint64_t, Words>>& query,
                         const std::vector<std::array<std::uint64_t, Words>>& train,
                         const MatcherOptions& options = {}) {
  options.check();
  if (query.empty() || train.empty()) return {};
  const std::vector<KnnMatch> forward = knn2(query, train);
  std::vector<KnnMatch> backward;
  if (options.cross_check) backward = knn2(train, query);
  std::vector<Match> matches;
  for (const KnnMatch& m : forward) {
    if (m.best.distance > options.max_distance || !passes_ratio_test(m, options.ratio)) continue;
    if (options.cross_check && backward[static_cast<std::size_t>(m.best.train)].best.train != m.query) continue;
    matches.push_back({m.query, m.best.train, m.best.distance});
  }
  return matches;
}

/// match() on OpenCV descriptor matrices (one descriptor per row, as cv::ORB, cv::BRISK and
/// descriptors_to_mat() write them): CV_8UC1, the same number of columns in both, a multiple of 8
/// bytes from 8 to 64 (64 to 512 bits; 32 for ORB, 64 for BRISK). A matrix with zero rows (also a
/// default-constructed cv::Mat) gives an empty result. Throws std::invalid_argument for another
/// type, different widths, or an unsupported width.
inline std::vector<Match> match(const cv::Mat& query, const cv::Mat& train, const MatcherOptions& options = {}) {
  options.check();
  for (const cv::Mat* mat : {&query, &train}) {
    const char* which = mat == &query ? "query" : "train";
    detail::require(mat->type() == CV_8UC1, std::string("match: the ") + which +
                                                " descriptors must be CV_8UC1 (8 bits per byte), got " +
                                                detail::type_name(mat->type()));
    detail::require(mat->dims <= 2, std::string("match: the ") + which + " descriptors must be a 2-D matrix");
  }
  if (query.rows == 0 || train.rows == 0) return {};
  detail::require(query.cols == train.cols, "match: query rows have " + std::to_string(query.cols) +
                                                " bytes but train rows have " + std::to_string(train.cols));
  detail::require(
      query.cols % 8 == 0 && query.cols >= 8 && query.cols <= 64,
      "match: descriptor rows must be 8, 16, ..., 64 bytes (a multiple of 64 bits), got " + std::to_string(query.cols));
  const auto run = [&](auto words) {
    constexpr std::size_t kWords = decltype(words)::value;
    return match(descriptors_from_mat<kWords>(query), descriptors_from_mat<kWords>(train), options);
  };
  switch (query.cols / 8) {
    case 1:
      return run(std::integral_constant<std::size_t, 1>{});
    case 2:
      return run(std::integral_constant<std::size_t, 2>{});
    case 3:
      return run(std::integral_constant<std::size_t, 3>{});
    case 4:
      return run(std::integral_constant<std::size_t, 4>{});
    case 5:
      return run(std::integral_constant<std::size_t, 5>{});
    case 6:
      return run(std::integral_constant<std::size_t, 6>{});
    case 7:
      return run(std::integral_constant<std::size_t, 7>{});
    default:
      return run(std::integral_constant<std::size_t, 8>{});
  }
}

}  // namespace affine_orb
