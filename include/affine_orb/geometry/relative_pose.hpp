#pragma once
/// \file
/// Relative camera pose (rotation, translation direction) from a fundamental matrix or a
/// homography between two views of one calibrated pinhole camera, with Eigen only.
///
/// Convention everywhere: a point with coordinates X1 in camera 1 has X2 = R X1 + t in camera 2
/// (x right, y down, z forward, the OpenCV camera frame); pixels x = K X / X_z with
/// K = [fx 0 cx; 0 fy cy; 0 0 1]. F is the fundamental matrix of x2ᵀ F x1 = 0 and H the homography
/// of x2 ~ H x1, both in pixels (model_selection.hpp). Only the direction of t can be recovered.
///
/// - From F: E = Kᵀ F K, decomposed by SVD into its four (R, t) (Hartley & Zisserman, Multiple View
///   Geometry, 2nd ed., Result 9.19).
/// - From H: K⁻¹ H K = ±σ₂ (R + t nᵀ / d) for the plane nᵀ X1 = d (d > 0) with σ₂ its middle singular
///   value; the sign is fixed by the correspondences (their depths are positive), and the
///   SVD-based decomposition of Ma, Soatto, Košecká & Sastry (An Invitation to 3-D Vision, 2004,
///   Sec. 5.3.3, after Faugeras & Lustman 1988) gives four (R, t, n). A pure rotation (t = 0, all
///   three singular values equal) gives R directly.
///
/// The hypothesis is chosen by the cheirality test: every correspondence is triangulated linearly
/// (DLT, Hartley & Zisserman Sec. 12.2) under each hypothesis and counts when it lies in front of
/// both cameras and reprojects within the χ² bound in both images. Homography hypotheses that only
/// points on the plane support can stay ambiguous (two of the four explain a plane equally well);
/// such a result is reported as failed rather than guessed, unless the competing hypotheses agree
/// on the rotation.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/detail/relative_pose.hpp"
#include "affine_orb/geometry/model_selection.hpp"

namespace affine_orb {

/// Intrinsics of a pinhole camera without distortion (rectified images), pixels.
struct PinholeCamera {
  double fx = 0.0;  ///< focal length along x, pixels
  double fy = 0.0;  ///< focal length along y, pixels
  double cx = 0.0;  ///< principal point x, pixels (pixel centres at integer coordinates)
  double cy = 0.0;  ///< principal point y, pixels

  /// Throws std::invalid_argument unless fx and fy are positive and finite and cx, cy finite.
  void check() const {
    detail::require_range(fx, detail::kPositive, "PinholeCamera: fx");
    detail::require_range(fy, detail::kPositive, "PinholeCamera: fy");
    detail::require(std::isfinite(cx) && std::isfinite(cy), "PinholeCamera: cx and cy must be finite");
  }

  /// K = [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d matrix() const {
    Eigen::Matrix3d k;
    k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
    return k;
  }

  /// K⁻¹.
  Eigen::Matrix3d inverse() const {
    Eigen::Matrix3d k;
    k << 1.0 / fx, 0.0, -cx / fx, 0.0, 1.0 / fy, -cy / fy, 0.0, 0.0, 1.0;
    return k;
  }

  /// The normalised ray (x, y, 1) of a pixel.
  Eigen::Vector3d ray(const cv::Point2f& pixel) const {
    return {(static_cast<double>(pixel.x) - cx) / fx, (static_cast<double>(pixel.y) - cy) / fy, 1.0};
  }

  /// The pixel of a point in camera coordinates (z != 0).
  Eigen::Vector2d project(const Eigen::Vector3d& point) const {
    return {fx * point.x() / point.z() + cx, fy * point.y() / point.z() + cy};
  }
};

