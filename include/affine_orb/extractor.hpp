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
#include "affine_orb/features.hpp"
#include "affine_orb/pyramid.hpp"

namespace affine_orb {

/// What to do when several views return the same scene point (SPEC §2).
enum class DuplicatePolicy {
  kKeepAll,  ///< Keep every view's keypoint: best for wide-baseline matching of two images.
  kMerge,    ///< Keep only the strongest of the keypoints of one level that different views put
             ///< within ExtractorOptions::merge_radius of each other: for SLAM, one point per corner.
};

/// How each (view, level) keeps its share of the budget among its candidates.
enum class Spreading {
  kQuadtree,   ///< distribute_quadtree(): spread over the image (ORB-SLAM2's octree distribution);
               ///< keeps tracking alive in weakly textured parts, the SLAM choice (SPEC §2).
  kStrongest,  ///< select_strongest(): the strongest corners wherever they are (cv::ORB's choice);
               ///< more repeatable, so more correct matches between two wide-baseline images.
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
  DuplicatePolicy duplicates = DuplicatePolicy::kMerge;
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
/// 3. with DuplicatePolicy::kMerge, candidates of one level that other views put within
///    merge_radius · s^l original pixels of a stronger one are dropped;
/// 4. the budget is split over views in proportion to their area (1/t) and, within a view, over
///    levels geometrically (level_budgets()); shortfalls are carried (allocate_with_carry()); each
///    (view, level) keeps its share by quadtree spreading (distribute_quadtree()) in original
///    coordinates, or its strongest candidates (select_strongest()), per
///    ExtractorOptions::spreading;
/// 5. kept keypoints are oriented and described in their view, then mapped back: position through
///    the inverse view map, orientation by mapping the direction vector, scale s^l·√t (SPEC §1).
///
/// Output order: by level (level 0 first), then by view, then raster order in the view.
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

    scratch_.resize(static_cast<std::size_t>(options_.threads));
    merge_.resize(static_cast<std::size_t>(options_.threads));
    for_each(n_views, [&](int v, int w) {
      detect_view(image, mask, view_work_[static_cast<std::size_t>(v)], scratch_[static_cast<std::size_t>(w)]);
    });
    if (options_.duplicates == DuplicatePolicy::kMerge && n_views > 1) merge_duplicates(image.size());

    // Budget (fixed per view set, see prepare_views()), then what each (view, level) offers.
    available_.clear();
    for (int v = 0; v < n_views; ++v) {
      for (int l = 0; l < levels; ++l) available_.push_back(static_cast<int>(level_of(v, l).alive.size()));
    }
    allocate_with_carry(budgets_, available_, take_);
    const cv::Rect2f region(0.0f, 0.0f, static_cast<float>(image.cols), static_cast<float>(image.rows));
    spread_.resize(static_cast<std::size_t>(options_.threads));
    for_each(n_views, [&](int v, int w) {
      SpreadWork& spread = spread_[static_cast<std::size_t>(w)];
      for (int l = 0; l < levels; ++l) {
        LevelWork& work = level_of(v, l);
        spread.points.clear();
        spread.responses.clear();
        for (int i : work.alive) {
          spread.points.push_back(work.original_points[static_cast<std::size_t>(i)]);
          spread.responses.push_back(work.responses[static_cast<std::size_t>(i)]);
        }
        const int target = take_[static_cast<std::size_t>(v * levels + l)];
        if (options_.spreading == Spreading::kQuadtree) {
          distribute_quadtree(spread.points, spread.responses, region, target, spread.quadtree, spread.kept);
        } else {
          select_strongest(spread.responses, target, spread.kept);
        }
        work.kept.clear();
        for (int k : spread.kept) work.kept.push_back(work.alive[static_cast<std::size_t>(k)]);
      }
      describe_view(view_work_[static_cast<std::size_t>(v)]);
    });

    Features<kBits> features;
    std::size_t total = 0;
    for (const ViewWork& w : view_work_) {
      for (const LevelWork& level : w.levels) total += level.keypoints.size();
    }
    features.keypoints.reserve(total);
    features.descriptors.reserve(total);
    features.views.reserve(total);
    for (int l = 0; l < levels; ++l) {
      for (int v = 0; v < n_views; ++v) {
        const LevelWork& work = level_of(v, l);
        features.keypoints.insert(features.keypoints.end(), work.keypoints.begin(), work.keypoints.end());
        features.descriptors.insert(features.descriptors.end(), work.descriptors.begin(), work.descriptors.end());
        features.views.insert(features.views.end(), work.keypoints.size(), v);
      }
    }
    return features;
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
    const std::vector<int> per_view = view_budgets();
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

