#pragma once
/// \file
/// Internals (namespace detail): the image's own keypoints as ORB-SLAM2's or ORB-SLAM3's
/// ORBextractor extracts them (ExtractorOptions::image_keypoints), so that a drop-in returns the
/// fork's keypoints, in the fork's order, with the fork's descriptor bits. What the forks do, per
/// pyramid level l of scale s^l (s^l and 1/s^l in float by repeated multiplication):
/// - the level is cv::resize (INTER_LINEAR) of level l − 1, of size cvRound(W / s^l) x
///   cvRound(H / s^l) (Pyramid::build_resized());
/// - FAST runs in cells over the region 16 pixels inside the level (the forks' EDGE_THRESHOLD 19
///   less 3): nCols = trunc(w / c) by nRows = trunc(h / c) cells of c = 30 (ORB-SLAM2) or 35
///   (ORB-SLAM3) pixels, each ceil(w / nCols) x ceil(h / nRows) plus 6 pixels of overlap, cut at
///   the region; each cell is its own image for cv::FAST with non-maximum suppression (a pixel
///   must score strictly above each of its 8 neighbours, neighbours outside the cell's scored
///   pixels count 0), at iniThFAST, and at minThFAST where that finds no corner
///   (detect_in_fork_cells());
/// - the level's budget round(N·(1 − f)/(1 − f^L)·f^l) with f = 1/s in float, the last level the
///   rest, is kept by the octree distribution (detection/detail/octree.hpp) of the region;
/// - a keypoint at level pixel p has the angle cv::fastAtan2 of the intensity centroid on the level,
///   rBRIEF bits on the level blurred 7x7, σ = 2, its position p·s^l (level 0: p), size
///   trunc(31·s^l) and octave l; the output is level by level, each in the octree's order.
/// A mask, which the forks ignore, drops the candidates whose level-0 position it masks before the
/// distribution; with no mask the output is the fork's. Levels whose region holds no whole cell
/// give no keypoints (the forks' arithmetic is undefined there).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/detection/detail/octree.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/orientation.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/cell_maxima.hpp"
#include "affine_orb/extraction/detail/extractor.hpp"

namespace affine_orb {
namespace detail {

/// Distance in level pixels from the level's edges to the region FAST runs in (EDGE_THRESHOLD − 3).
inline constexpr int kForkRegionBorder = 16;
/// ORB's patch diameter: a fork keypoint's size is trunc(31·s^l).
inline constexpr int kForkPatchSize = 31;

/// What tells the two forks' extractions apart.
struct ForkFlavour {
  int cell_size = 30;  ///< FAST cell side in level pixels: ORB-SLAM2 30, ORB-SLAM3 35
  OctreeTieOrder ties = OctreeTieOrder::kCreation;
};

/// The forks' per-level tables for `levels` levels of scale factor s, in float as they compute
/// them, and the level sizes of an image.
struct ForkScales {
  std::vector<float> factors;          ///< s^l by repeated multiplication
  std::vector<float> inverse_factors;  ///< 1 / s^l
  std::vector<int> budgets;            ///< keypoints per level for the extractor's nfeatures
  std::vector<cv::Size> sizes;         ///< level sizes of the last image (fork_level_sizes())

  void set(float scale_factor, int levels, int features) {
    factors.assign(static_cast<std::size_t>(levels), 1.0f);
    inverse_factors.assign(static_cast<std::size_t>(levels), 1.0f);
    for (std::size_t l = 1; l < factors.size(); ++l) factors[l] = factors[l - 1] * scale_factor;
    for (std::size_t l = 0; l < factors.size(); ++l) inverse_factors[l] = 1.0f / factors[l];
    budgets.assign(static_cast<std::size_t>(levels), 0);
    const float f = 1.0f / scale_factor;
    float per_level = static_cast<float>(features) * (1 - f) /
                      (1 - static_cast<float>(std::pow(static_cast<double>(f), static_cast<double>(levels))));
    int assigned = 0;
    for (std::size_t l = 0; l + 1 < budgets.size(); ++l) {
      budgets[l] = cvRound(per_level);
      assigned += budgets[l];
      per_level *= f;
    }
    budgets.back() = std::max(features - assigned, 0);
  }

