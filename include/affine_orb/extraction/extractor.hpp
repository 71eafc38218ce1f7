#pragma once
/// \file
/// Extractor<Descriptor>: Affine-ORB feature extraction (paper section 3, SPEC §1–§3). Oriented FAST
/// keypoints are detected on a scale pyramid of every simulated affine view, spread over the image
/// under an exact feature budget, described in their view by a descriptor policy (Rbrief, Brisk),
/// and mapped back to the original image.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/views/affine_views.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/detail/row_spans.hpp"
#include "affine_orb/extraction/detail/view_regions.hpp"
#include "affine_orb/extraction/detail/view_schedule.hpp"
#include "affine_orb/core/detail/worker_pool.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/detection/pyramid.hpp"

namespace affine_orb {

/// What to do when several views return the same scene point (SPEC §2).
enum class DuplicatePolicy {
  kKeepAll,  ///< Keep every view's keypoint: best for wide-baseline matching of two images.
  kMerge,    ///< Drop a view's candidates that repeat a keypoint chosen by an earlier view (views in
             ///< index order, the image first): see ExtractorOptions::repeat_levels and merge_radius.
};

/// How each (view, level) keeps its share of the budget among its candidates.
enum class Spreading {
  kQuadtree,   ///< distribute_quadtree(): spread over the image (ORB-SLAM2's octree distribution);
               ///< keeps tracking alive in weakly textured parts, the SLAM choice (SPEC §2).
  kStrongest,  ///< select_strongest(): the strongest corners wherever they are (cv::ORB's choice);
               ///< more repeatable, so more correct matches between two wide-baseline images.
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

/// Extraction parameters (SPEC §2).
struct ExtractorOptions {
  /// Number of features returned when the image has enough corners (exactly this many); ORB-SLAM2's
  /// configuration files use 1000 to 2000. Must be in [1, 1000000].
  int features = 1000;
  PyramidOptions pyramid;
  DetectorOptions detector;
  /// The simulated views; max_tilt = 1 gives a plain ORB-style extractor (one view, the image).
  AffineViewOptions views;
  /// How `features` relates to the views' keypoints; kAdditive is the choice measured in
  /// bench/eval_viewpoint (README, "Affine views that only add").
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
  /// different views as one (ExtractorOptions::repeat_levels); 2 px is the SPEC §7 duplicate cell
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

/// Extracts keypoints and descriptors from grey images.
///
/// For an image of size W x H and every view v of ExtractorOptions::views (affine_views.hpp), one
/// view at a time on each thread (its pixels live in that thread's buffers only while it is
/// processed; the image's pyramid is kept until the next call, see pyramid()):
/// 1. the view is rendered (render_view()) and a pyramid of PyramidOptions::levels levels is built
///    on it; for a tilted view, level pixels farther than 8 level pixels from the original image
///    repeat the nearest computed pixel of their row (only descriptor reads beyond the image, which
///    are extrapolation anyway, can see them);
/// 2. on each level, FAST candidates are detected (detect_candidates(), grid cells anchored at the
///    support border) among the level's valid pixels only: those whose support (a disc of
///    max(Descriptor::border(), DetectorOptions::support_radius()) level pixels) maps inside the
///    original image (detail::support_region()); a cell falls back to the minimum threshold when
///    its valid pixels hold no corner at the initial one. A candidate is kept if the mask pixel
///    nearest to its original position is non-zero;
/// 3. in view order (detail::ViewTurns), with DuplicatePolicy::kMerge, a tilted view drops its
///    candidates that repeat a keypoint chosen by an earlier view (detail::RepeatGrids,
///    ExtractorOptions::repeat_levels); then each level chooses what it describes: the image with
///    ViewBudget::kAdditive its final keypoints, exactly as with max_tilt = 1 (`features` of them,
///    levels geometric, shortfalls carried); every other view a shortlist
///    (ExtractorOptions::shortlist);
/// 4. the chosen keypoints are oriented and described in their view, then mapped back: position
///    through the inverse view map, orientation by mapping the direction vector, scale s^l·√t
///    (SPEC §1); a tilted view's keypoint is then snapped to a corner of the original image
///    (RefineOptions);
/// 5. once every view is done, a budget is split over the shortlisted views (kAdditive:
///    view_features · features over the tilted views, in proportion to t^view_weight_exponent;
///    kAreaSplit: `features` over all views, in proportion to their area 1/t) and, within a view,
///    over levels geometrically (level_budgets()); shortfalls are carried (allocate_with_carry(),
///    detail::ViewBudgets); each (view, level) keeps its share of its shortlist by quadtree
///    spreading (distribute_quadtree()) in original coordinates, or its strongest keypoints
///    (select_strongest()), per ExtractorOptions::spreading.
///
/// Output order: by octave (0 first), then by view, then by level, then raster order in the view.
/// The output does not depend on ExtractorOptions::threads.
///
/// Views on demand: extract_image() is stage 0 (the image alone, exactly extract() with
/// max_tilt = 1) and each extend() adds the views of further tilts, so that a caller pays for
/// views only when it needs them (match_images() in two_view.hpp escalates this way). The stage
/// {extract_image(), extend(views.max_tilt, round(view_features · features))} gives exactly
/// extract()'s keypoints.
///
/// An Extractor holds a workspace reused across calls (and, with ExtractorOptions::threads > 1, its
/// worker threads): it can be moved, not copied. Its size is the image's pyramid plus, per thread,
/// the buffers of the largest view; once they have held the largest view of an image size, a call
/// allocates only the three vectors it returns. One instance must not be used by two threads at
/// once; separate instances share nothing.
template <class Descriptor>
class Extractor {
 public:
  static constexpr int kBits = Descriptor::kBits;
  using DescriptorOptions = typename Descriptor::Options;

