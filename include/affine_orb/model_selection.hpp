#pragma once
/// \file
/// Homography-versus-fundamental model selection (paper eqs. 17–22, SPEC §5), the heuristic of
/// ORB-SLAM's monocular initializer: both models are estimated by RANSAC on the same random
/// 8-point sets, scored with the truncated χ² score, and the homography is chosen when it explains
/// a large enough share of the total score.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "affine_orb/detail/check.hpp"
#include "affine_orb/fundamental.hpp"
#include "affine_orb/homography.hpp"
#include "affine_orb/ransac.hpp"

namespace affine_orb {

/// Which model select_model() chose.
enum class GeometricModel {
  kNone,         ///< nothing chosen (success = false)
  kHomography,   ///< planar scene, pure rotation or too little parallax: x2 ~ H x1
  kFundamental,  ///< general scene with parallax: x2ᵀ F x1 = 0
};

/// Thresholds of select_model(). The defaults are ORB-SLAM2's initializer values except the
/// decision threshold, which is the paper's.
struct ModelSelectionOptions {
  /// RANSAC iteration control, shared by both models (same seed, hence the same sample sets).
  RansacOptions ransac;
  /// Standard deviation σ the squared errors are divided by, pixels. ORB-SLAM2 uses 1 px, the
  /// level-0 keypoint σ; but the transfer error x2 − H x1 carries the noise of both points, so with
  /// σ equal to the per-image keypoint noise a perfect plane scores R_H ≈ 0.41 (below the paper's
  /// 0.45: F is chosen) and only ~75 % of its points pass the homography test
  /// (tests/test_model_selection.cpp derives the 0.41). The default is therefore twice the ~1 px
  /// noise of level-0 FAST keypoints: 2 px.
  double sigma = 2.0;
  /// T_m for the homography's transfer errors: 5.991, the 95 % quantile of χ² with 2 degrees of
  /// freedom (paper eq. 20; ORB-SLAM2 Initializer::CheckHomography).
  double homography_chi2 = 5.991;
  /// T_m for the fundamental matrix's point-to-line distances: 3.841, the 95 % quantile of χ² with
  /// 1 degree of freedom (paper eq. 21; ORB-SLAM2 Initializer::CheckFundamental).
  double fundamental_chi2 = 3.841;
  /// Scoring constant T of both models: 5.991, so that scores of the two models compare (ORB-SLAM2
  /// Initializer::CheckFundamental scores F with the 2-dof value too).
  double score_constant = 5.991;
  /// H is chosen when R_H = S_H / (S_H + S_F) exceeds this (paper eq. 22: 0.45; ORB-SLAM2's
  /// Initializer uses 0.40).
  double homography_ratio_threshold = 0.45;

  /// Throws std::invalid_argument for invalid RANSAC options, a sigma or a χ² threshold that is
  /// not positive and finite, a score_constant below either χ² threshold or not finite, or a
  /// ratio threshold outside (0, 1).
  void check() const {
    ransac.check();
    homography_scoring().check();
    fundamental_scoring().check();
    detail::require(std::isfinite(homography_ratio_threshold) && homography_ratio_threshold > 0.0 &&
                        homography_ratio_threshold < 1.0,
                    "ModelSelectionOptions: homography_ratio_threshold must be in (0, 1), got " +
                        std::to_string(homography_ratio_threshold));
  }

  /// The homography's scoring parameters.
  TruncatedChi2Score homography_scoring() const { return {sigma, homography_chi2, score_constant}; }
  /// The fundamental matrix's scoring parameters.
  TruncatedChi2Score fundamental_scoring() const { return {sigma, fundamental_chi2, score_constant}; }
};

/// Outcome of select_model(). Both models are reported whenever they were found, whichever was
/// chosen.
struct ModelSelectionResult {
  /// True when at least one model was found and the data are not degenerate (see select_model()).
  bool success = false;
  GeometricModel model = GeometricModel::kNone;

  bool homography_found = false;
  /// x2 ~ H x1, pixels; unit Frobenius norm, H(2, 2) >= 0. Zero when !homography_found.
  Eigen::Matrix3d homography = Eigen::Matrix3d::Zero();
  /// S_H, sum of the symmetric transfer scores (paper eq. 20); 0 when !homography_found.
  double homography_score = 0.0;
  /// One entry per correspondence, 1 = inlier of the homography.
  std::vector<std::uint8_t> homography_inliers;
  int homography_inlier_count = 0;
  int homography_iterations = 0;

