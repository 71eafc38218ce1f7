#pragma once
/// \file
/// Scale pyramid: level l is the image resized by 1/s^l (s = scale factor), as in ORB and ORB-SLAM2.

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/detection/detail/opencv_resize.hpp"
#include "affine_orb/detection/detail/resize.hpp"

namespace affine_orb {

/// Scale pyramid parameters. Defaults are ORB-SLAM2's (docs/algorithm.md §2: factor 1.2, 8 levels).
struct PyramidOptions {
  /// Ratio s between the sizes of consecutive levels, in (1, 4]; level l is s^l times smaller. 1.2
  /// is ORB's and ORB-SLAM2's.
  double scale_factor = 1.2;
  /// Number of levels including the full-resolution level 0, in [1, 32]; 8 is ORB's and
  /// ORB-SLAM2's.
  int levels = 8;

  void check() const {
    detail::require_range(scale_factor, {1, 4, true}, "PyramidOptions::scale_factor");
    detail::require_range(levels, {1, 32}, "PyramidOptions::levels");
  }

  /// Nominal scale of level l, s^l.
  double scale(int level) const { return std::pow(scale_factor, level); }
};

/// Size of level l of an image of size `size`: round(W / s^l) x round(H / s^l), at least 1x1.
inline cv::Size pyramid_level_size(cv::Size size, const PyramidOptions& options, int level) {
  const double inv = 1.0 / options.scale(level);
  return {std::max(1, static_cast<int>(std::lround(size.width * inv))),
          std::max(1, static_cast<int>(std::lround(size.height * inv)))};
}

/// An image pyramid whose buffers are reused across builds: each level lives in storage grown to
/// the largest size it has held and never shrunk, so that pyramids of images of varying sizes built
/// one after the other on one Pyramid allocate nothing once it has seen the largest.
///
/// Level l is produced from level l−1 by bilinear interpolation with the pixel-centre convention
/// of cv::resize (fixed point, fractions of 1/128 pixel: detail/resize.hpp; within a grey level of
/// cv::resize with INTER_LINEAR), so a level-l pixel (x_l, y_l) corresponds to the level-0 point
/// ((x_l + 0.5)·W/W_l − 0.5, (y_l + 0.5)·H/H_l − 0.5): the ratios telescope across levels.
/// Levels are ROIs of their storage (their row step may exceed their width).
class Pyramid {
 public:
  explicit Pyramid(PyramidOptions options = {}) : options_(options) { options_.check(); }

  /// Builds the levels of a CV_8UC1 image (non-continuous ROIs are fine). Level 0 shares no
  /// memory with `image` (it is copied), so the pyramid stays valid if the caller's image changes.
  void build(const cv::Mat& image) {
    detail::require_gray8(image, "Pyramid::build");
    image.copyTo(level0(image.size()));
    build_from_level0();
  }

  /// Level 0, sized `size` (at least 1x1), for the caller to fill (e.g. to render a view into)
  /// before build_from_level0(); its previous content is undefined.
  cv::Mat& level0(cv::Size size) {
    detail::require(size.width >= 1 && size.height >= 1, "Pyramid::level0: the size must be at least 1x1");
    levels_.resize(static_cast<std::size_t>(options_.levels));
    storage_.resize(levels_.size());
    levels_[0] = detail::fit_buffer(storage_[0], size, CV_8UC1);
    return levels_[0];
  }

  /// Computes levels 1… from the level 0 filled after level0(). With `regions` (one per level,
  /// regions[0] unused), level l >= 1 is computed only on the runs of regions[l], the rest of each
  /// row repeating its nearest computed pixel (see detail::resize_bilinear()).
  void build_from_level0(const std::vector<RowSpans>* regions = nullptr) {
    detail::require(!levels_.empty() && !levels_[0].empty(), "Pyramid::build_from_level0: call level0() first");
    detail::require(regions == nullptr || static_cast<int>(regions->size()) == options_.levels,
                    "Pyramid::build_from_level0: one region per level expected");
    resize_work_.resize(levels_.size());
    for (int l = 1; l < options_.levels; ++l) {
      const std::size_t i = static_cast<std::size_t>(l);
      const cv::Size size = pyramid_level_size(levels_[0].size(), options_, l);
      levels_[i] = detail::fit_buffer(storage_[i], size, CV_8UC1);
      detail::resize_bilinear(levels_[i - 1], levels_[i], size, regions != nullptr ? &(*regions)[i] : nullptr,
                              resize_work_[i]);
    }
  }

  /// Builds the levels of a CV_8UC1 image as ORB-SLAM's ORBextractor::ComputePyramid does: level 0
  /// a copy, level l of size sizes[l] the bytes cv::resize (INTER_LINEAR) makes of level l − 1
  /// (detail/opencv_resize.hpp, in the pyramid's own buffers). `sizes` has one entry per level
  /// (sizes[0] is the image's). to_level0() keeps the pixel-centre convention, which is not
  /// ORB-SLAM's keypoint placement.
  void build_resized(const cv::Mat& image, const std::vector<cv::Size>& sizes) {
    detail::require_gray8(image, "Pyramid::build_resized");
    detail::require(static_cast<int>(sizes.size()) == options_.levels && sizes[0] == image.size(),
                    "Pyramid::build_resized: one size per level expected, the first the image's");
    image.copyTo(level0(image.size()));
    opencv_resize_work_.resize(levels_.size());
    for (int l = 1; l < options_.levels; ++l) {
      const std::size_t i = static_cast<std::size_t>(l);
      levels_[i] = detail::fit_buffer(storage_[i], sizes[i], CV_8UC1);
      detail::resize_linear_8u(levels_[i - 1], levels_[i], opencv_resize_work_[i]);
    }
  }

  /// Grows the storage to hold the levels of an image of `size` (allocated, not touched: pages
  /// become resident when a build writes them).
  void reserve(cv::Size size) {
    storage_.resize(static_cast<std::size_t>(options_.levels));
    for (int l = 0; l < options_.levels; ++l) {
      detail::fit_buffer(storage_[static_cast<std::size_t>(l)], pyramid_level_size(size, options_, l), CV_8UC1);
    }
  }

  const PyramidOptions& options() const { return options_; }
  int levels() const { return options_.levels; }
  bool empty() const { return levels_.empty(); }
  const cv::Mat& level(int l) const { return levels_.at(static_cast<std::size_t>(l)); }
  const std::vector<cv::Mat>& images() const { return levels_; }

  /// Maps a point in level-l pixel coordinates to level-0 pixel coordinates (exact for the
  /// resizing convention above, whatever the rounding of the level sizes).
  cv::Point2f to_level0(cv::Point2f p, int l) const { return to_level0(p, levels_.front().size(), level(l).size()); }

  /// The same for a level of size `level` of a level 0 of size `base`, without a pyramid.
  static cv::Point2f to_level0(cv::Point2f p, cv::Size base, cv::Size level) {
    const float rx = static_cast<float>(base.width) / static_cast<float>(level.width);
    const float ry = static_cast<float>(base.height) / static_cast<float>(level.height);
    return {(p.x + 0.5f) * rx - 0.5f, (p.y + 0.5f) * ry - 0.5f};
  }

 private:
  PyramidOptions options_;
  std::vector<cv::Mat> levels_;
  std::vector<cv::Mat> storage_;  ///< per level, the buffer levels_[l] is the top-left part of
  std::vector<detail::ResizeWork> resize_work_;
  std::vector<detail::OpenCvResizeWork> opencv_resize_work_;  ///< build_resized()'s, per level
};

}  // namespace affine_orb
