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
#include <cstring>
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
  std::vector<std::uint16_t> high;  ///< the x pass h, h >> 8: (height + 2r) rows of `width` values
  std::vector<std::uint16_t> low;   ///< the x pass, h & 255
};

/// smooth_square_q8() on the source rows `base` (step `step`, starting r rows above and r columns
/// left of the square) for a kernel of kTaps taps (0: kernel.size()). The x pass h < 2^16 is kept
/// as h >> 8 and h & 255, so that the y pass runs in 16 bits: with A = Σ k_j·(h_j >> 8) and
/// B = Σ k_j·(h_j & 255), both below 2^16, (256·A + B + 2^15) >> 16 = (A + (B >> 8) + 128) >> 8.
/// The kernel is symmetric, so taps j and n − 1 − j are added before multiplying (any partial sum
/// of the nonnegative terms stays below the total, below 2^16).
template <int kTaps>
inline void smooth_rows_q8(const std::uint8_t* base, std::ptrdiff_t step, cv::Size square,
                           const std::vector<std::uint16_t>& kernel, GaussianQ8Work& work, std::uint8_t* out,
                           std::ptrdiff_t out_step) {
  const int n = kTaps > 0 ? kTaps : static_cast<int>(kernel.size());
  const int half = n / 2;
  const int width = square.width;
  const int rows = square.height + 2 * half;
  work.high.resize(static_cast<std::size_t>(rows) * static_cast<std::size_t>(width));
  work.low.resize(work.high.size());
  std::uint16_t* high = work.high.data();
  std::uint16_t* low = work.low.data();
  const std::uint16_t* k = kernel.data();
#if defined(__SSE2__)
  if (width >= 8) {
    const __m128i zero = _mm_setzero_si128();
    const __m128i byte = _mm_set1_epi16(0xFF);
    const __m128i round = _mm_set1_epi16(128);
    __m128i weight[16];
    for (int j = 0; j <= half; ++j) weight[j] = _mm_set1_epi16(static_cast<short>(k[j]));
    for (int y = 0; y < rows; ++y) {
      const std::uint8_t* s = base + y * step;
      for (int x = 0;; x = std::min(x + 8, width - 8)) {
        auto at = [&](int i) {
          return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s + x + i)), zero);
        };
        __m128i sum = _mm_mullo_epi16(at(half), weight[half]);
        for (int i = 0; i < half; ++i) {
          sum = _mm_add_epi16(sum, _mm_mullo_epi16(_mm_add_epi16(at(i), at(n - 1 - i)), weight[i]));
        }
        _mm_storeu_si128(reinterpret_cast<__m128i*>(high + y * width + x), _mm_srli_epi16(sum, 8));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(low + y * width + x), _mm_and_si128(sum, byte));
        if (x + 8 >= width) break;
      }
    }
    for (int y = 0; y < square.height; ++y) {
      for (int x = 0;; x = std::min(x + 8, width - 8)) {
        auto column = [&](const std::uint16_t* plane, int j) {
          return _mm_loadu_si128(reinterpret_cast<const __m128i*>(plane + (y + j) * width + x));
        };
        __m128i a = _mm_mullo_epi16(column(high, half), weight[half]);
        __m128i b = _mm_mullo_epi16(column(low, half), weight[half]);
        for (int j = 0; j < half; ++j) {
          a = _mm_add_epi16(a, _mm_mullo_epi16(_mm_add_epi16(column(high, j), column(high, n - 1 - j)), weight[j]));
          b = _mm_add_epi16(b, _mm_mullo_epi16(_mm_add_epi16(column(low, j), column(low, n - 1 - j)), weight[j]));
        }
        const __m128i v = _mm_srli_epi16(_mm_add_epi16(_mm_add_epi16(a, _mm_srli_epi16(b, 8)), round), 8);
        _mm_storel_epi64(reinterpret_cast<__m128i*>(out + y * out_step + x), _mm_packus_epi16(v, v));
        if (x + 8 >= width) break;
      }
    }
    return;
  }
#endif
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* s = base + y * step;
    for (int x = 0; x < width; ++x) {
      std::uint32_t sum = 0;
      for (int i = 0; i < n; ++i) sum += k[i] * s[x + i];
      high[y * width + x] = static_cast<std::uint16_t>(sum >> 8);
      low[y * width + x] = static_cast<std::uint16_t>(sum & 255);
    }
  }
  for (int y = 0; y < square.height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint32_t sum = 1u << 15;
      for (int j = 0; j < n; ++j) {
        sum += k[j] * (256u * high[(y + j) * width + x] + low[(y + j) * width + x]);
      }
      out[y * out_step + x] = static_cast<std::uint8_t>(sum >> 16);
    }
  }
}

/// Writes the smoothing (file comment) of the pixels of `square` (inside `level`) into the same
/// pixels of `out` (of the level's size). The kernel has at most 31 taps.
inline void smooth_square_q8(const cv::Mat& level, cv::Rect square, const std::vector<std::uint16_t>& kernel,
                             GaussianQ8Work& work, cv::Mat& out) {
  const int r = static_cast<int>(kernel.size()) / 2;
  const cv::Rect source(square.x - r, square.y - r, square.width + 2 * r, square.height + 2 * r);
  const cv::Rect bounds(0, 0, level.cols, level.rows);
  const std::uint8_t* base = nullptr;
  std::ptrdiff_t step = 0;
  if ((source & bounds) == source) {
    base = level.ptr<std::uint8_t>(source.y) + source.x;
    step = static_cast<std::ptrdiff_t>(level.step[0]);
  } else {
    // The columns inside the level are copied, the others reflected one by one.
    work.tile.create(source.height, source.width, CV_8UC1);
    const int inside0 = std::clamp(-source.x, 0, source.width);
    const int inside1 = std::clamp(level.cols - source.x, inside0, source.width);
    for (int y = 0; y < source.height; ++y) {
      const std::uint8_t* row = level.ptr<std::uint8_t>(reflect101(source.y + y, level.rows));
      std::uint8_t* t = work.tile.ptr<std::uint8_t>(y);
      for (int x = 0; x < inside0; ++x) t[x] = row[reflect101(source.x + x, level.cols)];
      std::memcpy(t + inside0, row + source.x + inside0, static_cast<std::size_t>(inside1 - inside0));
      for (int x = inside1; x < source.width; ++x) t[x] = row[reflect101(source.x + x, level.cols)];
    }
    base = work.tile.ptr<std::uint8_t>(0);
    step = static_cast<std::ptrdiff_t>(work.tile.step[0]);
  }
  std::uint8_t* target = out.ptr<std::uint8_t>(square.y) + square.x;
  const std::ptrdiff_t target_step = static_cast<std::ptrdiff_t>(out.step[0]);
  if (kernel.size() == 7) {
    smooth_rows_q8<7>(base, step, square.size(), kernel, work, target, target_step);
  } else {
    smooth_rows_q8<0>(base, step, square.size(), kernel, work, target, target_step);
  }
}

}  // namespace affine_orb::detail