  bool fundamental_found = false;
  /// x2ᵀ F x1 = 0, pixels; rank 2, unit Frobenius norm, F(2, 2) >= 0. Zero when !fundamental_found.
  Eigen::Matrix3d fundamental = Eigen::Matrix3d::Zero();
  /// S_F, sum of the epipolar scores (paper eq. 21); 0 when !fundamental_found.
  double fundamental_score = 0.0;
  /// One entry per correspondence, 1 = inlier of the fundamental matrix.
  std::vector<std::uint8_t> fundamental_inliers;
  int fundamental_inlier_count = 0;
  int fundamental_iterations = 0;

  /// R_H = S_H / (S_H + S_F) (paper eq. 22); 0 when both scores are 0.
  double homography_ratio = 0.0;
};

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

}  // namespace detail

/// Estimates H and F from matched points and chooses one (paper eqs. 17–22, SPEC §5).
///
/// `points1[i]` (image 1) and `points2[i]` (image 2) are one correspondence, in pixels. Each RANSAC
/// iteration draws one set of 8 correspondences from options.ransac.seed: F is estimated from all
/// 8 (normalised 8-point), H from the first 4 (normalised 4-point DLT). Each search stops by its
/// own adaptive termination, so one of them sees a prefix of the other's sets: H needs only 4
/// inliers per sample, and its search also stops once any H that could still be chosen (S_H above
/// θ/(1 − θ) · S_F, hence supported by at least that score / 2T correspondences) would have been
/// sampled at the RANSAC confidence; when F is chosen the reported H is the best of that shorter
/// search. Each model is then refined on its inliers and scored on all correspondences; H is
/// chosen when R_H > options.homography_ratio_threshold (θ), F otherwise.
///
/// Throws std::invalid_argument when the lists differ in length, a coordinate is NaN or infinite,
/// or the options fail check(). Returns success = false (model kNone, both models still reported
/// when found) when there are fewer than 8 correspondences, when the points of either image lie
/// within σ of one line (variance across the best-fitting line <= σ²: all identical, all
/// collinear; such data cannot tell the models apart), or when neither model was found.
inline ModelSelectionResult select_model(const std::vector<cv::Point2f>& points1,
                                         const std::vector<cv::Point2f>& points2,
                                         const ModelSelectionOptions& options = {}) {
  options.check();
  const HomographyEstimator homography_estimator(points1, points2, options.homography_scoring());
  const FundamentalEstimator fundamental_estimator(points1, points2, options.fundamental_scoring());

  ModelSelectionResult result;
  const std::size_t n = points1.size();
  result.homography_inliers.assign(n, 0);
  result.fundamental_inliers.assign(n, 0);
  constexpr int kDrawSize = FundamentalEstimator::kSampleSize;
  if (n < static_cast<std::size_t>(kDrawSize)) return result;

  std::vector<Eigen::Vector2d> pixels(n);
  const double sigma_squared = options.sigma * options.sigma;
  for (const std::vector<cv::Point2f>* points : {&points1, &points2}) {
    for (std::size_t i = 0; i < n; ++i) pixels[i] = Eigen::Vector2d((*points)[i].x, (*points)[i].y);
    if (!(detail::spread_across_line(pixels) > sigma_squared)) return result;
  }

  RansacResult<Eigen::Matrix3d> f = ransac(fundamental_estimator, options.ransac, kDrawSize);
  RansacOptions h_options = options.ransac;
  if (f.success) {
    // H can only be chosen with S_H > θ/(1 − θ) · S_F; each correspondence adds at most 2T to S_H,
    // so such an H is supported by at least that score / 2T correspondences. Once an H with that
    // support would have been sampled (at the RANSAC confidence), searching on cannot change the
    // decision.
    const double theta = options.homography_ratio_threshold;
    const double needed_support = theta / (1.0 - theta) * f.score / (2.0 * options.score_constant);
    h_options.termination_inlier_ratio =
        std::max(h_options.termination_inlier_ratio, std::min(1.0, needed_support / static_cast<double>(n)));
  }
  RansacResult<HomographyModel> h = ransac(homography_estimator, h_options, kDrawSize);

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
  const double total = result.homography_score + result.fundamental_score;
  if (!(total > 0.0)) return result;
  result.homography_ratio = result.homography_score / total;
  result.success = true;
  result.model = result.homography_ratio > options.homography_ratio_threshold ? GeometricModel::kHomography
                                                                                : GeometricModel::kFundamental;
  return result;
}

}  // namespace affine_orb
