#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the quadtree's cell behind distribute_quadtree()
/// (detection/distribution.hpp).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"

namespace affine_orb {
namespace detail {

/// A quadtree cell: its box and the range [begin, end) of its members in QuadtreeWorkspace::index.
struct QuadCell {
  cv::Rect2f box;
  int begin;
  int end;
  int size() const { return end - begin; }
};

}  // namespace detail
}  // namespace affine_orb
