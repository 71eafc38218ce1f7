#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the DLT equations, the sample consistency test, the normalised
/// 4-point solver and a homography's local affine map behind geometry/homography.hpp and two_view/alignment.hpp.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/detail/geometry_linear.hpp"
#include "affine_orb/geometry/detail/normalization.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {
namespace detail {

/// The two DLT equations of x2 ~ H x1 (from x2 × H x1 = 0, Hartley & Zisserman eq. 4.3) for the
/// row-major vector of H, multiplied by `weight`.
inline void homography_equations(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double weight, double* row1,
                                 double* row2) {
  const double x = a.x() * weight, y = a.y() * weight, w = weight;
  const double u = b.x(), v = b.y();
  row1[0] = 0.0, row1[1] = 0.0, row1[2] = 0.0;
  row1[3] = -x, row1[4] = -y, row1[5] = -w;
  row1[6] = v * x, row1[7] = v * y, row1[8] = v * w;
  row2[0] = x, row2[1] = y, row2[2] = w;
  row2[3] = 0.0, row2[4] = 0.0, row2[5] = 0.0;
  row2[6] = -u * x, row2[7] = -u * y, row2[8] = -u * w;
}

/// True when the four correspondences can come from a homography between two views of points in
/// front of both cameras: no three points collinear in either image, and every point triple keeps
/// (or every triple flips) its orientation: det[H p_i, H p_j, H p_k] = det H · det[p_i, p_j, p_k],
/// and the third coordinates of the H p_i, which scale these determinants when the points are
/// dehomogenised, share one sign for points in front of both cameras.
inline bool homography_sample_consistent(const std::array<Eigen::Vector2d, 4>& x1,
                                         const std::array<Eigen::Vector2d, 4>& x2) {
  static constexpr int kTriples[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  int sign = 0;
  for (const auto& t : kTriples) {
    const double o1 = orientation(x1[t[0]], x1[t[1]], x1[t[2]]);
    const double o2 = orientation(x2[t[0]], x2[t[1]], x2[t[2]]);
    const double product = o1 * o2;
    if (!(product != 0.0)) return false;
    const int s = product > 0.0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return true;
}

/// Homography through four correspondences given in normalised coordinates (unit mean distance
/// scale), as a unit-norm matrix in those coordinates; nullopt for a degenerate sample.
inline std::optional<Eigen::Matrix3d> homography_4_point_normalized(const std::array<Eigen::Vector2d, 4>& x1,
                                                                    const std::array<Eigen::Vector2d, 4>& x2) {
  if (!homography_sample_consistent(x1, x2)) return std::nullopt;
  Matrix89d a;
  for (int i = 0; i < 4; ++i) {
    double row1[9], row2[9];
    homography_equations(x1[static_cast<std::size_t>(i)], x2[static_cast<std::size_t>(i)], 1.0, row1, row2);
    for (int c = 0; c < 9; ++c) {
      a(2 * i, c) = row1[c];
      a(2 * i + 1, c) = row2[c];
    }
  }
  const std::optional<Vector9d> h = null_vector_8x9(a);
  if (!h) return std::nullopt;
  const Eigen::Matrix3d hn = reshape_row_major(*h);
  // A unit-norm homography between normalised point sets has singular values of order one; a
  // vanishing determinant means the sample maps a line to a point.
  if (!(std::abs(hn.determinant()) > kRankTolerance)) return std::nullopt;
  return hn;
}

/// H's first-order (affine) map at x (pixels): d(π(H x))/dx for the projection
/// π(a, b, c) = (a/c, b/c). nullopt where H x lies at infinity or the map is not finite.
inline std::optional<Eigen::Matrix2d> homography_jacobian(const Eigen::Matrix3d& h, const Eigen::Vector2d& x) {
  const Eigen::Vector3d hx = h * Eigen::Vector3d(x.x(), x.y(), 1.0);
  if (!(std::abs(hx.z()) > 1e-12)) return std::nullopt;
  const Eigen::Vector2d projected = hx.head<2>() / hx.z();
  Eigen::Matrix2d jacobian;
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) jacobian(r, c) = (h(r, c) - projected(r) * h(2, c)) / hx.z();
  if (!jacobian.allFinite()) return std::nullopt;
  return jacobian;
}

}  // namespace detail
}  // namespace affine_orb
