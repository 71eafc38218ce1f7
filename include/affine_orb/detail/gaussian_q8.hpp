#pragma once
/// \file
/// The 8-bit Gaussian smoothing of rBRIEF (rbrief.hpp) on small squares of a level, giving the
/// bytes of cv::GaussianBlur, which is bit-exact for 8-bit images: an integer kernel k_0..k_(n−1)
/// in units of 1/256 that sums to 256, applied along x and then along y in exact integer
/// arithmetic and rounded once,
///   out(x, y) = (Σ_j k_j·h(x, y + j − r) + 2^15) >> 16,  h(x, y) = Σ_i k_i·I(x + i − r, y),
/// r = n/2, the image reflected about its edges (BORDER_REFLECT_101). The kernel is read from
/// cv::GaussianBlur's response to a line (gaussian_kernel_q8()) and the whole formula is checked
/// against cv::GaussianBlur before use, so nothing is assumed about OpenCV's kernel beyond what
/// is measured.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace affine_orb::detail {

/// Reflection of index i into [0, n) about the edges without repeating them (BORDER_REFLECT_101).
inline int reflect101(int i, int n) {
  if (n == 1) return 0;
  while (i < 0 || i >= n) i = i < 0 ? -i : 2 * (n - 1) - i;
  return i;
}

/// The smoothing of the file comment at one pixel, straight from the formula.
inline std::uint8_t gaussian_q8_pixel(const cv::Mat& image, int x, int y, const std::vector<std::uint16_t>& kernel) {
  const int r = static_cast<int>(kernel.size()) / 2;
  std::uint32_t sum = 0;
  for (int j = 0; j < static_cast<int>(kernel.size()); ++j) {
    const int yy = reflect101(y + j - r, image.rows);
    std::uint32_t h = 0;
    for (int i = 0; i < static_cast<int>(kernel.size()); ++i) {
      h += kernel[static_cast<std::size_t>(i)] * image.at<std::uint8_t>(yy, reflect101(x + i - r, image.cols));
    }
    sum += kernel[static_cast<std::size_t>(j)] * h;
  }
  return static_cast<std::uint8_t>((sum + (1u << 15)) >> 16);
}

/// The integer kernel of cv::GaussianBlur(size x size, σ) on 8-bit images, or an empty vector when
/// the formula of the file comment does not reproduce cv::GaussianBlur with it. Read from the
/// response to a vertical line of 255: column c of the result is round(255·k_c/256), which is k_c
/// for k_c < 128 and k_c − 1 or k_c above, settled by the sum of 256.
inline std::vector<std::uint16_t> gaussian_kernel_q8(int size, double sigma) {
  const int r = size / 2;
  const int width = 2 * size + 1;
  cv::Mat line(width, width, CV_8UC1, cv::Scalar(0));
  line.col(width / 2).setTo(255);
  cv::Mat response;
  cv::GaussianBlur(line, response, cv::Size(size, size), sigma, sigma, cv::BORDER_REFLECT_101);
  std::vector<std::uint16_t> kernel(static_cast<std::size_t>(size));
  int sum = 0;
  for (int i = 0; i < size; ++i) {
    kernel[static_cast<std::size_t>(i)] = response.at<std::uint8_t>(width / 2, width / 2 - r + i);
    sum += kernel[static_cast<std::size_t>(i)];
  }
  for (std::uint16_t& k : kernel) {
    if (sum < 256 && k >= 127) {
      ++k;
      ++sum;
    }
  }
  // The whole formula against cv::GaussianBlur on a deterministic pseudo-random image.
  cv::Mat test(37, 41, CV_8UC1);
  std::uint32_t state = 12345u;
  for (int y = 0; y < test.rows; ++y) {
    for (int x = 0; x < test.cols; ++x) {
      state = state * 1664525u + 1013904223u;
      test.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(state >> 24);
    }
  }
  cv::Mat expected;
  cv::GaussianBlur(test, expected, cv::Size(size, size), sigma, sigma, cv::BORDER_REFLECT_101);
  if (sum != 256) return {};
  for (int y = 0; y < test.rows; ++y) {
    for (int x = 0; x < test.cols; ++x) {
      if (gaussian_q8_pixel(test, x, y, kernel) != expected.at<std::uint8_t>(y, x)) return {};
    }
  }
  return kernel;
}

/// Buffers of smooth_square_q8(), reused across calls.
struct GaussianQ8Work {
  cv::Mat tile;                     ///< the source square with its margin, reflected at the level edges
  std::vector<std::uint16_t> rows;  ///< the x pass: (height + 2r) rows of `width` values
};

