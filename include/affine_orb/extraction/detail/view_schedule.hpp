#pragma once
/// \file
/// How the Extractor schedules the views of one image: the turn each view takes for what depends
/// on the views before it (ViewTurns), the keypoints earlier views chose, against which a later
/// view's candidates are repeats (RepeatGrids), and the nominal budget of every (view, level) with
/// the shortfalls carried among them (ViewBudgets). The Extractor's walk of an image (render,
/// detect, drop repeats, choose, describe, select, assemble) uses these; none of them touches
/// pixels.

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/pyramid.hpp"

namespace affine_orb::detail {

/// Gives views their turn in index order while they render, detect and describe in parallel.
/// WorkerPool hands out views in increasing order, so a thread waiting for view v's turn waits
/// for views already being processed: no deadlock, and what happens in the turns does not depend
/// on the number of threads.
class ViewTurns {
 public:
  /// The next turn is view `first`'s.
  void reset(int first = 0) {
    const std::lock_guard<std::mutex> lock(mutex_);
    next_ = first;
    failed_ = false;
  }
  /// Waits for view v's turn; false when a view failed (fail()): no turn comes any more.
  bool wait(int v) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return failed_ || next_ == v; });
    return !failed_;
  }
  /// Ends view v's turn: view v + 1's begins.
  void pass(int v) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      next_ = v + 1;
    }
    changed_.notify_all();
  }
  /// A view threw: every waiting and future wait() returns false.
  void fail() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failed_ = true;
    }
    changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int next_ = 0;
  bool failed_ = false;
};

/// Keypoints chosen so far (original pixels), one grid per pyramid level, and the repeat test of
/// ExtractorOptions::repeat_levels: a point of level l repeats an entered point of level l' when
/// |l − l'| <= reach and they are closer than merge_radius · s^max(l, l'). The grid of level l has
/// cells merge_radius · s^min(l + reach, levels − 1) wide, the largest radius a point of l is
/// compared with, so a 3x3 block of cells holds every candidate. Entering and testing cost O(1)
/// per point for spread-out points; the buffers are kept across reset() calls.
class RepeatGrids {
 public:
  /// Empties the grids for an image of `size` (pixels) and a pyramid of `pyramid.levels` levels.
  void reset(cv::Size size, const PyramidOptions& pyramid, double merge_radius, int reach) {
    require(size.width > 0 && size.height > 0, "RepeatGrids::reset: the image size must be positive");
    require_range(merge_radius, kPositive, "RepeatGrids::reset: merge_radius");
    require_range(reach, kNonNegative, "RepeatGrids::reset: reach");
    levels_ = pyramid.levels;
    reach_ = reach;
    grids_.resize(static_cast<std::size_t>(levels_));
    for (int l = 0; l < levels_; ++l) {
      Grid& grid = grids_[static_cast<std::size_t>(l)];
      const double radius = merge_radius * pyramid.scale(l);
      grid.radius_squared = radius * radius;
      grid.cell = merge_radius * pyramid.scale(std::min(l + reach, levels_ - 1));
      // Points lie in [−0.5, W − 0.5) x [−0.5, H − 0.5): cells floor(x / cell) + 2 ± 1 stay inside.
      grid.columns = static_cast<int>(std::floor(size.width / grid.cell)) + 5;
      const int rows = static_cast<int>(std::floor(size.height / grid.cell)) + 5;
      grid.head.assign(static_cast<std::size_t>(grid.columns) * static_cast<std::size_t>(rows), -1);
    }
    entries_.clear();
  }

  /// Enters p (original pixels, inside the image passed to reset()) as chosen at level l.
  void enter(cv::Point2f p, int l) {
    Grid& grid = grids_[static_cast<std::size_t>(l)];
    int& head = grid.head[grid.index(p, 0, 0)];
    entries_.push_back({p, head});
    head = static_cast<int>(entries_.size()) - 1;
  }

  /// Whether a point p of level l repeats an entered one (see the class comment).
  bool repeats(cv::Point2f p, int l) const {
    for (int q = std::max(l - reach_, 0); q <= std::min(l + reach_, levels_ - 1); ++q) {
      const Grid& grid = grids_[static_cast<std::size_t>(q)];
      const double radius_squared = grids_[static_cast<std::size_t>(std::max(l, q))].radius_squared;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          for (int k = grid.head[grid.index(p, dx, dy)]; k >= 0; k = entries_[static_cast<std::size_t>(k)].next) {
            const cv::Point2f e = entries_[static_cast<std::size_t>(k)].point;
            const double ex = e.x - p.x;
            const double ey = e.y - p.y;
            if (ex * ex + ey * ey < radius_squared) return true;
          }
        }
      }
    }
    return false;
  }

  /// Number of points entered since reset().
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    cv::Point2f point;
    int next;  ///< the previous entry of the same cell, −1 at the end
  };
  struct Grid {
    double radius_squared = 1.0;  ///< (merge_radius · s^l)², the repeat radius of level l squared
    double cell = 1.0;
    int columns = 0;
    std::vector<int> head;  ///< per cell, the last entry in it (−1: none)
    std::size_t index(cv::Point2f p, int dx, int dy) const {
      const int cx = static_cast<int>(std::floor(p.x / cell)) + 2 + dx;
      const int cy = static_cast<int>(std::floor(p.y / cell)) + 2 + dy;
      return static_cast<std::size_t>(cy) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(cx);
    }
  };
  int levels_ = 0;
  int reach_ = 0;
  std::vector<Grid> grids_;
  std::vector<Entry> entries_;
};

