#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the degeneracy test, GRIC, and the plane-and-parallax completion
/// behind select_model() (geometry/model_selection.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/fundamental.hpp"
#include "affine_orb/geometry/homography.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {
namespace detail {

/// Smallest eigenvalue of the 2x2 covariance of `points` (pixels²): the variance across their
/// best-fitting line.
inline double spread_across_line(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  double xx = 0.0, xy = 0.0, yy = 0.0;
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d d = p - mean;
    xx += d.x() * d.x();
    xy += d.x() * d.y();
    yy += d.y() * d.y();
  }
  const double n = static_cast<double>(points.size());
  xx /= n, xy /= n, yy /= n;
  const double half_trace = 0.5 * (xx + yy);
  const double half_difference = 0.5 * (xx - yy);
  return half_trace - std::sqrt(half_difference * half_difference + xy * xy);
}

/// True when the points of either image lie within σ (pixels) of one line: the variance across
/// their best-fitting line is at most σ² (all identical, all collinear). Such data cannot tell the
/// models apart.
inline bool within_a_line(const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                          double sigma) {
  std::vector<Eigen::Vector2d> pixels(points1.size());
  const double sigma_squared = sigma * sigma;
  for (const std::vector<cv::Point2f>* points : {&points1, &points2}) {
    for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = Eigen::Vector2d((*points)[i].x, (*points)[i].y);
    if (!(spread_across_line(pixels) > sigma_squared)) return true;
  }
  return false;
}

/// `options` for H's search under SelectionRule::kScoreRatio (threshold θ) once F scored `f_score`
/// on n correspondences: H can only be chosen with S_H > θ/(1 − θ) · S_F; each correspondence adds
/// at most 2T (T = score_constant) to S_H, so such an H is supported by at least that score / 2T
/// correspondences. Once an H with that support would have been sampled (at the RANSAC
/// confidence), searching on cannot change the decision: the termination inlier ratio is raised to
/// that support's share.
inline RansacOptions stop_once_decided(RansacOptions options, double theta, double f_score, double score_constant,
                                       std::size_t n) {
  const double needed_support = theta / (1.0 - theta) * f_score / (2.0 * score_constant);
  options.termination_inlier_ratio =
      std::max(options.termination_inlier_ratio, std::min(1.0, needed_support / static_cast<double>(n)));
  return options;
}

/// Torr's GRIC of one model (SelectionRule::kGric) from the squared residuals e² (pixels²).
inline double gric(const std::vector<double>& squared_residuals, double sigma, int manifold_dimension, int parameters) {
  constexpr double kDataDimension = 4.0;  // r: two 2-D points
  const double n = static_cast<double>(squared_residuals.size());
  const double cap = 2.0 * (kDataDimension - manifold_dimension);  // λ3·(r − d), λ3 = 2
  double sum = 0.0;
  for (double e2 : squared_residuals) sum += std::min(e2 / (sigma * sigma), cap);
  return sum + std::log(kDataDimension) * manifold_dimension * n + std::log(kDataDimension * n) * parameters;
}

/// Squared residuals of the correspondences for GRIC, in level-0 pixels² (each image's error
/// divided by the squared σ multiplier of `scales`): H, a quarter of the symmetric transfer error;
/// F, the squared Sampson distance (SelectionRule::kGric).
inline std::vector<double> homography_gric_residuals(const Eigen::Matrix3d& h, const std::vector<cv::Point2f>& points1,
                                                     const std::vector<cv::Point2f>& points2,
                                                     const InverseScaleSquares& scales) {
  const Eigen::Matrix3d h_inv = h.inverse();
  std::vector<double> out(points1.size());
  for (std::size_t i = 0; i < points1.size(); ++i) {
    const Eigen::Vector3d x1(points1[i].x, points1[i].y, 1.0);
    const Eigen::Vector3d x2(points2[i].x, points2[i].y, 1.0);
    const Eigen::Vector3d a = h * x1;
    const Eigen::Vector3d b = h_inv * x2;
    const double forward = (a.hnormalized() - x2.head<2>()).squaredNorm() * scales.image2(i);
    const double backward = (b.hnormalized() - x1.head<2>()).squaredNorm() * scales.image1(i);
    out[i] = std::isfinite(forward + backward) ? 0.25 * (forward + backward) : std::numeric_limits<double>::infinity();
  }
  return out;
}

