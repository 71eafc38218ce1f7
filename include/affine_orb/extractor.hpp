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
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/affine_views.hpp"
#include "affine_orb/descriptor.hpp"
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
  kMerge,    ///< Drop the keypoints that repeat a stronger one: with ViewBudget::kAdditive, see
             ///< ExtractorOptions::repeat_octaves; with kAreaSplit, the keypoints of one level that
             ///< other views put within ExtractorOptions::merge_radius of a stronger one.
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
  /// 51 against 123 / 71 / 50). Must be in [0, 16]; ignored with kAreaSplit or max_tilt < √2.
  double view_features = 1.0;
  /// ViewBudget::kAdditive: the tilted views share the views' budget in proportion to t^e for this
  /// exponent e. −1 is ASIFT's area weighting (a view of tilt t has 1/t of the image's pixels), 0
  /// equal shares; 1 (the more tilted views, which find what the image cannot, get more) measured
  /// best in bench/eval_viewpoint at 1000 + 1000 keypoints: 7515 distinct correct matches over the
  /// 31 Oxford pairs against 7464 (0) and 7403 (−1), graf 1→4 / 1→5 / 1→6 123 / 71 / 50 against
  /// 120 / 66 / 49 and 116 / 59 / 36, for 414 against 421 and 429 at 1→2. Must be in [−4, 4].
  double view_weight_exponent = 1.0;
  DuplicatePolicy duplicates = DuplicatePolicy::kMerge;
  /// ViewBudget::kAdditive with DuplicatePolicy::kMerge: a tilted-view candidate of level l is a
  /// repeat, and dropped before the budget, when a keypoint the image kept, or a stronger candidate
  /// of another view (or of another level of its own view), of a level l' with |l − l'| <=
  /// repeat_levels lies within merge_radius · s^max(l, l') original pixels. 0 (the same level
  /// only): measured best for matching two images in bench/eval_viewpoint at 1000 + 1000
  /// keypoints (1 found 2–13 % fewer distinct correct matches on graf 1→2 … 1→6 and 2.4 % fewer
  /// over the 31 Oxford pairs: a corner's copy at the next level is not a wasted keypoint there).
  /// Must be in [0, 4].
  int repeat_levels = 0;
  /// Location of the tilted views' keypoints in the original image.
  RefineOptions refine;
  /// Radius in original pixels, times the level scale s^l, within which kMerge treats keypoints of
  /// different views on the same level as one; 2 px is the SPEC §7 duplicate cell size.
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
/// For an image of size W x H and every view v of ExtractorOptions::views (affine_views.hpp):
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
///    with max_tilt = 1 (step 4 on its own); then, with DuplicatePolicy::kMerge, the tilted views'
///    candidates that repeat a kept image keypoint or a stronger tilted candidate are dropped
///    (ExtractorOptions::repeat_levels), and the tilted views share view_features · features.
///    ViewBudget::kAreaSplit: with kMerge, candidates of one level that other views put within
///    merge_radius · s^l original pixels of a stronger one are dropped, and all views share
///    `features`;
/// 4. a budget is split over views (kAreaSplit: in proportion to their area 1/t; kAdditive, over
///    the tilted views: to t^view_weight_exponent) and, within a view, over
///    levels geometrically (level_budgets()); shortfalls are carried (allocate_with_carry()); each
///    (view, level) keeps its share by quadtree spreading (distribute_quadtree()) in original
///    coordinates, or its strongest candidates (select_strongest()), per
///    ExtractorOptions::spreading;
/// 5. kept keypoints are oriented and described in their view, then mapped back: position through
///    the inverse view map, orientation by mapping the direction vector, scale s^l·√t (SPEC §1);
///    a tilted view's keypoint is then snapped to a corner of the original image (RefineOptions).
///
/// Output order: by octave (0 first), then by view, then by level, then raster order in the view.
///
/// An Extractor holds a workspace reused across calls (and, with ExtractorOptions::threads > 1, its
/// worker threads): it can be moved, not copied. One instance must not be used by two threads at
/// once; separate instances share nothing.
template <class Descriptor>
class Extractor {
 public:
  static constexpr int kBits = Descriptor::kBits;
  using DescriptorOptions = typename Descriptor::Options;

