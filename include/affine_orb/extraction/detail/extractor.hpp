#pragma once
/// \file
/// Internals of affine_orb/extraction/extractor.hpp (namespace detail): the buffers an Extractor
/// processes views in and the steps of its walk that need no Extractor state.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/features.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/view_regions.hpp"
#include "affine_orb/extraction/detail/view_schedule.hpp"
#include "affine_orb/extraction/extractor_options.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {
namespace detail {

/// Buffers of the budget step of one thread, reused across frames.
struct SpreadWork {
  std::vector<cv::Point2f> points;
  std::vector<float> responses;
  std::vector<int> kept;
  QuadtreeWorkspace quadtree;
};

/// The candidates of one level of the view a thread is processing.
struct LevelCandidates {
  Candidates detected;                       ///< the level's FAST corners and their scores, raster order
  std::vector<cv::Point2f> level_points;     ///< level pixels of the view
  std::vector<cv::Point2f> original_points;  ///< the same, original pixels
  std::vector<float> responses;
  std::vector<int> chosen;  ///< the candidates to describe, ascending
  std::vector<int> order;   ///< take_strongest()'s buffer: the detected corners by score
  /// Whether the detected corners include those at DetectorOptions::min_threshold; false when
  /// they are the corners scoring initial_threshold or more only (detect_level()).
  bool complete = true;
};

/// The buffers one thread of an Extractor processes views with, reused view after view and frame after frame:
/// everything that scales with a view's area.
template <class Descriptor>
struct ThreadWork {
  explicit ThreadWork(const PyramidOptions& options) : pyramid(options) {}
  cv::Mat scratch;  ///< one canvas row of the renderer
  Pyramid pyramid;  ///< a tilted view's levels (the image's are the Extractor's own)
  DetectorWorkspace detector;
  std::vector<LevelCandidates> levels;
  typename Descriptor::LevelData descriptor_data;  ///< one level at a time
  std::vector<cv::Point2f> describe_points;
  SpreadWork spread;
  /// Per level, whether the strong candidates of the last view this thread chose the strongest of
  /// were enough there (strong_enough()); where not, its next view detects all the level's
  /// candidates at once instead of the strong ones first (detect_level()), which only costs time.
  std::vector<char> strong_sufficed;
};

/// What a (view, level) keeps of its view once the view's pixels are gone: its described
/// keypoints (the final ones for the image with kAdditive, a shortlist otherwise), in raster
/// order of the view, and the selection among them.
template <int Bits>
struct LevelWork {
  RowSpans valid;  ///< level pixels whose support maps inside the original image (image-size dependent)
  std::vector<cv::Point2f> original_points;  ///< positions before snapping and sub-pixel shifts, original pixels
  std::vector<float> responses;
  std::vector<cv::KeyPoint> keypoints;
  std::vector<BinaryDescriptor<Bits>> descriptors;
  std::vector<int> kept;  ///< the output: indices into the described keypoints, ascending

