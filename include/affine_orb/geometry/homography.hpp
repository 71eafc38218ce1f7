#pragma once
/// \file
/// Homography estimation (paper eqs. 18–19, where it is called the "independent matrix L"):
/// normalised 4-point DLT for minimal samples, weighted least-squares DLT on inliers, and the
/// RANSAC estimator scored with the symmetric transfer error (paper eq. 20).
///
/// Convention everywhere: x2 ~ H x1 for homogeneous pixel coordinates, pixel centres at integer
/// coordinates; H is returned with unit Frobenius norm and H(2, 2) >= 0.

#include <algorithm>
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
#include "affine_orb/geometry/detail/homography.hpp"
#include "affine_orb/geometry/detail/normalization.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {

/// A homography with its inverse, both in pixels: x2 ~ h x1 and x1 ~ inverse x2.
struct HomographyModel {
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d inverse = Eigen::Matrix3d::Identity();

  /// The model of a pixel homography, scaled to unit Frobenius norm with h(2, 2) >= 0; nullopt when
  /// it is not finite or not invertible.
  static std::optional<HomographyModel> from_pixels(const Eigen::Matrix3d& h_pixels) {
    if (!h_pixels.allFinite()) return std::nullopt;
    HomographyModel model;
    model.h = detail::normalize_homogeneous(h_pixels);
    if (!model.h.allFinite()) return std::nullopt;
    bool invertible = false;
    double determinant = 0.0;
    model.h.computeInverseAndDetWithCheck(model.inverse, determinant, invertible, 0.0);
    if (!invertible || !model.inverse.allFinite()) return std::nullopt;
    return model;
  }
};

/// The homography through four exact correspondences (pixels, x2 ~ H x1) by the normalised DLT
/// (Hartley & Zisserman Algorithm 4.2). Returns nullopt for a degenerate configuration: repeated
/// points, three collinear points in either image, or an orientation-inconsistent set.
inline std::optional<Eigen::Matrix3d> homography_4_point(const std::array<Eigen::Vector2d, 4>& x1,
                                                         const std::array<Eigen::Vector2d, 4>& x2) {
  for (int i = 0; i < 4; ++i) {
    if (!x1[static_cast<std::size_t>(i)].allFinite() || !x2[static_cast<std::size_t>(i)].allFinite()) {
      return std::nullopt;
    }
  }
  const std::optional<Eigen::Matrix3d> t1 = detail::hartley_normalization(x1.data(), 4);
  const std::optional<Eigen::Matrix3d> t2 = detail::hartley_normalization(x2.data(), 4);
  if (!t1 || !t2) return std::nullopt;
  std::array<Eigen::Vector2d, 4> n1, n2;
  for (std::size_t i = 0; i < 4; ++i) {
    n1[i] = detail::apply_similarity(*t1, x1[i]);
    n2[i] = detail::apply_similarity(*t2, x2[i]);
  }
  const std::optional<Eigen::Matrix3d> hn = detail::homography_4_point_normalized(n1, n2);
  if (!hn) return std::nullopt;
  const std::optional<HomographyModel> model =
      HomographyModel::from_pixels(detail::similarity_inverse(*t2) * *hn * *t1);
  if (!model) return std::nullopt;
  return model->h;
}

/// RANSAC estimator of a homography (see ransac.hpp for the interface).
///
/// Minimal samples: 4 correspondences, normalised DLT (one model or none). Score: the symmetric
/// transfer error of ORB-SLAM's initializer (paper eq. 20): for x2 vs H x1 and for x1 vs H⁻¹ x2,
/// each squared distance d² (pixels²) contributes T − d²/σ² when d²/σ² < T_m; a correspondence is
/// an inlier when both directions pass. Refinement: a reweighted least-squares DLT step on the
/// inliers.
class HomographyEstimator {
 public:
  using Model = HomographyModel;
  static constexpr int kSampleSize = 4;
  static constexpr int kMaxModels = 1;

  /// Matched points in pixels (points2[i] ~ H points1[i]), scored with `scoring` (default σ = 1 px,
  /// T_m = T = 5.991), the σ of correspondence i multiplied by `scales` (the transfer error x2 − H x1
  /// by scales.image2[i], x1 − H⁻¹ x2 by scales.image1[i]; empty: σ for all). Throws
  /// std::invalid_argument when the lists differ in length, a coordinate is not finite, or
  /// `scoring` or `scales` fails its check(). Point sets that are all one point give an estimator
  /// that generates no model.
  HomographyEstimator(const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                      const TruncatedChi2Score& scoring = {}, const SigmaScales& scales = {})
      : data_(detail::normalize_correspondences(points1, points2, "HomographyEstimator")),
        scorer_(scoring),
        scales_(scales, points1.size()) {}

