#pragma once
/// \file
/// RowSpans: a region of an image given as one run of columns per row, the shape of the part of a
/// simulated view (or of one of its pyramid levels) that maps inside the original image.

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace affine_orb {

/// Rows [y0, y0 + rows()), row y0 + i holding the columns [begin[i], end[i]) (empty when
/// begin[i] >= end[i]); pixel coordinates of the image the region belongs to.
struct RowSpans {
  int y0 = 0;
  std::vector<int> begin;
  std::vector<int> end;

  int rows() const { return static_cast<int>(begin.size()); }

  /// Every row of `rect` with the columns of `rect`.
  static RowSpans rectangle(cv::Rect rect) {
    RowSpans spans;
    if (rect.width <= 0 || rect.height <= 0) return spans;
    spans.y0 = rect.y;
    spans.begin.assign(static_cast<std::size_t>(rect.height), rect.x);
    spans.end.assign(static_cast<std::size_t>(rect.height), rect.x + rect.width);
    return spans;
  }

  /// Clears and sizes the region to `rows` empty rows from row `first_row`.
  void reset(int first_row, int rows) {
    y0 = first_row;
    begin.assign(static_cast<std::size_t>(std::max(rows, 0)), 0);
    end.assign(static_cast<std::size_t>(std::max(rows, 0)), 0);
  }

  /// The run of row y (image row), [0, 0) outside the region's rows.
  std::pair<int, int> run(int y) const {
    const int i = y - y0;
    if (i < 0 || i >= rows()) return {0, 0};
    return {begin[static_cast<std::size_t>(i)], end[static_cast<std::size_t>(i)]};
  }

  /// Number of pixels.
  long long area() const {
    long long n = 0;
    for (std::size_t i = 0; i < begin.size(); ++i) n += std::max(0, end[i] - begin[i]);
    return n;
  }

  /// Smallest rectangle holding every pixel (empty for an empty region).
  cv::Rect bounds() const {
    int x0 = 0, x1 = 0, first = -1, last = -1;
    for (int i = 0; i < rows(); ++i) {
      const int b = begin[static_cast<std::size_t>(i)];
      const int e = end[static_cast<std::size_t>(i)];
      if (b >= e) continue;
      if (first < 0) {
        x0 = b;
        x1 = e;
        first = i;
      }
      x0 = std::min(x0, b);
      x1 = std::max(x1, e);
      last = i;
    }
    if (first < 0) return {};
    return {x0, y0 + first, x1 - x0, last - first + 1};
  }

  /// Into `out` (buffers reused): the region grown by one pixel in every direction, each row's run
  /// being the hull of the runs of that row and its two neighbours, widened by one column.
  void dilate_into(RowSpans& out) const {
    out.reset(y0 - 1, rows() + 2);
    for (int i = 0; i < out.rows(); ++i) {
      int b = 0, e = 0;
      for (int j = i - 2; j <= i; ++j) {
        if (j < 0 || j >= rows()) continue;
        const int rb = begin[static_cast<std::size_t>(j)];
        const int re = end[static_cast<std::size_t>(j)];
        if (rb >= re) continue;
        if (b >= e) {
          b = rb;
          e = re;
        } else {
          b = std::min(b, rb);
          e = std::max(e, re);
        }
      }
      if (b < e) {
        out.begin[static_cast<std::size_t>(i)] = b - 1;
        out.end[static_cast<std::size_t>(i)] = e + 1;
      }
    }
  }
};

}  // namespace affine_orb
