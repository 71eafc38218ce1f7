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
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/affine_views.hpp"
#include "affine_orb/descriptor.hpp"
#include "affine_orb/detail/buffer.hpp"
#include "affine_orb/detail/check.hpp"
#include "affine_orb/detail/row_spans.hpp"
#include "affine_orb/detail/view_regions.hpp"
#include "affine_orb/detail/worker_pool.hpp"
#include "affine_orb/detector.hpp"
#include "affine_orb/distribution.hpp"
#include "affine_orb/fast.hpp"
#include "affine_orb/features.hpp"
#include "affine_orb/pyramid.hpp"

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
  /// is not affine invariant), so snapping cost 4–25 % of the distinct correct matches on graf 1→2
  /// … 1→6 (bench/eval_viewpoint) and raised the median KITTI 06 frame-to-frame rotation error at
  /// K = 1 from 0.105° to 0.142° (affine_orb_sequence); the mapped position is already within
  /// Features' stated precision.
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
  /// Default 1, measured on the 31 Oxford pairs of bench/eval_viewpoint at 2000 keypoints in all:
  /// 1000 + 1000 found 7515 distinct correct matches in all, 500 + 1500 (3) 7307, the area split
  /// 6979; 3 does better only from about 40° of viewpoint change (graf 1→4 / 1→5 / 1→6: 147 / 72 /
  /// 51 against 123 / 71 / 50) — figures of the whole-frame selection before shortlists (with
  /// them the default finds 7352). Must be in [0, 16]; ignored with kAreaSplit or max_tilt < √2.
  double view_features = 1.0;
  /// ViewBudget::kAdditive: the tilted views share the views' budget in proportion to t^e for this
  /// exponent e. −1 is ASIFT's area weighting (a view of tilt t has 1/t of the image's pixels), 0
  /// equal shares; 1 (the more tilted views, which find what the image cannot, get more) measured
  /// best in bench/eval_viewpoint at 1000 + 1000 keypoints: 7515 distinct correct matches over the
  /// 31 Oxford pairs against 7464 (0) and 7403 (−1), graf 1→4 / 1→5 / 1→6 123 / 71 / 50 against
  /// 120 / 66 / 49 and 116 / 59 / 36, for 414 against 421 and 429 at 1→2 (whole-frame selection,
  /// before shortlists). Must be in [−4, 4].
  double view_weight_exponent = 1.0;
  DuplicatePolicy duplicates = DuplicatePolicy::kMerge;
  /// DuplicatePolicy::kMerge: a candidate of view v, level l is a repeat, and dropped before its
  /// view's selection, when a keypoint chosen by an earlier view (lower index; the image is view 0)
  /// of a level l' with |l − l'| <= repeat_levels lies within merge_radius · s^max(l, l') original
  /// pixels. "Chosen" is the final keypoints for the image with kAdditive and, for a shortlist
  /// (ExtractorOptions::shortlist), what it keeps at its nominal budget. 0 (the same level only):
  /// measured best for matching two images in bench/eval_viewpoint at 1000 + 1000 keypoints: 1
  /// found 7326 distinct correct matches over the 31 Oxford pairs against 7352, and 415 / 212 /
  /// 111 / 65 / 40 on graf 1→2 … 1→6 against 440 / 215 / 116 / 62 / 49 (a corner's copy at the
  /// next level is not a wasted keypoint there). Must be in [0, 4].
  int repeat_levels = 0;
  /// Location of the tilted views' keypoints in the original image.
  RefineOptions refine;
  /// With several views: a view's pixels exist only while it is processed (one view's buffers per
  /// thread, issue 16), so each (view, level) whose final share depends on the other views (every
  /// tilted view with kAdditive, every view with kAreaSplit) describes a shortlist of up to
  /// ceil(shortlist · its nominal budget) of its candidates, spread as the final selection is;
  /// once every view is done, the carrying of shortfalls and the final spreading choose among the
  /// shortlists. Above 1 it leaves room for carried shortfalls; larger costs description time
  /// and, with kQuadtree, moves the final choice away from the spreading of all candidates.
  /// 1.25 measured in bench/eval_viewpoint (31 Oxford pairs, 1000 + 1000 keypoints): quadtree
  /// spreading found 6043 distinct correct matches in all against 5995 with 2; with kStrongest
  /// the value makes no difference (7352). Must be in [1, 64].
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
/// 3. ViewBudget::kAdditive: the image (view 0) keeps `features` of its candidates exactly as
///    with max_tilt = 1 (step 4 on its own) and describes them; a tilted view, with
///    DuplicatePolicy::kMerge, drops its candidates that repeat a keypoint the image kept
///    (ExtractorOptions::repeat_levels), then describes a shortlist of each level
///    (ExtractorOptions::shortlist). ViewBudget::kAreaSplit: every view describes shortlists;
/// 4. once every view is done, with kMerge, shortlisted keypoints that repeat a stronger one of
///    another view are dropped (kAdditive: ExtractorOptions::repeat_levels; kAreaSplit: the same
///    level within merge_radius · s^l original pixels); then a budget is split over views
///    (kAreaSplit: `features`, in proportion to their area 1/t; kAdditive: view_features ·
///    features over the tilted views, in proportion to t^view_weight_exponent) and, within a view,
///    over levels geometrically (level_budgets()); shortfalls are carried (allocate_with_carry());
///    each (view, level) keeps its share by quadtree spreading (distribute_quadtree()) in original
///    coordinates, or its strongest keypoints (select_strongest()), per ExtractorOptions::spreading;
/// 5. keypoints are oriented and described in their view, then mapped back: position through the
///    inverse view map, orientation by mapping the direction vector, scale s^l·√t (SPEC §1); a
///    tilted view's keypoint is then snapped to a corner of the original image (RefineOptions).
///
/// Output order: by octave (0 first), then by view, then by level, then raster order in the view.
/// The output does not depend on ExtractorOptions::threads.
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
        turns_(std::make_unique<Turns>()) {}

  const ExtractorOptions& options() const { return options_; }
  const Descriptor& descriptor() const { return descriptor_; }

  /// The views used for the last image passed to extract() (empty before the first call).
  std::vector<AffineView> views() const {
    std::vector<AffineView> out;
    for (const ViewWork& w : view_work_) out.push_back(w.view);
    return out;
  }

  /// The pyramid of the original (untilted) image of the last extract() call.
  const Pyramid& pyramid() const {
    detail::require(!view_work_.empty() && !image_pyramid_.empty(), "Extractor::pyramid: extract() was not called yet");
    return image_pyramid_;
  }

  /// Keypoints (original pixel coordinates) and descriptors of a CV_8UC1 image (a ROI of a larger
  /// matrix is fine); see Features for the keypoint fields.
  ///
  /// `mask`: empty (everything allowed) or CV_8UC1 of the image size; a keypoint is kept only where
  /// the mask pixel nearest to its original position is non-zero.
  ///
  /// Throws std::invalid_argument for an empty image, a type other than CV_8UC1, or a mask of the
  /// wrong size or type. A valid image with no corners (flat, or smaller than the descriptor
  /// support on every level) gives an empty result.
  Features<kBits> extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    detail::require_gray8(image, "Extractor::extract");
    detail::require_mask(mask, image.size(), "Extractor::extract");
    prepare_views(image.size());
    const int n_views = static_cast<int>(view_work_.size());
    take_.assign(budgets_.size(), 0);
    if (merging()) reset_repeat_grids(image.size());
    turns_->reset();
    for_each(n_views, [&](int v, int w) { process_view(v, image, mask, thread_work_[static_cast<std::size_t>(w)]); });
    if (n_views > 1) select_across_views(image.size());
    return assemble();
  }

 private:
  /// Buffers of the budget step of one thread, reused across frames.
  struct SpreadWork {
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    std::vector<int> kept;
    QuadtreeWorkspace quadtree;
  };

  /// A keypoint accepted by the repeat suppression, in the grid of its level.
  struct RepeatKept {
    cv::Point2f point;
    int next;  ///< next accepted keypoint of the same cell, −1 at the end
  };
  /// Accepted keypoints of one level l on a grid of cells merge_radius · s^(l + repeat_levels)
  /// wide: the largest radius a point of l is compared with, so a 3x3 block of cells holds them all.
  struct RepeatGrid {
    double radius_squared = 1.0;  ///< (merge_radius · s^l)², the repeat radius of level l squared
    double cell = 1.0;
    int columns = 0;
    std::vector<int> head;  ///< per cell, the last accepted keypoint in it (−1: none)
    std::size_t index(cv::Point2f p, int dx, int dy) const {
      const int cx = static_cast<int>(std::floor(p.x / cell)) + 2 + dx;
      const int cy = static_cast<int>(std::floor(p.y / cell)) + 2 + dy;
      return static_cast<std::size_t>(cy) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(cx);
    }
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
    int budget = 0;  ///< the view's nominal budget, summed over its levels
  };

  /// Gives the views their turn in index order for what depends on the views before them (the
  /// repeat suppression, the image's pyramid for RefineOptions) while they render, detect and
  /// describe in parallel. WorkerPool hands out views in increasing order, so a thread waiting
  /// for its turn waits for views already being processed: no deadlock, and the output does not
  /// depend on the number of threads.
  struct Turns {
    std::mutex mutex;
    std::condition_variable changed;
    int next = 0;         ///< the view whose turn it is
    bool failed = false;  ///< a view threw: no turn comes any more

    void reset() {
      const std::lock_guard<std::mutex> lock(mutex);
      next = 0;
      failed = false;
    }
    /// Waits for view v's turn; false when a view failed (its exception is the one extract()
    /// rethrows).
    bool wait(int v) {
      std::unique_lock<std::mutex> lock(mutex);
      changed.wait(lock, [&] { return failed || next == v; });
      return !failed;
    }
    void pass(int v) {
      {
        const std::lock_guard<std::mutex> lock(mutex);
        next = v + 1;
      }
      changed.notify_all();
    }
    void fail() {
      {
        const std::lock_guard<std::mutex> lock(mutex);
        failed = true;
      }
      changed.notify_all();
    }
  };

  LevelWork& level_of(int v, int l) {
    return view_work_[static_cast<std::size_t>(v)].levels[static_cast<std::size_t>(l)];
  }

  bool additive() const { return options_.view_budget == ViewBudget::kAdditive; }
  bool merging() const { return options_.duplicates == DuplicatePolicy::kMerge; }

  /// Whether view v's keypoints are final when it is processed (the image with kAdditive, or the
  /// only view), rather than a shortlist chosen from once every view is done.
  bool direct(int v) const { return v == 0 && (additive() || view_work_.size() == 1); }

  /// (Re)builds the view set, the renderers and the valid regions when the image size changes;
  /// buffers are kept otherwise.
  void prepare_views(cv::Size size) {
    if (size == views_size_ && !view_work_.empty()) return;
    const std::vector<AffineView> views = make_views(options_.views, size);
    view_work_.clear();
    view_work_.resize(views.size());
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
    }
    budgets_.clear();
    std::vector<int> per_view;
    if (additive()) {
      per_view = view_budgets(1, static_cast<int>(std::lround(options_.view_features * options_.features)),
                              options_.view_weight_exponent);
      per_view.front() = options_.features;
    } else {
      per_view = view_budgets(0, options_.features, -1.0);
    }
    octave_shift_.clear();
    for (const AffineView& view : views) {
      // The level nearest (in log scale) to the scale s^l·√t is l + round(log √t / log s).
      octave_shift_.push_back(
          static_cast<int>(std::lround(0.5 * std::log(view.tilt) / std::log(options_.pyramid.scale_factor))));
    }
    for (std::size_t v = 0; v < views.size(); ++v) {
      const std::vector<int> per_level =
          level_budgets(per_view[v], options_.pyramid.scale_factor, options_.pyramid.levels);
      budgets_.insert(budgets_.end(), per_level.begin(), per_level.end());
      view_work_[v].budget = per_view[v];
    }
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

  /// Margin in level pixels around the original image within which a view and its pyramid levels
  /// are computed: more than the reach beyond a valid keypoint's support of the rBRIEF smoothing
  /// (3 level pixels) and of the bilinear interpolation between levels.
  static constexpr double kRenderMargin = 8.0;

  /// Support radius in level pixels around a candidate: the descriptor's and the ranking's.
  int support_border() const { return std::max(descriptor_.border(), options_.detector.support_radius()); }

  /// Runs fn(i, w) for every i in [0, n), on options_.threads threads (the calling thread
  /// included, the others kept in pool_ from the first call on); w in [0, threads) numbers the
  /// thread, for per-thread scratch buffers.
  template <class Fn>
  void for_each(int n, Fn fn) {
    if (options_.threads <= 1 || n <= 1) {
      for (int v = 0; v < n; ++v) fn(v, 0);
      return;
    }
    if (!pool_) pool_ = std::make_unique<detail::WorkerPool>(options_.threads);
    pool_->run(n, fn);
  }

  /// Budget of each view: views [first, n) share `total` in proportion to t^exponent (largest
  /// remainders, ties to the earlier view); views before `first` get 0. Exponent −1 weights by
  /// area W·H/t.
  std::vector<int> view_budgets(std::size_t first, int total, double exponent) const {
    const std::size_t n = view_work_.size();
    std::vector<int> budgets(n, 0);
    if (first >= n) return budgets;
    double total_weight = 0.0;
    for (std::size_t v = first; v < n; ++v) total_weight += std::pow(view_work_[v].view.tilt, exponent);
    std::vector<std::pair<double, std::size_t>> remainders;
    int assigned = 0;
    for (std::size_t v = first; v < n; ++v) {
      const double exact = total * std::pow(view_work_[v].view.tilt, exponent) / total_weight;
      budgets[v] = static_cast<int>(std::floor(exact));
      assigned += budgets[v];
      remainders.emplace_back(exact - budgets[v], v);
    }
    std::stable_sort(remainders.begin(), remainders.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t i = 0; assigned < total; ++i, ++assigned) ++budgets[remainders[i % remainders.size()].second];
    return budgets;
  }

  /// take_[g] for the (view, level) groups g in [begin, end) (index v·levels + l): their budgets
  /// with shortfalls carried among them (allocate_with_carry()), given available_[g − begin], what
  /// each offers.
  void take_range(int begin, int end) {
    range_budgets_.assign(budgets_.begin() + begin, budgets_.begin() + end);
    allocate_with_carry(range_budgets_, available_, range_take_);
    std::copy(range_take_.begin(), range_take_.end(), take_.begin() + begin);
  }

  /// Steps 1–3 and 5 for view v on the thread owning `work`.
  void process_view(int v, const cv::Mat& image, const cv::Mat& mask, ThreadWork& work) {
    try {
      process(v, image, mask, work);
    } catch (...) {
      turns_->fail();
      throw;
    }
  }

  /// Render, pyramid and candidates; in view v's turn, the repeats dropped and the keypoints to
  /// describe chosen (the final ones when direct(), else the shortlists), entered in the repeat
  /// grids; after the turn, their description.
  void process(int v, const cv::Mat& image, const cv::Mat& mask, ThreadWork& work) {
    ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    const int levels = options_.pyramid.levels;
    for (LevelWork& level : view.levels) level.clear();
    const bool empty = v != 0 && view.budget == 0;  // nothing of it could be kept
    Pyramid& pyramid = v == 0 ? image_pyramid_ : work.pyramid;
    if (!empty) {
      view.renderer.render(image, &view.regions.front(), work.scratch, pyramid.level0(view.view.size));
      pyramid.build_from_level0(view.view.is_identity() ? nullptr : &view.regions);
      detect_view(v, image, mask, pyramid, work);
    }
    if (!turns_->wait(v)) return;
    if (empty) {
      turns_->pass(v);
      return;
    }
    if (merging()) drop_repeats(v, work);
    const cv::Rect2f region(0.0f, 0.0f, static_cast<float>(image.cols), static_cast<float>(image.rows));
    if (direct(v)) {
      available_.clear();
      for (const LevelCandidates& c : work.levels) available_.push_back(static_cast<int>(c.responses.size()));
      take_range(0, levels);
    }
    for (int l = 0; l < levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      const std::size_t g = static_cast<std::size_t>(v * levels + l);
      const int target = direct(v) ? take_[g]
                                   : static_cast<int>(std::min<double>(static_cast<double>(c.responses.size()),
                                                                       std::ceil(options_.shortlist * budgets_[g])));
      spread(c.original_points, c.responses, region, target, work.spread);
      c.chosen = work.spread.kept;
      if (merging()) enter_repeat_references(c, l, direct(v) ? target : budgets_[g], region, work.spread);
    }
    turns_->pass(v);
    for (int l = 0; l < levels; ++l) {
      describe_level(v, l, pyramid, mask, work);
      if (direct(v)) {
        LevelWork& level = view.levels[static_cast<std::size_t>(l)];
        level.kept.resize(level.keypoints.size());
        std::iota(level.kept.begin(), level.kept.end(), 0);
      }
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

  /// Step 5 for the chosen candidates of view v, level l: orientation and descriptor in
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

  /// Step 4, once every view is done: the budget with carried shortfalls over the views whose
  /// keypoints are shortlists, and each one's final selection among its shortlist.
  void select_across_views(cv::Size size) {
    const int n_views = static_cast<int>(view_work_.size());
    const int levels = options_.pyramid.levels;
    const int first = additive() ? 1 : 0;
    available_.clear();
    for (int g = first * levels; g < n_views * levels; ++g) {
      available_.push_back(static_cast<int>(level_of(g / levels, g % levels).keypoints.size()));
    }
    take_range(first * levels, n_views * levels);
    const cv::Rect2f region(0.0f, 0.0f, static_cast<float>(size.width), static_cast<float>(size.height));
    for_each(n_views - first, [&](int i, int w) {
      ThreadWork& work = thread_work_[static_cast<std::size_t>(w)];
      for (int l = 0; l < levels; ++l) {
        LevelWork& level = level_of(i + first, l);
        spread(level.original_points, level.responses, region,
               take_[static_cast<std::size_t>((i + first) * levels + l)], work.spread);
        level.kept = work.spread.kept;
      }
    });
  }

  /// DuplicatePolicy::kMerge: empties the repeat grids, one per level l with cells
  /// merge_radius · s^(l + repeat_levels) wide over the original image.
  void reset_repeat_grids(cv::Size size) {
    const int levels = options_.pyramid.levels;
    const int reach = options_.repeat_levels;
    repeat_grids_.resize(static_cast<std::size_t>(levels));
    for (int l = 0; l < levels; ++l) {
      RepeatGrid& grid = repeat_grids_[static_cast<std::size_t>(l)];
      const double radius = options_.merge_radius * options_.pyramid.scale(l);
      grid.radius_squared = radius * radius;
      grid.cell = options_.merge_radius * options_.pyramid.scale(std::min(l + reach, levels - 1));
      // Points lie in [−0.5, W − 0.5) x [−0.5, H − 0.5): cells floor(x / cell) + 2 ± 1 stay inside.
      grid.columns = static_cast<int>(std::floor(size.width / grid.cell)) + 5;
      const int rows = static_cast<int>(std::floor(size.height / grid.cell)) + 5;
      grid.head.assign(static_cast<std::size_t>(grid.columns) * static_cast<std::size_t>(rows), -1);
    }
    repeat_kept_.clear();
  }

  /// Enters in the repeat grid of level l what later views must not repeat of the chosen
  /// candidates of `c`: those a selection of `take` among them keeps (all of them when they are
  /// the final keypoints; for a shortlist, its nominal budget: the final selection when no
  /// shortfall is carried, so that the rest of the shortlist suppresses nothing).
  void enter_repeat_references(const LevelCandidates& c, int l, int take, const cv::Rect2f& region, SpreadWork& work) {
    RepeatGrid& grid = repeat_grids_[static_cast<std::size_t>(l)];
    const auto enter = [&](cv::Point2f p) {
      int& head = grid.head[grid.index(p, 0, 0)];
      repeat_kept_.push_back({p, head});
      head = static_cast<int>(repeat_kept_.size()) - 1;
    };
    // Both selections keep exactly min(take, n) of n: with take >= n, every chosen candidate.
    if (take >= static_cast<int>(c.chosen.size())) {
      for (int i : c.chosen) enter(c.original_points[static_cast<std::size_t>(i)]);
      return;
    }
    work.points.clear();
    work.responses.clear();
    for (int i : c.chosen) {
      work.points.push_back(c.original_points[static_cast<std::size_t>(i)]);
      work.responses.push_back(c.responses[static_cast<std::size_t>(i)]);
    }
    spread(work.points, work.responses, region, take, work);
    for (int k : work.kept) enter(work.points[static_cast<std::size_t>(k)]);
  }

  /// Whether a candidate of level l at p (original pixels) repeats a keypoint chosen by an
  /// earlier view: one of a level l' with |l − l'| <= repeat_levels within merge_radius ·
  /// s^max(l, l').
  bool repeats(cv::Point2f p, int l) const {
    const int levels = options_.pyramid.levels;
    const int reach = options_.repeat_levels;
    for (int q = std::max(l - reach, 0); q <= std::min(l + reach, levels - 1); ++q) {
      const RepeatGrid& grid = repeat_grids_[static_cast<std::size_t>(q)];
      const double radius_squared = repeat_grids_[static_cast<std::size_t>(std::max(l, q))].radius_squared;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          for (int k = grid.head[grid.index(p, dx, dy)]; k >= 0; k = repeat_kept_[static_cast<std::size_t>(k)].next) {
            const cv::Point2f e = repeat_kept_[static_cast<std::size_t>(k)].point;
            const double ex = e.x - p.x;
            const double ey = e.y - p.y;
            if (ex * ex + ey * ey < radius_squared) return true;
          }
        }
      }
    }
    return false;
  }

  /// DuplicatePolicy::kMerge, in view v's turn: drops its candidates that repeat a keypoint chosen
  /// by an earlier view (repeats()).
  void drop_repeats(int v, ThreadWork& work) const {
    if (v == 0) return;
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      std::size_t n = 0;
      for (std::size_t i = 0; i < c.responses.size(); ++i) {
        if (repeats(c.original_points[i], l)) continue;
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

  /// The output: keypoints grouped by octave (0 first), then by view, then level, then raster order
  /// in the view.
  Features<kBits> assemble() {
    const int levels = options_.pyramid.levels;
    octave_start_.assign(static_cast<std::size_t>(levels) + 1, 0);
    for (const ViewWork& w : view_work_) {
      for (const LevelWork& level : w.levels) {
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
    for (std::size_t v = 0; v < view_work_.size(); ++v) {
      for (const LevelWork& level : view_work_[v].levels) {
        for (int i : level.kept) {
          const cv::KeyPoint& kp = level.keypoints[static_cast<std::size_t>(i)];
          const std::size_t slot = static_cast<std::size_t>(octave_start_[static_cast<std::size_t>(kp.octave)]++);
          features.keypoints[slot] = kp;
          features.descriptors[slot] = level.descriptors[static_cast<std::size_t>(i)];
          features.views[slot] = static_cast<int>(v);
        }
      }
    }
    return features;
  }

  ExtractorOptions options_;
  Descriptor descriptor_;
  /// Budget of each (view, level), index v·levels + l: views as ExtractorOptions::view_budget
  /// says, levels geometric within a view (fixed for a view set, computed by prepare_views()).
  std::vector<int> budgets_;
  /// Per frame: what each (view, level) takes (allocate_with_carry()); the candidates offered,
  /// budgets and result of the groups take_range() allocates.
  std::vector<int> take_;
  std::vector<int> available_;
  std::vector<int> range_budgets_;
  std::vector<int> range_take_;
  /// Per view (fixed for a view set, prepare_views()): a keypoint of its level l has the octave
  /// min(l + octave_shift_, levels − 1), the level nearest to its scale s^l·√t.
  std::vector<int> octave_shift_;
  /// The repeat grids (kMerge) and the buffer of assemble().
  std::vector<RepeatKept> repeat_kept_;
  std::vector<RepeatGrid> repeat_grids_;
  std::vector<int> octave_start_;
  cv::Size views_size_;
  std::vector<ViewWork> view_work_;
  /// The image's pyramid, kept until the next call (pyramid(), RefineOptions).
  Pyramid image_pyramid_;
  /// Per worker thread: the buffers views are processed in.
  std::vector<ThreadWork> thread_work_;
  std::unique_ptr<Turns> turns_;
  /// The worker threads when options_.threads > 1, started by the first extract().
  std::unique_ptr<detail::WorkerPool> pool_;
};

}  // namespace affine_orb