  /// The level sizes of an image of `size` into `sizes` (at least 1x1, where the forks fail).
  void fit(cv::Size size) {
    sizes.resize(factors.size());
    for (std::size_t l = 0; l < factors.size(); ++l) {
      sizes[l] = cv::Size(std::max(1, cvRound(static_cast<float>(size.width) * inverse_factors[l])),
                          std::max(1, cvRound(static_cast<float>(size.height) * inverse_factors[l])));
    }
  }
};

/// The cell grid of one level: the region [border, border + width) x [border, border + height)
/// split into columns x rows cells of cell_width x cell_height pixels (the last ones cut).
struct ForkCells {
  int width = 0;
  int height = 0;
  int columns = 0;
  int rows = 0;
  int cell_width = 0;
  int cell_height = 0;

  ForkCells(cv::Size level, int cell_size) {
    width = level.width - 2 * kForkRegionBorder;
    height = level.height - 2 * kForkRegionBorder;
    if (width <= 0 || height <= 0) return;
    columns = static_cast<int>(static_cast<float>(width) / static_cast<float>(cell_size));
    rows = static_cast<int>(static_cast<float>(height) / static_cast<float>(cell_size));
    if (columns == 0 || rows == 0) return;
    cell_width = static_cast<int>(std::ceil(static_cast<float>(width) / static_cast<float>(columns)));
    cell_height = static_cast<int>(std::ceil(static_cast<float>(height) / static_cast<float>(rows)));
  }

  bool empty() const { return columns == 0 || rows == 0; }

