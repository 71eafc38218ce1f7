#pragma once
/// \file
/// Internals (namespace detail): the corners cv::FAST with non-maximum suppression finds on the
/// image of each cell of a grid, from a level's FAST score map (detection/detail/fast.hpp), as the
/// forks' cells (ORB-SLAM2, ORB-SLAM3, stella_vslam) call it: a pixel must score strictly above each
/// of its 8 neighbours, those outside the cell counting 0; at the initial threshold, or at the
/// minimum one where that finds no corner. The cells' scored rectangles tile the region, so one
/// pass over each row of a row of cells marks the maxima of all its cells as bits
/// (mark_cell_rows()), with the neighbours across a cell's edge masked to 0, and each cell then
/// reads its own columns (append_cell_corners()).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/detection/detail/fast.hpp"

namespace affine_orb {
namespace detail {

/// Columns of slack a score map needs past each row's last scored pixel for mark_cell_rows(), whose
/// widest lanes read up to 32 columns past a run (padded_score_map()).
inline constexpr int kCellMaximaPadding = 64;

/// A score map of `size` in `storage` whose rows have kCellMaximaPadding columns of slack after them.
inline cv::Mat padded_score_map(cv::Mat& storage, cv::Size size) {
  const cv::Mat padded = fit_buffer(storage, cv::Size(size.width + kCellMaximaPadding, size.height), CV_8UC1);
  return padded.empty() ? padded : padded.colRange(0, size.width);
}

/// The cells of one row of a grid, side by side: cell j scores the columns [edges[j], edges[j + 1])
/// (level coordinates), and per row of the cells, which of their pixels are local maxima
/// (mark_cell_rows()), one bit per column from edges.front().
struct CellMaximaWork {
  std::vector<int> edges;
  /// Per column from edges.front(): 0xFF where the cell's image ends left of it (its first column),
  /// resp. right of it (its last), so that the neighbours there count 0; kCellMaximaPadding more.
  std::vector<std::uint8_t> drop_left;
  std::vector<std::uint8_t> drop_right;
  std::vector<std::uint64_t> strong;  ///< per row, words_per_row words: maxima of the initial threshold
  std::vector<std::uint64_t> weak;    ///< the same for the minimum threshold
  int words_per_row = 0;
  int first_row = 0;  ///< level row of the first row of bits
};

/// The drop masks and row width of `work` for its cells' columns `work.edges` (increasing, at
/// least two).
inline void set_cell_columns(CellMaximaWork& work) {
  const std::vector<int>& edges = work.edges;
  const int width = edges.back() - edges.front();
  work.drop_left.assign(static_cast<std::size_t>(width + kCellMaximaPadding), 0);
  work.drop_right.assign(work.drop_left.size(), 0);
  for (std::size_t j = 0; j + 1 < edges.size(); ++j) {
    work.drop_left[static_cast<std::size_t>(edges[j] - edges.front())] = 0xFF;
    work.drop_right[static_cast<std::size_t>(edges[j + 1] - 1 - edges.front())] = 0xFF;
  }
  work.words_per_row = width / 64 + 1;
}

/// Row y of the cells (`top`, `bottom`: the cells' first and last row, whose neighbours above,
/// resp. below, count 0) into bits: bit x − x0 of `strong` for the pixels of [x0, x1) that
/// cv::FAST's non-maximum suppression keeps on their cell's image (score strictly above each of
/// the 8 neighbours inside the cell, those outside counting 0) with a score of at least
/// `strong_floor`, and of `weak` with at least `weak_floor` (both >= 1). A neighbour below the
/// threshold counts 0 in cv::FAST but is below the pixel anyway, so the raw map values serve. The
/// scalar reference of mark_row(); `strong` and `weak` start zeroed.
inline void mark_row_scalar(const cv::Mat& scores, int y, bool top, bool bottom, int x0, int x1,
                            const std::uint8_t* drop_left, const std::uint8_t* drop_right, int strong_floor,
                            int weak_floor, std::uint64_t* strong, std::uint64_t* weak) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(scores.step[0]);
  const std::uint8_t* row = scores.ptr<std::uint8_t>(y);
  for (int x = x0; x < x1; ++x) {
    const std::uint8_t* p = row + x;
    const int o = x - x0;
    int left = p[-1], right = p[1], vertical = 0;
    if (!top) {
      left = std::max<int>(left, p[-step - 1]);
      right = std::max<int>(right, p[-step + 1]);
      vertical = p[-step];
    }
    if (!bottom) {
      left = std::max<int>(left, p[step - 1]);
      right = std::max<int>(right, p[step + 1]);
      vertical = std::max<int>(vertical, p[step]);
    }
    if (drop_left[o] != 0) left = 0;
    if (drop_right[o] != 0) right = 0;
    const int s = *p;
    if (s <= std::max({left, right, vertical})) continue;
    const std::uint64_t bit = std::uint64_t{1} << (o % 64);
    if (s >= strong_floor) strong[o / 64] |= bit;
    if (s >= weak_floor) weak[o / 64] |= bit;
  }
}

// mark_row_run() written once over S lanes: for Lanes128 here and, inside the AVX2 region,
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

/// mark_row_scalar() 32 pixels at a time.
inline void mark_row_avx2(const cv::Mat& scores, int y, bool top, bool bottom, int x0, int x1,
                          const std::uint8_t* drop_left, const std::uint8_t* drop_right, int strong_floor,
                          int weak_floor, std::uint64_t* strong, std::uint64_t* weak) {
  maxima256::mark_row_run<Lanes256>(scores, y, top, bottom, x0, x1, drop_left, drop_right, strong_floor, weak_floor,
                                    strong, weak);
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// mark_row_scalar() with the widest lanes the CPU runs: 32 with AVX2, 16 with SSE2 or NEON. The
/// lanes read up to 32 columns past x1 of the score map and of the drop masks
/// (kCellMaximaPadding).
inline void mark_row(const cv::Mat& scores, int y, bool top, bool bottom, int x0, int x1, const std::uint8_t* drop_left,
                     const std::uint8_t* drop_right, int strong_floor, int weak_floor, std::uint64_t* strong,
                     std::uint64_t* weak) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    mark_row_avx2(scores, y, top, bottom, x0, x1, drop_left, drop_right, strong_floor, weak_floor, strong, weak);
    return;
  }
#endif
#if AFFINE_ORB_SIMD128
  maxima128::mark_row_run<Lanes128>(scores, y, top, bottom, x0, x1, drop_left, drop_right, strong_floor, weak_floor,
                                    strong, weak);
#else
  mark_row_scalar(scores, y, top, bottom, x0, x1, drop_left, drop_right, strong_floor, weak_floor, strong, weak);
#endif
}

