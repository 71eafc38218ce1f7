#pragma once
/// \file
/// The regions of a simulated view the extractor works on: the part it renders exactly, and, per
/// pyramid level, the pixels whose descriptor support maps inside the original image.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <opencv2/core.hpp>

#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb::detail {

/// The map from the pixels of a pyramid level of size `level_size` of `view` to original pixels:
/// Pyramid::to_level0, then to_original.
inline cv::Matx23d level_to_original(const AffineView& view, cv::Size level_size) {
  const double rx = static_cast<double>(view.size.width) / level_size.width;
  const double ry = static_cast<double>(view.size.height) / level_size.height;
  const cv::Matx23d& m = view.to_original;
  return {m(0, 0) * rx, m(0, 1) * ry, m(0, 0) * (0.5 * rx - 0.5) + m(0, 1) * (0.5 * ry - 0.5) + m(0, 2),
          m(1, 0) * rx, m(1, 1) * ry, m(1, 0) * (0.5 * rx - 0.5) + m(1, 1) * (0.5 * ry - 0.5) + m(1, 2)};
}

/// The part of an image of size `size` (a view or one of its pyramid levels, mapped to original
/// pixels by `to_original`) within `margin` of its pixels of the original image: the pixels v
/// with to_original(v) in [−margin·e_x, W − 1 + margin·e_x] x [−margin·e_y, H − 1 + margin·e_y],
/// e_x and e_y the extents in original pixels of a unit disc of its pixels along x and y (a
/// superset of the points within `margin` of the image). One run per row, possibly empty.
inline RowSpans region_near_image(const cv::Matx23d& to_original, cv::Size size, cv::Size image_size, double margin) {
  RowSpans spans;
  spans.reset(0, size.height);
  const cv::Matx23d& m = to_original;
  const double ex = margin * std::hypot(m(0, 0), m(0, 1));
  const double ey = margin * std::hypot(m(1, 0), m(1, 1));
  const double bounds[2][2] = {{-ex, image_size.width - 1.0 + ex}, {-ey, image_size.height - 1.0 + ey}};
  for (int y = 0; y < size.height; ++y) {
    double lo = 0.0;
    double hi = size.width - 1.0;
    for (int k = 0; k < 2; ++k) {
      // m(k, 0)·x + m(k, 1)·y + m(k, 2) within bounds[k].
      const double a = m(k, 0);
      const double b = m(k, 1) * y + m(k, 2);
      if (std::abs(a) < 1e-12) {
        if (b < bounds[k][0] || b > bounds[k][1]) hi = -1.0;
        continue;
      }
      const double x0 = (bounds[k][0] - b) / a;
      const double x1 = (bounds[k][1] - b) / a;
      lo = std::max(lo, std::min(x0, x1));
      hi = std::min(hi, std::max(x0, x1));
    }
    if (hi < lo) continue;
    spans.begin[static_cast<std::size_t>(y)] = std::max(0, static_cast<int>(std::floor(lo)));
    spans.end[static_cast<std::size_t>(y)] = std::min(size.width, static_cast<int>(std::ceil(hi)) + 1);
  }
  return spans;
}

/// region_near_image() of a view: the view pixels within `margin` view pixels of the image.
inline RowSpans render_region(const AffineView& view, cv::Size image_size, double margin) {
  return region_near_image(view.to_original, view.size, image_size, margin);
}

/// The pixels (x, y) of a pyramid level of size `level_size` of `view`, at least `border` pixels
/// inside the level, whose support maps inside the original image of size `image_size`: with q the
/// original position of (x, y) (Pyramid::to_level0, then to_original) and r = border·W_v/W_l the
/// support radius in view pixels, q ± r·(e_x, e_y) lies in [0, W − 1] x [0, H − 1], e_x and e_y the
/// extents in original pixels of a unit disc of view pixels along x and y. The identity view needs
/// only the border. One run per row: the condition is affine in x, and the run's ends are checked
/// with the condition's own floating-point arithmetic.
inline RowSpans support_region(const AffineView& view, cv::Size image_size, cv::Size level_size, int border) {
  const cv::Rect roi(border, border, level_size.width - 2 * border, level_size.height - 2 * border);
  if (roi.width <= 0 || roi.height <= 0) return {};
  if (view.is_identity()) return RowSpans::rectangle(roi);
  const cv::Matx23d& back = view.to_original;
  const double radius = border * static_cast<double>(view.size.width) / level_size.width;
  const double margin_x = radius * std::hypot(back(0, 0), back(0, 1));
  const double margin_y = radius * std::hypot(back(1, 0), back(1, 1));
  auto original = [&](double x, int y) {
    return apply_affine(
        back, Pyramid::to_level0(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), view.size, level_size));
  };
  auto inside = [&](int x, int y) {
    const cv::Point2d q = original(x, y);
    return q.x - margin_x >= 0.0 && q.y - margin_y >= 0.0 && q.x + margin_x <= image_size.width - 1.0 &&
           q.y + margin_y <= image_size.height - 1.0;
  };
  RowSpans spans;
  spans.reset(roi.y, roi.height);
  const int x_min = roi.x;
  const int x_max = roi.x + roi.width - 1;
  const double limits[2][2] = {{margin_x, image_size.width - 1.0 - margin_x},
                               {margin_y, image_size.height - 1.0 - margin_y}};
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    // q = a·x + b per coordinate: solve for the bounds, then settle the ends exactly.
    const cv::Point2d q0 = original(0.0, y);
    const cv::Point2d q1 = original(1.0, y);
    const double a[2] = {q1.x - q0.x, q1.y - q0.y};
    const double b[2] = {q0.x, q0.y};
    double lo = x_min;
    double hi = x_max;
    for (int k = 0; k < 2; ++k) {
      if (std::abs(a[k]) < 1e-12) {
        if (b[k] < limits[k][0] || b[k] > limits[k][1]) hi = lo - 3.0;
        continue;
      }
      const double u = (limits[k][0] - b[k]) / a[k];
      const double w = (limits[k][1] - b[k]) / a[k];
      lo = std::max(lo, std::min(u, w));
      hi = std::min(hi, std::max(u, w));
    }
    if (hi < lo - 2.0) continue;
    int x0 = std::clamp(static_cast<int>(std::ceil(lo)), x_min, x_max);
    int x1 = std::clamp(static_cast<int>(std::floor(hi)), x_min, x_max);
    while (x0 <= x1 && !inside(x0, y)) ++x0;
    while (x0 <= x1 && x0 > x_min && inside(x0 - 1, y)) --x0;
    while (x1 >= x0 && !inside(x1, y)) --x1;
    while (x1 >= x0 && x1 < x_max && inside(x1 + 1, y)) ++x1;
    if (x0 > x1) continue;
    spans.begin[static_cast<std::size_t>(y - roi.y)] = x0;
    spans.end[static_cast<std::size_t>(y - roi.y)] = x1 + 1;
  }
  return spans;
}

}  // namespace affine_orb::detail