/// Writes the smoothing (file comment) of the pixels of `square` (inside `level`) into the same
/// pixels of `out` (of the level's size).
inline void smooth_square_q8(const cv::Mat& level, cv::Rect square, const std::vector<std::uint16_t>& kernel,
                             GaussianQ8Work& work, cv::Mat& out) {
  const int n = static_cast<int>(kernel.size());
  const int r = n / 2;
  const cv::Rect source(square.x - r, square.y - r, square.width + 2 * r, square.height + 2 * r);
  const cv::Rect bounds(0, 0, level.cols, level.rows);
  const std::uint8_t* base = nullptr;
  std::ptrdiff_t step = 0;
  if ((source & bounds) == source) {
    base = level.ptr<std::uint8_t>(source.y) + source.x;
    step = static_cast<std::ptrdiff_t>(level.step[0]);
  } else {
    work.tile.create(source.height, source.width, CV_8UC1);
    for (int y = 0; y < source.height; ++y) {
      const std::uint8_t* row = level.ptr<std::uint8_t>(reflect101(source.y + y, level.rows));
      std::uint8_t* t = work.tile.ptr<std::uint8_t>(y);
      for (int x = 0; x < source.width; ++x) t[x] = row[reflect101(source.x + x, level.cols)];
    }
    base = work.tile.ptr<std::uint8_t>(0);
    step = static_cast<std::ptrdiff_t>(work.tile.step[0]);
  }
  const int width = square.width;
  work.rows.resize(static_cast<std::size_t>(source.height) * static_cast<std::size_t>(width));
  std::uint16_t* h = work.rows.data();
  // x pass (sums below 2^16: 255·256 at most).
  for (int y = 0; y < source.height; ++y) {
    const std::uint8_t* s = base + y * step;
    std::uint16_t* d = h + static_cast<std::ptrdiff_t>(y) * width;
#if defined(__SSE2__)
    if (width >= 8) {
      const __m128i zero = _mm_setzero_si128();
      for (int x = 0;; x = std::min(x + 8, width - 8)) {
        __m128i sum = zero;
        for (int i = 0; i < n; ++i) {
          const __m128i v = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s + x + i)), zero);
          sum = _mm_add_epi16(
              sum, _mm_mullo_epi16(v, _mm_set1_epi16(static_cast<short>(kernel[static_cast<std::size_t>(i)]))));
        }
        _mm_storeu_si128(reinterpret_cast<__m128i*>(d + x), sum);
        if (x + 8 >= width) break;
      }
      continue;
    }
#endif
    for (int x = 0; x < width; ++x) {
      std::uint32_t sum = 0;
      for (int i = 0; i < n; ++i) sum += kernel[static_cast<std::size_t>(i)] * s[x + i];
      d[x] = static_cast<std::uint16_t>(sum);
    }
  }
  // y pass in 32 bits, one rounding.
  for (int y = 0; y < square.height; ++y) {
    std::uint8_t* d = out.ptr<std::uint8_t>(square.y + y) + square.x;
    const std::uint16_t* column = h + static_cast<std::ptrdiff_t>(y) * width;
#if defined(__SSE2__)
    if (width >= 8) {
      const __m128i round = _mm_set1_epi32(1 << 15);
      for (int x = 0;; x = std::min(x + 8, width - 8)) {
        __m128i lo = round;
        __m128i hi = round;
        for (int j = 0; j < n; ++j) {
          const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(column + j * width + x));
          const __m128i k = _mm_set1_epi16(static_cast<short>(kernel[static_cast<std::size_t>(j)]));
          const __m128i p_lo = _mm_mullo_epi16(v, k);
          const __m128i p_hi = _mm_mulhi_epu16(v, k);
          lo = _mm_add_epi32(lo, _mm_unpacklo_epi16(p_lo, p_hi));
          hi = _mm_add_epi32(hi, _mm_unpackhi_epi16(p_lo, p_hi));
        }
        const __m128i words = _mm_packs_epi32(_mm_srli_epi32(lo, 16), _mm_srli_epi32(hi, 16));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(d + x), _mm_packus_epi16(words, words));
        if (x + 8 >= width) break;
      }
      continue;
    }
#endif
    for (int x = 0; x < width; ++x) {
      std::uint32_t sum = 1u << 15;
      for (int j = 0; j < n; ++j) sum += kernel[static_cast<std::size_t>(j)] * column[j * width + x];
      d[x] = static_cast<std::uint8_t>(sum >> 16);
    }
  }
}

}  // namespace affine_orb::detail
