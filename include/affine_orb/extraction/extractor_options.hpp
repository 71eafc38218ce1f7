#pragma once
/// \file
/// ExtractorOptions: what Extractor<Descriptor> extracts (docs/algorithm.md §2): the budget, the simulated
/// views, how the budget is shared between the image and its views, duplicates across views,
/// spreading, snapping and threads. Every default says which bench chose it.

#include <cmath>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {

/// How each (view, level) keeps its share of the budget among its candidates.
enum class Spreading {
  kQuadtree,   ///< distribute_quadtree(): spread over the image (ORB-SLAM2's octree distribution);
               ///< keeps tracking alive in weakly textured parts, the SLAM choice (docs/algorithm.md §2).
  kStrongest,  ///< select_strongest(): the strongest corners wherever they are (cv::ORB's choice);
               ///< more repeatable, so more correct matches between two wide-baseline images.
};

/// The image's own keypoints (view 0) are affine_orb's: its pyramid, detect_candidates() and the
/// `spreading`, `carry_shortfalls` and `subpixel` options.
struct AffineOrbKeypoints {};

/// The image's keypoints are ORB-SLAM2's ORBextractor's (raulmur/ORB_SLAM2 f2e6f51), keypoint for
/// keypoint in its order, with its rBRIEF bits under Rbrief: cv::resize pyramid, FAST in 30-pixel
/// cells, octree distribution, positions p·s^l (extraction/detail/fork_image.hpp). The octree's
/// order among nodes of equal size, the heap address in ORB-SLAM2, is creation order here
/// (detection/detail/octree.hpp). Uses `features`, `pyramid` and the detector's thresholds; the
/// other detector fields, `spreading`, `carry_shortfalls` and `subpixel` do not apply to them.
struct OrbSlam2Keypoints {};

/// The image's keypoints are ORB-SLAM3's (v1.0, shanpenghui/ORB_SLAM3_Fixed 060181f): as
/// OrbSlam2Keypoints with 35-pixel cells and ORB-SLAM3's node order (left edge).
struct OrbSlam3Keypoints {};

/// A rectangle in which stella_vslam finds no keypoint (its Preprocessing.mask_rectangles), in
/// fractions of the image's width (x) and height (y): 0 <= min < max <= 1.
struct MaskRectangle {
  float x_min = 0.0f;
  float x_max = 1.0f;
  float y_min = 0.0f;
  float y_max = 1.0f;
};

/// The image's keypoints are stella_vslam's orb_extractor's (stella-cv/stella_vslam b0e60d6),
/// keypoint for keypoint in its order, with its rBRIEF bits under Rbrief: cv::resize pyramid, FAST
/// in 64-pixel cells, of each grid cell of `min_size` the strongest keypoint, positions p·s^l
/// (extraction/detail/stella_image.hpp). Its scale factor, levels and FAST thresholds are
/// `pyramid` and `detector`'s; `features` sets only what the views add (AdditiveBudget), and the
/// other detector fields, `spreading`, `carry_shortfalls` and `subpixel` do not apply to them.
struct StellaVslamKeypoints {
  /// Its Preprocessing.min_size: area in level-0 pixels² of the grid cells each of which keeps its
  /// strongest keypoint, cells of side trunc(√min_size) level-0 pixels; [1, 100000000]; default 800
  /// (stella_vslam's).
  int min_size = 800;
  /// Its Preprocessing.mask_rectangles: no keypoint in them (filled with cv::rectangle, LINE_AA,
  /// as stella_vslam does), nor in a FAST cell with a corner in them; used only when extract() gets
  /// no mask, and then as the views' mask too. Default none.
  std::vector<MaskRectangle> mask_rectangles;

  void check() const {
    detail::require_range(min_size, {1.0, 100000000.0}, "StellaVslamKeypoints: min_size");
    for (const MaskRectangle& r : mask_rectangles) {
      detail::require_range(r.x_min, {0.0, 1.0}, "StellaVslamKeypoints: mask_rectangles x_min");
      detail::require_range(r.y_min, {0.0, 1.0}, "StellaVslamKeypoints: mask_rectangles y_min");
      detail::require_range(r.x_max, {r.x_min, 1.0, true}, "StellaVslamKeypoints: mask_rectangles x_max");
      detail::require_range(r.y_max, {r.y_min, 1.0, true}, "StellaVslamKeypoints: mask_rectangles y_max");
    }
  }
};

