#pragma once
/// \file
/// The final estimate of a homography from all its inliers: iteratively reweighted least squares
/// of the Sampson error (the first-order approximation of the Gold Standard reprojection error,
/// Hartley & Zisserman, Multiple View Geometry, 2nd ed., Sec. 4.2.6) with Cauchy weights, by the
/// normalised DLT. RANSAC's local optimisation (HomographyEstimator::refine()) fits a hard inlier
/// set at a tight threshold by the transfer error in image 2 alone; this fit takes every
/// correspondence within a wider bound (4 px by default), weighs it by how well it agrees, and accounts for the noise
/// of both images, so that its estimate comes close to the maximum-likelihood one.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/detail/geometry_linear.hpp"
#include "affine_orb/geometry/detail/homography.hpp"
#include "affine_orb/geometry/detail/normalization.hpp"
#include "affine_orb/geometry/homography.hpp"

namespace affine_orb {

/// Options of refine_homography().
struct HomographyRefinementOptions {
  /// Scale c of the Cauchy weight 1 / (1 + d²/c²) of a correspondence with Sampson distance d,
  /// pixels; (0, inf); default 2, about twice the spread of correct keypoint matches (median
  /// residual 1.1–1.3 px, docs/two_view.md, "Reading"): on synthetic planes at that
  /// noise it comes closer to the maximum-likelihood estimate than 1 or 1.5 (test_ransac).
  double cauchy_scale = 2.0;
  /// A correspondence takes part, and is an inlier of the result, when both its transfer errors
  /// (x2 against H x1, x1 against H⁻¹ x2) are at most this, pixels; (0, inf); default 4, the tight
  /// gate of the guided rounds: on bench/eval_two_view it gives the matcher's own homography a
  /// higher AUC@5 than 2, 2.4 or 3 px (--sweep; docs/two_view.md).
  double max_error = 4.0;
  /// Most reweighting iterations; [1, 100]; default 10 (the estimate settles within a few).
  int iterations = 10;

