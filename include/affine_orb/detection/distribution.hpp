#pragma once
/// \file
/// Feature budget and spatial spreading (docs/algorithm.md §2): how many features each pyramid level gets, and
/// which candidates of a level are kept so that they cover the image instead of clumping on the
/// strongest texture.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/detection/detail/distribution.hpp"

namespace affine_orb {

/// Splits a budget of `total` features over `levels` pyramid levels geometrically with ratio
/// 1/scale_factor, as ORB and ORB-SLAM2 do: level 0 gets round(N·(1−f)/(1−f^L)) with f = 1/s,
/// each next level f times the previous (rounded), and the last level the remainder, so that the
/// budgets sum to exactly `total`. `budgets` (its buffer reused) receives one entry per level.
inline void level_budgets(int total, double scale_factor, int levels, std::vector<int>& budgets) {
  detail::require_range(total, detail::kNonNegative, "level_budgets: total");
  detail::require_range(levels, detail::kPositive, "level_budgets: levels");
  detail::require_range(scale_factor, {1, std::numeric_limits<double>::infinity(), true, true},
                        "level_budgets: scale_factor");
  // max(): GCC 12 does not see that require() threw for levels < 1 and warns about back().
  budgets.assign(static_cast<std::size_t>(std::max(levels, 1)), 0);
  const double f = 1.0 / scale_factor;
  double per_level = total * (1.0 - f) / (1.0 - std::pow(f, levels));
  int assigned = 0;
  for (int l = 0; l + 1 < levels; ++l) {
    const int n = std::min(static_cast<int>(std::lround(per_level)), total - assigned);
    budgets[static_cast<std::size_t>(l)] = n;
    assigned += n;
    per_level *= f;
  }
  budgets.back() = total - assigned;
}

/// level_budgets() returning the result.
inline std::vector<int> level_budgets(int total, double scale_factor, int levels) {
  std::vector<int> budgets;
  level_budgets(total, scale_factor, levels, budgets);
  return budgets;
}

/// Distributes `wanted` features over groups (levels, views) that offer `available[i]` candidates
/// each and were given `budgets[i]`: every group takes what it can of its budget plus the shortfall
/// carried from the groups before it; whatever is still missing after the last group is taken, in
/// group order, from the groups that have candidates left. `take` (its buffer reused) receives
/// the result, which sums to min(Σ budgets, Σ available).
inline void allocate_with_carry(const std::vector<int>& budgets, const std::vector<int>& available,
                                std::vector<int>& take) {
  detail::require(budgets.size() == available.size(), "allocate_with_carry: size mismatch");
  take.assign(budgets.size(), 0);
  long carry = 0;
  for (std::size_t i = 0; i < budgets.size(); ++i) {
    const long want = budgets[i] + carry;
    take[i] = static_cast<int>(std::min<long>(want, available[i]));
    carry = want - take[i];
  }
  for (std::size_t i = 0; i < budgets.size() && carry > 0; ++i) {
    const long extra = std::min<long>(carry, available[i] - take[i]);
    take[i] += static_cast<int>(extra);
    carry -= extra;
  }
}

/// allocate_with_carry() returning the result.
inline std::vector<int> allocate_with_carry(const std::vector<int>& budgets, const std::vector<int>& available) {
  std::vector<int> take;
  allocate_with_carry(budgets, available, take);
  return take;
}

/// The `target` strongest of `responses` (ties: the lower index), as indices ascending, into `kept`
/// (its buffer reused); all of them when there are no more than `target`. cv::ORB's selection (no
/// spatial spreading).
inline void select_strongest(const std::vector<float>& responses, int target, std::vector<int>& kept) {
  detail::require_range(target, detail::kNonNegative, "select_strongest: target");
  kept.resize(responses.size());
  std::iota(kept.begin(), kept.end(), 0);
  if (static_cast<std::size_t>(target) < kept.size()) {
    std::nth_element(kept.begin(), kept.begin() + target, kept.end(), [&](int a, int b) {
      const float ra = responses[static_cast<std::size_t>(a)];
      const float rb = responses[static_cast<std::size_t>(b)];
      return ra > rb || (ra == rb && a < b);
    });
    kept.resize(static_cast<std::size_t>(target));
  }
  std::sort(kept.begin(), kept.end());
}

/// select_strongest() returning the result.
inline std::vector<int> select_strongest(const std::vector<float>& responses, int target) {
  std::vector<int> kept;
  select_strongest(responses, target, kept);
  return kept;
}

/// Buffers of distribute_quadtree(), reused across calls so that the extractor does not allocate
/// once they have grown to the largest level seen.
struct QuadtreeWorkspace {
  std::vector<int> index;             ///< candidate indices grouped by cell
  std::vector<cv::Point2f> position;  ///< their positions, in the same order (read sequentially)
  std::vector<int> index_scratch;     ///< the same two during a split
  std::vector<cv::Point2f> position_scratch;
  std::vector<unsigned char> quadrant;  ///< per member of the cell being split: its quadrant
  std::vector<detail::QuadCell> cells;
  std::vector<detail::QuadCell> children;
  std::vector<detail::QuadCell> next;
  std::vector<int> order;  ///< splittable cells, most populated first
  std::vector<char> split;
  std::vector<char> taken;
  std::vector<int> rest;
};

namespace detail {

/// Orders candidate indices strongest first: the larger response, ties the lower index.
struct StrongerCandidate {
  const std::vector<float>& responses;

