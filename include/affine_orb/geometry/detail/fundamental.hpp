#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the 8-point equations, least squares with the rank-2 projection
/// and denormalisation behind geometry/fundamental.hpp.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/detail/geometry_linear.hpp"
#include "affine_orb/geometry/detail/normalization.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {
namespace detail {

/// The epipolar equation x2ᵀ F x1 = 0 for the row-major vector of F (Hartley & Zisserman eq. 11.3),
/// multiplied by `weight`.
inline void fundamental_equation(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double weight, double* row) {
  const double x = a.x(), y = a.y(), u = b.x() * weight, v = b.y() * weight;
  row[0] = u * x, row[1] = u * y, row[2] = u;
  row[3] = v * x, row[4] = v * y, row[5] = v;
  row[6] = weight * x, row[7] = weight * y, row[8] = weight;
}

/// A rank-2, unit-norm pixel F from a normalised-coordinate solution vector; nullopt if not finite.
inline std::optional<Eigen::Matrix3d> denormalize_fundamental(const Vector9d& f, const Eigen::Matrix3d& t1,
                                                              const Eigen::Matrix3d& t2) {
  const Eigen::Matrix3d fn = enforce_rank2(reshape_row_major(f));
  const Eigen::Matrix3d pixels = t2.transpose() * fn * t1;
  if (!pixels.allFinite() || !(pixels.norm() > 0.0)) return std::nullopt;
  const Eigen::Matrix3d normalized = normalize_homogeneous(pixels);
  if (!normalized.allFinite()) return std::nullopt;
  return normalized;
}

/// Least-squares 8-point solution over `points1/2[indices]` (normalised coordinates), with each
/// equation weighted by the inverse Sampson gradient norm of `previous` when given.
inline std::optional<Vector9d> fundamental_least_squares(const std::vector<Eigen::Vector2d>& points1,
                                                         const std::vector<Eigen::Vector2d>& points2,
                                                         const std::vector<std::size_t>& indices,
                                                         const Eigen::Matrix3d* previous) {
  Eigen::Matrix<double, Eigen::Dynamic, 9> a(static_cast<Eigen::Index>(indices.size()), 9);
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const Eigen::Vector2d& x1 = points1[indices[k]];
    const Eigen::Vector2d& x2 = points2[indices[k]];
    double weight = 1.0;
    if (previous != nullptr) {
      const Eigen::Vector3d l2 = *previous * x1.homogeneous();
      const Eigen::Vector3d l1 = previous->transpose() * x2.homogeneous();
      const double gradient = std::sqrt(l2.x() * l2.x() + l2.y() * l2.y() + l1.x() * l1.x() + l1.y() * l1.y());
      if (gradient > 0.0 && std::isfinite(gradient)) weight = 1.0 / gradient;
    }
    double row[9];
    fundamental_equation(x1, x2, weight, row);
    for (int c = 0; c < 9; ++c) a(static_cast<Eigen::Index>(k), c) = row[c];
  }
  const Matrix9d normal = a.transpose() * a;
  return smallest_eigenvector(normal);
}

}  // namespace detail
}  // namespace affine_orb
