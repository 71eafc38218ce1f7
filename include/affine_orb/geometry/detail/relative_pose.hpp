#pragma once
/// \file
/// Internals (namespace detail, not part of the API): triangulation and the input checks behind
/// geometry/relative_pose.hpp.

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
#include "affine_orb/geometry/model_selection.hpp"

namespace affine_orb {
namespace detail {

/// Linear (DLT) triangulation of the normalised rays y1, y2 with cameras [I | 0] and [R | t]
/// (Hartley & Zisserman Sec. 12.2): the null vector of the 4x4 system x × (P X) = 0. nullopt for a
/// point at infinity or a non-finite result.
inline std::optional<Eigen::Vector3d> triangulate(const Eigen::Vector3d& y1, const Eigen::Vector3d& y2,
                                                  const Eigen::Matrix3d& r, const Eigen::Vector3d& t) {
  Eigen::Matrix<double, 3, 4> p2;
  p2 << r, t;
  Eigen::Matrix4d a;
  a.row(0) << -1.0, 0.0, y1.x(), 0.0;
  a.row(1) << 0.0, -1.0, y1.y(), 0.0;
  a.row(2) = y2.x() * p2.row(2) - p2.row(0);
  a.row(3) = y2.y() * p2.row(2) - p2.row(1);
  for (int i = 0; i < 4; ++i) a.row(i).normalize();
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (!(std::abs(x(3)) > 1e-12 * x.head<3>().norm())) return std::nullopt;
  const Eigen::Vector3d point = x.head<3>() / x(3);
  if (!point.allFinite()) return std::nullopt;
  return point;
}

/// Throws unless the inputs of a relative-pose function are consistent (the camera is checked by
/// PinholeCamera::check()).
inline void require_pose_inputs(const Eigen::Matrix3d& model, const std::vector<cv::Point2f>& points1,
                                const std::vector<cv::Point2f>& points2, const std::vector<std::uint8_t>& inliers,
                                const char* who) {
  require(model.allFinite(), std::string(who) + ": the matrix has a non-finite entry");
  require(points1.size() == points2.size(), std::string(who) + ": points1 has " + std::to_string(points1.size()) +
                                                " points but points2 has " + std::to_string(points2.size()));
  require(inliers.empty() || inliers.size() == points1.size(),
          std::string(who) + ": the inlier mask must be empty or have one entry per correspondence");
  for (std::size_t i = 0; i < points1.size(); ++i) {
    require(std::isfinite(points1[i].x) && std::isfinite(points1[i].y) && std::isfinite(points2[i].x) &&
                std::isfinite(points2[i].y),
            std::string(who) + ": non-finite point coordinate");
  }
}

}  // namespace detail
}  // namespace affine_orb
