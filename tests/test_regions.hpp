#pragma once
// Regions and spreads for the tests of detection and extraction: a rotated quadrilateral as row
// spans, membership in row spans, and how many cells of a grid a selection occupies.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/row_spans.hpp"

namespace affine_orb::test {

/// Whether pixel (x, y) belongs to `region`.
inline bool in_region(const affine_orb::RowSpans& region, int x, int y) {
  const auto [b, e] = region.run(y);
  return x >= b && x < e;
}

/// A rotated quadrilateral region, at least `inset` pixels inside the image.
inline affine_orb::RowSpans quad_region(cv::Size size, double angle_degrees, int inset) {
  affine_orb::RowSpans region;
  region.reset(0, size.height);
  const double a = angle_degrees * CV_PI / 180.0;
  const cv::Point2d centre(size.width / 2.0, size.height / 2.0);
  const cv::Point2d u(std::cos(a), std::sin(a));
  const cv::Point2d v(-std::sin(a), std::cos(a));
  const double half_u = 0.45 * size.width;
  const double half_v = 0.3 * size.height;
  for (int y = inset; y < size.height - inset; ++y) {
    int first = -1;
    int last = -1;
    for (int x = inset; x < size.width - inset; ++x) {
      const cv::Point2d d(x - centre.x, y - centre.y);
      if (std::abs(d.dot(u)) <= half_u && std::abs(d.dot(v)) <= half_v) {
        if (first < 0) first = x;
        last = x;
      }
    }
    if (first >= 0) {
      region.begin[static_cast<std::size_t>(y)] = first;
      region.end[static_cast<std::size_t>(y)] = last + 1;
    }
  }
  return region;
}

/// Number of cells of a g x g grid over `region` that hold at least one of the chosen points.
inline int occupied_cells(const std::vector<cv::Point2f>& points, const std::vector<int>& chosen, cv::Rect2f region,
                          int g) {
  std::set<int> cells;
  for (int i : chosen) {
    const cv::Point2f& p = points[static_cast<std::size_t>(i)];
    const int cx = std::min(g - 1, static_cast<int>((p.x - region.x) / region.width * static_cast<float>(g)));
    const int cy = std::min(g - 1, static_cast<int>((p.y - region.y) / region.height * static_cast<float>(g)));
    cells.insert(cy * g + cx);
  }
  return static_cast<int>(cells.size());
}

}  // namespace affine_orb::test
