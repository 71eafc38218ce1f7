#pragma once
/// \file
/// Internals (namespace detail): the corners cv::FAST with non-maximum suppression finds on the
/// image of one cell, from a level's FAST score map (detection/detail/fast.hpp), as the forks' cells
/// (ORB-SLAM2, ORB-SLAM3, stella_vslam) call it: a pixel must score strictly above each of its 8
/// neighbours, those outside the cell counting 0; at the initial threshold, or at the minimum one
/// where that finds no corner.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/detection/corner.hpp"
#include "affine_orb/detection/detail/fast.hpp"

namespace affine_orb {
namespace detail {

/// Whether the pixel at `p` (score s >= 1, in `cell`) is a local maximum as cv::FAST's non-maximum
/// suppression on the cell's image decides: s strictly above each of its 8 neighbours inside the
/// cell, those outside counting 0. A neighbour below the threshold counts 0 in cv::FAST but is
/// below s anyway, so the raw map values serve for every threshold. Used for the pixels on a cell's
/// edge; interior_maxima() decides the others.
inline bool fork_local_max(const std::uint8_t* p, std::ptrdiff_t step, int x, int y, const cv::Rect& cell) {
  const int s = *p;
  const bool left = x > cell.x;
  const bool right = x < cell.x + cell.width - 1;
  const bool up = y > cell.y;
  const bool down = y < cell.y + cell.height - 1;
  if (left && s <= p[-1]) return false;
  if (right && s <= p[1]) return false;
  if (up && ((left && s <= p[-step - 1]) || s <= p[-step] || (right && s <= p[-step + 1]))) return false;
  if (down && ((left && s <= p[step - 1]) || s <= p[step] || (right && s <= p[step + 1]))) return false;
  return true;
}

/// Appends the pixel at (x, y) of `scores` to `maxima` when its score is at least `floor` (>= 1)
/// and it is a local maximum of the cell (fork_local_max()).
inline void push_if_local_max(const cv::Mat& scores, int x, int y, const cv::Rect& cell, int floor,
                              std::vector<Corner>& maxima) {
  const std::uint8_t* p = scores.ptr<std::uint8_t>(y) + x;
  if (*p >= floor && fork_local_max(p, static_cast<std::ptrdiff_t>(scores.step[0]), x, y, cell)) {
    maxima.push_back({x, y, *p});
  }
}

/// The pixels of columns [x0, x1) of row y of `scores` whose score is at least `floor` (>= 1) and
/// exceeds all 8 neighbours, appended to `maxima` in order; the caller keeps columns x0 − 1 … x1 of
/// rows y − 1 … y + 1 inside the map. The scalar reference of interior_maxima().
inline void interior_maxima_scalar(const cv::Mat& scores, int y, int x0, int x1, int floor,
                                   std::vector<Corner>& maxima) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(scores.step[0]);
  const std::uint8_t* row = scores.ptr<std::uint8_t>(y);
  for (int x = x0; x < x1; ++x) {
    const std::uint8_t* p = row + x;
    const int s = *p;
    if (s >= floor && s > p[-step - 1] && s > p[-step] && s > p[-step + 1] && s > p[-1] && s > p[1] &&
        s > p[step - 1] && s > p[step] && s > p[step + 1]) {
      maxima.push_back({x, y, s});
    }
  }
}

// interior_maxima_run() written once over S lanes: for Lanes128 here and, inside the AVX2 region,
// Lanes256 (an instantiation takes the target of its definition: fast_lanes.inc explains it).
#if AFFINE_ORB_SIMD128
namespace maxima128 {
#include "affine_orb/extraction/detail/maxima_lanes.inc"
}  // namespace maxima128
#endif
#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
namespace maxima256 {
#include "affine_orb/extraction/detail/maxima_lanes.inc"
}  // namespace maxima256

/// interior_maxima_scalar() 32 pixels at a time, for runs of at least 32 columns.
inline void interior_maxima_avx2(const cv::Mat& scores, int y, int x0, int x1, int floor, std::vector<Corner>& maxima) {
  maxima256::interior_maxima_run<Lanes256>(scores, y, x0, x1, floor, maxima);
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// interior_maxima_scalar() with the widest lanes the CPU runs and the run fills: 32 with AVX2, 16
/// with SSE2 or NEON; the scalar reference for shorter runs.
inline void interior_maxima(const cv::Mat& scores, int y, int x0, int x1, int floor, std::vector<Corner>& maxima) {
#if AFFINE_ORB_AVX2
  if (x1 - x0 >= 32 && cpu_has_avx2()) {
    interior_maxima_avx2(scores, y, x0, x1, floor, maxima);
    return;
  }
#endif
#if AFFINE_ORB_SIMD128
  if (x1 - x0 >= Lanes128::kLanes) {
    maxima128::interior_maxima_run<Lanes128>(scores, y, x0, x1, floor, maxima);
    return;
  }
#endif
  interior_maxima_scalar(scores, y, x0, x1, floor, maxima);
}

/// Appends to `points` (level pixels relative to the region's corner `origin`) and `responses` the
/// corners cv::FAST with non-maximum suppression finds on the image of one cell (`cell`: its scored
/// pixels, level coordinates) at `initial_threshold`, or at `min_threshold` where that finds none,
/// in raster order, from the level's score map `scores` (scores of at least min_threshold, 0
/// elsewhere). `maxima` is a buffer for the cell's local maxima: once it holds one at
/// `initial_threshold`, the rows after collect none below it, which could not be kept.
inline void suppress_in_cell(const cv::Mat& scores, cv::Rect cell, cv::Point origin, int initial_threshold,
                             int min_threshold, std::vector<Corner>& maxima, std::vector<cv::Point2f>& points,
                             std::vector<float>& responses) {
  maxima.clear();
  const int last_x = cell.x + cell.width - 1;
  const int last_y = cell.y + cell.height - 1;
  bool strong = false;
  int floor = 1;
  for (int y = cell.y; y <= last_y; ++y) {
    const std::size_t before = maxima.size();
    if (y == cell.y || y == last_y || cell.width < 3) {
      for (int x = cell.x; x <= last_x; ++x) push_if_local_max(scores, x, y, cell, floor, maxima);
    } else {
      push_if_local_max(scores, cell.x, y, cell, floor, maxima);
      interior_maxima(scores, y, cell.x + 1, last_x, floor, maxima);
      push_if_local_max(scores, last_x, y, cell, floor, maxima);
    }
    for (std::size_t i = before; i < maxima.size() && !strong; ++i) strong = maxima[i].score >= initial_threshold;
    if (strong) floor = std::max(initial_threshold, 1);
  }
  const int threshold = strong ? initial_threshold : min_threshold;
  for (const Corner& c : maxima) {
    if (c.score < threshold) continue;
    points.emplace_back(static_cast<float>(c.x - origin.x), static_cast<float>(c.y - origin.y));
    responses.push_back(static_cast<float>(c.score));
  }
}

}  // namespace detail
}  // namespace affine_orb
