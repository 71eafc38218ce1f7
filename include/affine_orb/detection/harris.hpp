#pragma once
/// \file
/// Harris corner response (Harris & Stephens, 1988) at a pixel, the ranking score ORB uses
/// (Rublee et al., ICCV 2011, section 3.1).

#include <cstdint>

#include <opencv2/core.hpp>

namespace affine_orb {

/// Half-size in pixels of the neighbourhood harris_response() reads around its pixel, for a block of
/// side `block_size`: the block plus the 3x3 Sobel support.
constexpr int harris_radius(int block_size) { return block_size / 2 + 1; }

/// Harris response R = det(M) − k·trace(M)² of the structure tensor M = Σ [Ix² IxIy; IxIy Iy²] summed
/// over the block_size x block_size window centred on integer pixel (x, y) of a CV_8UC1 image, with
/// 3x3 Sobel derivatives normalised to intensity units per pixel (divided by 8·255). The caller
/// guarantees that harris_radius(block_size) pixels around (x, y) lie inside the image.
/// ORB uses block_size = 7 and k = 0.04.
inline float harris_response(const cv::Mat& image, int x, int y, int block_size = 7, float k = 0.04f) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const int r = block_size / 2;
  double a = 0.0;
  double b = 0.0;
  double c = 0.0;
  for (int v = -r; v <= r; ++v) {
    const std::uint8_t* p = image.ptr<std::uint8_t>(y + v) + x;
    for (int u = -r; u <= r; ++u) {
      const std::uint8_t* q = p + u;
      const int ix = (q[-step + 1] + 2 * q[1] + q[step + 1]) - (q[-step - 1] + 2 * q[-1] + q[step - 1]);
      const int iy = (q[step - 1] + 2 * q[step] + q[step + 1]) - (q[-step - 1] + 2 * q[-step] + q[-step + 1]);
      a += static_cast<double>(ix) * ix;
      b += static_cast<double>(iy) * iy;
      c += static_cast<double>(ix) * iy;
    }
  }
  const double norm = 1.0 / (8.0 * 255.0);
  const double n2 = norm * norm;
  a *= n2;
  b *= n2;
  c *= n2;
  return static_cast<float>(a * b - c * c - k * (a + b) * (a + b));
}

}  // namespace affine_orb
