#pragma once
/// \file
/// Fundamental-matrix estimation (paper eq. 17, where it is called the "base matrix H"):
/// normalised 8-point algorithm with rank-2 enforcement, Sampson-reweighted least squares on
/// inliers, and the RANSAC estimator scored with point-to-epipolar-line distances (paper eq. 21).
///
/// Convention everywhere: x2ᵀ F x1 = 0 for homogeneous pixel coordinates, pixel centres at
/// integer coordinates; F is returned with rank 2, unit Frobenius norm and F(2, 2) >= 0.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/detail/fundamental.hpp"
#include "affine_orb/geometry/detail/geometry_linear.hpp"
#include "affine_orb/geometry/detail/normalization.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {

/// The fundamental matrix of n >= 8 correspondences (pixels, x2ᵀ F x1 = 0) by the normalised
/// 8-point algorithm with rank-2 enforcement (Hartley & Zisserman Algorithm 11.1; least squares
/// when n > 8). Returns nullopt for fewer than 8 correspondences, lists of different lengths,
/// non-finite coordinates or a degenerate configuration (repeated points, all points collinear,
/// any other set that does not determine F up to scale).
inline std::optional<Eigen::Matrix3d> fundamental_8_point(const std::vector<Eigen::Vector2d>& x1,
                                                          const std::vector<Eigen::Vector2d>& x2) {
  if (x1.size() != x2.size() || x1.size() < 8) return std::nullopt;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    if (!x1[i].allFinite() || !x2[i].allFinite()) return std::nullopt;
  }
  const std::optional<Eigen::Matrix3d> t1 = detail::hartley_normalization(x1.data(), x1.size());
  const std::optional<Eigen::Matrix3d> t2 = detail::hartley_normalization(x2.data(), x2.size());
  if (!t1 || !t2) return std::nullopt;
  std::vector<Eigen::Vector2d> n1(x1.size()), n2(x2.size());
  std::vector<std::size_t> all(x1.size());
  for (std::size_t i = 0; i < x1.size(); ++i) {
    n1[i] = detail::apply_similarity(*t1, x1[i]);
    n2[i] = detail::apply_similarity(*t2, x2[i]);
    all[i] = i;
  }
  const std::optional<detail::Vector9d> f = detail::fundamental_least_squares(n1, n2, all, nullptr);
  if (!f) return std::nullopt;
  return detail::denormalize_fundamental(*f, *t1, *t2);
}

/// Squared distances (pixels²) of x2 to the epipolar line F x1 and of x1 to the line Fᵀ x2.
/// Non-finite (and then treated as an outlier) when a line is undefined.
inline std::array<double, 2> epipolar_squared_distances(const Eigen::Matrix3d& f, const Eigen::Vector2d& x1,
                                                        const Eigen::Vector2d& x2) {
  const double a2 = f(0, 0) * x1.x() + f(0, 1) * x1.y() + f(0, 2);
  const double b2 = f(1, 0) * x1.x() + f(1, 1) * x1.y() + f(1, 2);
  const double c2 = f(2, 0) * x1.x() + f(2, 1) * x1.y() + f(2, 2);
  const double a1 = f(0, 0) * x2.x() + f(1, 0) * x2.y() + f(2, 0);
  const double b1 = f(0, 1) * x2.x() + f(1, 1) * x2.y() + f(2, 1);
  const double residual = a2 * x2.x() + b2 * x2.y() + c2;  // x2ᵀ F x1, shared by both directions
  const double r2 = residual * residual;
  return {r2 / (a2 * a2 + b2 * b2), r2 / (a1 * a1 + b1 * b1)};
}

/// RANSAC estimator of a fundamental matrix (see ransac.hpp for the interface).
///
/// Minimal samples: 8 correspondences, normalised 8-point with rank-2 enforcement (one model or
/// none). Score (paper eq. 21): the squared distances of x2 to F x1 and of x1 to Fᵀ x2, each
/// contributing T − d²/σ² when d²/σ² < T_m; a correspondence is an inlier when both pass.
/// Refinement: a Sampson-reweighted 8-point least-squares step on the inliers.
class FundamentalEstimator {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kSampleSize = 8;
  static constexpr int kMaxModels = 1;

