#pragma once
/// \file
/// Hartley's isotropic normalisation of 2-D point sets and the conversions the geometric estimators
/// share (cv::Point2f input to Eigen, finiteness checks).

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"

namespace affine_orb::detail {

/// Mean distance to the centroid below which a point set is treated as a single point: the
/// normalising scale would then be infinite. Relative to the coordinates' magnitude (pixels).
inline constexpr double kMinMeanSpreadRelative = 1e-12;

/// Hartley's normalising similarity T (Hartley, "In defense of the eight-point algorithm", PAMI
/// 1997, Sec. 5): T x moves the centroid of `points` to the origin and scales them so that their
/// mean distance to it is √2. Returns nullopt when the points (all `count` of them) coincide.
inline std::optional<Eigen::Matrix3d> hartley_normalization(const Eigen::Vector2d* points, std::size_t count) {
  if (count == 0) return std::nullopt;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < count; ++i) centroid += points[i];
  centroid /= static_cast<double>(count);
  double mean_distance = 0.0;
  for (std::size_t i = 0; i < count; ++i) mean_distance += (points[i] - centroid).norm();
  mean_distance /= static_cast<double>(count);
  const double magnitude = centroid.cwiseAbs().maxCoeff() + mean_distance;
  if (!(mean_distance > kMinMeanSpreadRelative * magnitude) || !std::isfinite(mean_distance)) {
    return std::nullopt;
  }
  const double scale = std::sqrt(2.0) / mean_distance;
  Eigen::Matrix3d t;
  t << scale, 0.0, -scale * centroid.x(), 0.0, scale, -scale * centroid.y(), 0.0, 0.0, 1.0;
  return t;
}

/// Applies a normalising similarity (as returned by hartley_normalization) to one point.
inline Eigen::Vector2d apply_similarity(const Eigen::Matrix3d& t, const Eigen::Vector2d& p) {
  return {t(0, 0) * p.x() + t(0, 2), t(1, 1) * p.y() + t(1, 2)};
}

/// Inverse of a normalising similarity [s 0 tx; 0 s ty; 0 0 1].
inline Eigen::Matrix3d similarity_inverse(const Eigen::Matrix3d& t) {
  Eigen::Matrix3d inv;
  const double s = 1.0 / t(0, 0);
  inv << s, 0.0, -t(0, 2) * s, 0.0, s, -t(1, 2) * s, 0.0, 0.0, 1.0;
  return inv;
}

/// Matched points in pixels and in Hartley-normalised coordinates, as the estimators consume them.
struct NormalizedCorrespondences {
  std::vector<Eigen::Vector2d> pixels1;      ///< image-1 points, pixels
  std::vector<Eigen::Vector2d> pixels2;      ///< image-2 points, pixels
  std::vector<Eigen::Vector2d> normalized1;  ///< t1 · pixels1
  std::vector<Eigen::Vector2d> normalized2;  ///< t2 · pixels2
  Eigen::Matrix3d t1 = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d t2 = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d t1_inverse = Eigen::Matrix3d::Identity();  ///< similarity_inverse(t1)
  Eigen::Matrix3d t2_inverse = Eigen::Matrix3d::Identity();  ///< similarity_inverse(t2)
  /// False when all points of one image coincide (or there are none): no model can be estimated,
  /// the normalised coordinates are then left empty.
  bool normalizable = false;
};

/// Converts matched pixel coordinates, checking that both lists have the same length and every
/// coordinate is finite (std::invalid_argument otherwise; `who` names the caller), and normalises
/// each image's points with its own Hartley similarity.
inline NormalizedCorrespondences normalize_correspondences(const std::vector<cv::Point2f>& points1,
                                                           const std::vector<cv::Point2f>& points2, const char* who) {
  require(points1.size() == points2.size(), std::string(who) + ": points1 has " + std::to_string(points1.size()) +
                                                " points but points2 has " + std::to_string(points2.size()));
  NormalizedCorrespondences c;
  const std::size_t n = points1.size();
  c.pixels1.resize(n);
  c.pixels2.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Point2f& a = points1[i];
    const cv::Point2f& b = points2[i];
    if (!(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(b.x) && std::isfinite(b.y))) {
      require(false, std::string(who) + ": correspondence " + std::to_string(i) + " has a non-finite coordinate");
    }
    c.pixels1[i] = Eigen::Vector2d(a.x, a.y);
    c.pixels2[i] = Eigen::Vector2d(b.x, b.y);
  }
  const std::optional<Eigen::Matrix3d> t1 = hartley_normalization(c.pixels1.data(), n);
  const std::optional<Eigen::Matrix3d> t2 = hartley_normalization(c.pixels2.data(), n);
  if (!t1 || !t2) return c;
  c.t1 = *t1;
  c.t2 = *t2;
  c.t1_inverse = similarity_inverse(c.t1);
  c.t2_inverse = similarity_inverse(c.t2);
  c.normalized1.resize(n);
  c.normalized2.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    c.normalized1[i] = apply_similarity(c.t1, c.pixels1[i]);
    c.normalized2[i] = apply_similarity(c.t2, c.pixels2[i]);
  }
  c.normalizable = true;
  return c;
}

}  // namespace affine_orb::detail