/// Thresholds of the cheirality test that chooses among the pose hypotheses.
struct RelativePoseOptions {
  /// Standard deviation of a keypoint position in one image, pixels: 1 px, ORB-SLAM2's level-0 σ.
  /// The reprojection error of a triangulated point in one image carries that image's noise only
  /// (unlike the transfer error that ModelSelectionOptions::sigma scales, hence its 2 px).
  double sigma = 1.0;
  /// A triangulated correspondence counts when its squared reprojection error in each image is
  /// below reprojection_chi2 · σ²: 5.991, the 95 % quantile of χ² with 2 degrees of freedom (the
  /// homography bound of ModelSelectionOptions; ORB-SLAM2's Initializer::CheckRT uses 4 px²).
  double reprojection_chi2 = 5.991;
  /// The chosen hypothesis must explain at least this many correspondences: 8, the number the
  /// 8-point algorithm needs to fix E; fewer cannot confirm a two-view geometry.
  int min_good_points = 8;
  /// Another hypothesis that explains at least this share of the best one's count competes with it.
  /// Two decompositions of a plane's homography both explain every point on the plane; only
  /// points off the plane (or behind a camera) tell them apart, and with keypoint noise the counts
  /// of the two differ by up to 2 % on points of a plane alone (tests/test_relative_pose.cpp, ten
  /// synthetic planes at 0.5 px noise). 0.95 treats anything closer than 5 % as a tie, so a scene
  /// a tenth of whose points lie off the plane is resolved. (ORB-SLAM2's Initializer uses 0.7 for
  /// F and 0.75 for H, with a stricter count that also demands parallax.)
  double ambiguity_ratio = 0.95;
  /// Competitors whose rotation differs from the best one's by at most this angle (degrees) leave
  /// the rotation determined; a larger difference makes the result ambiguous (success = false).
  /// The same angle decides whether the translation directions agree (RelativePose::
  /// translation_unique). 1°: twice the accuracy the tests demand of a recovered rotation (0.5°),
  /// and well below the 180° twist between an essential matrix's wrong and right rotations.
  double tolerance_degrees = 1.0;

  /// Throws std::invalid_argument for a σ or χ² bound that is not positive and finite, a
  /// min_good_points below 1, an ambiguity_ratio outside (0, 1] or a tolerance outside (0, 180].
  void check() const {
    detail::require_range(sigma, detail::kPositive, "RelativePoseOptions: sigma");
    detail::require_range(reprojection_chi2, detail::kPositive, "RelativePoseOptions: reprojection_chi2");
    detail::require_range(min_good_points, detail::kPositive, "RelativePoseOptions: min_good_points");
    detail::require_range(ambiguity_ratio, {0, 1, true}, "RelativePoseOptions: ambiguity_ratio");
    detail::require_range(tolerance_degrees, {0, 180, true}, "RelativePoseOptions: tolerance_degrees");
  }
};

/// One candidate motion of a decomposition: X2 = rotation · X1 + translation. For a homography,
/// `normal` is the plane's unit normal n in camera 1 and translation = t / d (plane nᵀ X1 = d);
/// for an essential matrix translation has unit length and normal is zero.
struct PoseHypothesis {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

/// A recovered relative pose: X2 = rotation · X1 + translation (camera coordinates).
struct RelativePose {
  /// True when one rotation is supported (see relative_pose_from_fundamental()).
  bool success = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  /// Unit direction of t; zero for a pure rotation (homography with equal singular values).
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  /// From a homography: the plane's unit normal n in camera 1 (nᵀ X1 = d > 0); zero otherwise.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  /// False when a competing hypothesis has the same rotation but another translation direction
  /// (points too far away, or too little baseline, to tell the sign of t).
  bool translation_unique = false;
  /// Correspondences the chosen hypothesis explains (in front of both cameras, small reprojection
  /// error) and the largest count of any other hypothesis.
  int good_points = 0;
  int runner_up_points = 0;
};

/// Angle in degrees of the rotation a⁻¹ b = aᵀ b (0 … 180), accurate for small angles too.
inline double rotation_angle_degrees(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d m = a.transpose() * b;
  const double sine2 = Eigen::Vector3d(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)).norm();
  const double cosine2 = m.trace() - 1.0;
  return std::atan2(sine2, cosine2) * 180.0 / 3.14159265358979323846;
}

/// Angle in degrees between two directions (0 … 180); 0 when either is zero.
inline double direction_angle_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  if (a.norm() == 0.0 || b.norm() == 0.0) return 0.0;
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / 3.14159265358979323846;
}