  explicit Extractor(ExtractorOptions options = {}, DescriptorOptions descriptor_options = {})
      : options_((options.check(), options)),
        descriptor_(descriptor_options),
        image_pyramid_(options_.pyramid),
        thread_work_(static_cast<std::size_t>(options_.threads), ThreadWork(options_.pyramid)),
        turns_(std::make_unique<detail::ViewTurns>()) {}

  const ExtractorOptions& options() const { return options_; }
  const Descriptor& descriptor() const { return descriptor_; }

  /// The views of ExtractorOptions::views for the last image passed to extract() or
  /// extract_image() (empty before the first call), in view index order (Features::views).
  std::vector<AffineView> views() const {
    std::vector<AffineView> out;
    for (const ViewWork& w : view_work_) out.push_back(w.view);
    return out;
  }

  /// The pyramid of the original (untilted) image of the last extract() or extract_image() call.
  const Pyramid& pyramid() const {
    detail::require(!view_work_.empty() && !image_pyramid_.empty(), "Extractor::pyramid: extract() was not called yet");
    return image_pyramid_;
  }

  /// Keypoints (original pixel coordinates) and descriptors of a CV_8UC1 image (a ROI of a larger
  /// matrix is fine), every view at once; see Features for the keypoint fields.
  ///
  /// `mask`: empty (everything allowed) or CV_8UC1 of the image size; a keypoint is kept only where
  /// the mask pixel nearest to its original position is non-zero.
  ///
  /// Throws std::invalid_argument for an empty image, a type other than CV_8UC1, or a mask of the
  /// wrong size or type. A valid image with no corners (flat, or smaller than the descriptor
  /// support on every level) gives an empty result.
  Features<kBits> extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    begin(image, mask);
    const int n_views = static_cast<int>(view_work_.size());
    if (additive()) {
      budgets_.set_view(0, options_.features, options_.pyramid.scale_factor);
      budgets_.share(tilts_, 1, n_views, static_cast<int>(std::lround(options_.view_features * options_.features)),
                     options_.view_weight_exponent, options_.pyramid.scale_factor);
    } else {
      budgets_.share(tilts_, 0, n_views, options_.features, -1.0, options_.pyramid.scale_factor);
    }
    run_views(image, mask, 0, n_views);
    return assemble(0, n_views);
  }

  /// Views on demand, stage 0: the keypoints of the image alone, exactly extract()'s with
  /// views.max_tilt = 1 (the image's `features` keypoints). The Extractor keeps `image` and `mask`
  /// (cv::Mat headers, not copies) for extend(): their pixels must not change until the last
  /// extend() of this image. Same arguments, checks and exceptions as extract(); also throws
  /// std::invalid_argument unless ExtractorOptions::view_budget is ViewBudget::kAdditive.
  Features<kBits> extract_image(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    detail::require(additive(), "Extractor::extract_image: views on demand need ViewBudget::kAdditive");
    begin(image, mask);
    budgets_.set_view(0, options_.features, options_.pyramid.scale_factor);
    run_views(image, mask, 0, 1);
    staged_image_ = image;
    staged_mask_ = mask;
    staged_views_ = 1;
    return assemble(0, 1);
  }