  explicit Extractor(ExtractorOptions options = {}, DescriptorOptions descriptor_options = {})
      : options_((options.check(), options)), descriptor_(descriptor_options) {}

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
    detail::require(!view_work_.empty(), "Extractor::pyramid: extract() was not called yet");
    return view_work_.front().pyramid;
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
    const int levels = options_.pyramid.levels;
    const std::size_t threads = static_cast<std::size_t>(options_.threads);

    scratch_.resize(threads);
    merge_.resize(threads);
    spread_.resize(threads);
    for_each(n_views, [&](int v, int w) {
      detect_view(image, mask, view_work_[static_cast<std::size_t>(v)], scratch_[static_cast<std::size_t>(w)]);
    });
    const cv::Rect2f region(0.0f, 0.0f, static_cast<float>(image.cols), static_cast<float>(image.rows));
    take_.assign(budgets_.size(), 0);
    if (options_.view_budget == ViewBudget::kAdditive) {
      // The image first, alone, exactly as with max_tilt = 1; then the tilted views around it.
      take_range(0, levels);
      for_each(levels, [&](int l, int w) { spread_level(0, l, region, spread_[static_cast<std::size_t>(w)]); });
      if (n_views > 1) {
        if (options_.duplicates == DuplicatePolicy::kMerge) suppress_repeats(image.size());
        take_range(levels, n_views * levels);
        for_each(n_views - 1, [&](int v, int w) {
          for (int l = 0; l < levels; ++l) spread_level(v + 1, l, region, spread_[static_cast<std::size_t>(w)]);
        });
      }
    } else {
      if (options_.duplicates == DuplicatePolicy::kMerge && n_views > 1) merge_duplicates(image.size());
      take_range(0, n_views * levels);
      for_each(n_views, [&](int v, int w) {
        for (int l = 0; l < levels; ++l) spread_level(v, l, region, spread_[static_cast<std::size_t>(w)]);
      });
    }
    for_each(n_views, [&](int v, int) { describe_view(v, mask); });
    return assemble();
  }

 private:
  /// A candidate in merge order, with its original position copied so that the visit in that
  /// order reads memory sequentially.
  struct MergeRef {
    float response;
    int view;
    int index;
    cv::Point2f point;
  };
  struct MergeKept {
    cv::Point2f point;
    int view;
    int next;  ///< next kept candidate of the same cell, −1 at the end
  };
  /// Buffers of merge_duplicates() reused across frames.
  struct MergeWork {
    std::vector<MergeRef> order;
    std::vector<int> head;  ///< per grid cell, the last kept candidate in it (−1: none)
    std::vector<MergeKept> kept;
  };

  /// Buffers of the budget step of one thread, reused across frames.
  struct SpreadWork {
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    std::vector<int> kept;
    QuadtreeWorkspace quadtree;
  };

  /// A tilted-view candidate in repeat-suppression order (suppress_repeats()).
  struct RepeatRef {
    float response;
    int view;
    int level;
    int index;
    cv::Point2f point;
  };
  /// A keypoint accepted by suppress_repeats(), in the grid of its level.
  struct RepeatKept {
    cv::Point2f point;
    int view;
    int level;
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

  struct LevelWork {
    RowSpans valid;  ///< level pixels whose support maps inside the original image (image-size dependent)
    Candidates candidates;
    std::vector<cv::Point2f> level_points;     ///< candidate positions, level pixels of the view
    std::vector<cv::Point2f> original_points;  ///< the same, original pixels
    std::vector<float> responses;
    std::vector<int> alive;        ///< candidates that survived the support, mask and duplicate checks
    std::vector<char> keep_flags;  ///< merge_duplicates(): candidate kept
    std::vector<int> kept;         ///< candidates chosen by the budget
    std::vector<cv::Point2f> kept_points;
    typename Descriptor::LevelData descriptor_data;
    std::vector<cv::KeyPoint> keypoints;
    std::vector<BinaryDescriptor<kBits>> descriptors;
  };

  struct ViewWork {
    AffineView view;
    detail::ViewRenderer renderer;
    /// Per level, the pixels computed (the rest repeats the row's edge pixels): level 0 is
    /// rendered, the others resized, within kRenderMargin level pixels of the image.
    std::vector<RowSpans> regions;
    cv::Mat scratch;
    cv::Mat image;
    Pyramid pyramid;
    std::vector<LevelWork> levels;
  };

  LevelWork& level_of(int v, int l) {
    return view_work_[static_cast<std::size_t>(v)].levels[static_cast<std::size_t>(l)];
  }

  /// (Re)builds the view set, the renderers and the valid regions when the image size changes;
  /// buffers are kept otherwise.
  void prepare_views(cv::Size size) {
    if (size == views_size_ && !view_work_.empty()) return;
    const std::vector<AffineView> views = make_views(options_.views, size);
    view_work_.clear();
    view_work_.resize(views.size(), ViewWork{AffineView{}, {}, {}, {}, {}, Pyramid(options_.pyramid), {}});
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
    }
    budgets_.clear();
    std::vector<int> per_view;
    if (options_.view_budget == ViewBudget::kAdditive) {
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
  /// with shortfalls carried among them (allocate_with_carry()), given what each offers.
  void take_range(int begin, int end) {
    const int levels = options_.pyramid.levels;
    range_budgets_.assign(budgets_.begin() + begin, budgets_.begin() + end);
    available_.clear();
    for (int g = begin; g < end; ++g)
      available_.push_back(static_cast<int>(level_of(g / levels, g % levels).alive.size()));
    allocate_with_carry(range_budgets_, available_, range_take_);
    std::copy(range_take_.begin(), range_take_.end(), take_.begin() + begin);
  }

  /// Step 4 for (view v, level l): keeps take_ of its surviving candidates, by quadtree spreading
  /// or strength (ExtractorOptions::spreading), into LevelWork::kept.
  void spread_level(int v, int l, const cv::Rect2f& region, SpreadWork& spread) {
    LevelWork& work = level_of(v, l);
    spread.points.clear();
    spread.responses.clear();
    for (int i : work.alive) {
      spread.points.push_back(work.original_points[static_cast<std::size_t>(i)]);
      spread.responses.push_back(work.responses[static_cast<std::size_t>(i)]);
    }
    const int target = take_[static_cast<std::size_t>(v * options_.pyramid.levels + l)];
    if (options_.spreading == Spreading::kQuadtree) {
      distribute_quadtree(spread.points, spread.responses, region, target, spread.quadtree, spread.kept);
    } else {
      select_strongest(spread.responses, target, spread.kept);
    }
    work.kept.clear();
    for (int k : spread.kept) work.kept.push_back(work.alive[static_cast<std::size_t>(k)]);
  }

  /// Step 1–2 for one view: render, pyramid, candidates in the valid regions, mask check.
  void detect_view(const cv::Mat& image, const cv::Mat& mask, ViewWork& work, DetectorWorkspace& detector) {
    work.renderer.render(image, &work.regions.front(), work.scratch, work.image);
    work.pyramid.build_swap(work.image, work.view.is_identity() ? nullptr : &work.regions);
    const int border = support_border();
    const cv::Matx23d& back = work.view.to_original;
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelWork& level = work.levels[static_cast<std::size_t>(l)];
      level.level_points.clear();
      level.original_points.clear();
      level.responses.clear();
      level.alive.clear();
      if (level.valid.rows() == 0) continue;
      const cv::Mat& level_image = work.pyramid.level(l);
      detect_candidates(level_image, level.valid, cv::Point(border, border), options_.detector, detector,
                        level.candidates);
      const Candidates& candidates = level.candidates;
      for (std::size_t i = 0; i < candidates.corners.size(); ++i) {
        const Corner& c = candidates.corners[i];
        const cv::Point2f p(static_cast<float>(c.x), static_cast<float>(c.y));
        const cv::Point2d q = apply_affine(back, work.pyramid.to_level0(p, l));
        const int mx = cvRound(q.x);
        const int my = cvRound(q.y);
        if (mx < 0 || my < 0 || mx >= image.cols || my >= image.rows) continue;
        if (!mask.empty() && mask.at<std::uint8_t>(my, mx) == 0) continue;
        level.alive.push_back(static_cast<int>(level.level_points.size()));
        level.level_points.push_back(p);
        level.original_points.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y));
        level.responses.push_back(candidates.responses[i]);
      }
    }
  }

  /// Step 3: per level, visits candidates from the strongest down (ties: lower view, lower index)
  /// and drops one when a kept candidate of another view lies within the merge radius. Integer
  /// (FAST) responses are visited by a counting sort, others by a comparison sort; kept candidates
  /// are found again through a grid of cells one radius wide over the original image.
  void merge_duplicates(cv::Size size) {
    for_each(options_.pyramid.levels, [&](int l, int w) { merge_level(l, size, merge_[static_cast<std::size_t>(w)]); });
  }

  /// merge_duplicates() for level l, with the buffers `m`.
  void merge_level(int l, cv::Size size, MergeWork& m) {
    const int n_views = static_cast<int>(view_work_.size());
    order_candidates(l, m);
    const double radius = options_.merge_radius * options_.pyramid.scale(l);
    const double radius_squared = radius * radius;
    const double cell = radius;
    // Cells of points in [−0.5, W − 0.5): floor(x / cell) + 1 lies in [0, columns − 1].
    const int columns = static_cast<int>(std::floor(size.width / cell)) + 3;
    const int rows = static_cast<int>(std::floor(size.height / cell)) + 3;
    m.head.assign(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows), -1);
    m.kept.clear();
    for (int v = 0; v < n_views; ++v) {
      LevelWork& work = level_of(v, l);
      work.keep_flags.assign(work.level_points.size(), 0);
    }
    for (const MergeRef& r : m.order) {
      const cv::Point2f& p = r.point;
      const int cx = static_cast<int>(std::floor(p.x / cell)) + 1;
      const int cy = static_cast<int>(std::floor(p.y / cell)) + 1;
      bool duplicate = false;
      for (int y = cy - 1; y <= cy + 1 && !duplicate; ++y) {
        for (int x = cx - 1; x <= cx + 1 && !duplicate; ++x) {
          for (int k = m.head[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns) +
                              static_cast<std::size_t>(x)];
               k >= 0; k = m.kept[static_cast<std::size_t>(k)].next) {
            const MergeKept& o = m.kept[static_cast<std::size_t>(k)];
            const double dx = o.point.x - p.x;
            const double dy = o.point.y - p.y;
            if (o.view != r.view && dx * dx + dy * dy < radius_squared) {
              duplicate = true;
              break;
            }
          }
        }
      }
      if (duplicate) continue;
      int& head =
          m.head[static_cast<std::size_t>(cy) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(cx)];
      m.kept.push_back({p, r.view, head});
      head = static_cast<int>(m.kept.size()) - 1;
      level_of(r.view, l).keep_flags[static_cast<std::size_t>(r.index)] = 1;
    }
    for (int v = 0; v < n_views; ++v) {
      LevelWork& work = level_of(v, l);
      work.alive.clear();
      for (std::size_t i = 0; i < work.keep_flags.size(); ++i) {
        if (work.keep_flags[i]) work.alive.push_back(static_cast<int>(i));
      }
    }
  }

  /// Whether every response is a FAST score (an integer in [0, 255]), so that candidates can be
  /// ordered by a counting sort.
  static bool fast_scores(const std::vector<float>& responses) {
    return std::all_of(responses.begin(), responses.end(),
                       [](float r) { return r >= 0.0f && r <= 255.0f && r == std::floor(r); });
  }

  /// `out` = the elements `visit` offers, by descending FAST score 0..255, in the order offered
  /// within a score (a counting sort). visit(take) calls take(score, element) for every element,
  /// the same sequence each time it is called (twice: counting, then placing).
  template <class Visit, class Ref>
  static void order_by_score(Visit visit, std::vector<Ref>& out) {
    std::array<int, 257> start{};
    visit([&](float score, const Ref&) { ++start[static_cast<std::size_t>(256 - static_cast<int>(score))]; });
    int total = 0;
    for (int& count : start) {
      const int c = count;
      count = total;
      total += c;
    }
    out.resize(static_cast<std::size_t>(total));
    visit([&](float score, const Ref& ref) {
      out[static_cast<std::size_t>(start[static_cast<std::size_t>(256 - static_cast<int>(score))]++)] = ref;
    });
  }

  /// `out` = the elements `visit` offers (see order_by_score()), strongest first, ties in the order
  /// offered: by a counting sort when every score is a FAST score (`integral`), else by a stable
  /// comparison sort.
  template <class Visit, class Ref>
  static void order_strongest_first(Visit visit, bool integral, std::vector<Ref>& out) {
    if (integral) {
      order_by_score(visit, out);
      return;
    }
    out.clear();
    visit([&](float, const Ref& ref) { out.push_back(ref); });
    std::stable_sort(out.begin(), out.end(), [](const Ref& a, const Ref& b) { return a.response > b.response; });
  }

  /// m.order: the candidates of level l, strongest first, ties to the lower view, then the lower
  /// index.
  void order_candidates(int l, MergeWork& m) {
    const int n_views = static_cast<int>(view_work_.size());
    // Views, then indices, in increasing order: the tie order.
    const auto visit = [&](auto&& take) {
      for (int v = 0; v < n_views; ++v) {
        const LevelWork& work = level_of(v, l);
        for (int i : work.alive) {
          const float r = work.responses[static_cast<std::size_t>(i)];
          take(r, MergeRef{r, v, i, work.original_points[static_cast<std::size_t>(i)]});
        }
      }
    };
    bool integral = true;
    for (int v = 0; v < n_views && integral; ++v) integral = fast_scores(level_of(v, l).responses);
    order_strongest_first(visit, integral, m.order);
  }

  /// ViewBudget::kAdditive, step 3: visits the tilted views' candidates from the strongest down
  /// (ties: lower view, lower level, lower index) and drops each one that repeats a keypoint kept
  /// from the image or an already accepted tilted candidate (ExtractorOptions::repeat_levels).
  void suppress_repeats(cv::Size size) {
    const int n_views = static_cast<int>(view_work_.size());
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
    auto accept = [&](cv::Point2f p, int v, int l) {
      RepeatGrid& grid = repeat_grids_[static_cast<std::size_t>(l)];
      int& head = grid.head[grid.index(p, 0, 0)];
      repeat_kept_.push_back({p, v, l, head});
      head = static_cast<int>(repeat_kept_.size()) - 1;
    };
    for (int l = 0; l < levels; ++l) {
      const LevelWork& work = level_of(0, l);
      for (int i : work.kept) accept(work.original_points[static_cast<std::size_t>(i)], 0, l);
    }
    order_tilted_candidates();
    for (int v = 1; v < n_views; ++v) {
      for (int l = 0; l < levels; ++l) {
        LevelWork& work = level_of(v, l);
        work.keep_flags.assign(work.level_points.size(), 0);
      }
    }
    for (const RepeatRef& r : repeat_order_) {
      bool repeat = false;
      for (int q = std::max(r.level - reach, 0); q <= std::min(r.level + reach, levels - 1) && !repeat; ++q) {
        const RepeatGrid& grid = repeat_grids_[static_cast<std::size_t>(q)];
        const double radius_squared = repeat_grids_[static_cast<std::size_t>(std::max(r.level, q))].radius_squared;
        for (int dy = -1; dy <= 1 && !repeat; ++dy) {
          for (int dx = -1; dx <= 1 && !repeat; ++dx) {
            for (int k = grid.head[grid.index(r.point, dx, dy)]; k >= 0;
                 k = repeat_kept_[static_cast<std::size_t>(k)].next) {
              const RepeatKept& e = repeat_kept_[static_cast<std::size_t>(k)];
              // Candidates of one view and level are distinct corners (FAST's non-maximum suppression).
              if (e.view == r.view && e.level == r.level) continue;
              const double ex = e.point.x - r.point.x;
              const double ey = e.point.y - r.point.y;
              if (ex * ex + ey * ey < radius_squared) {
                repeat = true;
                break;
              }
            }
          }
        }
      }
      if (repeat) continue;
      accept(r.point, r.view, r.level);
      level_of(r.view, r.level).keep_flags[static_cast<std::size_t>(r.index)] = 1;
    }
    for (int v = 1; v < n_views; ++v) {
      for (int l = 0; l < levels; ++l) {
        LevelWork& work = level_of(v, l);
        work.alive.clear();
        for (std::size_t i = 0; i < work.keep_flags.size(); ++i) {
          if (work.keep_flags[i]) work.alive.push_back(static_cast<int>(i));
        }
      }
    }
  }

  /// repeat_order_: the surviving candidates of the tilted views, strongest first, ties to the
  /// lower view, then level, then index (a counting sort for FAST's integer scores).
  void order_tilted_candidates() {
    const int n_views = static_cast<int>(view_work_.size());
    const int levels = options_.pyramid.levels;
    // Views, then levels, then indices, in increasing order: the tie order.
    const auto visit = [&](auto&& take) {
      for (int v = 1; v < n_views; ++v) {
        for (int l = 0; l < levels; ++l) {
          const LevelWork& work = level_of(v, l);
          for (int i : work.alive) {
            const float r = work.responses[static_cast<std::size_t>(i)];
            take(r, RepeatRef{r, v, l, i, work.original_points[static_cast<std::size_t>(i)]});
          }
        }
      }
    };
    bool integral = true;
    for (int v = 1; v < n_views && integral; ++v) {
      for (int l = 0; l < levels && integral; ++l) integral = fast_scores(level_of(v, l).responses);
    }
    order_strongest_first(visit, integral, repeat_order_);
  }

  /// RefineOptions: the strongest FAST corner of the original image's level o within
  /// options_.refine.radius level-o pixels of `point` (original pixels), as a level-0 point, if
  /// one scores at least the detector's minimum threshold and lies where the mask allows (ties:
  /// the nearer pixel, then raster order).
  std::optional<cv::Point2f> refine_point(cv::Point2f point, int o, const cv::Mat& mask) const {
    const Pyramid& original = view_work_.front().pyramid;
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

  /// Step 5 for view v: orientation and descriptor in the view, keypoints mapped back (and, for a
  /// tilted view, refined on the original image: RefineOptions).
  void describe_view(int v, const cv::Mat& mask) {
    ViewWork& work = view_work_[static_cast<std::size_t>(v)];
    const cv::Matx23d& back = work.view.to_original;
    const float sqrt_tilt = static_cast<float>(std::sqrt(work.view.tilt));
    const bool identity = work.view.is_identity();
    const int top = options_.pyramid.levels - 1;
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelWork& level = work.levels[static_cast<std::size_t>(l)];
      level.keypoints.clear();
      level.descriptors.clear();
      if (level.kept.empty()) continue;
      level.kept_points.clear();
      for (int i : level.kept) level.kept_points.push_back(level.level_points[static_cast<std::size_t>(i)]);
      descriptor_.prepare(work.pyramid.level(l), level.kept_points, level.descriptor_data);
      const float scale = static_cast<float>(options_.pyramid.scale(l)) * sqrt_tilt;
      const int octave = std::min(l + octave_shift_[static_cast<std::size_t>(v)], top);
      for (int i : level.kept) {
        const cv::Point2f p = level.level_points[static_cast<std::size_t>(i)];
        const float angle = descriptor_.orientation(level.descriptor_data, p);
        level.descriptors.push_back(descriptor_.describe(level.descriptor_data, p, angle));
        // The direction (cos θ, sin θ) in the view, mapped to the original image.
        const double dx = back(0, 0) * std::cos(angle) + back(0, 1) * std::sin(angle);
        const double dy = back(1, 0) * std::cos(angle) + back(1, 1) * std::sin(angle);
        const float original_angle = identity ? angle : static_cast<float>(std::atan2(dy, dx));
        cv::Point2f position = level.original_points[static_cast<std::size_t>(i)];
        if (!identity && options_.refine.enabled) {
          if (const std::optional<cv::Point2f> refined = refine_point(position, octave, mask)) position = *refined;
        }
        level.keypoints.emplace_back(position, Descriptor::kPatchSize * scale, radians_to_degrees_0_360(original_angle),
                                     level.responses[static_cast<std::size_t>(i)], octave);
      }
    }
  }

  /// The output: keypoints grouped by octave (0 first), then by view, then level, then raster order
  /// in the view.
  Features<kBits> assemble() {
    const int levels = options_.pyramid.levels;
    octave_start_.assign(static_cast<std::size_t>(levels) + 1, 0);
    for (const ViewWork& w : view_work_) {
      for (const LevelWork& level : w.levels) {
        for (const cv::KeyPoint& kp : level.keypoints) ++octave_start_[static_cast<std::size_t>(kp.octave) + 1];
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
        for (std::size_t i = 0; i < level.keypoints.size(); ++i) {
          const std::size_t slot =
              static_cast<std::size_t>(octave_start_[static_cast<std::size_t>(level.keypoints[i].octave)]++);
          features.keypoints[slot] = level.keypoints[i];
          features.descriptors[slot] = level.descriptors[i];
          features.views[slot] = static_cast<int>(v);
        }
      }
    }
    return features;
  }

  ExtractorOptions options_;
  /// Budget of each (view, level), index v·levels + l: views in proportion to their area 1/t,
  /// levels geometric within a view (fixed for a view set, computed by prepare_views()).
  std::vector<int> budgets_;
  /// Per frame: candidates each (view, level) offers, and what it takes (allocate_with_carry());
  /// the budgets of the groups take_range() allocates, and their result.
  std::vector<int> available_;
  std::vector<int> take_;
  std::vector<int> range_budgets_;
  std::vector<int> range_take_;
  /// Per view (fixed for a view set, prepare_views()): a keypoint of its level l has the octave
  /// min(l + octave_shift_, levels − 1), the level nearest to its scale s^l·√t.
  std::vector<int> octave_shift_;
  /// Buffers of suppress_repeats() and assemble().
  std::vector<RepeatRef> repeat_order_;
  std::vector<RepeatKept> repeat_kept_;
  std::vector<RepeatGrid> repeat_grids_;
  std::vector<int> octave_start_;
  /// Per worker thread: the buffers of the budget step.
  std::vector<SpreadWork> spread_;
  /// Per worker thread: the buffers of merge_level().
  std::vector<MergeWork> merge_;
  /// Per worker thread: the detection buffers (one score map reused by every level of every view).
  std::vector<DetectorWorkspace> scratch_;
  Descriptor descriptor_;
  cv::Size views_size_;
  std::vector<ViewWork> view_work_;
  /// The worker threads when options_.threads > 1, started by the first extract().
  std::unique_ptr<detail::WorkerPool> pool_;
};

}  // namespace affine_orb