  /// Throws std::invalid_argument for a value outside its range.
  void check() const {
    detail::require_range(cauchy_scale, detail::kPositive, "HomographyRefinementOptions: cauchy_scale");
    detail::require_range(max_error, detail::kPositive, "HomographyRefinementOptions: max_error");
    detail::require_range(iterations, {1.0, 100.0}, "HomographyRefinementOptions: iterations");
  }
};

/// Outcome of refine_homography().
struct RefinedHomography {
  /// True when at least one reweighting step gave a homography.
  bool success = false;
  /// x2 ~ homography x1, pixels, unit Frobenius norm; the start when !success.
  Eigen::Matrix3d homography = Eigen::Matrix3d::Identity();
  /// Per correspondence, 1 = both transfer errors under `homography` at most max_error.
  std::vector<std::uint8_t> inliers;
  int inlier_count = 0;
  /// Reweighting steps taken.
  int iterations = 0;
};

namespace detail {

/// Both transfer errors of correspondence `i` under `model` are at most `bound` pixels.
inline bool within_transfer(const NormalizedCorrespondences& data, std::size_t i, const HomographyModel& model,
                            double bound) {
  const Eigen::Vector2d forward = (model.h * data.pixels1[i].homogeneous()).hnormalized() - data.pixels2[i];
  const Eigen::Vector2d backward = (model.inverse * data.pixels2[i].homogeneous()).hnormalized() - data.pixels1[i];
  return forward.squaredNorm() <= bound * bound && backward.squaredNorm() <= bound * bound;
}

/// Per correspondence of `data`, 1 when within_transfer() at `bound`.
inline std::vector<std::uint8_t> transfer_inliers(const NormalizedCorrespondences& data, const HomographyModel& model,
                                                  double bound) {
  std::vector<std::uint8_t> inliers(data.pixels1.size(), 0);
  for (std::size_t i = 0; i < data.pixels1.size(); ++i) inliers[i] = within_transfer(data, i, model, bound) ? 1 : 0;
  return inliers;
}

/// The normal matrix Σ wᵢ Aᵢᵀ Mᵢ Aᵢ of one reweighting step, for Hn (`model` in normalised
/// coordinates): Aᵢ the two DLT equations of correspondence i, Mᵢ the inverse of the covariance of
/// their residual under isotropic pixel noise in both images (Sampson), wᵢ the Cauchy weight of
/// its Sampson distance under Hn; correspondences outside max_error are left out. `used` counts
/// the ones taken. The equations of x1 = (x, y) ↔ x2 = (u, v) are A = R ⊗ pᵀ with p = (x, y, 1)
/// and R = [0 −1 v; 1 0 −u] (homography_equations()), so Aᵀ (w M) A = (Rᵀ w M R) ⊗ p pᵀ: a 3 x 3
/// matrix times the 3 x 3 blocks of p pᵀ, accumulated on the upper blocks and mirrored at the end.
inline Matrix9d sampson_normal_matrix(const NormalizedCorrespondences& data, const HomographyModel& model,
                                      const HomographyRefinementOptions& options, std::size_t& used) {
  const Eigen::Matrix3d hn = data.t2 * model.h * data.t1_inverse;
  const double s1 = 1.0 / data.t1(0, 0), s2 = 1.0 / data.t2(0, 0);  // normalised units → pixels
  const double inverse_c2 = 1.0 / (options.cauchy_scale * options.cauchy_scale);
  Matrix9d normal = Matrix9d::Zero();
  used = 0;
  for (std::size_t i = 0; i < data.pixels1.size(); ++i) {
    if (!within_transfer(data, i, model, options.max_error)) continue;
    const Eigen::Vector2d& a = data.normalized1[i];
    const Eigen::Vector2d& b = data.normalized2[i];
    const Eigen::Vector3d p = a.homogeneous();
    const Eigen::Vector3d mapped = hn * p;
    const Eigen::Vector2d residual(-mapped.y() + b.y() * mapped.z(), mapped.x() - b.x() * mapped.z());
    const double w3 = mapped.z();
    // Jacobian of the residual with respect to (x1, y1, x2, y2) in pixels.
    Eigen::Matrix<double, 2, 4> j;
    j << (-hn(1, 0) + b.y() * hn(2, 0)) / s1, (-hn(1, 1) + b.y() * hn(2, 1)) / s1, 0.0, w3 / s2,
        (hn(0, 0) - b.x() * hn(2, 0)) / s1, (hn(0, 1) - b.x() * hn(2, 1)) / s1, -w3 / s2, 0.0;
    const Eigen::Matrix2d covariance = j * j.transpose();
    bool invertible = false;
    double determinant = 0.0;
    Eigen::Matrix2d m;
    covariance.computeInverseAndDetWithCheck(m, determinant, invertible, 0.0);
    if (!invertible || !m.allFinite()) continue;
    const double sampson_squared = residual.dot(m * residual);
    const double weight = 1.0 / (1.0 + sampson_squared * inverse_c2);
    Eigen::Matrix<double, 2, 3> r;
    r << 0.0, -1.0, b.y(), 1.0, 0.0, -b.x();
    const Eigen::Matrix3d c = r.transpose().lazyProduct((weight * m).lazyProduct(r));
    const Eigen::Matrix3d outer = p.lazyProduct(p.transpose());
    for (int row = 0; row < 3; ++row) {
      for (int col = row; col < 3; ++col) normal.block<3, 3>(3 * row, 3 * col) += c(row, col) * outer;
    }
    ++used;
  }
  for (int row = 1; row < 3; ++row) {
    for (int col = 0; col < row; ++col) {
      normal.block<3, 3>(3 * row, 3 * col) = normal.block<3, 3>(3 * col, 3 * row).transpose();
    }
  }
  return normal;
}

}  // namespace detail

/// Refines `start` (x2 ~ start x1, pixels) on the correspondences points1[i] ↔ points2[i] (pixels)
/// by iteratively reweighted least squares (HomographyRefinementOptions): each step takes the
/// correspondences whose transfer errors under the current estimate are within max_error, weighs
/// each by the Cauchy weight of its Sampson distance, and solves the weighted Sampson-normalised
/// DLT; it stops after `iterations` steps, or when a step fails (fewer than four correspondences
/// taken, a degenerate set), keeping the last estimate. Throws std::invalid_argument when the
/// lists differ in length, a coordinate is not finite, `start` is not an invertible finite
/// homography, or the options fail their check().
inline RefinedHomography refine_homography(const std::vector<cv::Point2f>& points1,
                                           const std::vector<cv::Point2f>& points2, const Eigen::Matrix3d& start,
                                           const HomographyRefinementOptions& options = {}) {
  options.check();
  const detail::NormalizedCorrespondences data =
      detail::normalize_correspondences(points1, points2, "refine_homography");
  std::optional<HomographyModel> current = HomographyModel::from_pixels(start);
  detail::require(current.has_value(), "refine_homography: the start must be a finite, invertible homography");
  RefinedHomography result;
  for (int step = 0; step < options.iterations && data.normalizable; ++step) {
    std::size_t used = 0;
    const detail::Matrix9d normal = detail::sampson_normal_matrix(data, *current, options, used);
    if (used < 4) break;
    const std::optional<detail::Vector9d> h = detail::smallest_eigenvector(normal);
    if (!h) break;
    const std::optional<HomographyModel> next =
        HomographyModel::from_pixels(data.t2_inverse * detail::reshape_row_major(*h) * data.t1);
    if (!next) break;
    current = next;
    result.success = true;
    result.iterations = step + 1;
  }
  result.homography = current->h;
  result.inliers = detail::transfer_inliers(data, *current, options.max_error);
  result.inlier_count = static_cast<int>(std::count(result.inliers.begin(), result.inliers.end(), 1));
  return result;
}

/// Per correspondence points1[i] ↔ points2[i] (pixels), 1 when both its transfer errors under
/// `homography` (x2 against H x1, x1 against H⁻¹ x2) are at most `max_error` pixels: the inliers
/// refine_homography() reports, for a homography found otherwise. Throws std::invalid_argument
/// when the lists differ in length, a coordinate is not finite, `homography` is not an invertible
/// finite homography, or max_error is not positive and finite.
inline std::vector<std::uint8_t> transfer_inliers(const std::vector<cv::Point2f>& points1,
                                                  const std::vector<cv::Point2f>& points2,
                                                  const Eigen::Matrix3d& homography, double max_error) {
  detail::require_range(max_error, detail::kPositive, "transfer_inliers: max_error");
  const detail::NormalizedCorrespondences data =
      detail::normalize_correspondences(points1, points2, "transfer_inliers");
  const std::optional<HomographyModel> model = HomographyModel::from_pixels(homography);
  detail::require(model.has_value(), "transfer_inliers: the homography must be finite and invertible");
  return detail::transfer_inliers(data, *model, max_error);
}

}  // namespace affine_orb