/// The Sampson distance with per-image noise: x2ᵀ F x1 has variance σ²·(m2²·|∇ in image 2|² +
/// m1²·|∇ in image 1|²) for σ multipliers m1, m2 (Hartley & Zisserman Sec. 4.2.6, first order).
inline std::vector<double> fundamental_gric_residuals(const Eigen::Matrix3d& f, const std::vector<cv::Point2f>& points1,
                                                      const std::vector<cv::Point2f>& points2,
                                                      const InverseScaleSquares& scales) {
  std::vector<double> out(points1.size());
  for (std::size_t i = 0; i < points1.size(); ++i) {
    const Eigen::Vector3d x1(points1[i].x, points1[i].y, 1.0);
    const Eigen::Vector3d x2(points2[i].x, points2[i].y, 1.0);
    const Eigen::Vector3d l2 = f * x1;
    const Eigen::Vector3d l1 = f.transpose() * x2;
    const double algebraic = x2.dot(l2);
    const double norm = l2.head<2>().squaredNorm() / scales.image2(i) + l1.head<2>().squaredNorm() / scales.image1(i);
    out[i] = norm > 0.0 ? algebraic * algebraic / norm : std::numeric_limits<double>::infinity();
  }
  return out;
}

/// GRIC of the homography h and of the fundamental matrix f on all correspondences (GRIC's σ in
/// pixels; see gric() and the residual functions above).
inline double homography_gric(const Eigen::Matrix3d& h, const std::vector<cv::Point2f>& points1,
                              const std::vector<cv::Point2f>& points2, const InverseScaleSquares& scales,
                              double sigma) {
  return gric(homography_gric_residuals(h, points1, points2, scales), sigma, 2, 8);
}
inline double fundamental_gric(const Eigen::Matrix3d& f, const std::vector<cv::Point2f>& points1,
                               const std::vector<cv::Point2f>& points2, const InverseScaleSquares& scales,
                               double sigma) {
  return gric(fundamental_gric_residuals(f, points1, points2, scales), sigma, 3, 7);
}

/// RANSAC estimator (ransac.hpp interface) of the epipole e' of image 2 given a homography H, on
/// correspondences off the plane of H: the model is F = [e']× H (plane and parallax, Hartley &
/// Zisserman Result 13.3), scored as FundamentalEstimator scores F. A minimal sample is two
/// correspondences: x2 and H x1 span the line l = x2 × H x1 through e', and two lines meet at e'.
/// Refinement: e' as the least-squares meeting point of the inliers' lines (each scaled to a unit
/// normal, so that lᵀ e' is a distance in pixels for a finite e').
class ParallaxEstimator {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kSampleSize = 2;
  static constexpr int kMaxModels = 1;

  /// `h` maps image 1 to image 2 (pixels); `scoring` and `scales` as for FundamentalEstimator.
  ParallaxEstimator(const Eigen::Matrix3d& h, const std::vector<cv::Point2f>& points1,
                    const std::vector<cv::Point2f>& points2, const TruncatedChi2Score& scoring,
                    const SigmaScales& scales)
      : h_(h), fundamental_(points1, points2, scoring, scales) {
    lines_.reserve(points1.size());
    for (std::size_t i = 0; i < points1.size(); ++i) {
      const Eigen::Vector3d x2(points2[i].x, points2[i].y, 1.0);
      const Eigen::Vector3d line = x2.cross(h_ * Eigen::Vector3d(points1[i].x, points1[i].y, 1.0));
      const double normal = line.head<2>().norm();
      lines_.push_back(normal > 0.0 && std::isfinite(normal) ? Eigen::Vector3d(line / normal)
                                                             : Eigen::Vector3d::Zero());
    }
  }

  std::size_t size() const { return lines_.size(); }

  /// [e']× H for the meeting point e' of the two sampled lines; none when they coincide (or a line
  /// is undefined: x2 = H x1).
  ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const {
    return from_epipole(lines_[static_cast<std::size_t>(sample[0])].cross(lines_[static_cast<std::size_t>(sample[1])]));
  }