/// The nominal budget of every (view, level) group of a view set (group index v · levels + l) and
/// what each group takes once the candidates are known, with shortfalls carried among a range of
/// groups (allocate_with_carry()). Buffers are kept, so that sharing and taking allocate nothing
/// once they have grown.
class ViewBudgets {
 public:
  /// Sizes the groups for `views` views of `levels` levels each, every budget 0.
  void resize(std::size_t views, int levels) {
    levels_ = levels;
    per_view_.assign(views, 0);
    per_group_.assign(views * static_cast<std::size_t>(levels), 0);
    take_.assign(per_group_.size(), 0);
  }

  /// Views [first, last) share `total` keypoints in proportion to tilts[v]^exponent (largest
  /// remainders; ties to the earlier view), and each view's share is split over its levels
  /// geometrically (level_budgets()). Exponent −1 weights by a view's area W·H/t, 0 gives equal
  /// shares. Other views keep their budgets.
  void share(const std::vector<double>& tilts, int first, int last, int total, double exponent, double scale_factor) {
    require(first >= 0 && first <= last && static_cast<std::size_t>(last) <= per_view_.size() &&
                tilts.size() == per_view_.size(),
            "ViewBudgets::share: bad view range");
    require_range(total, kNonNegative, "ViewBudgets::share: total");
    remainders_.clear();
    double total_weight = 0.0;
    for (int v = first; v < last; ++v) total_weight += std::pow(tilts[static_cast<std::size_t>(v)], exponent);
    int assigned = 0;
    for (int v = first; v < last; ++v) {
      const double exact = total * std::pow(tilts[static_cast<std::size_t>(v)], exponent) / total_weight;
      const int floor = static_cast<int>(std::floor(exact));
      per_view_[static_cast<std::size_t>(v)] = floor;
      assigned += floor;
      remainders_.push_back({exact - floor, v});
    }
    // Larger remainder first, the earlier view on ties (std::sort, unlike std::stable_sort,
    // allocates nothing).
    std::sort(remainders_.begin(), remainders_.end(), [](const Remainder& a, const Remainder& b) {
      return a.fraction > b.fraction || (a.fraction == b.fraction && a.view < b.view);
    });
    for (std::size_t i = 0; assigned < total && !remainders_.empty(); ++i, ++assigned) {
      ++per_view_[static_cast<std::size_t>(remainders_[i % remainders_.size()].view)];
    }
    for (int v = first; v < last; ++v) set_view(v, per_view_[static_cast<std::size_t>(v)], scale_factor);
  }

  /// View v gets `total` keypoints, split over its levels geometrically (level_budgets()).
  void set_view(int v, int total, double scale_factor) {
    per_view_[static_cast<std::size_t>(v)] = total;
    level_budgets(total, scale_factor, levels_, levels_buffer_);
    std::copy(levels_buffer_.begin(), levels_buffer_.end(),
              per_group_.begin() + static_cast<std::ptrdiff_t>(v) * levels_);
  }

  /// The nominal budget of view v (summed over its levels) and of group g.
  int view(int v) const { return per_view_[static_cast<std::size_t>(v)]; }
  int group(int g) const { return per_group_[static_cast<std::size_t>(g)]; }

  /// What each group g in [begin, end) takes, given what each offers, available[g − begin]: their
  /// budgets with shortfalls carried among them (allocate_with_carry()) when `carry`, else each
  /// min(its budget, what it offers).
  void allocate(int begin, int end, const std::vector<int>& available, bool carry) {
    require(end - begin == static_cast<int>(available.size()), "ViewBudgets::allocate: size mismatch");
    if (carry) {
      range_budgets_.assign(per_group_.begin() + begin, per_group_.begin() + end);
      allocate_with_carry(range_budgets_, available, range_take_);
      std::copy(range_take_.begin(), range_take_.end(), take_.begin() + begin);
      return;
    }
    for (int g = begin; g < end; ++g) {
      take_[static_cast<std::size_t>(g)] =
          std::min(per_group_[static_cast<std::size_t>(g)], available[static_cast<std::size_t>(g - begin)]);
    }
  }
  /// What group g takes, as the last allocate() over it decided.
  int take(int g) const { return take_[static_cast<std::size_t>(g)]; }

 private:
  struct Remainder {
    double fraction;
    int view;
  };
  int levels_ = 1;
  std::vector<int> per_view_;
  std::vector<int> per_group_;
  std::vector<int> take_;
  std::vector<Remainder> remainders_;
  std::vector<int> levels_buffer_;
  std::vector<int> range_budgets_;
  std::vector<int> range_take_;
};

/// How many of `available` candidates a group with nominal budget `budget` describes when its final
/// share is decided only once every view is done: ceil(factor · budget), at most what it has
/// (ExtractorOptions::shortlist).
inline int shortlist_size(int available, int budget, double factor) {
  return static_cast<int>(std::min<double>(static_cast<double>(available), std::ceil(factor * budget)));
}

}  // namespace affine_orb::detail
