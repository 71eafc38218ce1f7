#pragma once
/// \file
/// Corner candidates of one image (a pyramid level of the original image or of a simulated view):
/// FAST-9 with non-maximum suppression, on a grid whose cells fall back to a lower threshold when
/// they have no corner at the initial one (docs/algorithm.md §2, ORB-SLAM2's iniThFAST/minThFAST behaviour).

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/harris.hpp"

namespace affine_orb {

/// How candidates are ranked by the budget and the spatial spreading.
enum class ScoreType {
  kFast,    ///< FAST score (largest threshold at which the pixel is a corner); ORB-SLAM2's choice.
  kHarris,  ///< Harris response on a 7x7 block, k = 0.04; cv::ORB's default.
};

/// Corner detection parameters.
struct DetectorOptions {
  /// FAST threshold in grey levels tried first in every grid cell, in [1, 254]; 20 is ORB-SLAM2's
  /// iniThFAST. bench/eval_blur compares 20/7 with 10/4 on blurred frames.
  int initial_threshold = 20;
  /// FAST threshold in grey levels for cells that have no corner at initial_threshold (needed in
  /// texture-poor regions), in [1, initial_threshold]; 7 is ORB-SLAM2's minThFAST.
  int min_threshold = 7;
  /// Side of the grid cells in level pixels, in [4, 4096]; 30 is ORB-SLAM2's.
  int cell_size = 30;
  /// Ranking score for the budget and the spreading.
  ScoreType score = ScoreType::kFast;
  /// Harris block side in pixels when score == kHarris, odd, in [3, 15]; 7 is ORB's.
  int harris_block_size = 7;
  /// Harris k (dimensionless) when score == kHarris, in [0, 0.25]; 0.04 is ORB's and Harris &
  /// Stephens'.
  float harris_k = 0.04f;

  void check() const {
    detail::require_range(initial_threshold, {1, 254}, "DetectorOptions::initial_threshold");
    detail::require(
        min_threshold >= 1 && min_threshold <= initial_threshold,
        "DetectorOptions::min_threshold must be in [1, initial_threshold], got " + std::to_string(min_threshold));
    detail::require_range(cell_size, {4, 4096}, "DetectorOptions::cell_size");
    detail::require(score == ScoreType::kFast || score == ScoreType::kHarris, "DetectorOptions::score is invalid");
    detail::require_range(harris_block_size, {3, 15}, "DetectorOptions::harris_block_size");
    detail::require(harris_block_size % 2 == 1,
                    "DetectorOptions::harris_block_size must be odd, got " + std::to_string(harris_block_size));
    detail::require_range(harris_k, {0, 0.25}, "DetectorOptions::harris_k");
  }