  /// FundamentalEstimator's epipolar score (paper eq. 21) of correspondence `index`.
  PointScore score(const Model& model, std::size_t index) const { return fundamental_.score(model, index); }

  double max_point_score() const { return fundamental_.max_point_score(); }

  /// [e']× H with e' the least-squares meeting point of the inliers' lines (the eigenvector of the
  /// smallest eigenvalue of Σ l lᵀ); nullopt with fewer than two inliers.
  std::optional<Model> refine(const Model&, const std::vector<std::uint8_t>& inliers) const {
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    int count = 0;
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      if (inliers[i] == 0) continue;
      scatter += lines_[i] * lines_[i].transpose();
      ++count;
    }
    if (count < kSampleSize) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
    if (solver.info() != Eigen::Success) return std::nullopt;
    const ModelSet<Model, kMaxModels> set = from_epipole(solver.eigenvectors().col(0));
    if (set.count == 0) return std::nullopt;
    return set.models[0];
  }

 private:
  ModelSet<Model, kMaxModels> from_epipole(const Eigen::Vector3d& e) const {
    ModelSet<Model, kMaxModels> set;
    if (!e.allFinite() || !(e.norm() > 0.0)) return set;
    Eigen::Matrix3d skew;
    skew << 0.0, -e.z(), e.y(), e.z(), 0.0, -e.x(), -e.y(), e.x(), 0.0;
    const Eigen::Matrix3d f = normalize_homogeneous(skew * h_);
    if (f.allFinite()) set.push(f);
    return set;
  }

  Eigen::Matrix3d h_;
  FundamentalEstimator fundamental_;
  std::vector<Eigen::Vector3d> lines_;
};

/// The best plane-and-parallax completion of `h`, fitted to the homography outliers (flag 0 in
/// `homography_inliers`), and how many of them it explains (SelectionRule::kPlaneParallax).
struct ParallaxCompletion {
  bool found = false;
  Eigen::Matrix3d fundamental = Eigen::Matrix3d::Zero();  ///< [e']× H, unit norm
  int inlier_count = 0;                                   ///< homography outliers it explains
};

inline ParallaxCompletion complete_by_parallax(const Eigen::Matrix3d& h, const std::vector<cv::Point2f>& points1,
                                               const std::vector<cv::Point2f>& points2, const SigmaScales& scales,
                                               const std::vector<std::uint8_t>& homography_inliers,
                                               const TruncatedChi2Score& scoring, const RansacOptions& ransac_options) {
  std::vector<cv::Point2f> off1, off2;
  SigmaScales off_scales;
  for (std::size_t i = 0; i < points1.size(); ++i) {
    if (homography_inliers[i] != 0) continue;
    off1.push_back(points1[i]);
    off2.push_back(points2[i]);
    if (!scales.image1.empty()) {
      off_scales.image1.push_back(scales.image1[i]);
      off_scales.image2.push_back(scales.image2[i]);
    }
  }
  const ParallaxEstimator estimator(h, off1, off2, scoring, off_scales);
  const RansacResult<Eigen::Matrix3d> best = ransac(estimator, ransac_options);
  ParallaxCompletion out;
  if (!best.success) return out;
  out.found = true;
  out.fundamental = best.model;
  out.inlier_count = best.inlier_count;
  return out;
}

/// `f` (the RANSAC result of `estimator`), or `candidate` locally optimised as ransac() optimises
/// (optimise_locally(), RansacOptions::refinement_passes) when that scores higher on all
/// correspondences: DEGENSAC's remedy for an F sampled from a dominant plane, whose 8-point
/// samples rarely hold enough points off the plane. The iteration count stays f's.
inline RansacResult<Eigen::Matrix3d> keep_better_fundamental(const FundamentalEstimator& estimator,
                                                             const Eigen::Matrix3d& candidate,
                                                             const RansacOptions& options,
                                                             RansacResult<Eigen::Matrix3d> f) {
  RansacResult<Eigen::Matrix3d> optimised =
      optimise_locally(estimator, evaluate_model(estimator, candidate), options.refinement_passes);
  if (f.success && !(optimised.score > f.score)) return f;
  optimised.success = optimised.inlier_count >= FundamentalEstimator::kSampleSize;
  optimised.iterations = f.iterations;
  return optimised;
}