  /// Views on demand, next stage: the keypoints that the tilted views of ExtractorOptions::views
  /// with tilt in (extracted_tilt(), up_to_tilt] add to the image of the last extract_image(),
  /// `features` of them in all when there are enough corners (shared over the stage's views in
  /// proportion to t^view_weight_exponent, then over levels and with shortfalls carried as in
  /// extract()). With DuplicatePolicy::kMerge a candidate is dropped when it repeats a keypoint
  /// of an earlier stage or of an earlier view of this stage. Earlier stages' keypoints are not
  /// changed: the union of the stages so far is a superset of the stages before. Returns only the
  /// stage's keypoints (Features::views index views()); an empty result when no view is left up
  /// to `up_to_tilt` (views beyond views.max_tilt do not exist).
  ///
  /// Throws std::invalid_argument before extract_image() (or after an extract(), which ends the
  /// staged image), for up_to_tilt not finite, or features outside [0, 1000000].
  Features<kBits> extend(double up_to_tilt, int features) {
    detail::require(staged_views_ > 0, "Extractor::extend: call extract_image() first");
    detail::require(std::isfinite(up_to_tilt), "Extractor::extend: up_to_tilt must be finite");
    detail::require(features >= 0 && features <= 1000000, "Extractor::extend: features must be in [0, 1000000]");
    const int first = staged_views_;
    int last = first;
    // The same 0.1 % tolerance as view_parameters(), so that 2.83 includes 2√2.
    while (last < static_cast<int>(view_work_.size()) &&
           tilts_[static_cast<std::size_t>(last)] <= up_to_tilt * (1.0 + 1e-3)) {
      ++last;
    }
    if (last == first) return {};
    // What the earlier stages finally kept is what this stage must not repeat.
    if (merging()) {
      repeats_.reset(staged_image_.size(), options_.pyramid, options_.merge_radius, options_.repeat_levels);
      for (int v = 0; v < first; ++v) enter_kept(v);
    }
    budgets_.share(tilts_, first, last, features, options_.view_weight_exponent, options_.pyramid.scale_factor);
    run_views(staged_image_, staged_mask_, first, last);
    staged_views_ = last;
    return assemble(first, last);
  }

  /// The largest tilt whose views the staged extraction of the current image has extracted: 1
  /// after extract_image(), 0 when no staged extraction is under way.
  double extracted_tilt() const {
    return staged_views_ > 0 ? tilts_[static_cast<std::size_t>(staged_views_ - 1)] : 0.0;
  }

 private:
  /// Buffers of the budget step of one thread, reused across frames.
  struct SpreadWork {
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    std::vector<int> kept;
    QuadtreeWorkspace quadtree;
  };

  /// The candidates of one level of the view a thread is processing.
  struct LevelCandidates {
    Candidates detected;
    std::vector<cv::Point2f> level_points;     ///< level pixels of the view
    std::vector<cv::Point2f> original_points;  ///< the same, original pixels
    std::vector<float> responses;
    std::vector<int> chosen;  ///< the candidates to describe, ascending
  };

  /// The buffers one thread processes views with, reused view after view and frame after frame:
  /// everything that scales with a view's area.
  struct ThreadWork {
    explicit ThreadWork(const PyramidOptions& options) : pyramid(options) {}
    cv::Mat scratch;  ///< one canvas row of the renderer
    Pyramid pyramid;  ///< a tilted view's levels (the image's are image_pyramid_)
    DetectorWorkspace detector;
    std::vector<LevelCandidates> levels;
    typename Descriptor::LevelData descriptor_data;  ///< one level at a time
    std::vector<cv::Point2f> describe_points;
    SpreadWork spread;
  };

  /// What a (view, level) keeps of its view once the view's pixels are gone: its described
  /// keypoints (the final ones for the image with kAdditive, a shortlist otherwise), in raster
  /// order of the view, and the selection among them.
  struct LevelWork {
    RowSpans valid;  ///< level pixels whose support maps inside the original image (image-size dependent)
    std::vector<cv::Point2f> original_points;  ///< unrefined positions, original pixels
    std::vector<float> responses;
    std::vector<cv::KeyPoint> keypoints;
    std::vector<BinaryDescriptor<kBits>> descriptors;
    std::vector<int> kept;  ///< the output: indices into the described keypoints, ascending

    void clear() {
      original_points.clear();
      responses.clear();
      keypoints.clear();
      descriptors.clear();
      kept.clear();
    }
  };