  void clear() {
    original_points.clear();
    responses.clear();
    keypoints.clear();
    descriptors.clear();
    kept.clear();
  }
};

/// A view and its per-level records (fixed for an image size; the view by prepare_views(), the
/// rest by prepare_view() the first time the view is extracted at that size).
template <int Bits>
struct ViewWork {
  AffineView view;
  bool prepared = false;  ///< renderer, regions and levels are set (prepare_view())
  ViewRenderer renderer;
  /// Per level, the pixels computed (the rest repeats the row's edge pixels): level 0 is
  /// rendered, the others resized, within kRenderMargin level pixels of the image.
  std::vector<RowSpans> regions;
  std::vector<LevelWork<Bits>> levels;
};

/// Sets up the record of `view` of an image of `size`: its renderer and, per level, the valid pixels
/// (support border `border` level pixels, detail::support_region()) and the pixels computed
/// (within `margin` level pixels of the image, detail::region_near_image()).
template <int Bits>
void prepare_view(const AffineView& view, cv::Size size, double antialias, const PyramidOptions& pyramid, int border,
                  double margin, ViewWork<Bits>& work) {
  work.view = view;
  work.prepared = true;
  work.renderer = ViewRenderer(view, antialias);
  work.levels.resize(static_cast<std::size_t>(pyramid.levels));
  work.regions.resize(static_cast<std::size_t>(pyramid.levels));
  for (int l = 0; l < pyramid.levels; ++l) {
    const cv::Size level_size = pyramid_level_size(view.size, pyramid, l);
    work.levels[static_cast<std::size_t>(l)].valid = support_region(view, size, level_size, border);
    work.regions[static_cast<std::size_t>(l)] =
        region_near_image(level_to_original(view, level_size), level_size, size, margin);
  }
}

/// Where corner `corner` of level l of `view` (in `pyramid`) lies in the original image, into
/// `original`; whether that position lies in the image and the mask allows it.
template <int Bits>
bool map_candidate(const ViewWork<Bits>& view, int l, const cv::Mat& image, const cv::Mat& mask, const Pyramid& pyramid,
                   const Corner& corner, cv::Point2f& original) {
  const cv::Point2f p(static_cast<float>(corner.x), static_cast<float>(corner.y));
  const cv::Point2d q = apply_affine(view.view.to_original, pyramid.to_level0(p, l));
  original = cv::Point2f(static_cast<float>(q.x), static_cast<float>(q.y));
  const int mx = cvRound(q.x);
  const int my = cvRound(q.y);
  if (mx < 0 || my < 0 || mx >= image.cols || my >= image.rows) return false;
  return mask.empty() || mask.at<std::uint8_t>(my, mx) != 0;
}

/// The FAST corners of level l of `view` (in `pyramid`) among the level's valid pixels (support
/// border `border` level pixels) under `detector`, into c.detected.
template <int Bits>
void detect_corners(const ViewWork<Bits>& view, int l, const Pyramid& pyramid, int border,
                    const DetectorOptions& detector, DetectorWorkspace& workspace, LevelCandidates& c) {
  c.detected.corners.clear();
  c.detected.responses.clear();
  const RowSpans& valid = view.levels[static_cast<std::size_t>(l)].valid;
  if (valid.rows() == 0) return;
  detect_candidates(pyramid.level(l), valid, cv::Point(border, border), detector, workspace, c.detected);
}

/// The FAST candidates of level l of `view` (detect_corners()), kept where map_candidate()
/// allows them, into c's candidates.
template <int Bits>
void collect_candidates(const ViewWork<Bits>& view, int l, const cv::Mat& image, const cv::Mat& mask,
                        const Pyramid& pyramid, int border, const DetectorOptions& detector,
                        DetectorWorkspace& workspace, LevelCandidates& c) {
  c.level_points.clear();
  c.original_points.clear();
  c.responses.clear();
  detect_corners(view, l, pyramid, border, detector, workspace, c);
  for (std::size_t i = 0; i < c.detected.corners.size(); ++i) {
    const Corner& corner = c.detected.corners[i];
    cv::Point2f original;
    if (!map_candidate(view, l, image, mask, pyramid, corner, original)) continue;
    c.level_points.emplace_back(static_cast<float>(corner.x), static_cast<float>(corner.y));
    c.original_points.push_back(original);
    c.responses.push_back(c.detected.responses[i]);
  }
}

/// Step 2 of an Extractor for level l of a view. Without a selection of the strongest
/// (`strongest` < 0): collect_candidates(). With one (at most `strongest` candidates, the
/// strongest by FAST score: Spreading::kStrongest, ScoreType::kFast): the level's corners alone
/// (detect_corners()), which keep_strongest() maps and tests in decreasing score; with
/// `strong_first`, only the corners scoring initial_threshold or more when there are at least
/// `strongest` of them (c.complete false). The fallback corners of the cells without such a
/// corner all score less, and whether a pixel is a local maximum does not depend on the
/// threshold, so the selection keeps the same corners from either set, for less scoring.
template <int Bits>
void detect_level(const ViewWork<Bits>& view, int l, const cv::Mat& image, const cv::Mat& mask, const Pyramid& pyramid,
                  int border, const DetectorOptions& detector, int strongest, bool strong_first,
                  DetectorWorkspace& workspace, LevelCandidates& c) {
  c.complete = true;
  if (strongest < 0) {
    collect_candidates(view, l, image, mask, pyramid, border, detector, workspace, c);
    return;
  }
  if (strong_first && detector.min_threshold < detector.initial_threshold) {
    DetectorOptions strong = detector;
    strong.min_threshold = detector.initial_threshold;
    detect_corners(view, l, pyramid, border, strong, workspace, c);
    c.complete = static_cast<int>(c.detected.corners.size()) < strongest;
    if (!c.complete) return;
  }
  detect_corners(view, l, pyramid, border, detector, workspace, c);
}

/// Step 3 of an Extractor, in a tilted view's turn, with DuplicatePolicy::kMerge: drops the
/// candidates of level l that repeat a keypoint chosen by an earlier view (`repeats`).
inline void drop_repeats(const RepeatGrids& repeats, int l, LevelCandidates& c) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < c.responses.size(); ++i) {
    if (repeats.repeats(c.original_points[i], l)) continue;
    c.level_points[n] = c.level_points[i];
    c.original_points[n] = c.original_points[i];
    c.responses[n] = c.responses[i];
    ++n;
  }
  c.level_points.resize(n);
  c.original_points.resize(n);
  c.responses.resize(n);
}

