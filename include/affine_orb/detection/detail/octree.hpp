#pragma once
/// \file
/// Internals (namespace detail): ORB-SLAM's octree distribution of one pyramid level's FAST
/// candidates (ORBextractor::DistributeOctTree of ORB-SLAM2 and ORB-SLAM3), step for step, so that
/// the same candidates in the same order give the same keypoints in the same order.
///
/// The algorithm, as the forks run it on a level's FAST region of width W and height H (level
/// pixels, origin at the region's corner):
/// 1. round(W / H) initial nodes (at least one here; the forks divide by zero below that) split
///    the region into columns of width h = W / n, node i covering x in [trunc(h·i), trunc(h·(i+1)));
///    candidate k goes to node trunc(x_k / h); empty nodes are dropped.
/// 2. A pass walks the node list from its front: every node with more than one candidate is
///    divided at ceil(width / 2) and ceil(height / 2) into four children (top left, top right,
///    bottom left, bottom right; a candidate goes left when x < the split, top when y < it), the
///    non-empty children are put at the front of the list in that order, and the parent is removed.
///    The passes end when the list holds at least `target` nodes or a pass adds none.
/// 3. When a pass ends with fewer than `target` nodes but dividing every node it created would
///    give more than `target`, the nodes with more than one candidate that the last pass created
///    are sorted by (candidate count, tie order) and divided from the last of that order to the
///    first, stopping as soon as the list holds `target` nodes; this repeats on the nodes those
///    divisions created until the list is full or no longer grows.
/// 4. Every node keeps its strongest candidate (the first of equal responses), in list order.
///
/// The tie order of step 3: ORB-SLAM2 sorts std::pair<int, ExtractorNode*>, so nodes of equal
/// count go by heap address, which differs from run to run; affine_orb takes the nodes in creation
/// order, the order of increasing addresses of a heap that only grows (OctreeTieOrder::kCreation).
/// ORB-SLAM3 compares the count, then the node's left edge, with std::sort, which this file calls
/// with the same comparison on the same sequence (OctreeTieOrder::kLeftEdge).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace affine_orb {
namespace detail {

/// How step 3 orders nodes of equal candidate count (see the file comment).
enum class OctreeTieOrder {
  kCreation,  ///< ORB-SLAM2: later-created nodes first (heap addresses of a growing heap)
  kLeftEdge,  ///< ORB-SLAM3: std::sort by (count, left edge), from the last
};

/// A node: the rectangle [x0, x1] x [y0, y1] it splits, its candidates (a range of
/// OctreeWorkspace::keys) and its links in the node list.
struct OctreeNode {
  int x0 = 0;
  int y0 = 0;
  int x1 = 0;
  int y1 = 0;
  int begin = 0;  ///< first of its candidates in OctreeWorkspace::keys
  int end = 0;    ///< one past its last
  int prev = -1;  ///< list links, -1 at the ends
  int next = -1;
  int count() const { return end - begin; }
};

/// Buffers of distribute_octree(), reused across calls. Nodes are numbered in creation order.
struct OctreeWorkspace {
  std::vector<OctreeNode> nodes;
  std::vector<int> keys;                      ///< candidate indices, each node's contiguous and in input order
  std::vector<int> scratch;                   ///< the partition buffer of a division
  std::vector<std::pair<int, int>> created;   ///< (count, node) of the last pass's nodes to divide
  std::vector<std::pair<int, int>> dividing;  ///< step 3's sorted copy of `created`
  std::vector<int> column_start;              ///< step 1: first key of each column, then its fill
  int head = -1;
  int tail = -1;
  int size = 0;  ///< nodes in the list
};

/// Appends node n at the back of the list.
inline void octree_push_back(OctreeWorkspace& w, int n) {
  OctreeNode& node = w.nodes[static_cast<std::size_t>(n)];
  node.prev = w.tail;
  node.next = -1;
  if (w.tail >= 0) w.nodes[static_cast<std::size_t>(w.tail)].next = n;
  if (w.head < 0) w.head = n;
  w.tail = n;
  ++w.size;
}

/// Puts node n at the front of the list.
inline void octree_push_front(OctreeWorkspace& w, int n) {
  OctreeNode& node = w.nodes[static_cast<std::size_t>(n)];
  node.prev = -1;
  node.next = w.head;
  if (w.head >= 0) w.nodes[static_cast<std::size_t>(w.head)].prev = n;
  if (w.tail < 0) w.tail = n;
  w.head = n;
  ++w.size;
}

/// Removes node n from the list and returns the node after it (-1 at the end).
inline int octree_erase(OctreeWorkspace& w, int n) {
  const OctreeNode node = w.nodes[static_cast<std::size_t>(n)];
  if (node.prev >= 0)
    w.nodes[static_cast<std::size_t>(node.prev)].next = node.next;
  else
    w.head = node.next;
  if (node.next >= 0)
    w.nodes[static_cast<std::size_t>(node.next)].prev = node.prev;
  else
    w.tail = node.prev;
  --w.size;
  return node.next;
}

/// Divides node n (step 2): its candidates are partitioned stably over the four children, the
/// non-empty ones are created and put at the list's front in order, and those with more than one
/// candidate are appended to w.created. Does not remove n.
inline void octree_divide(OctreeWorkspace& w, int n, const std::vector<cv::Point2f>& points) {
  const OctreeNode parent = w.nodes[static_cast<std::size_t>(n)];
  const int half_x = static_cast<int>(std::ceil(static_cast<float>(parent.x1 - parent.x0) / 2));
  const int half_y = static_cast<int>(std::ceil(static_cast<float>(parent.y1 - parent.y0) / 2));
  const int split_x = parent.x0 + half_x;
  const int split_y = parent.y0 + half_y;
  const auto child_of = [&](int key) {
    const cv::Point2f& p = points[static_cast<std::size_t>(key)];
    const int right = p.x < static_cast<float>(split_x) ? 0 : 1;
    const int bottom = p.y < static_cast<float>(split_y) ? 0 : 2;
    return right + bottom;
  };
  int counts[4] = {0, 0, 0, 0};
  for (int k = parent.begin; k < parent.end; ++k) ++counts[child_of(w.keys[static_cast<std::size_t>(k)])];
  int starts[4];
  starts[0] = parent.begin;
  for (int c = 1; c < 4; ++c) starts[c] = starts[c - 1] + counts[c - 1];
  int fill[4] = {starts[0], starts[1], starts[2], starts[3]};
  for (int k = parent.begin; k < parent.end; ++k) {
    const int key = w.keys[static_cast<std::size_t>(k)];
    w.scratch[static_cast<std::size_t>(fill[child_of(key)]++)] = key;
  }
  std::copy(w.scratch.begin() + parent.begin, w.scratch.begin() + parent.end, w.keys.begin() + parent.begin);
  const int xs[3] = {parent.x0, split_x, parent.x1};
  const int ys[3] = {parent.y0, split_y, parent.y1};
  for (int c = 0; c < 4; ++c) {
    if (counts[c] == 0) continue;
    OctreeNode child;
    child.x0 = xs[c % 2];
    child.x1 = xs[c % 2 + 1];
    child.y0 = ys[c / 2];
    child.y1 = ys[c / 2 + 1];
    child.begin = starts[c];
    child.end = starts[c] + counts[c];
    const int id = static_cast<int>(w.nodes.size());
    w.nodes.push_back(child);
    octree_push_front(w, id);
    if (counts[c] > 1) w.created.emplace_back(counts[c], id);
  }
}

/// Step 1: the initial column nodes of a region of width x height, their candidates in input
/// order, the empty ones left out.
inline void octree_start(const std::vector<cv::Point2f>& points, int width, int height, OctreeWorkspace& w) {
  const int columns = std::max(1, static_cast<int>(std::round(static_cast<float>(width) / static_cast<float>(height))));
  const float column_width = static_cast<float>(width) / static_cast<float>(columns);
  w.nodes.clear();
  w.created.clear();
  w.head = w.tail = -1;
  w.size = 0;
  w.keys.resize(points.size());
  w.scratch.resize(points.size());
  // Counting sort of the candidates by column, stable; the column of candidate k in scratch[k].
  std::vector<int>& start = w.column_start;
  start.assign(static_cast<std::size_t>(columns) + 1, 0);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int c = std::min(static_cast<int>(points[k].x / column_width), columns - 1);
    w.scratch[k] = c;
    ++start[static_cast<std::size_t>(c) + 1];
  }
  for (int c = 0; c < columns; ++c) start[static_cast<std::size_t>(c) + 1] += start[static_cast<std::size_t>(c)];
  for (std::size_t k = 0; k < points.size(); ++k) {
    w.keys[static_cast<std::size_t>(start[static_cast<std::size_t>(w.scratch[k])]++)] = static_cast<int>(k);
  }
  // The fill moved each start to the next column's: column c now begins at start[c − 1].
  for (int c = 0; c < columns; ++c) {
    OctreeNode node;
    node.x0 = static_cast<int>(column_width * static_cast<float>(c));
    node.x1 = static_cast<int>(column_width * static_cast<float>(c + 1));
    node.y0 = 0;
    node.y1 = height;
    node.begin = c == 0 ? 0 : start[static_cast<std::size_t>(c) - 1];
    node.end = start[static_cast<std::size_t>(c)];
    if (node.count() == 0) continue;
    w.nodes.push_back(node);
    octree_push_back(w, static_cast<int>(w.nodes.size()) - 1);
  }
}

