#pragma once
/// \file
/// Homography-versus-fundamental model selection (paper eqs. 17–22, docs/algorithm.md §5): both models are
/// estimated by RANSAC on the same random 8-point sets and scored with the truncated χ² score of
/// ORB-SLAM's monocular initializer; a SelectionRule then chooses: by default a plane-and-parallax
/// test of the F hypothesis (after DEGENSAC), or the paper's score ratio (eq. 22), GRIC or COLMAP's
/// inlier ratio. Keypoint octaves, when given, scale each correspondence's σ.

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
#include "affine_orb/geometry/detail/model_selection.hpp"
#include "affine_orb/geometry/fundamental.hpp"
#include "affine_orb/geometry/homography.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace affine_orb {

/// Which model select_model() chose.
enum class GeometricModel {
  kNone,         ///< nothing chosen (success = false)
  kHomography,   ///< planar scene, pure rotation or too little parallax: x2 ~ H x1
  kFundamental,  ///< general scene with parallax: x2ᵀ F x1 = 0
};

/// "homography", "fundamental" or "none": the name affine_orb_match prints and the Python module
/// returns.
inline const char* model_name(GeometricModel model) {
  switch (model) {
    case GeometricModel::kHomography:
      return "homography";
    case GeometricModel::kFundamental:
      return "fundamental";
    default:
      return "none";
  }
}

/// How select_model() chooses between the two estimates. bench/bench_model_selection measures
/// every rule on its labelled real and synthetic pairs (docs/model_selection.md).
enum class SelectionRule {
  /// Paper eq. 22 (ORB-SLAM's initializer): H when R_H = S_H / (S_H + S_F) >
  /// ScoreRatioOptions::threshold.
  kScoreRatio,
  /// Torr's Geometric Robust Information Criterion (P. H. S. Torr, "Geometric motion segmentation
  /// and model selection", Phil. Trans. R. Soc. A 356, 1998): GRIC = Σ ρ(e²/σ²) + λ1·d·n + λ2·k
  /// with ρ(x) = min(x, λ3·(r − d)), r = 4 (two 2-D points), λ1 = ln r, λ2 = ln(r·n), λ3 = 2;
  /// H: manifold dimension d = 2, k = 8 parameters; F: d = 3, k = 7. H when GRIC(H) < GRIC(F).
  /// e² is, for H, a quarter of the symmetric transfer error (x2 − H x1 and x1 − H⁻¹ x2 each carry
  /// the noise of both points: ≈ 2σ² per correspondence, the distance to the 2-codimensional
  /// variety); for F the squared Sampson distance. σ is GricOptions::sigma.
  kGric,
  /// COLMAP's two-view rule (J. L. Schönberger and J.-M. Frahm, "Structure-from-Motion Revisited",
  /// CVPR 2016; COLMAP's two-view geometry estimation): H when the homography's inliers exceed
  /// InlierRatioOptions::threshold times the fundamental matrix's inliers (each counted by its own
  /// χ² test, homography_chi2 and fundamental_chi2 at σ).
  kInlierRatio,
  /// A plane test of the F hypothesis after DEGENSAC (O. Chum, T. Werner and J. Matas, "Two-view
  /// geometry estimation unaffected by a dominant plane", CVPR 2005: a pair whose epipolar
  /// geometry a homography explains except for a plane-and-parallax completion that gains no
  /// significant support is planar). The best H is completed by plane and parallax, F = [e']× H,
  /// with the epipole e' of image 2 estimated by RANSAC from pairs of the homography's outliers
  /// (two parallax correspondences fix e': the lines through x2 and H x1 meet there), and the
  /// homography outliers the completion explains (fundamental_chi2 at σ) are compared with the
  /// number expected by chance: an outlier at transfer distance r = |x2 − H x1| from its H
  /// prediction passes the epipolar test of threshold t for a line through H x1 of random direction
  /// with probability (2/π)·asin(min(1, t/r)). H when (explained − 2 − expected) /
  /// √max(1, expected) <= PlaneParallaxOptions::significance (the two correspondences of the sample that fixed
  /// e' agree with it by construction): the scene shows no parallax off the plane beyond chance. The
  /// completion, locally optimised, also replaces the RANSAC F when it scores higher on all
  /// correspondences (DEGENSAC's estimate of F: 8-point samples from a scene dominated by a plane
  /// rarely hold enough points off it).
  /// The default: the only rule right on every class of bench/bench_model_selection's labelled
  /// pairs (docs/model_selection.md).
  kPlaneParallax,
};