/// The indices of c.detected's corners by decreasing FAST score, the earlier first among equal
/// scores (select_strongest()'s order), into c.order: a stable counting sort on the 8-bit scores.
inline void order_by_score(LevelCandidates& c) {
  std::array<int, 257> start{};
  for (const Corner& corner : c.detected.corners) ++start[static_cast<std::size_t>(256 - corner.score)];
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  c.order.resize(c.detected.corners.size());
  for (std::size_t i = 0; i < c.detected.corners.size(); ++i) {
    const std::size_t bin = static_cast<std::size_t>(255 - c.detected.corners[i].score);
    c.order[static_cast<std::size_t>(start[bin]++)] = static_cast<int>(i);
  }
}

/// The first `strongest` corners of c.detected in order_by_score() whose position map_candidate()
/// allows and, with `repeats` (DuplicatePolicy::kMerge, a tilted view's turn), repeats no
/// keypoint of an earlier view, as c's candidates in raster order: the corners a selection of
/// the `strongest` strongest keeps among all that pass, tested only until that many pass.
template <int Bits>
void take_strongest(const ViewWork<Bits>& view, int l, const cv::Mat& image, const cv::Mat& mask,
                    const Pyramid& pyramid, const RepeatGrids* repeats, int strongest, LevelCandidates& c) {
  order_by_score(c);
  std::size_t taken = 0;  // the corners taken move to the front of c.order
  cv::Point2f original;
  for (std::size_t k = 0; k < c.order.size() && static_cast<int>(taken) < strongest; ++k) {
    const Corner& corner = c.detected.corners[static_cast<std::size_t>(c.order[k])];
    if (!map_candidate(view, l, image, mask, pyramid, corner, original)) continue;
    if (repeats && repeats->repeats(original, l)) continue;
    c.order[taken++] = c.order[k];
  }
  std::sort(c.order.begin(), c.order.begin() + static_cast<std::ptrdiff_t>(taken));
  c.level_points.clear();
  c.original_points.clear();
  c.responses.clear();
  for (std::size_t k = 0; k < taken; ++k) {
    const std::size_t i = static_cast<std::size_t>(c.order[k]);
    map_candidate(view, l, image, mask, pyramid, c.detected.corners[i], original);
    c.level_points.emplace_back(static_cast<float>(c.detected.corners[i].x),
                                static_cast<float>(c.detected.corners[i].y));
    c.original_points.push_back(original);
    c.responses.push_back(c.detected.responses[i]);
  }
}

/// For level l of a view detected for a selection of the `strongest` strongest (detect_level()),
/// in the view's turn with a merge (step 3), else right after step 2: take_strongest(); when
/// fewer than that pass among the strong corners alone (c.complete false), all the level's
/// corners are detected and taken from again, so that the selection sees every candidate it
/// could keep.
template <int Bits>
void keep_strongest(const ViewWork<Bits>& view, int l, const cv::Mat& image, const cv::Mat& mask,
                    const Pyramid& pyramid, int border, const DetectorOptions& detector, const RepeatGrids* repeats,
                    int strongest, DetectorWorkspace& workspace, LevelCandidates& c) {
  take_strongest(view, l, image, mask, pyramid, repeats, strongest, c);
  if (c.complete || static_cast<int>(c.responses.size()) >= strongest) return;
  detect_level(view, l, image, mask, pyramid, border, detector, strongest, false, workspace, c);
  take_strongest(view, l, image, mask, pyramid, repeats, strongest, c);
}