/// Step 3 on the nodes of w.created: sorted by (count, tie order), divided from the last of that
/// order until the list holds `target` nodes, repeated on what the divisions create until the list
/// is full or stops growing.
inline void octree_divide_largest(OctreeWorkspace& w, const std::vector<cv::Point2f>& points, int target,
                                  OctreeTieOrder ties) {
  while (true) {
    const int before = w.size;
    w.dividing = w.created;
    w.created.clear();
    if (ties == OctreeTieOrder::kCreation) {
      std::sort(w.dividing.begin(), w.dividing.end());
    } else {
      const std::vector<OctreeNode>& nodes = w.nodes;
      std::sort(w.dividing.begin(), w.dividing.end(),
                [&nodes](const std::pair<int, int>& a, const std::pair<int, int>& b) {
                  if (a.first != b.first) return a.first < b.first;
                  return nodes[static_cast<std::size_t>(a.second)].x0 < nodes[static_cast<std::size_t>(b.second)].x0;
                });
    }
    for (std::size_t j = w.dividing.size(); j-- > 0;) {
      const int n = w.dividing[j].second;
      octree_divide(w, n, points);
      octree_erase(w, n);
      if (w.size >= target) break;
    }
    if (w.size >= target || w.size == before) return;
  }
}

/// ORB-SLAM's octree distribution (the file comment) of `points` (level pixels relative to the
/// corner of a region of width x height, each inside it) with `responses`: the indices of the kept
/// candidates, one per final node in list order, into `kept` (its buffer reused). A `target` of 0
/// still runs one pass, as the forks do.
inline void distribute_octree(const std::vector<cv::Point2f>& points, const std::vector<float>& responses, int width,
                              int height, int target, OctreeTieOrder ties, OctreeWorkspace& w, std::vector<int>& kept) {
  kept.clear();
  if (points.empty() || width <= 0 || height <= 0) return;
  octree_start(points, width, height, w);
  while (true) {
    const int before = w.size;
    w.created.clear();
    int n = w.head;
    while (n >= 0) {
      if (w.nodes[static_cast<std::size_t>(n)].count() == 1) {
        n = w.nodes[static_cast<std::size_t>(n)].next;
        continue;
      }
      octree_divide(w, n, points);
      n = octree_erase(w, n);
    }
    if (w.size >= target || w.size == before) break;
    if (w.size + 3 * static_cast<int>(w.created.size()) > target) {
      octree_divide_largest(w, points, target, ties);
      break;
    }
  }
  for (int n = w.head; n >= 0; n = w.nodes[static_cast<std::size_t>(n)].next) {
    const OctreeNode& node = w.nodes[static_cast<std::size_t>(n)];
    int best = w.keys[static_cast<std::size_t>(node.begin)];
    for (int k = node.begin + 1; k < node.end; ++k) {
      const int key = w.keys[static_cast<std::size_t>(k)];
      if (responses[static_cast<std::size_t>(key)] > responses[static_cast<std::size_t>(best)]) best = key;
    }
    kept.push_back(best);
  }
}

}  // namespace detail
}  // namespace affine_orb