  /// The pixels cv::FAST scores in cell (i, j) (row i, column j), in level coordinates: the cell's
  /// image less kFastRadius on every side; empty for the cells the forks skip.
  cv::Rect scored(int i, int j) const {
    const int right = kForkRegionBorder + width;
    const int bottom = kForkRegionBorder + height;
    const int x0 = kForkRegionBorder + j * cell_width;
    const int y0 = kForkRegionBorder + i * cell_height;
    if (y0 >= bottom - 3 || x0 >= right - 6) return {};
    const int x1 = std::min(x0 + cell_width + 6, right);
    const int y1 = std::min(y0 + cell_height + 6, bottom);
    return cv::Rect(cv::Point(x0 + kFastRadius, y0 + kFastRadius), cv::Point(x1 - kFastRadius, y1 - kFastRadius));
  }
};

/// The FAST candidates of one level as the fork finds them (file comment), in the fork's order:
/// cells row by row, raster order within a cell. `storage` holds the score map and `maxima` the
/// local maxima of a row of cells, both reused across calls.
inline void detect_in_fork_cells(const cv::Mat& level, const ForkCells& cells, int initial_threshold, int min_threshold,
                                 cv::Mat& storage, CellMaximaWork& maxima, std::vector<cv::Point2f>& points,
                                 std::vector<float>& responses) {
  points.clear();
  responses.clear();
  if (cells.empty()) return;
  const cv::Rect region(kForkRegionBorder + kFastRadius, kForkRegionBorder + kFastRadius, cells.width - 2 * kFastRadius,
                        cells.height - 2 * kFastRadius);
  if (region.width <= 0 || region.height <= 0) return;
  cv::Mat scores = padded_score_map(storage, level.size());
  score_rect(level, region, min_threshold, scores);
  // The cells' scored rectangles tile the region: each column of cells starts where the one before
  // ends, and the last reaches the region's edge (ForkCells::scored()).
  maxima.edges.clear();
  for (int j = 0; j < cells.columns; ++j) {
    const cv::Rect cell = cells.scored(0, j);
    if (cell.width <= 0) continue;
    if (maxima.edges.empty()) maxima.edges.push_back(cell.x);
    maxima.edges.push_back(cell.x + cell.width);
  }
  if (maxima.edges.size() < 2) return;
  set_cell_columns(maxima);
  const cv::Point origin(kForkRegionBorder, kForkRegionBorder);
  for (int i = 0; i < cells.rows; ++i) {
    const cv::Rect band = cells.scored(i, 0);
    if (band.height <= 0) continue;
    mark_cell_rows(scores, band.y, band.y + band.height, initial_threshold, min_threshold, maxima);
    for (int j = 0; j + 1 < static_cast<int>(maxima.edges.size()); ++j) {
      append_cell_corners(scores, maxima, j, origin, points, responses);
    }
  }
}

/// Buffers of the fork's extraction of an image, reused across frames.
struct ForkImageWork {
  ForkScales scales;
  cv::Mat score_storage;
  CellMaximaWork maxima;            ///< the local maxima of a row of cells
  std::vector<cv::Point2f> points;  ///< the level's candidates, relative to its region
  std::vector<float> responses;
  OctreeWorkspace octree;
  std::vector<int> kept;
};

/// Whether a descriptor policy gives the orientation in degrees too and describes under a rotation
/// given by its cosine and sine (Rbrief: the fork's angle and bits).
template <class D, class = void>
struct HasOrientationDegrees : std::false_type {};
template <class D>
struct HasOrientationDegrees<D,
                             std::void_t<decltype(std::declval<const D&>().orientation_degrees(
                                             std::declval<const typename D::LevelData&>(), cv::Point2f())),
                                         decltype(std::declval<const D&>().describe_rotated(
                                             std::declval<const typename D::LevelData&>(), cv::Point2f(), 0.0f, 0.0f))>>
    : std::true_type {};

/// Drops the candidates of level l whose level-0 position p·s^l the mask pixel nearest to it masks.
inline void drop_masked(const cv::Mat& mask, float factor, std::vector<cv::Point2f>& points,
                        std::vector<float>& responses) {
  std::size_t n = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const float x = (points[k].x + kForkRegionBorder) * factor;
    const float y = (points[k].y + kForkRegionBorder) * factor;
    const int mx = std::min(std::max(cvRound(x), 0), mask.cols - 1);
    const int my = std::min(std::max(cvRound(y), 0), mask.rows - 1);
    if (mask.at<std::uint8_t>(my, mx) == 0) continue;
    points[n] = points[k];
    responses[n] = responses[k];
    ++n;
  }
  points.resize(n);
  responses.resize(n);
}

/// ORB-SLAM's rotation of the rBRIEF pattern for a keypoint angle in degrees: the cosine and sine
/// (std::cos, std::sin in float) of the angle in radians.
struct OrbRotation {
  std::pair<float, float> operator()(float degrees) const {
    const float radians = degrees_to_steering(degrees);
    return {std::cos(radians), std::sin(radians)};
  }
};

/// Appends to `out` the keypoints `kept` (indices into `points`, level pixels relative to the
/// level's `corner`, and `responses`) of pyramid level l (`level`, scale `factor`) as the forks
/// return them: angle on the level, rBRIEF bits under `rotation` (the cosine and sine of an angle in
/// degrees; other descriptors steer by the angle in radians), position p·s^l, size trunc(31·s^l),
/// octave l. `describe_points` and `data` are the thread's buffers.
template <class Descriptor, int Bits, class Rotation>
void append_fork_keypoints(const Descriptor& descriptor, const cv::Mat& level, int l, float factor, cv::Point2f corner,
                           const std::vector<int>& kept, const std::vector<cv::Point2f>& points,
                           const std::vector<float>& responses, Rotation rotation,
                           std::vector<cv::Point2f>& describe_points, typename Descriptor::LevelData& data,
                           LevelWork<Bits>& out) {
  describe_points.clear();
  for (int k : kept) describe_points.push_back(points[static_cast<std::size_t>(k)] + corner);
  descriptor.prepare(level, describe_points, data);
  const float size = static_cast<float>(static_cast<int>(kForkPatchSize * factor));
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const cv::Point2f p = describe_points[i];
    float degrees = 0.0f;
    if constexpr (HasOrientationDegrees<Descriptor>::value) {
      degrees = descriptor.orientation_degrees(data, p);
      const std::pair<float, float> r = rotation(degrees);
      out.descriptors.push_back(descriptor.describe_rotated(data, p, r.first, r.second));
    } else {
      const float steering = descriptor.orientation(data, p);
      degrees = radians_to_degrees_0_360(steering);
      out.descriptors.push_back(descriptor.describe(data, p, steering));
    }
    const cv::Point2f position = l == 0 ? p : cv::Point2f(p.x * factor, p.y * factor);
    const float response = responses[static_cast<std::size_t>(kept[i])];
    out.keypoints.emplace_back(position, size, degrees, response, l);
    out.original_points.push_back(position);
    out.responses.push_back(response);
  }
  out.kept.resize(out.keypoints.size());
  std::iota(out.kept.begin(), out.kept.end(), 0);
}