/// Whether `c`, as keep_strongest() leaves it, holds `strongest` candidates scoring
/// `initial_threshold` or more: whether the selection of that many needs none of the fallback
/// corners.
inline bool strong_enough(const LevelCandidates& c, int strongest, int initial_threshold) {
  const auto strong = std::count_if(c.responses.begin(), c.responses.end(),
                                    [&](float r) { return r >= static_cast<float>(initial_threshold); });
  return strong >= strongest;
}

/// The box, in original pixels, that the spreading of a view's level l divides (Extractor's step
/// 5), given the level's valid pixels: for the image (an identity view), the pixels of the level
/// that can hold a candidate (the valid rectangle, at the support border from the level's edges,
/// from pixel edge to pixel edge), as ORB-SLAM2's octree divides the FAST region of the level; for
/// a tilted view, whose valid region is not a rectangle in the original image, the whole image. The
/// image's levels divide their candidate rectangle because the support border grows to 18·s^l
/// original pixels: quadtree cells over the whole image would lie mostly outside it along the
/// edges, and each would still keep one keypoint from a thin strip of candidates, crowding the
/// border, where keypoints rarely match in the next frame (test_extractor checks the density along
/// the edges).
inline cv::Rect2f spread_region(const AffineView& view, const RowSpans& valid_pixels, cv::Size size,
                                const PyramidOptions& pyramid, int l) {
  const cv::Rect2f image(0.0f, 0.0f, static_cast<float>(size.width), static_cast<float>(size.height));
  if (!view.is_identity()) return image;
  const cv::Rect valid = valid_pixels.bounds();
  if (valid.empty()) return image;
  const cv::Size level_size = pyramid_level_size(size, pyramid, l);
  // Pixel edges x − 0.5 and x + 0.5 of the first and last valid pixels, in original pixels.
  const cv::Point2f tl = Pyramid::to_level0(cv::Point2f(valid.x - 0.5f, valid.y - 0.5f), size, level_size);
  const cv::Point2f br =
      Pyramid::to_level0(cv::Point2f(valid.x + valid.width - 0.5f, valid.y + valid.height - 0.5f), size, level_size);
  return cv::Rect2f(tl, br);
}

/// The octave shift of a view of tilt t: its level l's keypoints have the octave l + shift, the
/// level nearest (in log scale) to their scale s^l·√t, l + round(log √t / log s).
inline int octave_shift(double tilt, double scale_factor) {
  return static_cast<int>(std::lround(0.5 * std::log(tilt) / std::log(scale_factor)));
}

/// The smallest size that holds every tilted view of `views` (all but view 0); empty for none.
inline cv::Size largest_tilted(const std::vector<AffineView>& views) {
  cv::Size largest;
  for (std::size_t v = 1; v < views.size(); ++v) {
    largest.width = std::max(largest.width, views[v].size.width);
    largest.height = std::max(largest.height, views[v].size.height);
  }
  return largest;
}

/// CornerSnapOptions: the strongest FAST corner of level o of the original image's pyramid within
/// `radius` level-o pixels of `point` (original pixels), as a level-0 point, if one scores at
/// least `min_threshold` and lies where the mask allows (ties: the nearer pixel, then raster
/// order).
inline std::optional<cv::Point2f> snap_to_corner(const Pyramid& original, cv::Point2f point, int o, int radius,
                                                 int min_threshold, const cv::Mat& mask) {
  const cv::Mat& level = original.level(o);
  const cv::Size base = original.level(0).size();
  const double rx = static_cast<double>(base.width) / level.cols;
  const double ry = static_cast<double>(base.height) / level.rows;
  const double x = (point.x + 0.5) / rx - 0.5;
  const double y = (point.y + 0.5) / ry - 0.5;
  const int cx = static_cast<int>(std::lround(x));
  const int cy = static_cast<int>(std::lround(y));
  int best_score = -1;
  double best_distance = 0.0;
  cv::Point best;
  for (int py = std::max(cy - radius, kFastRadius); py <= std::min(cy + radius, level.rows - 1 - kFastRadius); ++py) {
    for (int px = std::max(cx - radius, kFastRadius); px <= std::min(cx + radius, level.cols - 1 - kFastRadius); ++px) {
      const int score = fast_score(level.ptr<std::uint8_t>(py) + px, static_cast<std::ptrdiff_t>(level.step[0]));
      if (score < min_threshold) continue;
      const double distance = (px - x) * (px - x) + (py - y) * (py - y);
      if (score > best_score || (score == best_score && distance < best_distance)) {
        best_score = score;
        best_distance = distance;
        best = {px, py};
      }
    }
  }
  if (best_score < 0) return std::nullopt;
  const cv::Point2f snapped =
      Pyramid::to_level0(cv::Point2f(static_cast<float>(best.x), static_cast<float>(best.y)), base, level.size());
  if (!mask.empty() && mask.at<std::uint8_t>(cvRound(snapped.y), cvRound(snapped.x)) == 0) return std::nullopt;
  return snapped;
}

