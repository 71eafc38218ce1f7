#pragma once
/// \file
/// Internals (namespace detail): the image's own keypoints as stella_vslam's orb_extractor
/// (stella-cv/stella_vslam b0e60d6, src/stella_vslam/feature/orb_extractor.cc, orb_impl.cc,
/// orb_params.cc) extracts them (StellaVslamKeypoints), so that a drop-in returns its
/// keypoints, in its order, with its descriptor bits. What it does, per pyramid level l of scale
/// s^l (s^l in float by repeated multiplication, orb_params::calc_scale_factors):
/// - the level is cv::resize (INTER_LINEAR) of level l − 1, of size std::round(W / s^l) x
///   std::round(H / s^l) in double (orb_extractor::compute_image_pyramid);
/// - FAST runs in cells over the region 19 pixels inside the level (orb_patch_radius_): cell (i, j)
///   starts 64·i rows and 64·j columns into it, spans 64 + 6 pixels cut at the region, and is
///   skipped when it starts within 6 pixels of the region's far edge; trunc(w / 64) + 1 columns by
///   trunc(h / 64) + 1 rows. Each cell is its own image for cv::FAST with non-maximum suppression
///   at ini_fast_thr, and at min_fast_thr where that finds no corner (compute_fast_keypoints);
/// - with a mask, a cell is skipped when the mask is 0 at one of its four corners (the far ones
///   one past its last pixel), and a corner dropped when the mask is 0 at it, the mask read at
///   (trunc(y·s^l), trunc(x·s^l)) of level pixel (x, y), the product in float;
/// - the candidates, cells row by row and raster order in a cell, are binned into a grid of
///   ceil(w / d) x ceil(h / d) cells over the region, d = (float) trunc(√min_size) / s^l, of
///   exact width w / columns and height h / rows (double); each grid cell, in raster order, keeps
///   its strongest candidate, the first of equal responses (distribute_keypoints);
/// - a keypoint at level pixel p has the angle cv::fastAtan2 of the intensity centroid on the
///   level, rBRIEF bits on the level blurred 7x7, σ = 2, with the pattern rotated by stella's
///   polynomial cosine and sine (util/trigonometric.h, stella_cos()), its position p·s^l (level 0:
///   p), size trunc(31·s^l) and octave l; the output is level by level.
/// Levels whose region is narrower than a cell's FAST border give no keypoints (stella's unsigned
/// arithmetic wraps there).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/extractor.hpp"
#include "affine_orb/extraction/detail/fork_image.hpp"
#include "affine_orb/extraction/extractor_options.hpp"

namespace affine_orb {
namespace detail {

/// Distance in level pixels from the level's edges to the region its FAST cells cover.
inline constexpr int kStellaRegionBorder = 19;
/// Side of a FAST cell in level pixels, and the overlap added to it.
inline constexpr int kStellaCellSize = 64;
inline constexpr int kStellaCellOverlap = 6;

/// π as stella_vslam's float constant.
inline constexpr float kStellaPi = 3.14159265358979f;

/// stella_vslam's cosine (util/trigonometric.h): v reduced by floor(v / 2π) turns and folded onto
/// [0, π/2] by symmetry, then 0.99940307 + v²(−0.49558072 + 0.03679168 v²), every step in float.
inline float stella_cos(float v) {
  constexpr float kPi = kStellaPi;
  constexpr float kHalfPi = kPi / 2.0f;
  constexpr float kTwoPi = 2.0f * kPi;
  const auto poly = [](float x) {
    const float x2 = x * x;
    return 0.99940307f + x2 * (-0.49558072f + 0.03679168f * x2);
  };
  v = v - static_cast<float>(cvFloor(v * (1.0f / kTwoPi))) * kTwoPi;
  v = v > 0.0f ? v : -v;
  if (v < kHalfPi) return poly(v);
  if (v < kPi) return -poly(kPi - v);
  if (v < 3.0f * kHalfPi) return -poly(v - kPi);
  return poly(kTwoPi - v);
}

/// stella_vslam's rotation of the rBRIEF pattern for a keypoint angle in degrees: the angle in
/// radians (degrees·π/180 in double, then float), its stella_cos() and its sine stella_cos(π/2 − a).
struct StellaRotation {
  std::pair<float, float> operator()(float degrees) const {
    const float a = static_cast<float>(static_cast<double>(degrees) * CV_PI / 180.0);
    return {stella_cos(a), stella_cos(kStellaPi / 2.0f - a)};
  }
};

/// The level sizes stella builds for an image of `size` from the scale factors s^l (at least 1x1).
inline void stella_level_sizes(const std::vector<float>& factors, cv::Size size, std::vector<cv::Size>& sizes) {
  sizes.resize(factors.size());
  for (std::size_t l = 0; l < factors.size(); ++l) {
    const double s = static_cast<double>(factors[l]);
    sizes[l] = cv::Size(std::max(1, static_cast<int>(std::round(size.width * 1.0 / s))),
                        std::max(1, static_cast<int>(std::round(size.height * 1.0 / s))));
  }
}

/// The FAST cells of one level: the region [19, 19 + width) x [19, 19 + height).
struct StellaCells {
  int width = 0;
  int height = 0;
  int columns = 0;
  int rows = 0;

