#pragma once
/// \file
/// Feature budget and spatial spreading (SPEC §2): how many features each pyramid level gets, and
/// which candidates of a level are kept so that they cover the image instead of clumping on the
/// strongest texture.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/detail/check.hpp"

namespace affine_orb {

/// Splits a budget of `total` features over `levels` pyramid levels geometrically with ratio
/// 1/scale_factor, as ORB and ORB-SLAM2 do: level 0 gets round(N·(1−f)/(1−f^L)) with f = 1/s,
/// each next level f times the previous (rounded), and the last level the remainder, so that the
/// budgets sum to exactly `total`.
inline std::vector<int> level_budgets(int total, double scale_factor, int levels) {
  detail::require(total >= 0, "level_budgets: total must be >= 0");
  detail::require(levels >= 1, "level_budgets: levels must be >= 1");
  detail::require(std::isfinite(scale_factor) && scale_factor > 1.0, "level_budgets: scale_factor must be > 1");
  std::vector<int> budgets(static_cast<std::size_t>(levels), 0);
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
  return budgets;
}

/// Distributes `wanted` features over groups (levels, views) that offer `available[i]` candidates
/// each and were given `budgets[i]`: every group takes what it can of its budget plus the shortfall
/// carried from the groups before it; whatever is still missing after the last group is taken, in
/// group order, from the groups that have candidates left. The result sums to
/// min(Σ budgets, Σ available).
inline std::vector<int> allocate_with_carry(const std::vector<int>& budgets, const std::vector<int>& available) {
  detail::require(budgets.size() == available.size(), "allocate_with_carry: size mismatch");
  std::vector<int> take(budgets.size(), 0);
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
  return take;
}

/// The `target` strongest of `responses` (ties: the lower index), as indices ascending; all of
/// them when there are no more than `target`. cv::ORB's selection (no spatial spreading).
inline std::vector<int> select_strongest(const std::vector<float>& responses, int target) {
  detail::require(target >= 0, "select_strongest: target must be >= 0");
  std::vector<int> kept(responses.size());
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
  return kept;
}

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
/// Returns indices into `points`, ascending. `responses[i]` ranks point i (larger is better).
inline std::vector<int> distribute_quadtree(const std::vector<cv::Point2f>& points, const std::vector<float>& responses,
                                            cv::Rect2f region, int target) {
  detail::require(points.size() == responses.size(), "distribute_quadtree: points and responses differ in size");
  detail::require(target >= 0, "distribute_quadtree: target must be >= 0");
  const int n = static_cast<int>(points.size());
  std::vector<int> kept;
  if (target == 0 || n == 0) return kept;
  auto stronger = [&](int a, int b) {
    return responses[static_cast<std::size_t>(a)] > responses[static_cast<std::size_t>(b)] ||
           (responses[static_cast<std::size_t>(a)] == responses[static_cast<std::size_t>(b)] && a < b);
  };
  if (n <= target) {
    kept.resize(static_cast<std::size_t>(n));
    std::iota(kept.begin(), kept.end(), 0);
    return kept;
  }

  // Cells hold ranges of one index buffer; splitting a cell partitions its range in place (the
  // order of a cell's members does not matter: every step depends only on the member set).
  struct Cell {
    cv::Rect2f box;
    int begin;
    int end;
    int size() const { return end - begin; }
  };
  std::vector<Cell> cells;
  std::vector<int> index(static_cast<std::size_t>(n));
  const int roots = std::max(1, static_cast<int>(std::lround(region.width / std::max(region.height, 1.0f))));
  const float root_width = region.width / static_cast<float>(roots);
  {
    std::vector<int> root_of(static_cast<std::size_t>(n));
    std::vector<int> start(static_cast<std::size_t>(roots) + 1, 0);
    for (int i = 0; i < n; ++i) {
      const cv::Point2f& p = points[static_cast<std::size_t>(i)];
      const int r = std::clamp(static_cast<int>((p.x - region.x) / root_width), 0, roots - 1);
      root_of[static_cast<std::size_t>(i)] = r;
      ++start[static_cast<std::size_t>(r) + 1];
    }
    for (int r = 0; r < roots; ++r) start[static_cast<std::size_t>(r) + 1] += start[static_cast<std::size_t>(r)];
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i)
      index[static_cast<std::size_t>(fill[static_cast<std::size_t>(root_of[static_cast<std::size_t>(i)])]++)] = i;
    for (int r = 0; r < roots; ++r) {
      if (start[static_cast<std::size_t>(r)] == start[static_cast<std::size_t>(r) + 1]) continue;
      cells.push_back({{region.x + r * root_width, region.y, root_width, region.height},
                       start[static_cast<std::size_t>(r)],
                       start[static_cast<std::size_t>(r) + 1]});
    }
  }