/// ExtractorOptions::subpixel: the offset, in level pixels, of the vertex of the parabola through
/// the FAST arc strengths (pixel_strength(), the score + 1 without the threshold) of the pixel at
/// `p` of `level` and its two neighbours, along x and along y separately, each clamped to
/// [−0.5, 0.5]; 0 along an axis where the parabola has no maximum (for a detected corner, where
/// the three are equal) or a neighbour's circle leaves the level.
inline cv::Point2f subpixel_offset(const cv::Mat& level, cv::Point p) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(level.step[0]);
  const std::array<std::ptrdiff_t, 16> offset = circle_offsets(step);
  const std::uint8_t* centre = level.ptr<std::uint8_t>(p.y) + p.x;
  const int strength = pixel_strength(centre, offset);
  // The vertex of the parabola through (−1, before), (0, strength), (1, after).
  const auto vertex = [strength](int before, int after) {
    const int curvature = before - 2 * strength + after;
    if (curvature >= 0) return 0.0f;
    return std::clamp(0.5f * static_cast<float>(before - after) / static_cast<float>(curvature), -0.5f, 0.5f);
  };
  const int reach = kFastRadius + 1;
  cv::Point2f shift(0.0f, 0.0f);
  if (p.x >= reach && p.x < level.cols - reach) {
    shift.x = vertex(pixel_strength(centre - 1, offset), pixel_strength(centre + 1, offset));
  }
  if (p.y >= reach && p.y < level.rows - reach) {
    shift.y = vertex(pixel_strength(centre - step, offset), pixel_strength(centre + step, offset));
  }
  return shift;
}

/// Step 4 of an Extractor for the chosen candidates of level l of `view` (in work.levels[l]):
/// orientation and descriptor in the view at the integer level position, keypoints mapped back
/// with octave `octave` (from the sub-pixel position with ExtractorOptions::subpixel; for a tilted
/// view, snapped on the original image's pyramid `original`: CornerSnapOptions), appended to the
/// level's record `level`.
template <class Descriptor, int Bits>
void describe_level(const Descriptor& descriptor, const AffineView& view, const Pyramid& pyramid, int l, int octave,
                    const ExtractorOptions& options, const Pyramid& original, const cv::Mat& mask,
                    ThreadWork<Descriptor>& work, LevelWork<Bits>& level) {
  const LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
  const std::vector<int>& chosen = c.chosen;
  if (chosen.empty()) return;
  const cv::Matx23d& back = view.to_original;
  const bool identity = view.is_identity();
  work.describe_points.clear();
  for (int i : chosen) work.describe_points.push_back(c.level_points[static_cast<std::size_t>(i)]);
  descriptor.prepare(pyramid.level(l), work.describe_points, work.descriptor_data);
  const float scale = static_cast<float>(options.pyramid.scale(l) * std::sqrt(view.tilt));
  for (int i : chosen) {
    const std::size_t k = static_cast<std::size_t>(i);
    const cv::Point2f p = c.level_points[k];
    const float angle = descriptor.orientation(work.descriptor_data, p);
    level.descriptors.push_back(descriptor.describe(work.descriptor_data, p, angle));
    // The direction (cos θ, sin θ) in the view, mapped to the original image.
    const double dx = back(0, 0) * std::cos(angle) + back(0, 1) * std::sin(angle);
    const double dy = back(1, 0) * std::cos(angle) + back(1, 1) * std::sin(angle);
    const float original_angle = identity ? angle : static_cast<float>(std::atan2(dy, dx));
    cv::Point2f position = c.original_points[k];
    if (options.subpixel) {
      const cv::Point2f shifted = p + subpixel_offset(pyramid.level(l), cv::Point(cvRound(p.x), cvRound(p.y)));
      const cv::Point2d q = apply_affine(back, pyramid.to_level0(shifted, l));
      position = cv::Point2f(static_cast<float>(q.x), static_cast<float>(q.y));
    }
    if (!identity && options.snap_to_corners) {
      if (const std::optional<cv::Point2f> snapped = snap_to_corner(
              original, position, octave, options.snap_to_corners->radius, options.detector.min_threshold, mask)) {
        position = *snapped;
      }
    }
    level.keypoints.emplace_back(position, Descriptor::kPatchSize * scale, radians_to_degrees_0_360(original_angle),
                                 c.responses[k], octave);
    level.original_points.push_back(c.original_points[k]);
    level.responses.push_back(c.responses[k]);
  }
}
/// Keeps `target` of `points` by quadtree spreading over `region` or by strength (`spreading`),
/// into work.kept (ascending indices).
inline void spread(Spreading spreading, const std::vector<cv::Point2f>& points, const std::vector<float>& responses,
                   const cv::Rect2f& region, int target, SpreadWork& work) {
  if (spreading == Spreading::kQuadtree) {
    distribute_quadtree(points, responses, region, target, work.quadtree, work.kept);
  } else {
    select_strongest(responses, target, work.kept);
  }
}

