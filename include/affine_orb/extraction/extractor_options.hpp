#pragma once
/// \file
/// ExtractorOptions: what Extractor<Descriptor> extracts (docs/algorithm.md §2): the budget, the simulated
/// views, how the budget is shared between the image and its views, duplicates across views,
/// spreading, refinement and threads. Every default says which bench chose it.

#include <cmath>
#include <string>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {

/// What to do when several views return the same scene point (docs/algorithm.md §2).
enum class DuplicatePolicy {
  kKeepAll,  ///< Keep every view's keypoint: best for wide-baseline matching of two images.
  kMerge,    ///< Drop a view's candidates that repeat a keypoint chosen by an earlier view (views in
             ///< index order, the image first): see ExtractorOptions::repeat_levels and merge_radius.
};

/// How each (view, level) keeps its share of the budget among its candidates.
enum class Spreading {
  kQuadtree,   ///< distribute_quadtree(): spread over the image (ORB-SLAM2's octree distribution);
               ///< keeps tracking alive in weakly textured parts, the SLAM choice (docs/algorithm.md §2).
  kStrongest,  ///< select_strongest(): the strongest corners wherever they are (cv::ORB's choice);
               ///< more repeatable, so more correct matches between two wide-baseline images.
};

/// Whose extraction the image's own keypoints (view 0) are: affine_orb's, or exactly those of a
/// SLAM system's ORB extractor, so that a drop-in gives that system its own keypoints and bits.
enum class ImageKeypoints {
  /// affine_orb's: its pyramid, detect_candidates() and the `spreading`, `carry_shortfalls` and
  /// `subpixel` options.
  kAffineOrb,
  /// ORB-SLAM2's ORBextractor (raulmur/ORB_SLAM2 f2e6f51), keypoint for keypoint in its order, with
  /// its rBRIEF bits under Rbrief: cv::resize pyramid, FAST in 30-pixel cells, octree distribution,
  /// positions p·s^l (extraction/detail/fork_image.hpp). The octree's order among nodes of equal
  /// size, the heap address in ORB-SLAM2, is creation order here (detection/detail/octree.hpp).
  /// Uses `features`, `pyramid` and the detector's thresholds; the other detector fields,
  /// `spreading`, `carry_shortfalls` and `subpixel` do not apply to the image's keypoints.
  kOrbSlam2,
  /// ORB-SLAM3's (v1.0, shanpenghui/ORB_SLAM3_Fixed 060181f): as kOrbSlam2 with 35-pixel cells and
  /// ORB-SLAM3's node order (left edge).
  kOrbSlam3,
};

/// How the feature budget is shared between the image and its tilted views.
enum class ViewBudget {
  /// The image is extracted exactly as with max_tilt = 1 (`features` keypoints, the same ones); the
  /// tilted views add up to view_features · features keypoints where the image has none at that
  /// place and scale (see ExtractorOptions::repeat_levels). Turning the views on never takes a
  /// keypoint away from the image: at small baselines the result matches like plain extraction,
  /// at wide ones the views' keypoints add matches (bench/eval_viewpoint).
  kAdditive,
  /// `features` in total, split over all views in proportion to their area 1/t (ASIFT's weighting):
  /// the image keeps about 1/Σ(1/t) of them (1/9 for the 18 default views), which costs matches at
  /// small baselines.
  kAreaSplit,
};

/// Where a keypoint of a tilted view is put in the original image.
struct RefineOptions {
  /// Snap each tilted-view keypoint to the strongest FAST corner (score >= the detector's minimum
  /// threshold) of the original image's pyramid level o nearest to its scale s^l·√t (its octave),
  /// within `radius` level-o pixels of its mapped position, so that it lies on a pixel of level o
  /// as an image keypoint would; keypoints without such a corner keep their mapped position. The
  /// descriptor and angle stay those of the view. Off by default, by measurement: FAST's peak in
  /// the original image is not the same scene point as its peak in a tilted view (the circle test
  /// is not affine invariant), so snapping loses distinct correct matches on the graf pairs
  /// (bench/eval_viewpoint) and raises the KITTI 06 frame-to-frame rotation error
  /// (affine_orb_sequence); the mapped position is already within Features' stated precision.
  bool enabled = false;
  /// Search radius in level-o pixels: 1 covers the mapped position's error of at most
  /// t·s^l / (2·s^o) ≈ √t / 2 <= 0.85 level-o pixels for tilts up to 2√2.
  int radius = 1;