/// Whose extraction the image's own keypoints (view 0) are: affine_orb's, or exactly those of a
/// SLAM system's ORB extractor, so that a drop-in gives that system its own keypoints and bits.
using ImageKeypoints = std::variant<AffineOrbKeypoints, OrbSlam2Keypoints, OrbSlam3Keypoints, StellaVslamKeypoints>;

/// The additive view budget (ExtractorOptions::view_budget): the image is extracted exactly as
/// with max_tilt = 1 (`features` keypoints, the same ones) and the tilted views add keypoints where
/// the image has none at that place and scale, so turning the views on never takes a keypoint
/// away from the image (docs/extraction.md, "Affine views that only add").
struct AdditiveBudget {
  /// Keypoints the tilted views add, fraction of `features`; [0, 16]; default 1. Unused below
  /// max_tilt √2.
  double view_features = 1.0;
  /// The tilted views share them in proportion to t^e; [−4, 4]; −1 is ASIFT's area weighting, 0
  /// equal shares; default 1 (bench/eval_viewpoint).
  double view_weight_exponent = 1.0;

  void check() const {
    detail::require_range(view_features, {0.0, 16.0}, "AdditiveBudget: view_features");
    detail::require_range(view_weight_exponent, {-4.0, 4.0}, "AdditiveBudget: view_weight_exponent");
  }
};

/// The area-split view budget (ExtractorOptions::view_budget): `features` in total, split over
/// all views in proportion to their area 1/t (ASIFT's weighting); the image keeps about 1/Σ(1/t)
/// of them (1/9 for the 18 default views), which costs matches at small baselines.
struct AreaSplitBudget {};

/// How the feature budget is shared between the image and its tilted views.
using ViewBudget = std::variant<AdditiveBudget, AreaSplitBudget>;

/// Merging of keypoints that several views return (ExtractorOptions::merge_duplicates): a
/// candidate of view v, level l is dropped before its view's selection when a keypoint chosen by
/// an earlier view (lower index; the image is view 0) of a level l' with |l − l'| <=
/// repeat_levels lies within radius · s^max(l, l') original pixels. "Chosen" is the final
/// keypoints for the image under AdditiveBudget and, for a shortlist (ExtractorOptions::shortlist),
/// what it keeps at its nominal budget.
struct MergeOptions {
  /// Original pixels at level 0 (times s^l); (0, 64]; default 2, docs/algorithm.md §7's cell.
  double radius = 2.0;
  /// Level distance within which keypoints repeat; [0, 4]; default 0 (bench/eval_viewpoint).
  int repeat_levels = 0;

  void check() const {
    detail::require_range(radius, {0.0, 64.0, true}, "MergeOptions: radius");
    detail::require_range(repeat_levels, {0.0, 4.0}, "MergeOptions: repeat_levels");
  }
};

/// Snapping of tilted-view keypoints to corners of the original image
/// (ExtractorOptions::snap_to_corners): each moves to the strongest FAST corner (score >= the
/// detector's minimum threshold) of the image's pyramid level o nearest to its scale s^l·√t, within
/// `radius` level-o pixels of its mapped position, so that it lies on a pixel of level o as an image
/// keypoint would; without such a corner it keeps its mapped position. Angle and descriptor stay the
/// view's. FAST's peak in a tilted view is not the same scene point as in the image (the circle test
/// is not affine invariant), so snapping loses correct matches on the graf pairs (bench/eval_viewpoint).
struct CornerSnapOptions {
  /// Search radius, level-o pixels; [0, 8]; default 1, which covers the mapped position's error of
  /// at most √t / 2 <= 0.85 level-o pixels for tilts up to 2√2.
  int radius = 1;

  void check() const { detail::require_range(radius, {0.0, 8.0}, "CornerSnapOptions: radius"); }
};

