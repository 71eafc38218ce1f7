#pragma once
/// \file
/// Small fixed-size linear algebra shared by the homography and fundamental-matrix estimators:
/// null vectors of 8x9 systems, least-squares solutions of homogeneous systems through their 9x9
/// normal matrix, rank-2 projection and the orientation of point triples.

#include <array>
#include <cmath>
#include <optional>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace affine_orb::detail {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix89d = Eigen::Matrix<double, 8, 9>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// Relative size (to the largest entry, resp. the largest eigenvalue) under which a pivot or a
/// second-smallest eigenvalue counts as zero: the system then has more than a one-dimensional null
/// space (a degenerate sample such as repeated or collinear points) and no model is returned.
/// Far below the ~1e-4 relative level that 1 px of noise leaves in normalised coordinates, far
/// above double rounding (~1e-16).
inline constexpr double kRankTolerance = 1e-10;

/// The unit null vector of an 8x9 matrix of rank 8, by Gaussian elimination with full pivoting.
/// Returns nullopt when the rank is below 8 (some pivot is below kRankTolerance times the largest
/// entry) or the input is not finite.
inline std::optional<Vector9d> null_vector_8x9(Matrix89d a) {
  std::array<int, 9> column = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const double largest = a.cwiseAbs().maxCoeff();
  if (!(largest > 0.0) || !std::isfinite(largest)) return std::nullopt;
  const double tolerance = kRankTolerance * largest;
  for (int k = 0; k < 8; ++k) {
    int pivot_row = k;
    int pivot_col = k;
    double pivot = 0.0;
    for (int c = k; c < 9; ++c) {
      for (int r = k; r < 8; ++r) {
        const double v = std::abs(a(r, c));
        if (v > pivot) {
          pivot = v;
          pivot_row = r;
          pivot_col = c;
        }
      }
    }
    if (!(pivot > tolerance)) return std::nullopt;
    a.row(k).swap(a.row(pivot_row));
    a.col(k).swap(a.col(pivot_col));
    std::swap(column[static_cast<std::size_t>(k)], column[static_cast<std::size_t>(pivot_col)]);
    for (int r = k + 1; r < 8; ++r) {
      const double factor = a(r, k) / a(k, k);
      a.row(r).segment(k, 9 - k) -= factor * a.row(k).segment(k, 9 - k);
    }
  }
  // Upper-triangular in the permuted columns; the last permuted column is the free variable.
  Vector9d permuted;
  permuted(8) = 1.0;
  for (int k = 7; k >= 0; --k) {
    double sum = 0.0;
    for (int c = k + 1; c < 9; ++c) sum += a(k, c) * permuted(c);
    permuted(k) = -sum / a(k, k);
  }
  Vector9d x;
  for (int k = 0; k < 9; ++k) x(column[static_cast<std::size_t>(k)]) = permuted(k);
  const double norm = x.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return std::nullopt;
  return x / norm;
}

/// The unit vector x minimising xᵀ M x for a symmetric positive semi-definite 9x9 normal matrix
/// M = Aᵀ A (the least-squares solution of A x = 0 with ‖x‖ = 1). Returns nullopt when M is not
/// finite or its null space is more than one-dimensional (second-smallest eigenvalue below
/// kRankTolerance times the largest), i.e. the rows do not determine x.
inline std::optional<Vector9d> smallest_eigenvector(const Matrix9d& normal) {
  if (!normal.allFinite()) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Matrix9d> solver(normal);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Vector9d& values = solver.eigenvalues();  // ascending
  if (!(values(8) > 0.0) || !(values(1) > kRankTolerance * values(8))) return std::nullopt;
  return Vector9d(solver.eigenvectors().col(0));
}

/// The 3x3 matrix whose rows are consecutive triples of `v` (row-major reshape).
inline Eigen::Matrix3d reshape_row_major(const Vector9d& v) {
  Eigen::Matrix3d m;
  m << v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8);
  return m;
}

/// The closest rank-2 matrix in Frobenius norm (smallest singular value set to zero).
inline Eigen::Matrix3d enforce_rank2(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d singular = svd.singularValues();
  singular(2) = 0.0;
  return svd.matrixU() * singular.asDiagonal() * svd.matrixV().transpose();
}

/// Twice the signed area of the triangle (a, b, c): positive when counter-clockwise in a frame
/// with y up (clockwise on screen), zero when collinear.
inline double orientation(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

/// Scales a matrix to unit Frobenius norm with a non-negative bottom-right entry (the sign of a
/// homogeneous matrix is arbitrary; fixing it makes results comparable).
inline Eigen::Matrix3d normalize_homogeneous(const Eigen::Matrix3d& m) {
  const double norm = m.norm();
  return (m(2, 2) < 0.0 ? -1.0 : 1.0) * m / norm;
}

}  // namespace affine_orb::detail