/// SelectionRule::kScoreRatio's parameter.
struct ScoreRatioOptions {
  /// H is chosen when R_H = S_H / (S_H + S_F) exceeds this, unitless (paper eq. 22: 0.45;
  /// ORB-SLAM2's Initializer uses 0.40).
  double threshold = 0.45;
  /// Throws std::invalid_argument unless threshold is in (0, 1).
  void check() const { detail::require_range(threshold, {0, 1, true, true}, "ScoreRatioOptions: threshold"); }
};

/// SelectionRule::kGric's parameter.
struct GricOptions {
  /// σ of GRIC, pixels: the noise of one keypoint coordinate, which GRIC's residuals (distances to
  /// the model's variety in the 4-D space of correspondences) are measured against. 1 px, the
  /// localisation of level-0 FAST keypoints (ModelSelectionOptions::sigma is twice it because the
  /// eq. 20–21 residuals carry both points' noise).
  double sigma = 1.0;
  /// Throws std::invalid_argument unless sigma is positive and finite.
  void check() const { detail::require_range(sigma, detail::kPositive, "GricOptions: sigma"); }
};

/// SelectionRule::kInlierRatio's parameter.
struct InlierRatioOptions {
  /// H when homography inliers > this · fundamental inliers, unitless. 0.8 is COLMAP's
  /// max_H_inlier_ratio (TwoViewGeometryOptions), there with one pixel threshold for both models.
  double threshold = 0.8;
  /// Throws std::invalid_argument unless threshold is positive and finite.
  void check() const { detail::require_range(threshold, detail::kPositive, "InlierRatioOptions: threshold"); }
};

/// SelectionRule::kPlaneParallax's parameter.
struct PlaneParallaxOptions {
  /// H when the parallax support exceeds its chance expectation by at most this many standard
  /// deviations (a z-score, unitless; see SelectionRule::kPlaneParallax). The default 3.8 lies
  /// between the scores of bench/bench_model_selection's planar and pure-rotation pairs and those
  /// of its real 3-D pairs (KITTI 00 and 06; the margin: docs/model_selection.md).
  double significance = 3.8;
  /// Throws std::invalid_argument unless significance is finite.
  void check() const {
    detail::require(std::isfinite(significance),
                    "PlaneParallaxOptions: significance must be finite, got " + std::to_string(significance));
  }
};

/// Options of select_model(): the fields every rule uses at the top level, each rule's own
/// parameter in its nested struct (only the chosen rule's is read).
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
  /// The decision rule; it reads its own nested options below and no other rule's.
  SelectionRule rule = SelectionRule::kPlaneParallax;
  /// Scale factor s between pyramid levels, for the select_model() overload that takes keypoint
  /// octaves: a keypoint of octave o is located to about s^o level-0 pixels, so its errors are
  /// measured against σ·s^o (ORB-SLAM2's Frame keeps these σ² per level, mvLevelSigma2, and its
  /// pose optimisation uses them). 1.2 is PyramidOptions::scale_factor's default, ORB's.
  double level_scale_factor = 1.2;

  ScoreRatioOptions score_ratio;        ///< SelectionRule::kScoreRatio only
  GricOptions gric;                     ///< SelectionRule::kGric only
  InlierRatioOptions inlier_ratio;      ///< SelectionRule::kInlierRatio only
  PlaneParallaxOptions plane_parallax;  ///< SelectionRule::kPlaneParallax only

  /// Throws std::invalid_argument for invalid RANSAC options, an invalid rule, a sigma or χ²
  /// threshold that is not positive and finite, a score_constant below either χ² threshold or not
  /// finite, a level_scale_factor outside [1, 4], or nested rule options that fail their check()
  /// (all four are checked, whichever rule is chosen).
  void check() const {
    ransac.check();
    homography_scoring().check();
    fundamental_scoring().check();
    detail::require(rule == SelectionRule::kScoreRatio || rule == SelectionRule::kGric ||
                        rule == SelectionRule::kInlierRatio || rule == SelectionRule::kPlaneParallax,
                    "ModelSelectionOptions: rule is invalid");
    detail::require_range(level_scale_factor, {1, 4}, "ModelSelectionOptions: level_scale_factor");
    score_ratio.check();
    gric.check();
    inlier_ratio.check();
    plane_parallax.check();
  }

  /// The homography's scoring parameters.
  TruncatedChi2Score homography_scoring() const { return {sigma, homography_chi2, score_constant}; }
  /// The fundamental matrix's scoring parameters.
  TruncatedChi2Score fundamental_scoring() const { return {sigma, fundamental_chi2, score_constant}; }
};