/// Extraction parameters (docs/algorithm.md §2).
struct ExtractorOptions {
  /// Keypoints of the image (exactly this many when it has enough corners and carry_shortfalls
  /// holds); [1, 1000000]; default 1000 (ORB-SLAM2's configurations use 1000 to 2000).
  int features = 1000;
  /// Whose extraction the image's keypoints are; the views are affine_orb's either way. A fork's
  /// needs AdditiveBudget. Default AffineOrbKeypoints.
  ImageKeypoints image_keypoints = AffineOrbKeypoints{};
  /// The scale pyramid of the image and of every view.
  PyramidOptions pyramid;
  /// FAST thresholds, cells and ranking.
  DetectorOptions detector;
  /// The simulated views; max_tilt = 1 gives a plain ORB-style extractor (one view, the image).
  AffineViewOptions views;
  /// How `features` relates to the views' keypoints; default AdditiveBudget (docs/extraction.md,
  /// "Affine views that only add").
  ViewBudget view_budget = AdditiveBudget{};
  /// What a (view, level) with fewer candidates than its share does with the difference. true
  /// (default): the next level or view takes it on, and what is still missing after the last is
  /// taken in order from those with candidates left (allocate_with_carry()), a fixed count for
  /// matching two images. false: each keeps at most its share, as ORB-SLAM's extractor does
  /// (docs/slam.md, "Shortfalls").
  bool carry_shortfalls = true;
  /// Merging of keypoints that several views return; nullopt keeps every view's keypoint (for
  /// wide-baseline matching of two images). Default MergeOptions{}.
  std::optional<MergeOptions> merge_duplicates = MergeOptions{};
  /// Snapping of the tilted views' keypoints to the image's corners; default nullopt (off, by
  /// measurement: CornerSnapOptions).
  std::optional<CornerSnapOptions> snap_to_corners;
  /// Sub-pixel keypoint positions: along x and y separately, a keypoint moves to the vertex of the
  /// parabola through the FAST arc strengths (score + 1) of it and its two neighbours, by at most
  /// 0.5 level pixels, before mapping to the original image. Only KeyPoint::pt changes: selection,
  /// merging, angles, descriptors and the mask use the integer level position (so compute() on the
  /// returned keypoints may give other bits). Default false; the ORB-SLAM adapters keep it off
  /// (bench/eval_two_view --placement, docs/two_view.md).
  bool subpixel = false;
  /// Shortlist of each (view, level) whose final share depends on the other views (the tilted
  /// views under AdditiveBudget, every view under AreaSplitBudget): it describes up to
  /// ceil(shortlist · its nominal budget) candidates, spread as the final selection is, and the
  /// final selection chooses among the shortlists once every view is done. [1, 64]; default 1.25
  /// (bench/eval_viewpoint).
  double shortlist = 1.25;
  /// Selection within each (view, level); kQuadtree for SLAM, kStrongest for matching two images
  /// (bench/eval_viewpoint measures both). Default kQuadtree.
  Spreading spreading = Spreading::kQuadtree;
  /// Threads for the views, the calling one included, kept until the Extractor is destroyed; the
  /// output does not depend on it. [1, 256]; default 1.
  int threads = 1;

  /// The additive budget's parameters, or nullptr under AreaSplitBudget.
  const AdditiveBudget* additive_budget() const { return std::get_if<AdditiveBudget>(&view_budget); }
  /// Whether the image's keypoints are a SLAM system's (any ImageKeypoints but AffineOrbKeypoints).
  bool fork_keypoints() const { return !std::holds_alternative<AffineOrbKeypoints>(image_keypoints); }

  /// Throws std::invalid_argument for a value outside its range or a fork's keypoints without
  /// AdditiveBudget.
  void check() const {
    detail::require_range(features, {1.0, 1000000.0}, "ExtractorOptions: features");
    pyramid.check();
    detector.check();
    views.check();
    if (additive_budget()) additive_budget()->check();
    detail::require(!fork_keypoints() || additive_budget(),
                    "ExtractorOptions: image_keypoints: a fork's keypoints need the AdditiveBudget view_budget");
    if (const auto* stella = std::get_if<StellaVslamKeypoints>(&image_keypoints)) stella->check();
    if (merge_duplicates) merge_duplicates->check();
    if (snap_to_corners) snap_to_corners->check();
    detail::require_range(shortlist, {1.0, 64.0}, "ExtractorOptions: shortlist");
    detail::require(spreading == Spreading::kQuadtree || spreading == Spreading::kStrongest,
                    "ExtractorOptions: spreading is invalid");
    detail::require_range(threads, {1.0, 256.0}, "ExtractorOptions: threads");
  }
};

}  // namespace affine_orb