  /// A view and its per-level records (fixed for an image size, prepare_views()).
  struct ViewWork {
    AffineView view;
    detail::ViewRenderer renderer;
    /// Per level, the pixels computed (the rest repeats the row's edge pixels): level 0 is
    /// rendered, the others resized, within kRenderMargin level pixels of the image.
    std::vector<RowSpans> regions;
    std::vector<LevelWork> levels;
  };

  /// Margin in level pixels around the original image within which a view and its pyramid levels
  /// are computed: more than the reach beyond a valid keypoint's support of the rBRIEF smoothing
  /// (3 level pixels) and of the bilinear interpolation between levels.
  static constexpr double kRenderMargin = 8.0;

  // ---- The walk of one image ------------------------------------------------------------------

  /// Checks the arguments, prepares the view set for the image size and empties the repeat grids;
  /// ends any staged extraction.
  void begin(const cv::Mat& image, const cv::Mat& mask) {
    detail::require_gray8(image, "Extractor::extract");
    detail::require_mask(mask, image.size(), "Extractor::extract");
    prepare_views(image.size());
    staged_views_ = 0;
    staged_image_ = cv::Mat();
    staged_mask_ = cv::Mat();
    if (merging()) repeats_.reset(image.size(), options_.pyramid, options_.merge_radius, options_.repeat_levels);
  }

  /// Steps 1–5 for views [first, last), whose budgets are set: every view processed (in parallel,
  /// taking turns in view order), then the final selection of the shortlisted ones.
  void run_views(const cv::Mat& image, const cv::Mat& mask, int first, int last) {
    turns_->reset(first);
    for_each(last - first,
             [&](int i, int w) { process_view(first + i, image, mask, thread_work_[static_cast<std::size_t>(w)]); });
    const int shortlisted = first == 0 && direct(0) ? 1 : first;
    if (shortlisted < last) select_shortlisted(image.size(), shortlisted, last);
  }

  /// Steps 1–4 for view v on the thread owning `work`; a failure ends every turn still to come.
  void process_view(int v, const cv::Mat& image, const cv::Mat& mask, ThreadWork& work) {
    try {
      ViewWork& view = view_work_[static_cast<std::size_t>(v)];
      for (LevelWork& level : view.levels) level.clear();
      const bool empty = v != 0 && budgets_.view(v) == 0;  // nothing of it could be kept
      Pyramid& pyramid = v == 0 ? image_pyramid_ : work.pyramid;
      if (!empty) {
        view.renderer.render(image, &view.regions.front(), work.scratch, pyramid.level0(view.view.size));
        pyramid.build_from_level0(view.view.is_identity() ? nullptr : &view.regions);
        detect_view(v, image, mask, pyramid, work);
      }
      if (!turns_->wait(v)) return;
      if (!empty) {
        if (merging()) drop_repeats(v, work);
        choose(v, image.size(), work);
      }
      turns_->pass(v);
      if (!empty) describe_view(v, pyramid, mask, work);
    } catch (...) {
      turns_->fail();
      throw;
    }
  }