  /// Matched points in pixels (points2[i]ᵀ F points1[i] = 0), scored with `scoring` (default
  /// σ = 1 px, T_m = 3.841, T = 5.991), the σ of correspondence i multiplied by `scales` (the
  /// distance of x2 to F x1 by scales.image2[i], of x1 to Fᵀ x2 by scales.image1[i]; empty: σ for
  /// all). Throws std::invalid_argument when the lists differ in length, a coordinate is not
  /// finite, or `scoring` or `scales` fails its check(). Point sets that are all one point give an
  /// estimator that generates no model.
  FundamentalEstimator(const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                       const TruncatedChi2Score& scoring = {1.0, 3.841, 5.991}, const SigmaScales& scales = {})
      : data_(detail::normalize_correspondences(points1, points2, "FundamentalEstimator")),
        scorer_(scoring),
        scales_(scales, points1.size()) {}

  std::size_t size() const { return data_.pixels1.size(); }

  /// The fundamental matrix through the eight sampled correspondences, or none when they do not
  /// determine it (repeated points, collinear points, exact planar configurations...).
  ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const {
    ModelSet<Model, kMaxModels> set;
    if (!data_.normalizable) return set;
    detail::Matrix89d a;
    for (int i = 0; i < 8; ++i) {
      const std::size_t k = static_cast<std::size_t>(sample[static_cast<std::size_t>(i)]);
      double row[9];
      detail::fundamental_equation(data_.normalized1[k], data_.normalized2[k], 1.0, row);
      for (int c = 0; c < 9; ++c) a(i, c) = row[c];
    }
    const std::optional<detail::Vector9d> f = detail::null_vector_8x9(a);
    if (!f) return set;
    const std::optional<Model> model = detail::denormalize_fundamental(*f, data_.t1, data_.t2);
    if (model) set.push(*model);
    return set;
  }

  /// Epipolar score of correspondence `index` (paper eq. 21, both images).
  PointScore score(const Model& model, std::size_t index) const {
    const std::array<double, 2> d = epipolar_squared_distances(model, data_.pixels1[index], data_.pixels2[index]);
    PointScore s;
    s.inlier = true;
    // NaN for an undefined epipolar line. d[0] is measured in image 2, d[1] in image 1.
    scorer_.add(d[0], scales_.image2(index), s);
    scorer_.add(d[1], scales_.image1(index), s);
    return s;
  }

  /// Both directions at zero distance.
  double max_point_score() const { return scorer_.max_score(2); }

  /// One step of the Sampson-reweighted 8-point least squares over the inliers (normalised
  /// coordinates): every equation is divided by the gradient norm of its residual under `model`,
  /// so that the step minimises the Sampson approximation of the geometric error (Hartley &
  /// Zisserman, Multiple View Geometry, 2nd ed., Sec. 11.4.3); ransac() iterates it (local
  /// optimisation). Returns nullopt with fewer than eight inliers or a degenerate inlier set.
  std::optional<Model> refine(const Model& model, const std::vector<std::uint8_t>& inliers) const {
    if (!data_.normalizable || inliers.size() != size()) return std::nullopt;
    std::vector<std::size_t> used;
    for (std::size_t i = 0; i < inliers.size(); ++i) {
      if (inliers[i] != 0) used.push_back(i);
    }
    if (used.size() < static_cast<std::size_t>(kSampleSize)) return std::nullopt;
    // The model in normalised coordinates: x2ᵀ F x1 = (T2 x2)ᵀ T2⁻ᵀ F T1⁻¹ (T1 x1).
    const Eigen::Matrix3d previous = data_.t2_inverse.transpose() * model * data_.t1_inverse;
    const std::optional<detail::Vector9d> f =
        detail::fundamental_least_squares(data_.normalized1, data_.normalized2, used, &previous);
    if (!f) return std::nullopt;
    return detail::denormalize_fundamental(*f, data_.t1, data_.t2);
  }

 private:
  detail::NormalizedCorrespondences data_;
  Chi2Scorer scorer_;
  InverseScaleSquares scales_;
};

}  // namespace affine_orb