  explicit StellaCells(cv::Size level) {
    width = level.width - 2 * kStellaRegionBorder;
    height = level.height - 2 * kStellaRegionBorder;
    if (width <= 2 * kFastRadius || height <= 2 * kFastRadius) return;
    columns = width / kStellaCellSize + 1;
    rows = height / kStellaCellSize + 1;
  }

  bool empty() const { return columns == 0; }

  /// The image of cell (i, j) in level coordinates; empty for the cells stella skips.
  cv::Rect image(int i, int j) const {
    const int right = kStellaRegionBorder + width;
    const int bottom = kStellaRegionBorder + height;
    const int x0 = kStellaRegionBorder + j * kStellaCellSize;
    const int y0 = kStellaRegionBorder + i * kStellaCellSize;
    if (y0 >= bottom - kStellaCellOverlap || x0 >= right - kStellaCellOverlap) return {};
    const int x1 = std::min(x0 + kStellaCellSize + kStellaCellOverlap, right);
    const int y1 = std::min(y0 + kStellaCellSize + kStellaCellOverlap, bottom);
    return cv::Rect(cv::Point(x0, y0), cv::Point(x1, y1));
  }
};

/// Whether stella's mask test masks level pixel (x, y) of a level of scale `factor`.
inline bool stella_masked(const cv::Mat& mask, int x, int y, float factor) {
  const int my = static_cast<int>(static_cast<float>(y) * factor);
  const int mx = static_cast<int>(static_cast<float>(x) * factor);
  return mask.at<std::uint8_t>(my, mx) == 0;
}

/// Whether stella skips the cell of image `c` under `mask`: the mask is 0 at one of its corners.
inline bool stella_cell_masked(const cv::Mat& mask, const cv::Rect& c, float factor) {
  const int x1 = c.x + c.width;
  const int y1 = c.y + c.height;
  return stella_masked(mask, c.x, c.y, factor) || stella_masked(mask, c.x, y1, factor) ||
         stella_masked(mask, x1, c.y, factor) || stella_masked(mask, x1, y1, factor);
}

/// Drops the candidates from index `first` on (relative to the region) that `mask` masks.
inline void drop_stella_masked(const cv::Mat& mask, float factor, std::size_t first, std::vector<cv::Point2f>& points,
                               std::vector<float>& responses) {
  std::size_t n = first;
  for (std::size_t k = first; k < points.size(); ++k) {
    const int x = static_cast<int>(points[k].x) + kStellaRegionBorder;
    const int y = static_cast<int>(points[k].y) + kStellaRegionBorder;
    if (stella_masked(mask, x, y, factor)) continue;
    points[n] = points[k];
    responses[n] = responses[k];
    ++n;
  }
  points.resize(n);
  responses.resize(n);
}

/// The FAST candidates of one level (scale `factor`) as stella finds them (file comment), relative
/// to the region, in its order; `storage` holds the score map and `maxima` the local maxima of a
/// row of cells.
inline void detect_in_stella_cells(const cv::Mat& level, const StellaCells& cells, float factor,
                                   const DetectorOptions& detector, const cv::Mat& mask, cv::Mat& storage,
                                   CellMaximaWork& maxima, std::vector<cv::Point2f>& points,
                                   std::vector<float>& responses) {
  points.clear();
  responses.clear();
  if (cells.empty()) return;
  const int inset = kStellaRegionBorder + kFastRadius;
  cv::Mat scores = padded_score_map(storage, level.size());
  score_rect(level, cv::Rect(inset, inset, cells.width - 2 * kFastRadius, cells.height - 2 * kFastRadius),
             detector.min_threshold, scores);
  // The cells' scored rectangles tile the region (StellaCells::image()).
  maxima.edges.clear();
  for (int j = 0; j < cells.columns; ++j) {
    const cv::Rect c = cells.image(0, j);
    if (c.empty() || c.width <= 2 * kFastRadius) continue;
    if (maxima.edges.empty()) maxima.edges.push_back(c.x + kFastRadius);
    maxima.edges.push_back(c.x + c.width - kFastRadius);
  }
  if (maxima.edges.size() < 2) return;
  set_cell_columns(maxima);
  const cv::Point origin(kStellaRegionBorder, kStellaRegionBorder);
  for (int i = 0; i < cells.rows; ++i) {
    const cv::Rect band = cells.image(i, 0);
    if (band.empty() || band.height <= 2 * kFastRadius) continue;
    mark_cell_rows(scores, band.y + kFastRadius, band.y + band.height - kFastRadius, detector.initial_threshold,
                   detector.min_threshold, maxima);
    for (int j = 0; j < cells.columns; ++j) {
      const cv::Rect c = cells.image(i, j);
      if (c.empty() || c.width <= 2 * kFastRadius || (!mask.empty() && stella_cell_masked(mask, c, factor))) continue;
      const std::size_t first = points.size();
      append_cell_corners(scores, maxima, j, origin, points, responses);
      if (!mask.empty()) drop_stella_masked(mask, factor, first, points, responses);
    }
  }
}

/// stella's grid selection of a level's candidates (`points` relative to the region of
/// `width` x `height`, `responses`) for cells of side `side` / `factor` level pixels: into `kept`,
/// per grid cell in raster order, the index of its strongest candidate, the first of equal
/// responses. `best` is a reused buffer.
inline void select_stella_grid(const std::vector<cv::Point2f>& points, const std::vector<float>& responses, int width,
                               int height, int side, float factor, std::vector<int>& best, std::vector<int>& kept) {
  kept.clear();
  if (points.empty()) return;
  const double cell = static_cast<double>(static_cast<float>(side) / factor);
  const int columns = static_cast<int>(std::ceil(width / cell));
  const int rows = static_cast<int>(std::ceil(height / cell));
  const double dx = static_cast<double>(width) / columns;
  const double dy = static_cast<double>(height) / rows;
  best.assign(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows), -1);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int ix = std::min(static_cast<int>(points[k].x / dx), columns - 1);
    const int iy = std::min(static_cast<int>(points[k].y / dy), rows - 1);
    int& b = best[static_cast<std::size_t>(iy) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(ix)];
    if (b < 0 || responses[k] > responses[static_cast<std::size_t>(b)]) b = static_cast<int>(k);
  }
  for (int b : best) {
    if (b >= 0) kept.push_back(b);
  }
}