  /// Step 2 for view v: candidates of every level into work.levels, with the support and mask checks.
  void detect_view(int v, const cv::Mat& image, const cv::Mat& mask, const Pyramid& pyramid, ThreadWork& work) {
    const ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    const int border = support_border();
    const cv::Matx23d& back = view.view.to_original;
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      c.level_points.clear();
      c.original_points.clear();
      c.responses.clear();
      const RowSpans& valid = view.levels[static_cast<std::size_t>(l)].valid;
      if (valid.rows() == 0) continue;
      detect_candidates(pyramid.level(l), valid, cv::Point(border, border), options_.detector, work.detector,
                        c.detected);
      for (std::size_t i = 0; i < c.detected.corners.size(); ++i) {
        const Corner& corner = c.detected.corners[i];
        const cv::Point2f p(static_cast<float>(corner.x), static_cast<float>(corner.y));
        const cv::Point2d q = apply_affine(back, pyramid.to_level0(p, l));
        const int mx = cvRound(q.x);
        const int my = cvRound(q.y);
        if (mx < 0 || my < 0 || mx >= image.cols || my >= image.rows) continue;
        if (!mask.empty() && mask.at<std::uint8_t>(my, mx) == 0) continue;
        c.level_points.push_back(p);
        c.original_points.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y));
        c.responses.push_back(c.detected.responses[i]);
      }
    }
  }

  /// Step 3, in view v's turn, with DuplicatePolicy::kMerge: drops the candidates of a tilted view
  /// that repeat a keypoint chosen by an earlier view.
  void drop_repeats(int v, ThreadWork& work) const {
    if (v == 0) return;
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      std::size_t n = 0;
      for (std::size_t i = 0; i < c.responses.size(); ++i) {
        if (repeats_.repeats(c.original_points[i], l)) continue;
        c.level_points[n] = c.level_points[i];
        c.original_points[n] = c.original_points[i];
        c.responses[n] = c.responses[i];
        ++n;
      }
      c.level_points.resize(n);
      c.original_points.resize(n);
      c.responses.resize(n);
    }
  }

  /// Step 3, in view v's turn: the candidates each level describes (its final keypoints when
  /// direct(v), else its shortlist), entered in the repeat grids for the views after it.
  void choose(int v, cv::Size size, ThreadWork& work) {
    const int levels = options_.pyramid.levels;
    if (direct(v)) {
      available_.clear();
      for (const LevelCandidates& c : work.levels) available_.push_back(static_cast<int>(c.responses.size()));
      budgets_.allocate(v * levels, (v + 1) * levels, available_);
    }
    for (int l = 0; l < levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      const int g = v * levels + l;
      const int target = direct(v) ? budgets_.take(g)
                                   : detail::shortlist_size(static_cast<int>(c.responses.size()), budgets_.group(g),
                                                            options_.shortlist);
      const cv::Rect2f region = spread_region(v, l, size);
      spread(c.original_points, c.responses, region, target, work.spread);
      c.chosen = work.spread.kept;
      if (merging()) enter_repeat_references(c, l, direct(v) ? target : budgets_.group(g), region, work.spread);
    }
  }

  /// Step 4 for view v: every level's chosen candidates described and mapped back; a direct view's
  /// are its output as they are.
  void describe_view(int v, const Pyramid& pyramid, const cv::Mat& mask, ThreadWork& work) {
    ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      describe_level(v, l, pyramid, mask, work);
      if (direct(v)) {
        LevelWork& level = view.levels[static_cast<std::size_t>(l)];
        level.kept.resize(level.keypoints.size());
        std::iota(level.kept.begin(), level.kept.end(), 0);
      }
    }
  }

  /// Step 4 for the chosen candidates of view v, level l: orientation and descriptor in
  /// the view, keypoints mapped back (and, for a tilted view, refined on the original image:
  /// RefineOptions), appended to the level's record.
  void describe_level(int v, int l, const Pyramid& pyramid, const cv::Mat& mask, ThreadWork& work) {
    const LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
    const std::vector<int>& chosen = c.chosen;
    if (chosen.empty()) return;
    const ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    LevelWork& level = level_of(v, l);
    const cv::Matx23d& back = view.view.to_original;
    const bool identity = view.view.is_identity();
    work.describe_points.clear();
    for (int i : chosen) work.describe_points.push_back(c.level_points[static_cast<std::size_t>(i)]);
    descriptor_.prepare(pyramid.level(l), work.describe_points, work.descriptor_data);
    const float scale = static_cast<float>(options_.pyramid.scale(l) * std::sqrt(view.view.tilt));
    const int octave = std::min(l + octave_shift_[static_cast<std::size_t>(v)], options_.pyramid.levels - 1);
    for (int i : chosen) {
      const std::size_t k = static_cast<std::size_t>(i);
      const cv::Point2f p = c.level_points[k];
      const float angle = descriptor_.orientation(work.descriptor_data, p);
      level.descriptors.push_back(descriptor_.describe(work.descriptor_data, p, angle));
      // The direction (cos θ, sin θ) in the view, mapped to the original image.
      const double dx = back(0, 0) * std::cos(angle) + back(0, 1) * std::sin(angle);
      const double dy = back(1, 0) * std::cos(angle) + back(1, 1) * std::sin(angle);
      const float original_angle = identity ? angle : static_cast<float>(std::atan2(dy, dx));
      cv::Point2f position = c.original_points[k];
      if (!identity && options_.refine.enabled) {
        if (const std::optional<cv::Point2f> refined = refine_point(position, octave, mask)) position = *refined;
      }
      level.keypoints.emplace_back(position, Descriptor::kPatchSize * scale, radians_to_degrees_0_360(original_angle),
                                   c.responses[k], octave);
      level.original_points.push_back(c.original_points[k]);
      level.responses.push_back(c.responses[k]);
    }
  }

  /// Step 5 for the shortlisted views [first, last): their budgets with shortfalls carried among
  /// all their (view, level) groups, and each group's final selection among its shortlist.
  void select_shortlisted(cv::Size size, int first, int last) {
    const int levels = options_.pyramid.levels;
    available_.clear();
    for (int g = first * levels; g < last * levels; ++g) {
      available_.push_back(static_cast<int>(level_of(g / levels, g % levels).keypoints.size()));
    }
    budgets_.allocate(first * levels, last * levels, available_);
    for_each(last - first, [&](int i, int w) {
      ThreadWork& work = thread_work_[static_cast<std::size_t>(w)];
      for (int l = 0; l < levels; ++l) {
        LevelWork& level = level_of(i + first, l);
        spread(level.original_points, level.responses, spread_region(i + first, l, size),
               budgets_.take((i + first) * levels + l), work.spread);
        level.kept = work.spread.kept;
      }
    });
  }

  /// The output of views [first, last): keypoints grouped by octave (0 first), then by view, then
  /// level, then raster order in the view.
  Features<kBits> assemble(int first, int last) {
    const int levels = options_.pyramid.levels;
    octave_start_.assign(static_cast<std::size_t>(levels) + 1, 0);
    for (int v = first; v < last; ++v) {
      for (const LevelWork& level : view_work_[static_cast<std::size_t>(v)].levels) {
        for (int i : level.kept) {
          ++octave_start_[static_cast<std::size_t>(level.keypoints[static_cast<std::size_t>(i)].octave) + 1];
        }
      }
    }
    for (int o = 0; o < levels; ++o)
      octave_start_[static_cast<std::size_t>(o) + 1] += octave_start_[static_cast<std::size_t>(o)];
    const std::size_t total = static_cast<std::size_t>(octave_start_.back());
    Features<kBits> features;
    features.keypoints.resize(total);
    features.descriptors.resize(total);
    features.views.resize(total);
    for (int v = first; v < last; ++v) {
      for (const LevelWork& level : view_work_[static_cast<std::size_t>(v)].levels) {
        for (int i : level.kept) {
          const cv::KeyPoint& kp = level.keypoints[static_cast<std::size_t>(i)];
          const std::size_t slot = static_cast<std::size_t>(octave_start_[static_cast<std::size_t>(kp.octave)]++);
          features.keypoints[slot] = kp;
          features.descriptors[slot] = level.descriptors[static_cast<std::size_t>(i)];
          features.views[slot] = v;
        }
      }
    }
    return features;
  }

  // ---- The pieces the walk uses ---------------------------------------------------------------

  LevelWork& level_of(int v, int l) {
    return view_work_[static_cast<std::size_t>(v)].levels[static_cast<std::size_t>(l)];
  }

  bool additive() const { return options_.view_budget == ViewBudget::kAdditive; }
  bool merging() const { return options_.duplicates == DuplicatePolicy::kMerge; }

  /// Whether view v's keypoints are final when it is processed (the image with kAdditive, or the
  /// only view), rather than a shortlist chosen from once every view is done.
  bool direct(int v) const { return v == 0 && (additive() || view_work_.size() == 1); }

  /// The box, in original pixels, that the spreading of view v, level l divides: for the image (an
  /// identity view), the pixels of the level that can hold a candidate (the valid rectangle, at
  /// support_border() level pixels from the level's edges, from pixel edge to pixel edge), as
  /// ORB-SLAM2's octree divides the FAST region of the level; for a tilted view, whose valid region
  /// is not a rectangle in the original image, the whole image. The image's levels divide their
  /// candidate rectangle because the support border grows to 18·s^l original pixels: quadtree cells
  /// over the whole image would lie mostly outside it along the edges, and each would still keep one
  /// keypoint from a thin strip of candidates, crowding the border, where keypoints rarely match in
  /// the next frame (test_extractor checks the density along the edges).
  cv::Rect2f spread_region(int v, int l, cv::Size size) const {
    const ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    const cv::Rect2f image(0.0f, 0.0f, static_cast<float>(size.width), static_cast<float>(size.height));
    if (!view.view.is_identity()) return image;
    const cv::Rect valid = view.levels[static_cast<std::size_t>(l)].valid.bounds();
    if (valid.empty()) return image;
    const cv::Size level_size = pyramid_level_size(size, options_.pyramid, l);
    // Pixel edges x − 0.5 and x + 0.5 of the first and last valid pixels, in original pixels.
    const cv::Point2f tl = Pyramid::to_level0(cv::Point2f(valid.x - 0.5f, valid.y - 0.5f), size, level_size);
    const cv::Point2f br = Pyramid::to_level0(
        cv::Point2f(valid.x + valid.width - 0.5f, valid.y + valid.height - 0.5f), size, level_size);
    return cv::Rect2f(tl, br);
  }

  /// Support radius in level pixels around a candidate: the descriptor's and the ranking's.
  int support_border() const { return std::max(descriptor_.border(), options_.detector.support_radius()); }

  /// (Re)builds the view set, the renderers and the valid regions when the image size changes;
  /// buffers are kept otherwise.
  void prepare_views(cv::Size size) {
    if (size == views_size_ && !view_work_.empty()) return;
    const std::vector<AffineView> views = make_views(options_.views, size);
    view_work_.clear();
    view_work_.resize(views.size());
    tilts_.clear();
    octave_shift_.clear();
    cv::Size largest_tilted;
    for (std::size_t v = 0; v < views.size(); ++v) {
      ViewWork& work = view_work_[v];
      work.view = views[v];
      work.renderer = detail::ViewRenderer(views[v], options_.views.antialias);
      work.levels.resize(static_cast<std::size_t>(options_.pyramid.levels));
      work.regions.resize(static_cast<std::size_t>(options_.pyramid.levels));
      for (int l = 0; l < options_.pyramid.levels; ++l) {
        const cv::Size level_size = pyramid_level_size(work.view.size, options_.pyramid, l);
        work.levels[static_cast<std::size_t>(l)].valid =
            detail::support_region(work.view, size, level_size, support_border());
        work.regions[static_cast<std::size_t>(l)] = detail::region_near_image(
            detail::level_to_original(work.view, level_size), level_size, size, kRenderMargin);
      }
      if (v > 0) {
        largest_tilted.width = std::max(largest_tilted.width, work.view.size.width);
        largest_tilted.height = std::max(largest_tilted.height, work.view.size.height);
      }
      tilts_.push_back(views[v].tilt);
      // The level nearest (in log scale) to the scale s^l·√t is l + round(log √t / log s).
      octave_shift_.push_back(
          static_cast<int>(std::lround(0.5 * std::log(views[v].tilt) / std::log(options_.pyramid.scale_factor))));
    }
    budgets_.resize(views.size(), options_.pyramid.levels);
    // Every thread's buffers sized for the largest tilted view now, so that which thread gets
    // which view in later frames never makes one allocate.
    for (ThreadWork& work : thread_work_) {
      work.levels.resize(static_cast<std::size_t>(options_.pyramid.levels));
      if (largest_tilted.area() > 0) {
        work.pyramid.reserve(largest_tilted);
        detail::fit_buffer(work.detector.scores, largest_tilted, CV_8UC1);
      }
    }
    views_size_ = size;
  }

  /// Runs fn(i, w) for every i in [0, n), on options_.threads threads (the calling thread
  /// included, the others kept in pool_ from the first call on); w in [0, threads) numbers the
  /// thread, for per-thread scratch buffers. Indices are handed out in increasing order.
  template <class Fn>
  void for_each(int n, Fn fn) {
    if (options_.threads <= 1 || n <= 1) {
      for (int v = 0; v < n; ++v) fn(v, 0);
      return;
    }
    if (!pool_) pool_ = std::make_unique<detail::WorkerPool>(options_.threads);
    pool_->run(n, fn);
  }

  /// Keeps take of `points` by quadtree spreading or strength (ExtractorOptions::spreading), into
  /// spread.kept (ascending indices).
  void spread(const std::vector<cv::Point2f>& points, const std::vector<float>& responses, const cv::Rect2f& region,
              int target, SpreadWork& work) const {
    if (options_.spreading == Spreading::kQuadtree) {
      distribute_quadtree(points, responses, region, target, work.quadtree, work.kept);
    } else {
      select_strongest(responses, target, work.kept);
    }
  }

  /// Enters in the repeat grid of level l what later views must not repeat of the chosen
  /// candidates of `c`: those a selection of `take` among them keeps (all of them when they are
  /// the final keypoints; for a shortlist, its nominal budget: the final selection when no
  /// shortfall is carried, so that the rest of the shortlist suppresses nothing).
  void enter_repeat_references(const LevelCandidates& c, int l, int take, const cv::Rect2f& region, SpreadWork& work) {
    // Both selections keep exactly min(take, n) of n: with take >= n, every chosen candidate.
    if (take >= static_cast<int>(c.chosen.size())) {
      for (int i : c.chosen) repeats_.enter(c.original_points[static_cast<std::size_t>(i)], l);
      return;
    }
    work.points.clear();
    work.responses.clear();
    for (int i : c.chosen) {
      work.points.push_back(c.original_points[static_cast<std::size_t>(i)]);
      work.responses.push_back(c.responses[static_cast<std::size_t>(i)]);
    }
    spread(work.points, work.responses, region, take, work);
    for (int k : work.kept) repeats_.enter(work.points[static_cast<std::size_t>(k)], l);
  }

  /// Enters the final keypoints of view v (its kept ones, unrefined positions) in the repeat grids.
  void enter_kept(int v) {
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      const LevelWork& level = level_of(v, l);
      for (int i : level.kept) repeats_.enter(level.original_points[static_cast<std::size_t>(i)], l);
    }
  }

  /// RefineOptions: the strongest FAST corner of the original image's level o within
  /// options_.refine.radius level-o pixels of `point` (original pixels), as a level-0 point, if
  /// one scores at least the detector's minimum threshold and lies where the mask allows (ties:
  /// the nearer pixel, then raster order).
  std::optional<cv::Point2f> refine_point(cv::Point2f point, int o, const cv::Mat& mask) const {
    const Pyramid& original = image_pyramid_;
    const cv::Mat& level = original.level(o);
    const cv::Size base = original.level(0).size();
    const double rx = static_cast<double>(base.width) / level.cols;
    const double ry = static_cast<double>(base.height) / level.rows;
    const double x = (point.x + 0.5) / rx - 0.5;
    const double y = (point.y + 0.5) / ry - 0.5;
    const int cx = static_cast<int>(std::lround(x));
    const int cy = static_cast<int>(std::lround(y));
    const int radius = options_.refine.radius;
    int best_score = -1;
    double best_distance = 0.0;
    cv::Point best;
    for (int py = std::max(cy - radius, kFastRadius); py <= std::min(cy + radius, level.rows - 1 - kFastRadius); ++py) {
      for (int px = std::max(cx - radius, kFastRadius); px <= std::min(cx + radius, level.cols - 1 - kFastRadius);
           ++px) {
        const int score = fast_score(level.ptr<std::uint8_t>(py) + px, static_cast<std::ptrdiff_t>(level.step[0]));
        if (score < options_.detector.min_threshold) continue;
        const double distance = (px - x) * (px - x) + (py - y) * (py - y);
        if (score > best_score || (score == best_score && distance < best_distance)) {
          best_score = score;
          best_distance = distance;
          best = {px, py};
        }
      }
    }
    if (best_score < 0) return std::nullopt;
    const cv::Point2f refined =
        Pyramid::to_level0(cv::Point2f(static_cast<float>(best.x), static_cast<float>(best.y)), base, level.size());
    if (!mask.empty() && mask.at<std::uint8_t>(cvRound(refined.y), cvRound(refined.x)) == 0) return std::nullopt;
    return refined;
  }

  ExtractorOptions options_;
  Descriptor descriptor_;
  /// Per view (fixed for a view set, prepare_views()): its tilt, and the octave shift: a keypoint
  /// of its level l has the octave min(l + shift, levels − 1), the level nearest to its scale
  /// s^l·√t.
  std::vector<double> tilts_;
  std::vector<int> octave_shift_;
  /// Nominal budget and final take of every (view, level), set per run.
  detail::ViewBudgets budgets_;
  /// Per run: what each (view, level) of the groups being allocated offers.
  std::vector<int> available_;
  /// DuplicatePolicy::kMerge: the keypoints chosen by the views processed so far.
  detail::RepeatGrids repeats_;
  std::vector<int> octave_start_;  ///< buffer of assemble()
  cv::Size views_size_;
  std::vector<ViewWork> view_work_;
  /// The image's pyramid, kept until the next call (pyramid(), RefineOptions).
  Pyramid image_pyramid_;
  /// Views on demand: the image and mask of extract_image() and how many views are extracted (0:
  /// no staged extraction under way).
  cv::Mat staged_image_;
  cv::Mat staged_mask_;
  int staged_views_ = 0;
  /// Per worker thread: the buffers views are processed in.
  std::vector<ThreadWork> thread_work_;
  std::unique_ptr<detail::ViewTurns> turns_;
  /// The worker threads when options_.threads > 1, started by the first extract().
  std::unique_ptr<detail::WorkerPool> pool_;
};

}  // namespace affine_orb
