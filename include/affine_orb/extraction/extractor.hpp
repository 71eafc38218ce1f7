#pragma once
/// \file
/// Extractor<Descriptor>: Affine-ORB feature extraction (paper section 3, docs/algorithm.md §1–§3). Oriented FAST
/// keypoints are detected on a scale pyramid of every simulated affine view, spread over the image
/// under an exact feature budget, described in their view by a descriptor policy (Rbrief, Brisk),
/// and mapped back to the original image.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/detail/worker_pool.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/extractor.hpp"
#include "affine_orb/extraction/detail/fork_image.hpp"
#include "affine_orb/extraction/detail/stella_image.hpp"
#include "affine_orb/extraction/detail/view_regions.hpp"
#include "affine_orb/extraction/detail/view_schedule.hpp"
#include "affine_orb/extraction/extractor_options.hpp"
#include "affine_orb/extraction/view_session.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {

/// Extracts keypoints and descriptors from grey images.
///
/// Every view v of ExtractorOptions::views (affine_views.hpp) is rendered, one at a time per
/// thread, and gets a pyramid, FAST candidates among its valid pixels (those whose descriptor
/// support maps inside the image), the mask, the merging of repeats, a selection under the view
/// budget, orientation and description in the view, and the mapping back to the original image:
/// the five steps of docs/algorithm.md, "Extractor's steps".
///
/// Output order: by octave (0 first), then by view, then by level, then raster order in the view.
/// The output does not depend on ExtractorOptions::threads.
///
/// Views on demand: extract_image() is stage 0 (the image alone, exactly extract() with
/// max_tilt = 1) and returns a ViewSession whose extend() adds the views of further tilts, so that
/// a caller pays for views only when it needs them (TwoViewMatcher escalates this way). The stages
/// {extract_image(), session.extend(views.max_tilt, round(view_features · features))} give exactly
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
        turns_(std::make_unique<detail::ViewTurns>()) {
    if (fork()) {
      fork_.scales.set(static_cast<float>(options_.pyramid.scale_factor), options_.pyramid.levels, options_.features);
    }
  }

  const ExtractorOptions& options() const { return options_; }
  const Descriptor& descriptor() const { return descriptor_; }

  /// The views of ExtractorOptions::views for the last image passed to extract() or
  /// extract_image() (empty before the first call), in view index order (Features::views).
  std::vector<AffineView> views() const {
    std::vector<AffineView> out;
    for (const ViewWork& w : view_work_) out.push_back(w.view);
    return out;
  }

  /// Keypoints (original pixel coordinates) and descriptors of a CV_8UC1 image (a ROI of a larger
  /// matrix is fine), every view at once; see Features for the keypoint fields.
  ///
  /// `mask`: empty (everything allowed) or CV_8UC1 of the image size; a keypoint is kept only where
  /// the mask pixel nearest to its original position is non-zero (under StellaVslamKeypoints
  /// the image's keypoints follow stella_vslam's own mask test, detail/stella_image.hpp, and without
  /// a mask its mask_rectangles are the mask).
  ///
  /// Throws std::invalid_argument for an empty image, a type other than CV_8UC1, or a mask of the
  /// wrong size or type. A valid image with no corners (flat, or smaller than the descriptor
  /// support on every level) gives an empty result.
  Features<kBits> extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    begin(image, mask);
    const cv::Mat& active_mask = effective_mask(image.size(), mask);
    const int n_views = static_cast<int>(view_work_.size());
    if (additive()) {
      budgets_.set_view(0, options_.features, options_.pyramid.scale_factor);
      const AdditiveBudget& budget = *options_.additive_budget();
      budgets_.share(tilts_, 1, n_views, static_cast<int>(std::lround(budget.view_features * options_.features)),
                     budget.view_weight_exponent, options_.pyramid.scale_factor);
    } else {
      budgets_.share(tilts_, 0, n_views, options_.features, -1.0, options_.pyramid.scale_factor);
    }
    run_views(image, active_mask, 0, n_views);
    return assemble(0, n_views);
  }

  /// extract(), and the original image's pyramid, which the views and the snapping use too:
  /// `levels[l]` receives a copy of level l, PyramidOptions::levels of them (cv::Mat::copyTo, so a
  /// matrix that already has the level's size and type is written in place). For callers that keep
  /// the pyramid, as ORB-SLAM's frames do.
  Features<kBits> extract(const cv::Mat& image, const cv::Mat& mask, std::vector<cv::Mat>& levels) {
    Features<kBits> features = extract(image, mask);
    levels.resize(image_pyramid_.images().size());
    for (std::size_t l = 0; l < levels.size(); ++l) image_pyramid_.images()[l].copyTo(levels[l]);
    return features;
  }

  /// Views on demand, stage 0: the keypoints of the image alone, exactly extract()'s with
  /// views.max_tilt = 1 (the image's `features` keypoints), and the ViewSession that adds the next
  /// stages, which holds `image` and `mask` (headers, not copies). Same arguments, checks and
  /// exceptions as extract(); also throws std::invalid_argument unless ExtractorOptions::view_budget
  /// is AdditiveBudget.
  StagedFeatures<Descriptor> extract_image(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    detail::require(additive(), "Extractor::extract_image: views on demand need the AdditiveBudget view_budget");
    begin(image, mask);
    const cv::Mat& active_mask = effective_mask(image.size(), mask);
    budgets_.set_view(0, options_.features, options_.pyramid.scale_factor);
    run_views(image, active_mask, 0, 1);
    return StagedFeatures<Descriptor>{assemble(0, 1), ViewSession<Descriptor>(this, image, active_mask)};
  }

 private:
  friend class ViewSession<Descriptor>;

  /// ViewSession::extend() of `session`, this Extractor's live session.
  Features<kBits> extend(ViewSession<Descriptor>& session, double up_to_tilt, int features) {
    detail::require(std::isfinite(up_to_tilt), "ViewSession::extend: up_to_tilt must be finite");
    detail::require_range(features, {0.0, 1000000.0}, "ViewSession::extend: features");
    const int first = session.extracted_views_;
    int last = first;
    // The same 0.1 % tolerance as view_parameters(), so that 2.83 includes 2√2.
    while (last < static_cast<int>(view_work_.size()) &&
           tilts_[static_cast<std::size_t>(last)] <= up_to_tilt * (1.0 + 1e-3)) {
      ++last;
    }
    if (last == first) return {};
    // What the earlier stages finally kept is what this stage must not repeat.
    if (merging()) {
      repeats_.reset(session.image_.size(), options_.pyramid, options_.merge_duplicates->radius,
                     options_.merge_duplicates->repeat_levels);
      for (int v = 0; v < first; ++v) enter_kept(v);
    }
    budgets_.share(tilts_, first, last, features, options_.additive_budget()->view_weight_exponent,
                   options_.pyramid.scale_factor);
    run_views(session.image_, session.mask_, first, last);
    session.extracted_views_ = last;
    session.extracted_tilt_ = tilts_[static_cast<std::size_t>(last - 1)];
    return assemble(first, last);
  }

  using SpreadWork = detail::SpreadWork;
  using LevelCandidates = detail::LevelCandidates;
  using ThreadWork = detail::ThreadWork<Descriptor>;
  using LevelWork = detail::LevelWork<kBits>;
  using ViewWork = detail::ViewWork<kBits>;

  /// Margin in level pixels around the original image within which a view and its pyramid levels
  /// are computed: more than the reach beyond a valid keypoint's support of the rBRIEF smoothing
  /// (3 level pixels) and of the bilinear interpolation between levels.
  static constexpr double kRenderMargin = 8.0;

  // ---- The walk of one image ------------------------------------------------------------------

  /// Checks the arguments, prepares the view set for the image size and empties the repeat grids.
  void begin(const cv::Mat& image, const cv::Mat& mask) {
    detail::require(!session_.open, "Extractor::extract: a ViewSession of this Extractor is open");
    detail::require_gray8(image, "Extractor::extract");
    detail::require_mask(mask, image.size(), "Extractor::extract");
    prepare_views(image.size());
    if (merging())
      repeats_.reset(image.size(), options_.pyramid, options_.merge_duplicates->radius,
                     options_.merge_duplicates->repeat_levels);
  }

  /// The mask of an extraction: the caller's, or under StellaVslamKeypoints without one its
  /// mask_rectangles' (detail::stella_rectangle_mask()), or none.
  const cv::Mat& effective_mask(cv::Size size, const cv::Mat& mask) {
    const auto* stella = std::get_if<StellaVslamKeypoints>(&options_.image_keypoints);
    if (!mask.empty() || !stella || stella->mask_rectangles.empty()) return mask;
    return detail::stella_rectangle_mask(stella->mask_rectangles, size, stella_.rectangle_mask);
  }

  /// Steps 1–5 for views [first, last), whose budgets are set: every view processed (in parallel,
  /// taking turns in view order), then the final selection of the shortlisted ones.
  void run_views(const cv::Mat& image, const cv::Mat& mask, int first, int last) {
    prepare_range(first, last);
    turns_->reset(first);
    detail::run_indexed(pool_, options_.threads, last - first, [&](int i, int w) {
      process_view(first + i, image, mask, thread_work_[static_cast<std::size_t>(w)]);
    });
    const int shortlisted = first == 0 && direct(0) ? 1 : first;
    if (shortlisted < last) select_shortlisted(image.size(), shortlisted, last);
  }

  /// Steps 1–4 for view v on the thread owning `work`; a failure ends every turn still to come.
  void process_view(int v, const cv::Mat& image, const cv::Mat& mask, ThreadWork& work) {
    if (v == 0 && fork()) {
      process_fork_image(image, mask, work);
      return;
    }
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
        if (drops_repeats(v)) drop_repeats(v, image, mask, pyramid, work);
        choose(v, image.size(), work);
      }
      turns_->pass(v);
      if (!empty) describe_view(v, pyramid, mask, work);
    } catch (...) {
      turns_->fail();
      throw;
    }
  }

  /// ExtractorOptions::image_keypoints of a SLAM system: the image's keypoints as it extracts them
  /// (detail::extract_slam_image()) on its pyramid, then, in view 0's turn, entered in the repeat
  /// grids for the views.
  void process_fork_image(const cv::Mat& image, const cv::Mat& mask, ThreadWork& work) {
    try {
      detail::extract_slam_image(descriptor_, image, mask, options_, image_pyramid_, fork_, stella_,
                                 work.describe_points, work.descriptor_data, view_work_[0].levels);
      if (!turns_->wait(0)) return;
      if (merging()) enter_kept(0);
      turns_->pass(0);
    } catch (...) {
      turns_->fail();
      throw;
    }
  }

  /// Step 2 for view v: candidates of every level into work.levels (detail::detect_level()); for
  /// a level that keeps its strongest (strongest_needed()), only the strong corners first where
  /// they sufficed in the thread's last view, and, unless a merge waits for the view's turn, its
  /// strongest taken at once (detail::keep_strongest()).
  void detect_view(int v, const cv::Mat& image, const cv::Mat& mask, const Pyramid& pyramid, ThreadWork& work) {
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      const std::size_t k = static_cast<std::size_t>(l);
      const int strongest = strongest_needed(v, l);
      const ViewWork& view = view_work_[static_cast<std::size_t>(v)];
      detail::detect_level(view, l, image, mask, pyramid, support_border(), options_.detector, strongest,
                           work.strong_sufficed[k] != 0, work.detector, work.levels[k]);
      if (strongest >= 0 && !drops_repeats(v)) {
        detail::keep_strongest(view, l, image, mask, pyramid, support_border(), options_.detector, nullptr, strongest,
                               work.detector, work.levels[k]);
      }
    }
  }

  /// Step 3, in tilted view v's turn: drops the candidates of every level that repeat a keypoint of
  /// an earlier view (detail::drop_repeats()), or, for a level that keeps its strongest, takes
  /// its strongest that repeat none (detail::keep_strongest()).
  void drop_repeats(int v, const cv::Mat& image, const cv::Mat& mask, const Pyramid& pyramid, ThreadWork& work) {
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      detail::LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      const int strongest = strongest_needed(v, l);
      if (strongest < 0) {
        detail::drop_repeats(repeats_, l, c);
        continue;
      }
      detail::keep_strongest(view_work_[static_cast<std::size_t>(v)], l, image, mask, pyramid, support_border(),
                             options_.detector, &repeats_, strongest, work.detector, c);
    }
  }

  /// The candidates of view v, level l that step 3 keeps at most when it chooses the strongest by
  /// FAST score (ExtractorOptions::spreading, DetectorOptions::score): its shortlist; −1 when it
  /// chooses otherwise or its final keypoints, whose budgets depend on every level's candidates.
  int strongest_needed(int v, int l) const {
    if (direct(v) || options_.spreading != Spreading::kStrongest || options_.detector.score != ScoreType::kFast) {
      return -1;
    }
    return detail::shortlist_size(std::numeric_limits<int>::max(), budgets_.group(v * options_.pyramid.levels + l),
                                  options_.shortlist);
  }

  /// Step 3, in view v's turn: the candidates each level describes (its final keypoints when
  /// direct(v), else its shortlist), entered in the repeat grids for the views after it.
  void choose(int v, cv::Size size, ThreadWork& work) {
    const int levels = options_.pyramid.levels;
    if (direct(v)) {
      available_.clear();
      for (const LevelCandidates& c : work.levels) available_.push_back(static_cast<int>(c.responses.size()));
      budgets_.allocate(v * levels, (v + 1) * levels, available_, options_.carry_shortfalls);
    }
    for (int l = 0; l < levels; ++l) {
      LevelCandidates& c = work.levels[static_cast<std::size_t>(l)];
      const int g = v * levels + l;
      const int target = direct(v) ? budgets_.take(g)
                                   : detail::shortlist_size(static_cast<int>(c.responses.size()), budgets_.group(g),
                                                            options_.shortlist);
      if (const int needed = strongest_needed(v, l); needed >= 0) {
        work.strong_sufficed[static_cast<std::size_t>(l)] =
            detail::strong_enough(c, needed, options_.detector.initial_threshold);
      }
      const cv::Rect2f region = spread_region(v, l, size);
      detail::spread(options_.spreading, c.original_points, c.responses, region, target, work.spread);
      c.chosen = work.spread.kept;
      if (merging()) {
        detail::enter_repeat_references(options_.spreading, c, l, direct(v) ? target : budgets_.group(g), region,
                                        work.spread, repeats_);
      }
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

  /// Step 4 for the chosen candidates of view v, level l (detail::describe_level()).
  void describe_level(int v, int l, const Pyramid& pyramid, const cv::Mat& mask, ThreadWork& work) {
    const int octave = std::min(l + octave_shift_[static_cast<std::size_t>(v)], options_.pyramid.levels - 1);
    detail::describe_level(descriptor_, view_work_[static_cast<std::size_t>(v)].view, pyramid, l, octave, options_,
                           image_pyramid_, mask, work, level_of(v, l));
  }

  /// Step 5 for the shortlisted views [first, last): their budgets with shortfalls carried among
  /// all their (view, level) groups, and each group's final selection among its shortlist.
  void select_shortlisted(cv::Size size, int first, int last) {
    const int levels = options_.pyramid.levels;
    available_.clear();
    for (int g = first * levels; g < last * levels; ++g) {
      available_.push_back(static_cast<int>(level_of(g / levels, g % levels).keypoints.size()));
    }
    budgets_.allocate(first * levels, last * levels, available_, options_.carry_shortfalls);
    detail::run_indexed(pool_, options_.threads, last - first, [&](int i, int w) {
      ThreadWork& work = thread_work_[static_cast<std::size_t>(w)];
      for (int l = 0; l < levels; ++l) {
        LevelWork& level = level_of(i + first, l);
        detail::spread(options_.spreading, level.original_points, level.responses, spread_region(i + first, l, size),
                       budgets_.take((i + first) * levels + l), work.spread);
        level.kept = work.spread.kept;
      }
    });
  }

  /// The output of views [first, last): keypoints grouped by octave (0 first), then by view, then
  /// level, then raster order in the view.
  Features<kBits> assemble(int first, int last) {
    return detail::assemble(view_work_, first, last, options_.pyramid.levels, octave_start_);
  }

  // ---- The pieces the walk uses ---------------------------------------------------------------

  LevelWork& level_of(int v, int l) {
    return view_work_[static_cast<std::size_t>(v)].levels[static_cast<std::size_t>(l)];
  }

  bool additive() const { return options_.additive_budget() != nullptr; }
  /// Whether the views' repeats are merged: ExtractorOptions::merge_duplicates, and views besides
  /// the image to merge (with the image alone the repeat grids would be filled and never read).
  bool merging() const { return options_.merge_duplicates.has_value() && view_work_.size() > 1; }
  /// Whether view v drops the repeats of earlier views in its turn (step 3): a level that keeps
  /// its strongest then takes them there, else right after detection.
  bool drops_repeats(int v) const { return merging() && v > 0; }
  bool fork() const { return options_.fork_keypoints(); }

  /// Whether view v's keypoints are final when it is processed (the image with kAdditive, or the
  /// only view), rather than a shortlist chosen from once every view is done.
  bool direct(int v) const { return v == 0 && (additive() || view_work_.size() == 1); }

  /// The box, in original pixels, that the spreading of view v, level l divides
  /// (detail::spread_region()).
  cv::Rect2f spread_region(int v, int l, cv::Size size) const {
    const ViewWork& view = view_work_[static_cast<std::size_t>(v)];
    return detail::spread_region(view.view, view.levels[static_cast<std::size_t>(l)].valid, size, options_.pyramid, l);
  }

  /// Support radius in level pixels around a candidate: the descriptor's and the ranking's.
  int support_border() const { return std::max(descriptor_.border(), options_.detector.support_radius()); }

  /// (Re)builds the view set when the image size changes (each view's renderer and valid regions
  /// follow the first time it runs, prepare_range()); buffers are kept otherwise.
  void prepare_views(cv::Size size) {
    if (size == views_size_ && !view_work_.empty()) return;
    const std::vector<AffineView> views = make_views(options_.views, size);
    view_work_.clear();
    view_work_.resize(views.size());
    tilts_.clear();
    octave_shift_.clear();
    for (std::size_t v = 0; v < views.size(); ++v) {
      view_work_[v].view = views[v];
      tilts_.push_back(views[v].tilt);
      octave_shift_.push_back(detail::octave_shift(views[v].tilt, options_.pyramid.scale_factor));
    }
    const cv::Size largest_tilted = detail::largest_tilted(views);
    budgets_.resize(views.size(), options_.pyramid.levels);
    // Every thread's buffers sized for the largest tilted view now, so that which thread gets
    // which view in later frames never makes one allocate.
    for (ThreadWork& work : thread_work_) {
      work.levels.resize(static_cast<std::size_t>(options_.pyramid.levels));
      work.strong_sufficed.assign(static_cast<std::size_t>(options_.pyramid.levels), 1);
      if (largest_tilted.area() > 0) {
        work.pyramid.reserve(largest_tilted);
        detail::fit_buffer(work.detector.scores, largest_tilted, CV_8UC1);
      }
    }
    views_size_ = size;
  }

  /// The renderers and valid regions of views [first, last) for the current image size, for those
  /// not prepared yet. Views on demand prepare only the views a stage reaches: preparing the 18
  /// tilted views for a new image size costs about a third of the image's 2000-keypoint extraction
  /// (callgrind, pairs of bench/eval_two_view), which a pair stage 0 verifies never needs.
  void prepare_range(int first, int last) {
    for (int v = first; v < last; ++v) {
      ViewWork& work = view_work_[static_cast<std::size_t>(v)];
      if (work.prepared) continue;
      const AffineView view = work.view;
      detail::prepare_view(view, views_size_, options_.views.antialias, options_.pyramid, support_border(),
                           kRenderMargin, work);
    }
  }

  /// Enters the final keypoints of view v (its kept ones, positions before snapping) in the repeat grids.
  void enter_kept(int v) {
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      const LevelWork& level = level_of(v, l);
      for (int i : level.kept) repeats_.enter(level.original_points[static_cast<std::size_t>(i)], l);
    }
  }

  /// Whether a ViewSession of this Extractor lives (it then holds the image being staged). The
  /// first member, so that a move it refuses moves nothing.
  detail::SessionFlag session_;
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
  /// merge_duplicates: the keypoints chosen by the views processed so far.
  detail::RepeatGrids repeats_;
  std::vector<int> octave_start_;  ///< buffer of assemble()
  cv::Size views_size_;
  std::vector<ViewWork> view_work_;
  /// The image's pyramid, kept until the next call (the views' snapping, CornerSnapOptions).
  Pyramid image_pyramid_;
  /// ImageKeypoints of a fork: the buffers of the image's extraction.
  detail::ForkImageWork fork_;
  /// StellaVslamKeypoints: its grid and rectangle mask.
  detail::StellaImageWork stella_;
  /// Per worker thread: the buffers views are processed in.
  std::vector<ThreadWork> thread_work_;
  std::unique_ptr<detail::ViewTurns> turns_;
  /// The worker threads when options_.threads > 1, started by the first extract().
  std::unique_ptr<detail::WorkerPool> pool_;
};

}  // namespace affine_orb