  /// Pixels around a candidate that ranking reads (FAST circle, or the Harris block with Sobel).
  int support_radius() const {
    return score == ScoreType::kHarris ? std::max(kFastRadius, harris_radius(harris_block_size)) : kFastRadius;
  }
};

/// Candidates of one image, all inside `roi`: integer positions, FAST scores, and the ranking
/// response (FAST score or Harris response per DetectorOptions::score).
struct Candidates {
  std::vector<Corner> corners;
  std::vector<float> responses;
};

/// Buffers of detect_candidates() reused across calls (the FAST score map and the grid).
struct DetectorWorkspace {
  cv::Mat scores;            ///< grown to the largest image seen, never shrunk; its top-left part is used
  std::vector<char> strong;  ///< per grid cell: has a corner at the initial threshold
  RowSpans margin;
};

/// Detects candidates among the pixels of `region` of a CV_8UC1 image, into `out` (its buffers
/// reused). The caller keeps the region at least options.support_radius() pixels inside the image.
/// The grid cells (cell_size x cell_size) are anchored at `grid_origin`. Every cell keeps the
/// non-maximum-suppressed corners (non_max_suppression(), 3x3 neighbourhoods of the whole image)
/// of its pixels in the region at initial_threshold, or, when it has none there, those at
/// min_threshold. Output in raster order.
inline void detect_candidates(const cv::Mat& image, const RowSpans& region, cv::Point grid_origin,
                              const DetectorOptions& options, DetectorWorkspace& work, Candidates& out) {
  detail::require_gray8(image, "detect_candidates");
  out.corners.clear();
  out.responses.clear();
  const RowSpans& all = region;
  const cv::Rect bounds = all.bounds() & cv::Rect(0, 0, image.cols, image.rows);
  if (bounds.empty()) return;
  if (work.scores.type() != CV_8UC1 || work.scores.rows < image.rows || work.scores.cols < image.cols) {
    work.scores.create(std::max(work.scores.rows, image.rows), std::max(work.scores.cols, image.cols), CV_8UC1);
  }
  cv::Mat scores = work.scores(cv::Rect(0, 0, image.cols, image.rows));
  std::vector<Corner>& corners = out.corners;
  // One score map at min_threshold over the region grown by one pixel, so that suppression at its
  // edge sees the true neighbours, and one suppression pass at min_threshold. Whether a pixel is a
  // local maximum does not depend on the threshold, so the corners at initial_threshold are
  // exactly those of these scoring at least initial_threshold.
  all.dilate_into(work.margin);
  detail::score_spans(image, work.margin, options.min_threshold, scores);
  detail::non_max_spans(scores, all, options.min_threshold, corners);

  // A cell is strong when it has a corner at initial_threshold: it keeps only those; the other
  // cells keep their corners at min_threshold. Filtering keeps the raster order.
  if (options.min_threshold < options.initial_threshold) {
    const int size = options.cell_size;
    auto cell_index = [&](int v, int origin) {
      return (v - origin) >= 0 ? (v - origin) / size : -((origin - v + size - 1) / size);
    };
    const int col0 = cell_index(bounds.x, grid_origin.x);
    const int row0 = cell_index(bounds.y, grid_origin.y);
    const int cols = cell_index(bounds.x + bounds.width - 1, grid_origin.x) - col0 + 1;
    const int rows = cell_index(bounds.y + bounds.height - 1, grid_origin.y) - row0 + 1;
    auto cell_of = [&](const Corner& c) {
      return static_cast<std::size_t>(cell_index(c.y, grid_origin.y) - row0) * static_cast<std::size_t>(cols) +
             static_cast<std::size_t>(cell_index(c.x, grid_origin.x) - col0);
    };
    work.strong.assign(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), 0);
    for (const Corner& c : corners) {
      if (c.score >= options.initial_threshold) work.strong[cell_of(c)] = 1;
    }
    corners.erase(
        std::remove_if(corners.begin(), corners.end(),
                       [&](const Corner& c) { return c.score < options.initial_threshold && work.strong[cell_of(c)]; }),
        corners.end());
  }

  out.responses.reserve(corners.size());
  for (const Corner& c : corners) {
    out.responses.push_back(options.score == ScoreType::kHarris
                                ? harris_response(image, c.x, c.y, options.harris_block_size, options.harris_k)
                                : static_cast<float>(c.score));
  }
}

/// Detects candidates inside `roi` of a CV_8UC1 image: detect_candidates() on the region `roi`
/// with the grid anchored at its corner. `scores` is a caller-owned buffer reused across calls
/// (the FAST score map). The caller keeps `roi` at least options.support_radius() pixels inside
/// the image.
inline Candidates detect_candidates(const cv::Mat& image, cv::Rect roi, const DetectorOptions& options,
                                    cv::Mat& scores) {
  Candidates out;
  roi &= cv::Rect(0, 0, image.cols, image.rows);
  if (roi.empty()) return out;
  DetectorWorkspace work;
  std::swap(work.scores, scores);
  detect_candidates(image, RowSpans::rectangle(roi), roi.tl(), options, work, out);
  std::swap(work.scores, scores);
  return out;
}

}  // namespace affine_orb