  void check() const {
    detail::require(radius >= 0 && radius <= 8,
                    "RefineOptions::radius must be in [0, 8], got " + std::to_string(radius));
  }
};

/// Extraction parameters (docs/algorithm.md §2).
struct ExtractorOptions {
  /// Number of features returned when the image has enough corners (exactly this many, with
  /// carry_shortfalls); ORB-SLAM2's configuration files use 1000 to 2000. Must be in [1, 1000000].
  int features = 1000;
  /// Whose extraction the image's keypoints are (ImageKeypoints); the views are affine_orb's
  /// either way. kOrbSlam2 and kOrbSlam3 need ViewBudget::kAdditive. Default kAffineOrb.
  ImageKeypoints image_keypoints = ImageKeypoints::kAffineOrb;
  PyramidOptions pyramid;
  DetectorOptions detector;
  /// The simulated views; max_tilt = 1 gives a plain ORB-style extractor (one view, the image).
  AffineViewOptions views;
  /// How `features` relates to the views' keypoints; kAdditive is the choice measured in
  /// bench/eval_viewpoint (docs/extraction.md, "Affine views that only add").
  ViewBudget view_budget = ViewBudget::kAdditive;
  /// ViewBudget::kAdditive: keypoints the tilted views add, as a fraction of `features` (the output
  /// has features + round(view_features · features) keypoints when there are enough corners).
  /// Range [0, 16]; ignored with kAreaSplit or max_tilt < √2. Default 1: at 2000 keypoints in all,
  /// 1000 + 1000 finds more distinct correct matches over the Oxford pairs than 500 + 1500 (3),
  /// which wins only from about 40° of viewpoint change (bench/eval_viewpoint).
  double view_features = 1.0;
  /// ViewBudget::kAdditive: the tilted views share the views' budget in proportion to t^e for this
  /// exponent e, in [−4, 4]. −1 is ASIFT's area weighting (a view of tilt t has 1/t of the image's
  /// pixels), 0 equal shares; the default 1 gives the more tilted views, which find what the image
  /// cannot, more, and finds the most distinct correct matches of the three over the Oxford pairs,
  /// most clearly from 40° of viewpoint change on (bench/eval_viewpoint).
  double view_weight_exponent = 1.0;
  /// What a (view, level) with fewer candidates than its share of the budget does with the
  /// difference. true: the next level (or view) takes it on, and what is still missing after the
  /// last is taken, in order, from those with candidates left (allocate_with_carry()), so that the
  /// output has `features` keypoints whenever the image has that many candidates, mostly from level
  /// 0 when the coarse levels run short. false: each keeps at most its own share and the output has
  /// fewer, as ORB-SLAM's own extractor does; the ORB-SLAM adapters use false, since its monocular
  /// initialisation matches level-0 keypoints only and takes the extra ones carried there
  /// (docs/slam.md, "Shortfalls"). Default true: a fixed count for matching two images.
  bool carry_shortfalls = true;
  DuplicatePolicy duplicates = DuplicatePolicy::kMerge;
  /// DuplicatePolicy::kMerge: a candidate of view v, level l is a repeat, and dropped before its
  /// view's selection, when a keypoint chosen by an earlier view (lower index; the image is view 0)
  /// of a level l' with |l − l'| <= repeat_levels lies within merge_radius · s^max(l, l') original
  /// pixels. "Chosen" is the final keypoints for the image with kAdditive and, for a shortlist
  /// (ExtractorOptions::shortlist), what it keeps at its nominal budget. Range [0, 4]; the default
  /// 0 (the same level only) finds more distinct correct matches on the graf pairs than 1 (a
  /// corner's copy at the next level is not a wasted keypoint there; bench/eval_viewpoint).
  int repeat_levels = 0;
  /// Location of the tilted views' keypoints in the original image.
  RefineOptions refine;
  /// Sub-pixel keypoint positions: each keypoint's integer position in its level (of the image or
  /// of a tilted view) moves to the vertex of the parabola through the FAST arc strengths (score + 1)
  /// of it and its two neighbours, along x and along y separately, by at most 0.5 level pixels,
  /// before it is mapped to the original image (KeyPoint::pt, pixels, level-0 coordinates); a
  /// RefineOptions snap still replaces a tilted view's position. Only the positions change: the
  /// candidates, the selection, the merging of views, the angles and the descriptors use the
  /// integer level positions (the descriptor samples whole level pixels), so the output is that of
  /// the option off but for KeyPoint::pt. The mask applies to the integer position, so a keypoint
  /// may lie up to half a level pixel beyond the mask's edge; descriptors computed again from the
  /// returned keypoints (cv::Feature2D::compute of opencv_feature2d.hpp) sample the rounded
  /// sub-pixel positions and may differ from the extraction's. It lowers the residual of correct
  /// matches and lets plain matching solve more pairs, while the two-view matcher solves as many
  /// (other ones); the SLAM uses are not measured (bench/eval_two_view --placement,
  /// docs/two_view.md, "Reading"). Off by default for those reasons and the mask and compute()
  /// above; the ORB-SLAM adapters keep it off.
  bool subpixel = false;
  /// With several views: a view's pixels exist only while it is processed (one view's buffers per
  /// thread), so each (view, level) whose final share depends on the other views (every
  /// tilted view with kAdditive, every view with kAreaSplit) describes a shortlist of up to
  /// ceil(shortlist · its nominal budget) of its candidates, spread as the final selection is;
  /// once every view is done, the carrying of shortfalls and the final spreading choose among the
  /// shortlists. Above 1 it leaves room for carried shortfalls; larger costs description time
  /// and, with kQuadtree, moves the final choice away from the spreading of all candidates. Range
  /// [1, 64]; the default 1.25 finds more distinct correct matches with quadtree spreading than 2
  /// and the same with kStrongest (bench/eval_viewpoint).
  double shortlist = 1.25;
  /// Radius in original pixels, times the level scale s^l, within which kMerge treats keypoints of
  /// different views as one (ExtractorOptions::repeat_levels); 2 px is the docs/algorithm.md §7 duplicate cell
  /// size.
  double merge_radius = 2.0;
  /// Selection within each (view, level); kQuadtree for SLAM, kStrongest for matching two images
  /// (bench/eval_viewpoint measures both).
  Spreading spreading = Spreading::kQuadtree;
  /// Threads for the views (1 = the calling thread only); an Extractor starts the other
  /// threads − 1 on its first extract() and keeps them until it is destroyed. The output does not
  /// depend on it.
  int threads = 1;