/// The four (R, t) of an essential matrix E = [t]× R (Hartley & Zisserman Result 9.19): with
/// E = U diag(s, s, 0) Vᵀ and det U = det V = 1, R ∈ {U W Vᵀ, U Wᵀ Vᵀ}, t = ±u₃, W the 90°
/// rotation about z. `e` need not have equal singular values (an estimate); it is used as
/// E ~ U diag(1, 1, 0) Vᵀ. Empty when e is zero or not finite.
inline std::vector<PoseHypothesis> essential_hypotheses(const Eigen::Matrix3d& e) {
  if (!e.allFinite()) return {};
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(e, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (!(svd.singularValues()(1) > 0.0)) return {};
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  if (u.determinant() < 0.0) u = -u;
  if (v.determinant() < 0.0) v = -v;
  Eigen::Matrix3d w;
  w << 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d r1 = u * w * v.transpose();
  const Eigen::Matrix3d r2 = u * w.transpose() * v.transpose();
  const Eigen::Vector3d t = u.col(2);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  return {{r1, t, zero}, {r1, -t, zero}, {r2, t, zero}, {r2, -t, zero}};
}

/// The closest rotation to `m` in the Frobenius norm (U diag(1, 1, det(U Vᵀ)) Vᵀ).
inline Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

/// The decompositions of a calibrated homography G = K⁻¹ H K, sign already fixed so that
/// G ~ +(R + t nᵀ / d) (correspondences have positive depths: x̂2ᵀ G x̂1 > 0 for normalised rays).
///
/// Ma, Soatto, Košecká & Sastry, An Invitation to 3-D Vision, Sec. 5.3.3: with G scaled to σ₂ = 1
/// and GᵀG = V diag(σ₁², 1, σ₃²) Vᵀ, the unit vectors u₁,₂ = (√(1 − σ₃²) v₁ ± √(σ₁² − 1) v₃) /
/// √(σ₁² − σ₃²) keep their length under G; with U₁ = [v₂, u₁, v₂×u₁], W₁ = [G v₂, G u₁, G v₂ × G u₁]
/// (same for index 2): R = W Uᵀ, n = v₂ × u, t/d = (G − R) n, and the pairs (R, −t/d, −n).
/// The `translation` of each hypothesis is t/d, `normal` is n. When σ₁² − σ₃² is below 1e-12 (a
/// pure rotation: G is itself a rotation) the single hypothesis (nearest rotation, 0, 0) is
/// returned. Empty when g is zero or not finite.
inline std::vector<PoseHypothesis> homography_hypotheses(const Eigen::Matrix3d& g) {
  if (!g.allFinite()) return {};
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(g, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  if (!(s(1) > 0.0)) return {};
  const Eigen::Matrix3d h = g / s(1);
  const double s1 = (s(0) / s(1)) * (s(0) / s(1));
  const double s3 = (s(2) / s(1)) * (s(2) / s(1));
  if (s1 - s3 < 1e-12) return {{nearest_rotation(h), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}};
  const Eigen::Matrix3d v = svd.matrixV();
  const Eigen::Vector3d v1 = v.col(0), v2 = v.col(1), v3 = v.col(2);
  const double a = std::sqrt(std::max(0.0, 1.0 - s3));
  const double b = std::sqrt(std::max(0.0, s1 - 1.0));
  const double c = std::sqrt(s1 - s3);
  std::vector<PoseHypothesis> out;
  for (const double sign : {1.0, -1.0}) {
    const Eigen::Vector3d u = (a * v1 + sign * b * v3) / c;
    Eigen::Matrix3d uu, ww;
    uu << v2, u, v2.cross(u);
    const Eigen::Vector3d hv2 = h * v2, hu = h * u;
    ww << hv2, hu, hv2.cross(hu);
    const Eigen::Matrix3d r = ww * uu.transpose();
    const Eigen::Vector3d n = v2.cross(u);
    const Eigen::Vector3d t = (h - r) * n;
    out.push_back({r, t, n});
    out.push_back({r, -t, -n});
  }
  return out;
}

/// Number of masked correspondences that `hypothesis` explains: triangulated in front of both
/// cameras and reprojected within the bound in both images; for a hypothesis with zero translation
/// (pure rotation), those whose transfer x2 ~ K R K⁻¹ x1 is within the bound.
inline int count_good_points(const PoseHypothesis& hypothesis, const PinholeCamera& camera,
                             const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                             const std::vector<std::uint8_t>& inliers, const RelativePoseOptions& options) {
  const double bound = options.reprojection_chi2 * options.sigma * options.sigma;
  const Eigen::Matrix3d& r = hypothesis.rotation;
  const Eigen::Vector3d& t = hypothesis.translation;
  const bool rotation_only = t.norm() == 0.0;
  auto error2 = [](const Eigen::Vector2d& a, const cv::Point2f& b) {
    return (a - Eigen::Vector2d(b.x, b.y)).squaredNorm();
  };
  int good = 0;
  for (std::size_t i = 0; i < points1.size(); ++i) {
    if (!inliers.empty() && inliers[i] == 0) continue;
    const Eigen::Vector3d y1 = camera.ray(points1[i]);
    const Eigen::Vector3d y2 = camera.ray(points2[i]);
    if (rotation_only) {
      const Eigen::Vector3d x2 = r * y1;
      if (x2.z() > 0.0 && error2(camera.project(x2), points2[i]) < bound) ++good;
      continue;
    }
    const std::optional<Eigen::Vector3d> x1 = detail::triangulate(y1, y2, r, t);
    if (!x1) continue;
    const Eigen::Vector3d x2 = r * *x1 + t;
    if (!(x1->z() > 0.0 && x2.z() > 0.0)) continue;
    if (error2(camera.project(*x1), points1[i]) < bound && error2(camera.project(x2), points2[i]) < bound) ++good;
  }
  return good;
}

/// The hypothesis among `hypotheses` that count_good_points() rates highest (ties: the first), with
/// the ambiguity tests of RelativePoseOptions; see RelativePose.
inline RelativePose choose_hypothesis(const std::vector<PoseHypothesis>& hypotheses, const PinholeCamera& camera,
                                      const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                                      const std::vector<std::uint8_t>& inliers, const RelativePoseOptions& options) {
  RelativePose pose;
  if (hypotheses.empty()) return pose;
  std::vector<int> counts;
  for (const PoseHypothesis& h : hypotheses) {
    counts.push_back(count_good_points(h, camera, points1, points2, inliers, options));
  }
  const std::size_t best = static_cast<std::size_t>(std::max_element(counts.begin(), counts.end()) - counts.begin());
  const PoseHypothesis& chosen = hypotheses[best];
  pose.rotation = chosen.rotation;
  const double length = chosen.translation.norm();
  pose.translation = length > 0.0 ? Eigen::Vector3d(chosen.translation / length) : Eigen::Vector3d::Zero();
  pose.normal = chosen.normal;
  pose.good_points = counts[best];
  bool rotation_unique = true;
  pose.translation_unique = true;
  for (std::size_t k = 0; k < hypotheses.size(); ++k) {
    if (k == best) continue;
    pose.runner_up_points = std::max(pose.runner_up_points, counts[k]);
    if (static_cast<double>(counts[k]) < options.ambiguity_ratio * static_cast<double>(counts[best])) continue;
    if (rotation_angle_degrees(chosen.rotation, hypotheses[k].rotation) > options.tolerance_degrees) {
      rotation_unique = false;
    }
    if (direction_angle_degrees(chosen.translation, hypotheses[k].translation) > options.tolerance_degrees) {
      pose.translation_unique = false;
    }
  }
  pose.success = rotation_unique && pose.good_points >= options.min_good_points;
  if (!pose.success) pose.translation_unique = false;
  return pose;
}

/// Relative pose from a fundamental matrix (x2ᵀ F x1 = 0, pixels) of two views of `camera`.
///
/// `points1[i]`, `points2[i]` (pixels) are correspondences; `inliers` is empty (use all) or one
/// entry per correspondence, non-zero = use it (ModelSelectionResult::fundamental_inliers).
/// E = Kᵀ F K gives four hypotheses (essential_hypotheses()); the one that explains the most
/// correspondences wins (count_good_points()). success = false when it explains fewer than
/// options.min_good_points, or when a competitor explaining at least options.ambiguity_ratio of its
/// count has a rotation more than options.tolerance_degrees away; competitors with the same
/// rotation and another translation direction clear RelativePose::translation_unique instead.
/// success = false too for a zero F.
///
/// Throws std::invalid_argument for invalid intrinsics or options, a non-finite F, lists of
/// different lengths, a mask of the wrong size, or a non-finite coordinate.
inline RelativePose relative_pose_from_fundamental(const Eigen::Matrix3d& fundamental, const PinholeCamera& camera,
                                                   const std::vector<cv::Point2f>& points1,
                                                   const std::vector<cv::Point2f>& points2,
                                                   const std::vector<std::uint8_t>& inliers = {},
                                                   const RelativePoseOptions& options = {}) {
  options.check();
  camera.check();
  detail::require_pose_inputs(fundamental, points1, points2, inliers, "relative_pose_from_fundamental");
  const Eigen::Matrix3d k = camera.matrix();
  return choose_hypothesis(essential_hypotheses(k.transpose() * fundamental * k), camera, points1, points2, inliers,
                           options);
}

/// Relative pose from a homography (x2 ~ H x1, pixels) of two views of `camera`: a plane seen
/// from two positions, or any scene under a pure rotation.
///
/// G = K⁻¹ H K is given the sign that makes x̂2ᵀ G x̂1 positive for most of the used
/// correspondences (their depths are positive), then decomposed (homography_hypotheses()); the
/// choice, the failure rules and the arguments are those of relative_pose_from_fundamental(). A
/// pure rotation gives translation = 0 and translation_unique = true. RelativePose::normal is the
/// plane normal of the chosen hypothesis (unit, camera 1). Points on the plane alone often leave
/// two hypotheses with different rotations (then success = false); include the correspondences
/// off the plane in the mask (relative_pose() uses all of them) to tell them apart.
inline RelativePose relative_pose_from_homography(const Eigen::Matrix3d& homography, const PinholeCamera& camera,
                                                  const std::vector<cv::Point2f>& points1,
                                                  const std::vector<cv::Point2f>& points2,
                                                  const std::vector<std::uint8_t>& inliers = {},
                                                  const RelativePoseOptions& options = {}) {
  options.check();
  camera.check();
  detail::require_pose_inputs(homography, points1, points2, inliers, "relative_pose_from_homography");
  Eigen::Matrix3d g = camera.inverse() * homography * camera.matrix();
  int votes = 0;
  for (std::size_t i = 0; i < points1.size(); ++i) {
    if (!inliers.empty() && inliers[i] == 0) continue;
    const double side = camera.ray(points2[i]).dot(g * camera.ray(points1[i]));
    votes += side > 0.0 ? 1 : (side < 0.0 ? -1 : 0);
  }
  if (votes < 0) g = -g;
  return choose_hypothesis(homography_hypotheses(g), camera, points1, points2, inliers, options);
}

/// Relative pose from the model select_model() chose; success = false when it chose none.
/// `points1`, `points2` are the lists select_model() was given.
/// - F: the hypotheses are scored on the fundamental matrix's inliers (all four share its
///   epipolar geometry, so outliers would only add noise).
/// - H: they are scored on all correspondences. Points off the plane, which the homography
///   rejects, satisfy only the true motion's epipolar geometry and so break the twofold ambiguity
///   of a plane; outliers fail the reprojection test under every hypothesis alike.
inline RelativePose relative_pose(const ModelSelectionResult& selection, const PinholeCamera& camera,
                                  const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                                  const RelativePoseOptions& options = {}) {
  switch (selection.model) {
    case GeometricModel::kHomography:
      return relative_pose_from_homography(selection.homography, camera, points1, points2, {}, options);
    case GeometricModel::kFundamental:
      return relative_pose_from_fundamental(selection.fundamental, camera, points1, points2,
                                            selection.fundamental_inliers, options);
    default:
      options.check();
      camera.check();
      return {};
  }
}

}  // namespace affine_orb