/// stella's mask of `rectangles` for an image of `size` into `mask` (255, the rectangles filled
/// with 0 by cv::rectangle, LINE_AA, their corners std::round(size · fraction) in float), built
/// when the image size changes (stella builds it once, for its first image).
inline const cv::Mat& stella_rectangle_mask(const std::vector<MaskRectangle>& rectangles, cv::Size size,
                                            cv::Mat& mask) {
  if (mask.size() == size) return mask;
  mask.create(size, CV_8UC1);
  mask.setTo(255);
  const auto at = [](int n, float fraction) {
    return static_cast<int>(static_cast<unsigned>(std::round(static_cast<float>(n) * fraction)));
  };
  for (const MaskRectangle& r : rectangles) {
    cv::rectangle(mask, cv::Point(at(size.width, r.x_min), at(size.height, r.y_min)),
                  cv::Point(at(size.width, r.x_max), at(size.height, r.y_max)), cv::Scalar(0), cv::FILLED, cv::LINE_AA);
  }
  return mask;
}

/// Buffers of stella's extraction of an image beyond the forks' (ForkImageWork), reused across
/// frames.
struct StellaImageWork {
  std::vector<int> best;   ///< per grid cell, its strongest candidate
  cv::Mat rectangle_mask;  ///< StellaVslamKeypoints::mask_rectangles at the last image size
};