  std::size_t size() const { return data_.pixels1.size(); }

  /// The homography through the four sampled correspondences, or none for a degenerate sample.
  ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const {
    ModelSet<Model, kMaxModels> set;
    if (!data_.normalizable) return set;
    std::array<Eigen::Vector2d, 4> n1, n2;
    for (std::size_t i = 0; i < 4; ++i) {
      n1[i] = data_.normalized1[static_cast<std::size_t>(sample[i])];
      n2[i] = data_.normalized2[static_cast<std::size_t>(sample[i])];
    }
    const std::optional<Eigen::Matrix3d> hn = detail::homography_4_point_normalized(n1, n2);
    if (!hn) return set;
    const std::optional<Model> model = HomographyModel::from_pixels(data_.t2_inverse * *hn * data_.t1);
    if (model) set.push(*model);
    return set;
  }

  /// Symmetric transfer score of correspondence `index` (paper eq. 20, both directions).
  PointScore score(const Model& model, std::size_t index) const {
    const Eigen::Vector2d& a = data_.pixels1[index];
    const Eigen::Vector2d& b = data_.pixels2[index];
    PointScore s;
    s.inlier = true;
    // NaN for a point mapped to infinity: an outlier.
    scorer_.add(transfer_squared(model.h, a, b), scales_.image2(index), s);
    scorer_.add(transfer_squared(model.inverse, b, a), scales_.image1(index), s);
    return s;
  }

  /// Both directions at zero error.
  double max_point_score() const { return scorer_.max_score(2); }

  /// One step of the reweighted least-squares DLT over the inliers (normalised coordinates):
  /// every equation is divided by the third homogeneous coordinate of H x1 under `model`, which
  /// turns the algebraic residual into the transfer error in image 2 (Hartley & Zisserman,
  /// Multiple View Geometry, 2nd ed., Sec. 4.2.4); ransac() iterates it (local
  /// optimisation). Returns nullopt with fewer than four inliers or a degenerate inlier set.
  std::optional<Model> refine(const Model& model, const std::vector<std::uint8_t>& inliers) const {
    if (!data_.normalizable || inliers.size() != size()) return std::nullopt;
    std::size_t count = 0;
    for (const std::uint8_t inlier : inliers) count += inlier != 0 ? 1 : 0;
    if (count < static_cast<std::size_t>(kSampleSize)) return std::nullopt;
    const Eigen::Matrix3d hn = data_.t2 * model.h * data_.t1_inverse;
    // The normal matrix AᵀA accumulated equation by equation: no matrix of all the equations, so
    // no allocation per call.
    detail::Matrix9d normal = detail::Matrix9d::Zero();
    for (std::size_t i = 0; i < inliers.size(); ++i) {
      if (inliers[i] == 0) continue;
      const Eigen::Vector2d& x1 = data_.normalized1[i];
      const Eigen::Vector2d& x2 = data_.normalized2[i];
      const double w = std::abs(hn(2, 0) * x1.x() + hn(2, 1) * x1.y() + hn(2, 2));
      Eigen::Matrix<double, 2, 9, Eigen::RowMajor> rows;
      detail::homography_equations(x1, x2, w > 0.0 && std::isfinite(w) ? 1.0 / w : 1.0, rows.row(0).data(),
                                   rows.row(1).data());
      normal.noalias() += rows.transpose().lazyProduct(rows);
    }
    const std::optional<detail::Vector9d> h = detail::smallest_eigenvector(normal);
    if (!h) return std::nullopt;
    return HomographyModel::from_pixels(data_.t2_inverse * detail::reshape_row_major(*h) * data_.t1);
  }

 private:
  /// Squared distance (pixels²) between q and the image of p under h.
  static double transfer_squared(const Eigen::Matrix3d& h, const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
    const double inv_w = 1.0 / (h(2, 0) * p.x() + h(2, 1) * p.y() + h(2, 2));
    const double u = (h(0, 0) * p.x() + h(0, 1) * p.y() + h(0, 2)) * inv_w - q.x();
    const double v = (h(1, 0) * p.x() + h(1, 1) * p.y() + h(1, 2)) * inv_w - q.y();
    return u * u + v * v;
  }

  detail::NormalizedCorrespondences data_;  // pixel H to normalised: T2 H T1⁻¹; back: T2⁻¹ Hn T1
  Chi2Scorer scorer_;
  InverseScaleSquares scales_;
};