/// The fork's keypoints of pyramid level l (`level`) into `out`, in the octree's order, described
/// by `descriptor` (file comment); `describe_points` and `data` are the thread's buffers.
template <class Descriptor, int Bits>
void extract_fork_level(const Descriptor& descriptor, const cv::Mat& level, int l, const ForkFlavour& flavour,
                        const DetectorOptions& detector, const cv::Mat& mask, ForkImageWork& work,
                        std::vector<cv::Point2f>& describe_points, typename Descriptor::LevelData& data,
                        LevelWork<Bits>& out) {
  const std::size_t li = static_cast<std::size_t>(l);
  const ForkCells cells(level.size(), flavour.cell_size);
  detect_in_fork_cells(level, cells, detector.initial_threshold, detector.min_threshold, work.score_storage,
                       work.maxima, work.points, work.responses);
  const float factor = work.scales.factors[li];
  if (!mask.empty()) drop_masked(mask, factor, work.points, work.responses);
  distribute_octree(work.points, work.responses, cells.width, cells.height, work.scales.budgets[li], flavour.ties,
                    work.octree, work.kept);
  if (work.kept.empty()) return;
  const cv::Point2f corner(static_cast<float>(kForkRegionBorder), static_cast<float>(kForkRegionBorder));
  append_fork_keypoints(descriptor, level, l, factor, corner, work.kept, work.points, work.responses, OrbRotation{},
                        describe_points, data, out);
}

/// The fork's flavour of ExtractorOptions::image_keypoints (OrbSlam2Keypoints or OrbSlam3Keypoints).
inline ForkFlavour fork_flavour(const ImageKeypoints& keypoints) {
  return std::holds_alternative<OrbSlam3Keypoints>(keypoints) ? ForkFlavour{35, OctreeTieOrder::kLeftEdge}
                                                              : ForkFlavour{30, OctreeTieOrder::kCreation};
}

/// The fork's keypoints of `image` (options.image_keypoints) into `levels`, one record per pyramid
/// level, on `pyramid`, which it builds as the fork does; `work`, `describe_points` and `data` are
/// reused buffers.
template <class Descriptor, int Bits>
void extract_fork_image(const Descriptor& descriptor, const cv::Mat& image, const cv::Mat& mask,
                        const ExtractorOptions& options, Pyramid& pyramid, ForkImageWork& work,
                        std::vector<cv::Point2f>& describe_points, typename Descriptor::LevelData& data,
                        std::vector<LevelWork<Bits>>& levels) {
  work.scales.fit(image.size());
  pyramid.build_resized(image, work.scales.sizes);
  const ForkFlavour flavour = fork_flavour(options.image_keypoints);
  for (int l = 0; l < options.pyramid.levels; ++l) {
    LevelWork<Bits>& level = levels[static_cast<std::size_t>(l)];
    level.clear();
    extract_fork_level(descriptor, pyramid.level(l), l, flavour, options.detector, mask, work, describe_points, data,
                       level);
  }
}

}  // namespace detail
}  // namespace affine_orb