/// Enters in `repeats` (level l) what later views must not repeat of the chosen
/// candidates of `c`: those a selection of `take` among them keeps (all of them when they are
/// the final keypoints; for a shortlist, its nominal budget: the final selection when no
/// shortfall is carried, so that the rest of the shortlist suppresses nothing).
inline void enter_repeat_references(Spreading spreading, const LevelCandidates& c, int l, int take,
                                    const cv::Rect2f& region, SpreadWork& work, RepeatGrids& repeats) {
  // Both selections keep exactly min(take, n) of n: with take >= n, every chosen candidate.
  if (take >= static_cast<int>(c.chosen.size())) {
    for (int i : c.chosen) repeats.enter(c.original_points[static_cast<std::size_t>(i)], l);
    return;
  }
  work.points.clear();
  work.responses.clear();
  for (int i : c.chosen) {
    work.points.push_back(c.original_points[static_cast<std::size_t>(i)]);
    work.responses.push_back(c.responses[static_cast<std::size_t>(i)]);
  }
  spread(spreading, work.points, work.responses, region, take, work);
  for (int k : work.kept) repeats.enter(work.points[static_cast<std::size_t>(k)], l);
}

/// The output of views [first, last) of an Extractor: keypoints grouped by octave (0 first), then by
/// view, then level, then raster order in the view. `octave_start` is a buffer reused across calls.
template <int Bits>
Features<Bits> assemble(const std::vector<ViewWork<Bits>>& view_work, int first, int last, int levels,
                        std::vector<int>& octave_start) {
  octave_start.assign(static_cast<std::size_t>(levels) + 1, 0);
  for (int v = first; v < last; ++v) {
    for (const LevelWork<Bits>& level : view_work[static_cast<std::size_t>(v)].levels) {
      for (int i : level.kept) {
        ++octave_start[static_cast<std::size_t>(level.keypoints[static_cast<std::size_t>(i)].octave) + 1];
      }
    }
  }
  for (int o = 0; o < levels; ++o)
    octave_start[static_cast<std::size_t>(o) + 1] += octave_start[static_cast<std::size_t>(o)];
  const std::size_t total = static_cast<std::size_t>(octave_start.back());
  Features<Bits> features;
  features.keypoints.resize(total);
  features.descriptors.resize(total);
  features.views.resize(total);
  for (int v = first; v < last; ++v) {
    for (const LevelWork<Bits>& level : view_work[static_cast<std::size_t>(v)].levels) {
      for (int i : level.kept) {
        const cv::KeyPoint& kp = level.keypoints[static_cast<std::size_t>(i)];
        const std::size_t slot = static_cast<std::size_t>(octave_start[static_cast<std::size_t>(kp.octave)]++);
        features.keypoints[slot] = kp;
        features.descriptors[slot] = level.descriptors[static_cast<std::size_t>(i)];
        features.views[slot] = v;
      }
    }
  }
  return features;
}

}  // namespace detail
}  // namespace affine_orb