/// Outcome of select_model(). Both models (estimate, score, inliers, iterations) and R_H are
/// reported under every rule whenever they were found, whichever was chosen; the GRIC values only
/// under SelectionRule::kGric, the parallax fields only under SelectionRule::kPlaneParallax (0
/// under the other rules: select_model() computes only what its rule needs).
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
  /// SelectionRule::kGric only (0 under the other rules and for a model not found): GRIC of each
  /// model on all correspondences, lower is better.
  double homography_gric = 0.0;
  double fundamental_gric = 0.0;
  /// SelectionRule::kPlaneParallax only (0 under the other rules): the homography outliers that the
  /// best plane-and-parallax completion F = [e']× H explains, the number of them expected by
  /// chance, and the z-score (count − 2 − expected) / √max(1, expected) compared with
  /// PlaneParallaxOptions::significance.
  int parallax_inlier_count = 0;
  double parallax_expected_count = 0.0;
  double parallax_significance = 0.0;

  /// The chosen model's inlier flags, one per correspondence (homography_inliers or
  /// fundamental_inliers); all 0 when no model was chosen.
  std::vector<std::uint8_t> chosen_inliers() const {
    if (model == GeometricModel::kHomography) return homography_inliers;
    if (model == GeometricModel::kFundamental) return fundamental_inliers;
    return std::vector<std::uint8_t>(std::max(homography_inliers.size(), fundamental_inliers.size()), 0);
  }
  /// The chosen model's inlier count; 0 when no model was chosen.
  int chosen_inlier_count() const {
    if (model == GeometricModel::kHomography) return homography_inlier_count;
    if (model == GeometricModel::kFundamental) return fundamental_inlier_count;
    return 0;
  }
};

/// select_model() with the σ of correspondence i multiplied by scales.image1[i] for errors measured in
/// image 1 and by scales.image2[i] for errors measured in image 2 (SigmaScales; empty lists: σ
/// everywhere). Throws std::invalid_argument, besides the cases of select_model(), when `scales`
/// fails SigmaScales::check().
inline ModelSelectionResult select_model(const std::vector<cv::Point2f>& points1,
                                         const std::vector<cv::Point2f>& points2, const SigmaScales& scales,
                                         const ModelSelectionOptions& options) {
  options.check();
  const HomographyEstimator homography_estimator(points1, points2, options.homography_scoring(), scales);
  const FundamentalEstimator fundamental_estimator(points1, points2, options.fundamental_scoring(), scales);
  const InverseScaleSquares inverse_scales(scales, points1.size());

  const std::size_t n = points1.size();
  constexpr int kDrawSize = FundamentalEstimator::kSampleSize;
  if (n < static_cast<std::size_t>(kDrawSize) || detail::within_a_line(points1, points2, options.sigma))
    return detail::reported_models<ModelSelectionResult>({}, {}, n);

  RansacResult<Eigen::Matrix3d> f = ransac(fundamental_estimator, options.ransac, kDrawSize);
  const RansacOptions h_options =
      f.success && options.rule == SelectionRule::kScoreRatio
          ? detail::stop_once_decided(options.ransac, options.score_ratio.threshold, f.score, options.score_constant, n)
          : options.ransac;
  RansacResult<HomographyModel> h = ransac(homography_estimator, h_options, kDrawSize);
  detail::ParallaxCompletion completion;
  if (h.success && options.rule == SelectionRule::kPlaneParallax) {
    completion = detail::complete_by_parallax(h.model.h, points1, points2, scales, h.inliers,
                                              options.fundamental_scoring(), options.ransac);
    if (completion.found)
      f = detail::keep_better_fundamental(fundamental_estimator, completion.fundamental, options.ransac, std::move(f));
  }

  ModelSelectionResult result = detail::reported_models<ModelSelectionResult>(std::move(h), std::move(f), n);
  if (result.homography_found && options.rule == SelectionRule::kGric) {
    result.homography_gric =
        detail::homography_gric(result.homography, points1, points2, inverse_scales, options.gric.sigma);
  }
  if (result.fundamental_found && options.rule == SelectionRule::kGric) {
    result.fundamental_gric =
        detail::fundamental_gric(result.fundamental, points1, points2, inverse_scales, options.gric.sigma);
  }
  if (result.homography_found && options.rule == SelectionRule::kPlaneParallax) {
    result.parallax_inlier_count = completion.inlier_count;
    result.parallax_expected_count =
        detail::parallax_expected_count(result.homography, points1, points2, inverse_scales, result.homography_inliers,
                                        options.fundamental_chi2 * options.sigma * options.sigma);
    result.parallax_significance =
        detail::parallax_significance(result.parallax_inlier_count, result.parallax_expected_count);
  }
  const double total = result.homography_score + result.fundamental_score;
  if (!(total > 0.0)) return result;
  result.homography_ratio = result.homography_score / total;
  result.success = true;
  result.model =
      detail::chooses_homography(result, options) ? GeometricModel::kHomography : GeometricModel::kFundamental;
  return result;
}

