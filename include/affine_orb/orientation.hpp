#pragma once
/// \file
/// Intensity-centroid orientation (Rosin, "Measuring corner properties", CVIU 1999; used by ORB,
/// Rublee et al. ICCV 2011, eqs. 1–3): θ = atan2(m01, m10) with the moments
/// m_pq = Σ x^p y^q I(x, y) over a disc centred on the keypoint.

#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/detail/check.hpp"

namespace affine_orb {

/// Precomputed disc of radius r: the pixel offsets (u, v) with u² + v² <= r², stored per row as the
/// half-width of the row, so that the disc is symmetric under 90° rotations and reflections.
class CentroidDisc {
 public:
  explicit CentroidDisc(int radius = 15) : radius_(radius) {
    detail::require(radius >= 1 && radius <= 255, "CentroidDisc: radius must be in [1, 255]");
    half_width_.resize(static_cast<std::size_t>(radius) + 1);
    for (int v = 0; v <= radius; ++v) {
      int u = 0;
      while ((u + 1) * (u + 1) + v * v <= radius * radius) ++u;
      half_width_[static_cast<std::size_t>(v)] = u;
    }
  }

  int radius() const { return radius_; }

  /// Orientation in radians, in (−π, π], of the disc centred on the integer pixel (x, y) of a
  /// CV_8UC1 image (x right, y down, angle from +x towards +y). The caller guarantees that the disc
  /// lies inside the image (radius() <= x < cols − radius(), likewise y).
  float angle(const cv::Mat& image, int x, int y) const {
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
    const std::uint8_t* center = image.ptr<std::uint8_t>(y) + x;
    std::int64_t m10 = 0;
    std::int64_t m01 = 0;
    const int w0 = half_width_[0];
    for (int u = -w0; u <= w0; ++u) m10 += u * center[u];
    for (int v = 1; v <= radius_; ++v) {
      const int w = half_width_[static_cast<std::size_t>(v)];
      const std::uint8_t* below = center + v * step;
      const std::uint8_t* above = center - v * step;
      std::int64_t row_sum = 0;
      for (int u = -w; u <= w; ++u) {
        const int b = below[u];
        const int a = above[u];
        m10 += u * (a + b);
        row_sum += b - a;
      }
      m01 += v * row_sum;
    }
    return std::atan2(static_cast<float>(m01), static_cast<float>(m10));
  }

 private:
  int radius_;
  std::vector<int> half_width_;
};

}  // namespace affine_orb