/// The homography outliers expected to pass the epipolar test of a plane-and-parallax completion
/// of `h` by chance (SelectionRule::kPlaneParallax): Σ (2/π)·asin(min(1, t/r)) over the outliers,
/// r = |x2 − H x1| and t the test's distance threshold in image 2 (pixels): t² = threshold_squared
/// divided by the correspondence's inverse scale square.
inline double parallax_expected_count(const Eigen::Matrix3d& h, const std::vector<cv::Point2f>& points1,
                                      const std::vector<cv::Point2f>& points2, const InverseScaleSquares& scales,
                                      const std::vector<std::uint8_t>& homography_inliers, double threshold_squared) {
  constexpr double kTwoOverPi = 0.63661977236758134;
  double sum = 0.0;
  for (std::size_t i = 0; i < points1.size(); ++i) {
    if (homography_inliers[i] != 0) continue;
    const Eigen::Vector2d mapped = (h * Eigen::Vector3d(points1[i].x, points1[i].y, 1.0)).hnormalized();
    const double r = (mapped - Eigen::Vector2d(points2[i].x, points2[i].y)).norm();
    const double t = std::sqrt(threshold_squared / scales.image2(i));
    sum += std::isfinite(r) && r > t ? kTwoOverPi * std::asin(t / r) : 1.0;
  }
  return sum;
}

/// SelectionRule::kPlaneParallax's z-score: the homography outliers a plane-and-parallax completion
/// explains beyond the two of the sample that fixed e' (which agree with it by construction), less
/// the number expected by chance, over √max(1, expected).
inline double parallax_significance(int inlier_count, double expected_count) {
  const int beyond_sample = std::max(0, inlier_count - ParallaxEstimator::kSampleSize);
  return (beyond_sample - expected_count) / std::sqrt(std::max(1.0, expected_count));
}

/// select_model()'s report of its two searches as its ModelSelectionResult (a template, so that this
/// file does not include its front): each model found with its score, inliers and their count, and
/// both iteration counts; a model not found keeps the result's defaults and n inlier flags of 0.
template <class Result>
Result reported_models(RansacResult<HomographyModel> h, RansacResult<Eigen::Matrix3d> f, std::size_t n) {
  Result result;
  result.homography_inliers.assign(n, 0);
  result.fundamental_inliers.assign(n, 0);
  result.homography_iterations = h.iterations;
  result.fundamental_iterations = f.iterations;
  if (h.success) {
    result.homography_found = true;
    result.homography = h.model.h;
    result.homography_score = h.score;
    result.homography_inliers = std::move(h.inliers);
    result.homography_inlier_count = h.inlier_count;
  }
  if (f.success) {
    result.fundamental_found = true;
    result.fundamental = f.model;
    result.fundamental_score = f.score;
    result.fundamental_inliers = std::move(f.inliers);
    result.fundamental_inlier_count = f.inlier_count;
  }
  return result;
}

/// Whether options.rule chooses the homography, from the models' statistics in `result`:
/// select_model()'s last step, on its ModelSelectionResult and ModelSelectionOptions (whose fields
/// this reads; a template, so that this file does not include its front).
template <class Result, class Options>
bool chooses_homography(const Result& result, const Options& options) {
  using Rule = decltype(options.rule);
  switch (options.rule) {
    case Rule::kScoreRatio:
      return result.homography_ratio > options.score_ratio.threshold;
    case Rule::kGric:
      return result.homography_found && (!result.fundamental_found || result.homography_gric < result.fundamental_gric);
    case Rule::kInlierRatio:
      return result.homography_found &&
             result.homography_inlier_count > options.inlier_ratio.threshold * result.fundamental_inlier_count;
    case Rule::kPlaneParallax:
      return result.homography_found && result.parallax_significance <= options.plane_parallax.significance;
  }
  return false;
}

}  // namespace detail
}  // namespace affine_orb