  bool operator()(int a, int b) const {
    const float ra = responses[static_cast<std::size_t>(a)];
    const float rb = responses[static_cast<std::size_t>(b)];
    return ra > rb || (ra == rb && a < b);
  }
};

/// True for a cell that distribute_quadtree() may split: more than one member and at least one
/// pixel wide and high.
inline bool splittable(const QuadCell& cell) {
  return cell.size() > 1 && cell.box.width >= 1.0f && cell.box.height >= 1.0f;
}

/// Sizes the member buffers of `work` for `points` and makes work.cells the root cells of
/// `region` that hold points: max(1, round(width/height)) cells side by side, roughly square.
/// Cells hold ranges of one member buffer (work.index and work.position), filled here by a
/// counting sort of all points on their root (work.rest holds each point's root, work.order the
/// bucket starts).
inline void make_root_cells(const std::vector<cv::Point2f>& points, cv::Rect2f region, QuadtreeWorkspace& work) {
  const std::size_t size = points.size();
  const int n = static_cast<int>(size);
  work.index.resize(size);
  work.position.resize(size);
  work.index_scratch.resize(size);
  work.position_scratch.resize(size);
  work.quadrant.resize(size);
  work.cells.clear();
  const int roots = std::max(1, static_cast<int>(std::lround(region.width / std::max(region.height, 1.0f))));
  const float root_width = region.width / static_cast<float>(roots);
  std::vector<int>& root_of = work.rest;
  root_of.resize(size);
  work.order.assign(static_cast<std::size_t>(roots) + 1, 0);
  for (int i = 0; i < n; ++i) {
    const cv::Point2f& p = points[static_cast<std::size_t>(i)];
    const int r = std::clamp(static_cast<int>((p.x - region.x) / root_width), 0, roots - 1);
    root_of[static_cast<std::size_t>(i)] = r;
    ++work.order[static_cast<std::size_t>(r) + 1];
  }
  for (int r = 0; r < roots; ++r)
    work.order[static_cast<std::size_t>(r) + 1] += work.order[static_cast<std::size_t>(r)];
  for (int r = 0; r < roots; ++r) {
    const int begin = work.order[static_cast<std::size_t>(r)];
    const int end = work.order[static_cast<std::size_t>(r) + 1];
    if (begin == end) continue;
    work.cells.push_back({{region.x + r * root_width, region.y, root_width, region.height}, begin, end});
  }
  for (int i = 0; i < n; ++i) {
    const std::size_t to =
        static_cast<std::size_t>(work.order[static_cast<std::size_t>(root_of[static_cast<std::size_t>(i)])]++);
    work.index[to] = i;
    work.position[to] = points[static_cast<std::size_t>(i)];
  }
}

/// Copies members [begin, end) of work.index_scratch/position_scratch back to work.index/position
/// grouped by work.quadrant (0 .. 3), a counting sort (the order of a cell's members does not
/// matter: every step depends only on the member set). Returns the bucket starts: quadrant q
/// covers [begin + start[q], begin + start[q + 1]).
inline std::array<int, 5> regroup_by_quadrant(int begin, int end, QuadtreeWorkspace& work) {
  std::array<int, 5> start = {0, 0, 0, 0, 0};
  for (int i = begin; i < end; ++i) ++start[work.quadrant[static_cast<std::size_t>(i)] + 1];
  for (int q = 0; q < 4; ++q) start[q + 1] += start[q];
  std::array<int, 4> fill = {start[0], start[1], start[2], start[3]};
  for (int i = begin; i < end; ++i) {
    const std::size_t to = static_cast<std::size_t>(begin + fill[work.quadrant[static_cast<std::size_t>(i)]]++);
    work.index[to] = work.index_scratch[static_cast<std::size_t>(i)];
    work.position[to] = work.position_scratch[static_cast<std::size_t>(i)];
  }
  return start;
}

/// Splits `cell` into four at its centre, quadrant q = (x >= cx) + 2·(y >= cy): regroups its
/// members by quadrant and appends the non-empty quadrants to work.children in the order of q.
/// Returns how many it appended.
inline int split_cell(const QuadCell& cell, QuadtreeWorkspace& work) {
  const float hw = cell.box.width * 0.5f;
  const float hh = cell.box.height * 0.5f;
  const float cx = cell.box.x + hw;
  const float cy = cell.box.y + hh;
  for (int i = cell.begin; i < cell.end; ++i) {
    const cv::Point2f& p = work.position[static_cast<std::size_t>(i)];
    work.quadrant[static_cast<std::size_t>(i)] = static_cast<unsigned char>((p.x >= cx) + 2 * (p.y >= cy));
    work.index_scratch[static_cast<std::size_t>(i)] = work.index[static_cast<std::size_t>(i)];
    work.position_scratch[static_cast<std::size_t>(i)] = p;
  }
  const std::array<int, 5> start = regroup_by_quadrant(cell.begin, cell.end, work);
  const cv::Rect2f boxes[4] = {
      {cell.box.x, cell.box.y, hw, hh}, {cx, cell.box.y, hw, hh}, {cell.box.x, cy, hw, hh}, {cx, cy, hw, hh}};
  int nonempty = 0;
  for (int q = 0; q < 4; ++q) {
    if (start[q] == start[q + 1]) continue;
    work.children.push_back({boxes[q], cell.begin + start[q], cell.begin + start[q + 1]});
    ++nonempty;
  }
  return nonempty;
}

/// One round of splitting work.cells: the splittable cells, most populated first (ties in cell
/// order), are split until there are `target` cells; work.cells becomes the cells not split
/// followed by the children. Returns false, changing nothing, when no cell is splittable.
inline bool split_round(int target, QuadtreeWorkspace& work) {
  work.order.clear();
  for (std::size_t i = 0; i < work.cells.size(); ++i) {
    if (splittable(work.cells[i])) work.order.push_back(static_cast<int>(i));
  }
  if (work.order.empty()) return false;
  // A stable sort by size, without its buffer.
  std::sort(work.order.begin(), work.order.end(), [&](int a, int b) {
    const int sa = work.cells[static_cast<std::size_t>(a)].size();
    const int sb = work.cells[static_cast<std::size_t>(b)].size();
    return sa > sb || (sa == sb && a < b);
  });
  work.split.assign(work.cells.size(), 0);
  int count = static_cast<int>(work.cells.size());
  work.children.clear();
  for (int idx : work.order) {
    if (count >= target) break;
    count += split_cell(work.cells[static_cast<std::size_t>(idx)], work) - 1;
    work.split[static_cast<std::size_t>(idx)] = 1;
  }
  work.next.clear();
  for (std::size_t i = 0; i < work.cells.size(); ++i) {
    if (!work.split[i]) work.next.push_back(work.cells[i]);
  }
  work.next.insert(work.next.end(), work.children.begin(), work.children.end());
  // Copied, not swapped, so that each buffer keeps its own capacity from call to call.
  work.cells.assign(work.next.begin(), work.next.end());
  return true;
}

/// Fills `kept` with the strongest member of each of work.cells, then drops the weakest of them
/// or adds the strongest other candidates so that exactly `target` (at most `n`, the number of
/// candidates) remain, in ascending order.
inline void keep_cell_winners(const std::vector<float>& responses, int n, int target, QuadtreeWorkspace& work,
                              std::vector<int>& kept) {
  const StrongerCandidate stronger{responses};
  work.taken.assign(static_cast<std::size_t>(n), 0);
  for (const QuadCell& cell : work.cells) {
    const int best = *std::min_element(work.index.begin() + cell.begin, work.index.begin() + cell.end, stronger);
    kept.push_back(best);
    work.taken[static_cast<std::size_t>(best)] = 1;
  }
  std::sort(kept.begin(), kept.end(), stronger);
  if (static_cast<int>(kept.size()) > target) {
    kept.resize(static_cast<std::size_t>(target));
  } else if (static_cast<int>(kept.size()) < target) {
    work.rest.clear();
    for (int i = 0; i < n; ++i) {
      if (!work.taken[static_cast<std::size_t>(i)]) work.rest.push_back(i);
    }
    const std::size_t missing = static_cast<std::size_t>(target) - kept.size();
    std::partial_sort(work.rest.begin(), work.rest.begin() + static_cast<std::ptrdiff_t>(missing), work.rest.end(),
                      stronger);
    kept.insert(kept.end(), work.rest.begin(), work.rest.begin() + static_cast<std::ptrdiff_t>(missing));
  }
  std::sort(kept.begin(), kept.end());
}

}  // namespace detail

/// Spatial spreading by a quadtree over `region` (the same role as ORB-SLAM2's octree distribution;
/// this is an independent formulation):
/// 1. the region is cut into max(1, round(width/height)) roughly square root cells;
/// 2. in rounds, every cell holding more than one candidate is split into four; when a full round
///    would overshoot `target` cells, the most populated cells are split first and the round stops
///    as soon as there are `target` cells; a cell smaller than one pixel is not split;
/// 3. the strongest candidate of each cell is kept (ties: the lower index);
/// 4. if that is more than `target`, the weakest are dropped; if fewer and more candidates exist,
///    the strongest remaining candidates are added, so exactly min(target, points.size()) indices
///    are returned.
/// `kept` receives indices into `points`, ascending; `responses[i]` ranks point i (larger is
/// better). `work` holds the buffers, reused across calls.
inline void distribute_quadtree(const std::vector<cv::Point2f>& points, const std::vector<float>& responses,
                                cv::Rect2f region, int target, QuadtreeWorkspace& work, std::vector<int>& kept) {
  detail::require(points.size() == responses.size(), "distribute_quadtree: points and responses differ in size");
  detail::require_range(target, detail::kNonNegative, "distribute_quadtree: target");
  const int n = static_cast<int>(points.size());
  kept.clear();
  if (target == 0 || n == 0) return;
  if (n <= target) {
    kept.resize(static_cast<std::size_t>(n));
    std::iota(kept.begin(), kept.end(), 0);
    return;
  }
  detail::make_root_cells(points, region, work);
  while (static_cast<int>(work.cells.size()) < target) {
    if (!detail::split_round(target, work)) break;
  }
  detail::keep_cell_winners(responses, n, target, work, kept);
}

/// distribute_quadtree() with fresh buffers, returning the kept indices.
inline std::vector<int> distribute_quadtree(const std::vector<cv::Point2f>& points, const std::vector<float>& responses,
                                            cv::Rect2f region, int target) {
  QuadtreeWorkspace work;
  std::vector<int> kept;
  distribute_quadtree(points, responses, region, target, work, kept);
  return kept;
}

}  // namespace affine_orb