/// Estimates H and F from matched points and chooses one (paper eqs. 17–22, docs/algorithm.md §5).
///
/// `points1[i]` (image 1) and `points2[i]` (image 2) are one correspondence, in pixels. Each RANSAC
/// iteration draws one set of 8 correspondences from options.ransac.seed: F is estimated from all
/// 8 (normalised 8-point), H from the first 4 (normalised 4-point DLT). Each search stops by its
/// own adaptive termination, so one of them sees a prefix of the other's sets: H needs only 4
/// inliers per sample, and under SelectionRule::kScoreRatio its search also stops once any H that
/// could still be chosen (S_H above θ/(1 − θ) · S_F, hence supported by at least that score / 2T
/// correspondences) would have been sampled at the RANSAC confidence; when F is chosen the
/// reported H is the best of that shorter search. Each model is then refined on its inliers and
/// scored on all correspondences, and options.rule chooses (see SelectionRule).
///
/// Throws std::invalid_argument when the lists differ in length, a coordinate is NaN or infinite,
/// or the options fail check(). Returns success = false (model kNone, both models still reported
/// when found) when there are fewer than 8 correspondences, when the points of either image lie
/// within σ of one line (variance across the best-fitting line <= σ²: all identical, all
/// collinear; such data cannot tell the models apart), or when neither model was found.
inline ModelSelectionResult select_model(const std::vector<cv::Point2f>& points1,
                                         const std::vector<cv::Point2f>& points2,
                                         const ModelSelectionOptions& options = {}) {
  return select_model(points1, points2, SigmaScales{}, options);
}

/// select_model() for matched keypoints with their pyramid octaves (cv::KeyPoint::octave of the
/// keypoint in image 1 and in image 2): every error measured in image k of correspondence i is
/// scored against σ·s^octavesk[i] instead of σ (s = options.level_scale_factor), the localisation
/// of a keypoint detected at that level; octave 0 everywhere gives select_model() without octaves.
/// Throws std::invalid_argument, besides the cases of select_model(), when an octave list does not
/// have one entry per correspondence or an octave is outside [0, 31].
inline ModelSelectionResult select_model(const std::vector<cv::Point2f>& points1,
                                         const std::vector<cv::Point2f>& points2, const std::vector<int>& octaves1,
                                         const std::vector<int>& octaves2, const ModelSelectionOptions& options = {}) {
  detail::require(octaves1.size() == points1.size() && octaves2.size() == points2.size(),
                  "select_model: octaves1 and octaves2 must have one entry per correspondence (" +
                      std::to_string(points1.size()) + "), got " + std::to_string(octaves1.size()) + " and " +
                      std::to_string(octaves2.size()));
  options.check();
  SigmaScales scales;
  for (const auto& [octaves, out] :
       {std::make_pair(&octaves1, &scales.image1), std::make_pair(&octaves2, &scales.image2)}) {
    for (const int octave : *octaves) {
      detail::require_range(octave, {0, 31}, "select_model: octaves");
      out->push_back(std::pow(options.level_scale_factor, octave));
    }
  }
  return select_model(points1, points2, scales, options);
}

}  // namespace affine_orb
