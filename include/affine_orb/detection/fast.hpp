#pragma once
/// \file
/// FAST-9 corner detection on the 16-pixel Bresenham circle of radius 3 (Rosten & Drummond, 2006),
/// with the FAST score and 3x3 non-maximum suppression.
///
/// Definitions used throughout (pixels of a CV_8UC1 image, x right, y down):
/// - a pixel p with intensity I_p is a corner at threshold t when 9 contiguous pixels of its circle
///   are all brighter than I_p + t or all darker than I_p − t (strict inequalities);
/// - its FAST score is the largest t for which it is still a corner (0 when it is not a corner at
///   t = 0). A pixel is a corner at threshold t exactly when its score is >= t.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/detection/corner.hpp"
#include "affine_orb/detection/detail/fast.hpp"

namespace affine_orb {

/// FAST score of the pixel at `p` (pointer into a CV_8UC1 image with row step `step` bytes); the
/// caller guarantees the 7x7 neighbourhood is inside the image.
inline int fast_score(const std::uint8_t* p, std::ptrdiff_t step) {
  return std::max(detail::pixel_strength(p, detail::circle_offsets(step)) - 1, 0);
}

/// Writes the FAST scores of the pixels of `rect` whose score is at least `threshold` into the
/// CV_8UC1 map `scores` (of the image size), 0 for the other pixels of `rect`; pixels outside `rect`
/// are left as they are. `rect` is clipped to the pixels whose circle lies inside the image.
/// Uses AVX2 or SSE2 where the target has them (SSE2: every x86-64), NEON on AArch64, a scalar loop
/// elsewhere; all write identical maps.
inline void fast_score_rect(const cv::Mat& image, cv::Rect rect, int threshold, cv::Mat& scores) {
  detail::require_gray8(image, "fast_score_rect");
  detail::require_range(threshold, {1, 255}, "fast_score_rect: threshold");
  detail::require(scores.type() == CV_8UC1 && scores.size() == image.size(),
                  "fast_score_rect: the score map must be CV_8UC1 of the image size");
  detail::score_rect(image, rect, threshold, scores);
}

/// Per-pixel FAST scores of `image` restricted to the rectangle `roi`, for pixels whose score is at
/// least `threshold` (in [1, 255]): `scores` is resized to the image size (CV_8UC1, its buffer
/// reused across calls) and holds those scores inside `roi`, 0 everywhere else. Scores never exceed
/// 254. This is the detection pass; see detect_fast() for a one-call interface.
inline void fast_score_map(const cv::Mat& image, cv::Rect roi, int threshold, cv::Mat& scores) {
  detail::require_gray8(image, "fast_score_map");
  scores.create(image.size(), CV_8UC1);
  scores.setTo(0);
  fast_score_rect(image, roi, threshold, scores);
}

/// fast_score_rect() for the pixels of `region`: their scores (0 below `threshold`) are written into
/// `scores` (CV_8UC1 of the image size), other pixels are left as they are. Pixels of the region
/// whose circle is not inside the image get 0.
inline void fast_score_spans(const cv::Mat& image, const RowSpans& region, int threshold, cv::Mat& scores) {
  detail::require_gray8(image, "fast_score_spans");
  detail::require_range(threshold, {1, 255}, "fast_score_spans: threshold");
  detail::require(scores.type() == CV_8UC1 && scores.size() == image.size(),
                  "fast_score_spans: the score map must be CV_8UC1 of the image size");
  detail::score_spans(image, region, threshold, scores);
}

/// Non-maximum suppression on a score map: the pixels of `roi` whose score is at least `threshold`
/// and a local maximum of their 3x3 neighbourhood, in raster order. Ties are broken in raster
/// order: a pixel must be strictly greater than its 4 neighbours that precede it (the row above
/// and its left neighbour) and at least equal to the 4 that follow, so a plateau of equal scores
/// (common in synthetic and saturated images) keeps one pixel instead of none.
inline std::vector<Corner> non_max_suppression(const cv::Mat& scores, cv::Rect roi, int threshold) {
  detail::require(!scores.empty() && scores.type() == CV_8UC1, "non_max_suppression: scores must be CV_8UC1");
  std::vector<Corner> corners;
  roi &= cv::Rect(1, 1, scores.cols - 2, scores.rows - 2);
  if (roi.empty()) return corners;
  threshold = std::max(threshold, 1);
  for (int y = roi.y; y < roi.y + roi.height; ++y)
    detail::non_max_row(scores, y, roi.x, roi.x + roi.width, threshold, corners);
  return corners;
}

/// non_max_suppression() on the pixels of `region` (those at least one pixel inside the map),
/// appending the corners to `corners` in raster order.
inline void non_max_suppression(const cv::Mat& scores, const RowSpans& region, int threshold,
                                std::vector<Corner>& corners) {
  detail::require(!scores.empty() && scores.type() == CV_8UC1, "non_max_suppression: scores must be CV_8UC1");
  detail::non_max_spans(scores, region, threshold, corners);
}

/// FAST-9 corners of a CV_8UC1 image at `threshold` (in [1, 255]), optionally non-maximum
/// suppressed, in raster order. Pixels closer than kFastRadius to the border are never corners.
inline std::vector<Corner> detect_fast(const cv::Mat& image, int threshold, bool suppress_non_max = true) {
  cv::Mat scores;
  const cv::Rect all(0, 0, image.cols, image.rows);
  fast_score_map(image, all, threshold, scores);
  if (suppress_non_max) return non_max_suppression(scores, all, threshold);
  std::vector<Corner> corners;
  for (int y = 0; y < scores.rows; ++y) {
    const std::uint8_t* row = scores.ptr<std::uint8_t>(y);
    for (int x = 0; x < scores.cols; ++x) {
      if (row[x] >= threshold) corners.push_back({x, y, row[x]});
    }
  }
  return corners;
}

}  // namespace affine_orb