  void check() const {
    detail::require(features >= 1 && features <= 1000000,
                    "ExtractorOptions::features must be in [1, 1000000], got " + std::to_string(features));
    pyramid.check();
    detector.check();
    views.check();
    detail::require(view_budget == ViewBudget::kAdditive || view_budget == ViewBudget::kAreaSplit,
                    "ExtractorOptions::view_budget is invalid");
    detail::require(image_keypoints == ImageKeypoints::kAffineOrb || image_keypoints == ImageKeypoints::kOrbSlam2 ||
                        image_keypoints == ImageKeypoints::kOrbSlam3,
                    "ExtractorOptions::image_keypoints is invalid");
    detail::require(image_keypoints == ImageKeypoints::kAffineOrb || view_budget == ViewBudget::kAdditive,
                    "ExtractorOptions::image_keypoints: a fork's keypoints need ViewBudget::kAdditive");
    detail::require(std::isfinite(view_features) && view_features >= 0.0 && view_features <= 16.0,
                    "ExtractorOptions::view_features must be in [0, 16], got " + std::to_string(view_features));
    detail::require(
        std::isfinite(view_weight_exponent) && view_weight_exponent >= -4.0 && view_weight_exponent <= 4.0,
        "ExtractorOptions::view_weight_exponent must be in [-4, 4], got " + std::to_string(view_weight_exponent));
    detail::require(repeat_levels >= 0 && repeat_levels <= 4,
                    "ExtractorOptions::repeat_levels must be in [0, 4], got " + std::to_string(repeat_levels));
    refine.check();
    detail::require(std::isfinite(shortlist) && shortlist >= 1.0 && shortlist <= 64.0,
                    "ExtractorOptions::shortlist must be in [1, 64], got " + std::to_string(shortlist));
    detail::require(duplicates == DuplicatePolicy::kKeepAll || duplicates == DuplicatePolicy::kMerge,
                    "ExtractorOptions::duplicates is invalid");
    detail::require(std::isfinite(merge_radius) && merge_radius > 0.0 && merge_radius <= 64.0,
                    "ExtractorOptions::merge_radius must be in (0, 64], got " + std::to_string(merge_radius));
    detail::require(spreading == Spreading::kQuadtree || spreading == Spreading::kStrongest,
                    "ExtractorOptions::spreading is invalid");
    detail::require(threads >= 1 && threads <= 256,
                    "ExtractorOptions::threads must be in [1, 256], got " + std::to_string(threads));
  }
};

}  // namespace affine_orb