  auto splittable = [](const Cell& c) { return c.size() > 1 && c.box.width >= 1.0f && c.box.height >= 1.0f; };
  std::vector<std::size_t> order;
  std::vector<char> split;
  std::vector<Cell> children;
  std::vector<Cell> next;
  while (static_cast<int>(cells.size()) < target) {
    order.clear();
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (splittable(cells[i])) order.push_back(i);
    }
    if (order.empty()) break;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return cells[a].size() > cells[b].size(); });
    split.assign(cells.size(), 0);
    int count = static_cast<int>(cells.size());
    children.clear();
    for (std::size_t idx : order) {
      if (count >= target) break;
      const Cell cell = cells[idx];
      const float hw = cell.box.width * 0.5f;
      const float hh = cell.box.height * 0.5f;
      const float cx = cell.box.x + hw;
      const float cy = cell.box.y + hh;
      // Quadrant q = (x >= cx) + 2·(y >= cy): partition the range by q, quadrant by quadrant.
      auto quadrant = [&](int m) {
        const cv::Point2f& p = points[static_cast<std::size_t>(m)];
        return (p.x >= cx ? 1 : 0) + (p.y >= cy ? 2 : 0);
      };
      int* first = index.data() + cell.begin;
      int* last = index.data() + cell.end;
      int* bounds[5] = {first, nullptr, nullptr, nullptr, last};
      for (int q = 0; q < 3; ++q) {
        bounds[q + 1] = std::partition(bounds[q], last, [&](int m) { return quadrant(m) == q; });
      }
      const cv::Rect2f boxes[4] = {
          {cell.box.x, cell.box.y, hw, hh}, {cx, cell.box.y, hw, hh}, {cell.box.x, cy, hw, hh}, {cx, cy, hw, hh}};
      int nonempty = 0;
      for (int q = 0; q < 4; ++q) {
        if (bounds[q] == bounds[q + 1]) continue;
        children.push_back(
            {boxes[q], static_cast<int>(bounds[q] - index.data()), static_cast<int>(bounds[q + 1] - index.data())});
        ++nonempty;
      }
      count += nonempty - 1;
      split[idx] = 1;
    }
    next.clear();
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (!split[i]) next.push_back(cells[i]);
    }
    next.insert(next.end(), children.begin(), children.end());
    cells.swap(next);
  }

  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  for (const Cell& cell : cells) {
    const int best = *std::min_element(index.begin() + cell.begin, index.begin() + cell.end, stronger);
    kept.push_back(best);
    taken[static_cast<std::size_t>(best)] = 1;
  }
  std::sort(kept.begin(), kept.end(), stronger);
  if (static_cast<int>(kept.size()) > target) {
    kept.resize(static_cast<std::size_t>(target));
  } else if (static_cast<int>(kept.size()) < target) {
    std::vector<int> rest;
    for (int i = 0; i < n; ++i) {
      if (!taken[static_cast<std::size_t>(i)]) rest.push_back(i);
    }
    const std::size_t missing = static_cast<std::size_t>(target) - kept.size();
    std::partial_sort(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(missing), rest.end(), stronger);
    kept.insert(kept.end(), rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(missing));
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace affine_orb