/// stella's keypoints of pyramid level l (`level`) into `out`, in its order (file comment); `mask`
/// is the caller's or the rectangles', or empty.
template <class Descriptor, int Bits>
void extract_stella_level(const Descriptor& descriptor, const cv::Mat& level, int l, const ExtractorOptions& options,
                          const cv::Mat& mask, ForkImageWork& work, StellaImageWork& stella,
                          std::vector<cv::Point2f>& describe_points, typename Descriptor::LevelData& data,
                          LevelWork<Bits>& out) {
  const float factor = work.scales.factors[static_cast<std::size_t>(l)];
  const StellaCells cells(level.size());
  detect_in_stella_cells(level, cells, factor, options.detector, mask, work.score_storage, work.maxima, work.points,
                         work.responses);
  const int side = static_cast<int>(
      std::sqrt(static_cast<double>(std::get<StellaVslamKeypoints>(options.image_keypoints).min_size)));
  select_stella_grid(work.points, work.responses, cells.width, cells.height, side, factor, stella.best, work.kept);
  if (work.kept.empty()) return;
  const cv::Point2f corner(static_cast<float>(kStellaRegionBorder), static_cast<float>(kStellaRegionBorder));
  append_fork_keypoints(descriptor, level, l, factor, corner, work.kept, work.points, work.responses, StellaRotation{},
                        describe_points, data, out);
}

/// stella's keypoints of `image` into `levels`, one record per pyramid level, on `pyramid`, which
/// it builds as stella does; `mask` is the caller's or the rectangles' (or empty).
template <class Descriptor, int Bits>
void extract_stella_image(const Descriptor& descriptor, const cv::Mat& image, const cv::Mat& mask,
                          const ExtractorOptions& options, Pyramid& pyramid, ForkImageWork& work,
                          StellaImageWork& stella, std::vector<cv::Point2f>& describe_points,
                          typename Descriptor::LevelData& data, std::vector<LevelWork<Bits>>& levels) {
  stella_level_sizes(work.scales.factors, image.size(), work.scales.sizes);
  pyramid.build_resized(image, work.scales.sizes);
  for (int l = 0; l < options.pyramid.levels; ++l) {
    LevelWork<Bits>& level = levels[static_cast<std::size_t>(l)];
    level.clear();
    extract_stella_level(descriptor, pyramid.level(l), l, options, mask, work, stella, describe_points, data, level);
  }
}

/// The image's keypoints of a SLAM system (options.image_keypoints: OrbSlam2Keypoints,
/// OrbSlam3Keypoints or StellaVslamKeypoints) into `levels`, on `pyramid`, which it builds as that
/// system does.
template <class Descriptor, int Bits>
void extract_slam_image(const Descriptor& descriptor, const cv::Mat& image, const cv::Mat& mask,
                        const ExtractorOptions& options, Pyramid& pyramid, ForkImageWork& work, StellaImageWork& stella,
                        std::vector<cv::Point2f>& describe_points, typename Descriptor::LevelData& data,
                        std::vector<LevelWork<Bits>>& levels) {
  if (std::holds_alternative<StellaVslamKeypoints>(options.image_keypoints)) {
    extract_stella_image(descriptor, image, mask, options, pyramid, work, stella, describe_points, data, levels);
  } else {
    extract_fork_image(descriptor, image, mask, options, pyramid, work, describe_points, data, levels);
  }
}

}  // namespace detail
}  // namespace affine_orb