/// The local maxima of rows [y0, y1) of the cells of `work` (set_cell_columns()) into its bits, at
/// `initial_threshold` (strong) and `min_threshold` (weak), from the level's score map `scores`
/// (scores of at least min_threshold, 0 elsewhere; padded_score_map()).
inline void mark_cell_rows(const cv::Mat& scores, int y0, int y1, int initial_threshold, int min_threshold,
                           CellMaximaWork& work) {
  const std::size_t words = static_cast<std::size_t>(work.words_per_row);
  work.first_row = y0;
  work.strong.assign(static_cast<std::size_t>(y1 - y0) * words, 0);
  work.weak.assign(work.strong.size(), 0);
  for (int y = y0; y < y1; ++y) {
    const std::size_t at = static_cast<std::size_t>(y - y0) * words;
    mark_row(scores, y, y == y0, y == y1 - 1, work.edges.front(), work.edges.back(), work.drop_left.data(),
             work.drop_right.data(), std::max(initial_threshold, 1), std::max(min_threshold, 1),
             work.strong.data() + at, work.weak.data() + at);
  }
}

/// Word w of one row of bits with the bits outside columns [begin, end) (from edges.front()) cleared.
inline std::uint64_t cell_word(const std::uint64_t* row, int w, int begin, int end) {
  std::uint64_t word = row[w];
  if (w == begin / 64) word &= ~std::uint64_t{0} << (begin % 64);
  if (w == (end - 1) / 64 && end % 64 != 0) word &= (std::uint64_t{1} << (end % 64)) - 1;
  return word;
}

/// Appends to `points` (level pixels relative to `origin`) and `responses` the corners cv::FAST
/// with non-maximum suppression finds on the image of cell j of `work` (mark_cell_rows()'s rows) at
/// the initial threshold, or at the minimum one where that finds none, in raster order.
inline void append_cell_corners(const cv::Mat& scores, const CellMaximaWork& work, int j, cv::Point origin,
                                std::vector<cv::Point2f>& points, std::vector<float>& responses) {
  const int x0 = work.edges.front();
  const int begin = work.edges[static_cast<std::size_t>(j)] - x0;
  const int end = work.edges[static_cast<std::size_t>(j) + 1] - x0;
  const std::size_t words = static_cast<std::size_t>(work.words_per_row);
  const std::size_t rows = work.strong.size() / words;
  bool strong = false;
  for (std::size_t r = 0; r < rows && !strong; ++r) {
    for (int w = begin / 64; w <= (end - 1) / 64 && !strong; ++w) {
      strong = cell_word(work.strong.data() + r * words, w, begin, end) != 0;
    }
  }
  const std::vector<std::uint64_t>& bits = strong ? work.strong : work.weak;
  for (std::size_t r = 0; r < rows; ++r) {
    const int y = work.first_row + static_cast<int>(r);
    const std::uint8_t* row = scores.ptr<std::uint8_t>(y);
    for (int w = begin / 64; w <= (end - 1) / 64; ++w) {
      for (std::uint64_t word = cell_word(bits.data() + r * words, w, begin, end); word != 0; word &= word - 1) {
        const int x = x0 + w * 64 + __builtin_ctzll(word);
        points.emplace_back(static_cast<float>(x - origin.x), static_cast<float>(y - origin.y));
        responses.push_back(static_cast<float>(row[x]));
      }
    }
  }
}

}  // namespace detail
}  // namespace affine_orb