/// HomographyEstimator whose samples must also agree with the keypoints' orientations: a sample's
/// homography is kept only when, at each of its four correspondences, it maps the direction of
/// image 1's keypoint orientation to within `max_difference` of image 2's (the direction times
/// the homography's Jacobian at image 1's point: orientations computed on affine-normalised
/// patches are covariant with the local affine map): the orientation part of a check of local
/// affine frames, which MODS applies to its hypotheses (Mishkin, Matas & Perdoch, "MODS: Fast and
/// robust method for two-view matching", CVIU 141, 2015). A sample holding a wrong match fails
/// it unless that match's orientations agree by chance, so most samples at a low inlier ratio are
/// rejected before they are scored on every correspondence, and a search draws several times the
/// samples in the same time. Score and refinement are HomographyEstimator's.
class OrientedHomographyEstimator {
 public:
  using Model = HomographyModel;
  static constexpr int kSampleSize = HomographyEstimator::kSampleSize;
  static constexpr int kMaxModels = HomographyEstimator::kMaxModels;

  /// Matched points in pixels (points2[i] ~ H points1[i]) with their keypoints' orientations in
  /// degrees (cv::KeyPoint::angle: from the x axis toward y), the largest orientation difference
  /// `max_difference` in degrees, (0, 180], and HomographyEstimator's `scoring` and `scales`.
  /// Throws std::invalid_argument when the lists differ in length, a value is not finite, or
  /// max_difference, `scoring` or `scales` is out of range.
  OrientedHomographyEstimator(const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                              const std::vector<float>& angles1, const std::vector<float>& angles2,
                              double max_difference, const TruncatedChi2Score& scoring = {},
                              const SigmaScales& scales = {})
      : base_(points1, points2, scoring, scales) {
    detail::require(angles1.size() == points1.size() && angles2.size() == points1.size(),
                    "OrientedHomographyEstimator: one orientation per point of each image needed");
    detail::require_range(max_difference, {0.0, 180.0, true}, "OrientedHomographyEstimator: max_difference");
    min_cosine_ = std::cos(max_difference * kRadiansPerDegree);
    points1_.reserve(points1.size());
    directions1_.reserve(points1.size());
    directions2_.reserve(points1.size());
    for (std::size_t i = 0; i < points1.size(); ++i) {
      detail::require(std::isfinite(angles1[i]) && std::isfinite(angles2[i]),
                      "OrientedHomographyEstimator: orientations must be finite");
      points1_.emplace_back(points1[i].x, points1[i].y);
      directions1_.push_back(direction(angles1[i]));
      directions2_.push_back(direction(angles2[i]));
    }
  }

  std::size_t size() const { return base_.size(); }

  /// HomographyEstimator's model of the sample, or none when it is degenerate or maps one of the
  /// sample's orientations more than max_difference away from its match's.
  ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const {
    const ModelSet<Model, kMaxModels> generated = base_.generate(sample);
    ModelSet<Model, kMaxModels> set;
    for (int m = 0; m < generated.count; ++m) {
      const Model& model = generated.models[static_cast<std::size_t>(m)];
      const auto agrees = [&](int i) { return oriented(model.h, static_cast<std::size_t>(i)); };
      if (std::all_of(sample.begin(), sample.end(), agrees)) set.push(model);
    }
    return set;
  }

  PointScore score(const Model& model, std::size_t index) const { return base_.score(model, index); }
  double max_point_score() const { return base_.max_point_score(); }
  std::optional<Model> refine(const Model& model, const std::vector<std::uint8_t>& inliers) const {
    return base_.refine(model, inliers);
  }

  /// True when `h` maps the orientation of correspondence `index` in image 1 to within
  /// max_difference of its orientation in image 2.
  bool oriented(const Eigen::Matrix3d& h, std::size_t index) const {
    const std::optional<Eigen::Matrix2d> jacobian = detail::homography_jacobian(h, points1_[index]);
    if (!jacobian) return false;  // the point maps to infinity
    const Eigen::Vector2d mapped = *jacobian * directions1_[index];
    const double norm = mapped.norm();
    return norm > 0.0 && mapped.dot(directions2_[index]) >= min_cosine_ * norm;
  }

 private:
  static constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;

  static Eigen::Vector2d direction(float degrees) {
    const double radians = static_cast<double>(degrees) * kRadiansPerDegree;
    return Eigen::Vector2d(std::cos(radians), std::sin(radians));
  }

  HomographyEstimator base_;
  std::vector<Eigen::Vector2d> points1_;
  std::vector<Eigen::Vector2d> directions1_;
  std::vector<Eigen::Vector2d> directions2_;
  double min_cosine_ = -1.0;
};

}  // namespace affine_orb
