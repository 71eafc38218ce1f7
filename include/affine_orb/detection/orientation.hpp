#pragma once
/// \file
/// Intensity-centroid orientation (Rosin, "Measuring corner properties", CVIU 1999; used by ORB,
/// Rublee et al. ICCV 2011, eqs. 1–3): θ = atan2(m01, m10) with the moments
/// m_pq = Σ x^p y^q I(x, y) over ORB's disc centred on the keypoint, computed as ORB computes it
/// (its disc, cv::fastAtan2), so that angles and steered descriptors equal ORB's bit for bit.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"

namespace affine_orb {

/// ORB's intensity-centroid disc of radius r, as row half-widths w[v] (|u| <= w[|v|] is inside):
/// w[v] = round(√(r² − v²)) for v <= ⌊r·√2/2 + 1⌋, and the rows above ⌈r·√2/2⌉ completed so that
/// the disc is symmetric under transposition (u <= w[v] ⟺ v <= w[u]). This is the disc of
/// OpenCV's ORB (Rublee et al., ICCV 2011) and of ORB-SLAM2's extractor; for r = 15 it is
/// {15, 15, 15, 15, 14, 14, 14, 13, 13, 12, 11, 10, 9, 8, 6, 3}.
inline std::vector<int> orb_disc_half_widths(int radius) {
  detail::require_range(radius, {1, 255}, "orb_disc_half_widths: radius");
  std::vector<int> w(static_cast<std::size_t>(radius) + 2, 0);
  const double diagonal = radius * std::sqrt(2.0) / 2.0;
  const int rounded_rows = std::min(static_cast<int>(std::floor(diagonal + 1.0)), radius);
  const int completed_from = static_cast<int>(std::ceil(diagonal));
  for (int v = 0; v <= rounded_rows; ++v)
    w[static_cast<std::size_t>(v)] =
        static_cast<int>(std::lround(std::sqrt(static_cast<double>(radius * radius - v * v))));
  // Rows from the top down take the column lengths of the rows from the middle up.
  for (int v = radius, column = 0; v >= completed_from; --v, ++column) {
    while (w[static_cast<std::size_t>(column)] == w[static_cast<std::size_t>(column) + 1]) ++column;
    w[static_cast<std::size_t>(v)] = column;
  }
  w.resize(static_cast<std::size_t>(radius) + 1);
  return w;
}

/// The keypoint angle ORB and ORB-SLAM store, in degrees in [0, 360), from the disc's moments:
/// cv::fastAtan2(m01, m10) (accurate to about 0.3°).
inline float orb_angle_degrees(std::int64_t m01, std::int64_t m10) {
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

/// The angle ORB steers its pattern by, in radians in [0, 2π): orb_angle_degrees() times the float
/// π/180, exactly as OpenCV's ORB and ORB-SLAM2 turn a keypoint's angle into the steering angle.
inline float degrees_to_steering(float degrees) { return degrees * static_cast<float>(CV_PI / 180.0); }

/// degrees_to_steering(orb_angle_degrees(m01, m10)).
inline float orb_angle(std::int64_t m01, std::int64_t m10) { return degrees_to_steering(orb_angle_degrees(m01, m10)); }

/// Precomputed ORB disc of radius r (orb_disc_half_widths()).
class CentroidDisc {
 public:
  explicit CentroidDisc(int radius = 15) : radius_(radius), half_width_(orb_disc_half_widths(radius)) {}

  /// Half-width of row ±v of the disc.
  int half_width(int v) const { return half_width_.at(static_cast<std::size_t>(v)); }
  int radius() const { return radius_; }

  /// Orientation (orb_angle(), radians in [0, 2π)) of the disc centred on the integer pixel (x, y)
  /// of a CV_8UC1 image (x right, y down, angle from +x towards +y). The caller guarantees that the
  /// disc lies inside the image (radius() <= x < cols − radius(), likewise y).
  float angle(const cv::Mat& image, int x, int y) const { return degrees_to_steering(degrees(image, x, y)); }

  /// The same orientation in degrees (orb_angle_degrees()), as ORB's keypoints carry it.
  float degrees(const cv::Mat& image, int x, int y) const {
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
    return orb_angle_degrees(m01, m10);
  }

 private:
  int radius_;
  std::vector<int> half_width_;
};

}  // namespace affine_orb