  /// Budget of each view, proportional to its area W·H/t, summing to options_.features (largest
  /// remainders, ties to the earlier view).
  std::vector<int> view_budgets() const {
    const std::size_t n = view_work_.size();
    double total_weight = 0.0;
    for (const ViewWork& w : view_work_) total_weight += 1.0 / w.view.tilt;
    std::vector<int> budgets(n, 0);
    std::vector<std::pair<double, std::size_t>> remainders;
    int assigned = 0;
    for (std::size_t v = 0; v < n; ++v) {
      const double exact = options_.features * (1.0 / view_work_[v].view.tilt) / total_weight;
      budgets[v] = static_cast<int>(std::floor(exact));
      assigned += budgets[v];
      remainders.emplace_back(exact - budgets[v], v);
    }
    std::stable_sort(remainders.begin(), remainders.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t i = 0; assigned < options_.features; ++i, ++assigned) ++budgets[remainders[i % n].second];
    return budgets;
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

  /// m.order: the candidates of level l, strongest first, ties to the lower view, then the lower
  /// index.
  void order_candidates(int l, MergeWork& m) {
    const int n_views = static_cast<int>(view_work_.size());
    m.order.clear();
    bool integral = true;
    for (int v = 0; v < n_views && integral; ++v) {
      for (float r : level_of(v, l).responses) {
        if (!(r >= 0.0f && r <= 255.0f && r == std::floor(r))) {
          integral = false;
          break;
        }
      }
    }
    if (!integral) {
      for (int v = 0; v < n_views; ++v) {
        const LevelWork& work = level_of(v, l);
        for (int i : work.alive) {
          m.order.push_back(
              {work.responses[static_cast<std::size_t>(i)], v, i, work.original_points[static_cast<std::size_t>(i)]});
        }
      }
      std::sort(m.order.begin(), m.order.end(), [](const MergeRef& a, const MergeRef& b) {
        return a.response > b.response ||
               (a.response == b.response && (a.view < b.view || (a.view == b.view && a.index < b.index)));
      });
      return;
    }
    // Counting sort on the scores 0..255, descending; within a score, visiting views and indices
    // in increasing order keeps the tie order.
    std::array<int, 257> start{};
    for (int v = 0; v < n_views; ++v) {
      const LevelWork& work = level_of(v, l);
      for (int i : work.alive)
        ++start[static_cast<std::size_t>(256 - static_cast<int>(work.responses[static_cast<std::size_t>(i)]))];
    }
    int total = 0;
    for (int& count : start) {
      const int c = count;
      count = total;
      total += c;
    }
    m.order.resize(static_cast<std::size_t>(total));
    for (int v = 0; v < n_views; ++v) {
      const LevelWork& work = level_of(v, l);
      for (int i : work.alive) {
        const float response = work.responses[static_cast<std::size_t>(i)];
        int& slot = start[static_cast<std::size_t>(256 - static_cast<int>(response))];
        m.order[static_cast<std::size_t>(slot++)] = {response, v, i, work.original_points[static_cast<std::size_t>(i)]};
      }
    }
  }

  /// Step 5 for one view: orientation and descriptor in the view, keypoints mapped back.
  void describe_view(ViewWork& work) {
    const cv::Matx23d& back = work.view.to_original;
    const float sqrt_tilt = static_cast<float>(std::sqrt(work.view.tilt));
    for (int l = 0; l < options_.pyramid.levels; ++l) {
      LevelWork& level = work.levels[static_cast<std::size_t>(l)];
      level.keypoints.clear();
      level.descriptors.clear();
      if (level.kept.empty()) continue;
      level.kept_points.clear();
      for (int i : level.kept) level.kept_points.push_back(level.level_points[static_cast<std::size_t>(i)]);
      descriptor_.prepare(work.pyramid.level(l), level.kept_points, level.descriptor_data);
      const float scale = static_cast<float>(options_.pyramid.scale(l)) * sqrt_tilt;
      for (int i : level.kept) {
        const cv::Point2f p = level.level_points[static_cast<std::size_t>(i)];
        const float angle = descriptor_.orientation(level.descriptor_data, p);
        level.descriptors.push_back(descriptor_.describe(level.descriptor_data, p, angle));
        // The direction (cos θ, sin θ) in the view, mapped to the original image.
        const double dx = back(0, 0) * std::cos(angle) + back(0, 1) * std::sin(angle);
        const double dy = back(1, 0) * std::cos(angle) + back(1, 1) * std::sin(angle);
        const float original_angle = work.view.is_identity() ? angle : static_cast<float>(std::atan2(dy, dx));
        level.keypoints.emplace_back(level.original_points[static_cast<std::size_t>(i)], Descriptor::kPatchSize * scale,
                                     radians_to_degrees_0_360(original_angle),
                                     level.responses[static_cast<std::size_t>(i)], l);
      }
    }
  }

  /// Buffers of the budget step of one thread, reused across frames.
  struct SpreadWork {
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    std::vector<int> kept;
    QuadtreeWorkspace quadtree;
  };

  ExtractorOptions options_;
  /// Budget of each (view, level), index v·levels + l: views in proportion to their area 1/t,
  /// levels geometric within a view (fixed for a view set, computed by prepare_views()).
  std::vector<int> budgets_;
  /// Per frame: candidates each (view, level) offers, and what it takes (allocate_with_carry()).
  std::vector<int> available_;
  std::vector<int> take_;
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
