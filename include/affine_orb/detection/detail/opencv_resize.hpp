#pragma once
/// \file
/// Internals (namespace detail): cv::resize with INTER_LINEAR on 8-bit single-channel images,
/// reproduced byte for byte into a caller's buffers (the SLAM forks build their pyramids with it,
/// and cv::resize allocates its tables on every call). The arithmetic, per axis of source size n
/// and destination size m (OpenCV's fixed point with 11-bit weights):
/// - destination index d samples f = (float)((d + 0.5)·n/m − 0.5), s = floor(f), weights
///   w0 = cvRound((1 − (f − s))·2048), w1 = cvRound((f − s)·2048); along x a sample before the
///   first or from the last column on takes that column alone (s clamped, weights 2048 and 0),
///   along y the two rows s and s + 1 are clamped to the image;
/// - a row of the source resized along x is h = I(s)·w0 + I(s + 1)·w1;
/// - a destination pixel from the rows h0 (row s) and h1 (row s + 1) with weights b0, b1 is
///   (((h0 >> 4)·b0 >> 16) + ((h1 >> 4)·b1 >> 16) + 2) >> 2, OpenCV's 16-bit vertical step.
/// Exactly halving both sizes (OpenCV then averages 2x2 blocks) and equal sizes (a copy) go to
/// cv::resize itself.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/simd.hpp"

namespace affine_orb {
namespace detail {

/// One axis of the resize: per destination index, its first source index and two weights.
struct CvResizeAxis {
  static constexpr std::size_t kBlock = 8;  ///< destination indices per AVX2 block
  std::vector<int> first;
  std::vector<int> second;  ///< min(first + 1, n − 1)
  std::vector<std::int16_t> w0;
  std::vector<std::int16_t> w1;
  std::vector<std::int16_t> pairs;  ///< w0, w1 interleaved
  /// Along x, per block of kBlock destination indices (the AVX2 kernel): the first source
  /// index of a 16-byte window holding every source the block reads, or −1 where none does (a
  /// window past the row's end, or sources more than 16 apart), and the vpshufb mask that spreads
  /// each index's two source bytes from it into the 16-bit lanes its w0, w1 pair multiplies.
  std::vector<int> window;
  std::vector<std::array<std::uint8_t, 32>> spread;
  int n = -1;
  int m = -1;

  /// `clamp_edges`: along x, a sample outside [0, n − 1) takes the edge column alone. Kept when
  /// the sizes are those of the last call.
  void set(int source, int destination, bool clamp_edges) {
    if (source == n && destination == m) return;
    n = source;
    m = destination;
    first.resize(static_cast<std::size_t>(m));
    second.resize(static_cast<std::size_t>(m));
    w0.resize(static_cast<std::size_t>(m));
    w1.resize(static_cast<std::size_t>(m));
    pairs.resize(2 * static_cast<std::size_t>(m));
    const double scale = 1.0 / (static_cast<double>(m) / static_cast<double>(n));
    for (int d = 0; d < m; ++d) {
      float f = static_cast<float>((d + 0.5) * scale - 0.5);
      int s = cvFloor(f);
      f -= static_cast<float>(s);
      if (clamp_edges && s < 0) {
        f = 0.0f;
        s = 0;
      }
      if (clamp_edges && s >= n - 1) {
        f = 0.0f;
        s = n - 1;
      }
      const std::size_t i = static_cast<std::size_t>(d);
      first[i] = s;
      second[i] = std::min(s + 1, n - 1);
      w0[i] = cv::saturate_cast<std::int16_t>((1.0f - f) * 2048.0f);
      w1[i] = cv::saturate_cast<std::int16_t>(f * 2048.0f);
      pairs[2 * i] = w0[i];
      pairs[2 * i + 1] = w1[i];
    }
    if (clamp_edges) {
      set_windows();
    } else {
      window.clear();
      spread.clear();
    }
  }

  /// window and spread for the current tables.
  void set_windows() {
    window.assign(static_cast<std::size_t>(m / kBlock), -1);
    spread.resize(window.size());
    for (std::size_t b = 0; b < window.size(); ++b) {
      const std::size_t d0 = b * kBlock;
      const int base = *std::min_element(first.begin() + static_cast<std::ptrdiff_t>(d0),
                                         first.begin() + static_cast<std::ptrdiff_t>(d0 + kBlock));
      const int top = *std::max_element(second.begin() + static_cast<std::ptrdiff_t>(d0),
                                        second.begin() + static_cast<std::ptrdiff_t>(d0 + kBlock));
      if (base + 16 > n || top - base >= 16) continue;
      window[b] = base;
      for (std::size_t k = 0; k < kBlock; ++k) {  // byte 4k of index k's lane pair: its first source
        spread[b][4 * k] = static_cast<std::uint8_t>(first[d0 + k] - base);
        spread[b][4 * k + 1] = 0x80;  // zero: the high byte of a 16-bit lane
        spread[b][4 * k + 2] = static_cast<std::uint8_t>(second[d0 + k] - base);
        spread[b][4 * k + 3] = 0x80;
      }
    }
  }
};

/// Buffers of resize_linear_8u(), reused across calls.
struct OpenCvResizeWork {
  CvResizeAxis x;
  CvResizeAxis y;
  std::vector<int> rows[2];  ///< two source rows resized along x
  int cached[2] = {-1, -1};  ///< which source row each holds
};

/// Destination indices [d0, d1) of source row `row` resized along x into `out`: the reference.
inline void resize_row_x_scalar(const std::uint8_t* row, const CvResizeAxis& x, int d0, int d1, int* out) {
  for (int d = d0; d < d1; ++d) {
    const std::size_t i = static_cast<std::size_t>(d);
    out[d] = row[x.first[i]] * x.w0[i] + row[x.second[i]] * x.w1[i];
  }
}

/// resize_row_x_scalar() from 0, four indices at a time with SSE2 where the target has it: each
/// pair of source bytes as two 16-bit lanes, times its two weights (x.pairs) by one multiply-add.
inline void resize_row_x_sse2(const std::uint8_t* row, const CvResizeAxis& x, int* out) {
  const int m = static_cast<int>(x.first.size());
  int d = 0;
#if defined(__SSE2__)
  const int* first = x.first.data();
  const int* second = x.second.data();
  const std::int16_t* pairs = x.pairs.data();
  for (; d + 4 <= m; d += 4) {
    const auto pair = [&](int k) {
      return static_cast<int>(row[first[d + k]]) | (static_cast<int>(row[second[d + k]]) << 16);
    };
    const __m128i pixels = _mm_set_epi32(pair(3), pair(2), pair(1), pair(0));
    const __m128i weights = _mm_loadu_si128(reinterpret_cast<const __m128i*>(pairs + 2 * d));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + d), _mm_madd_epi16(pixels, weights));
  }
#endif
  resize_row_x_scalar(row, x, d, m, out);
}

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// resize_row_x_scalar() from 0, eight indices at a time with AVX2 where a block has a window
/// (CvResizeAxis::window): its 16 source bytes in both halves, spread by one vpshufb into the
/// 16-bit lanes of the eight pairs, times the weights by one multiply-add; the other indices by the
/// reference (compiled outside this region, so its only copy runs on any CPU).
inline void resize_row_x_avx2(const std::uint8_t* row, const CvResizeAxis& x, int* out) {
  constexpr int kBlock = static_cast<int>(CvResizeAxis::kBlock);
  const std::size_t blocks = x.window.size();
  for (std::size_t b = 0; b < blocks; ++b) {
    const int d0 = static_cast<int>(b) * kBlock;
    if (x.window[b] < 0) {
      resize_row_x_scalar(row, x, d0, d0 + kBlock, out);
      continue;
    }
    const __m256i bytes =
        _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x.window[b])));
    const __m256i lanes =
        _mm256_shuffle_epi8(bytes, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x.spread[b].data())));
    const __m256i weights = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x.pairs.data() + 2 * d0));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + d0), _mm256_madd_epi16(lanes, weights));
  }
  resize_row_x_scalar(row, x, static_cast<int>(blocks) * kBlock, static_cast<int>(x.first.size()), out);
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// Source row `r` resized along x into `out`, with the widest kernel the CPU runs.
inline void resize_row_x(const cv::Mat& src, int r, const CvResizeAxis& x, std::vector<int>& out) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    resize_row_x_avx2(src.ptr<std::uint8_t>(r), x, out.data());
    return;
  }
#endif
  resize_row_x_sse2(src.ptr<std::uint8_t>(r), x, out.data());
}

/// Pixels [x0, width) of the destination row from the two source rows resized along x, h0 and h1,
/// with weights b0 and b1: (((h0 >> 4)·b0 >> 16) + ((h1 >> 4)·b1 >> 16) + 2) >> 2 each. The
/// reference of blend_resized_rows().
inline void blend_resized_rows_scalar(const int* h0, const int* h1, int b0, int b1, int x0, int width,
                                      std::uint8_t* out) {
  for (int x = x0; x < width; ++x) {
    out[x] = static_cast<std::uint8_t>((((h0[x] >> 4) * b0 >> 16) + ((h1[x] >> 4) * b1 >> 16) + 2) >> 2);
  }
}

/// blend_resized_rows_scalar() from 0, 8 pixels at a time with SSE2 (16-bit high multiplies, as
/// the formula's precision is) where the target has it.
inline void blend_resized_rows_sse2(const int* h0, const int* h1, int b0, int b1, int width, std::uint8_t* out) {
  int x = 0;
#if defined(__SSE2__)
  const __m128i v0 = _mm_set1_epi16(static_cast<short>(b0));
  const __m128i v1 = _mm_set1_epi16(static_cast<short>(b1));
  const __m128i two = _mm_set1_epi16(2);
  for (; x + 8 <= width; x += 8) {
    const __m128i a = _mm_packs_epi32(_mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h0 + x)), 4),
                                      _mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h0 + x + 4)), 4));
    const __m128i b = _mm_packs_epi32(_mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h1 + x)), 4),
                                      _mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h1 + x + 4)), 4));
    const __m128i sum = _mm_add_epi16(_mm_add_epi16(_mm_mulhi_epi16(a, v0), _mm_mulhi_epi16(b, v1)), two);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(_mm_srai_epi16(sum, 2), sum));
  }
#endif
  blend_resized_rows_scalar(h0, h1, b0, b1, x, width, out);
}

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// Sixteen values h[0..15] >> 4 as 16-bit lanes, in the quarter order of an in-lane pack: 0–3,
/// 8–11, 4–7, 12–15.
inline __m256i shifted_halves_avx2(const int* h) {
  return _mm256_packs_epi32(_mm256_srai_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(h)), 4),
                            _mm256_srai_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(h + 8)), 4));
}

/// blend_resized_rows_scalar() from 0, 16 pixels at a time with AVX2: the SSE2 kernel's arithmetic
/// on twice the lanes, the 64-bit quarters put back in pixel order after the in-lane packs; the
/// rest by the reference (compiled outside this region).
inline void blend_resized_rows_avx2(const int* h0, const int* h1, int b0, int b1, int width, std::uint8_t* out) {
  const __m256i v0 = _mm256_set1_epi16(static_cast<short>(b0));
  const __m256i v1 = _mm256_set1_epi16(static_cast<short>(b1));
  const __m256i two = _mm256_set1_epi16(2);
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const __m256i sum = _mm256_add_epi16(_mm256_add_epi16(_mm256_mulhi_epi16(shifted_halves_avx2(h0 + x), v0),
                                                          _mm256_mulhi_epi16(shifted_halves_avx2(h1 + x), v1)),
                                         two);
    const __m256i ordered = _mm256_permute4x64_epi64(_mm256_srai_epi16(sum, 2), 0xD8);  // pixels 0-7 | 8-15
    const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(ordered, ordered), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(bytes));
  }
  blend_resized_rows_scalar(h0, h1, b0, b1, x, width, out);
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// blend_resized_rows_scalar() from 0 with the widest kernel the CPU runs.
inline void blend_resized_rows(const int* h0, const int* h1, int b0, int b1, int width, std::uint8_t* out) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    blend_resized_rows_avx2(h0, h1, b0, b1, width, out);
    return;
  }
#endif
  blend_resized_rows_sse2(h0, h1, b0, b1, width, out);
}

/// The buffer holding source row `r` resized along x, computed unless one holds it already;
/// `keep` (0 or 1) is the buffer the caller still needs.
inline const std::vector<int>& resized_row(const cv::Mat& src, int r, int keep, OpenCvResizeWork& w) {
  for (int b = 0; b < 2; ++b) {
    if (w.cached[b] == r) return w.rows[b];
  }
  const int b = keep < 0 ? 0 : 1 - keep;
  resize_row_x(src, r, w.x, w.rows[b]);
  w.cached[b] = r;
  return w.rows[b];
}

/// cv::resize(src, dst, dst.size(), 0, 0, INTER_LINEAR) for CV_8UC1 `src` into the CV_8UC1 `dst`
/// (its size the destination's, its buffer written in place), the same bytes (file comment).
inline void resize_linear_8u(const cv::Mat& src, cv::Mat& dst, OpenCvResizeWork& w) {
  if (dst.size() == src.size() || (src.cols == 2 * dst.cols && src.rows == 2 * dst.rows)) {
    cv::resize(src, dst, dst.size(), 0.0, 0.0, cv::INTER_LINEAR);
    return;
  }
  w.x.set(src.cols, dst.cols, true);
  w.y.set(src.rows, dst.rows, false);
  for (std::vector<int>& row : w.rows) row.resize(static_cast<std::size_t>(dst.cols));
  w.cached[0] = w.cached[1] = -1;
  const int last = src.rows - 1;
  for (int d = 0; d < dst.rows; ++d) {
    const std::size_t di = static_cast<std::size_t>(d);
    const int r0 = std::clamp(w.y.first[di], 0, last);
    const int r1 = std::clamp(w.y.first[di] + 1, 0, last);
    const std::vector<int>& h0 = resized_row(src, r0, -1, w);
    const int keep = &h0 == &w.rows[0] ? 0 : 1;
    const std::vector<int>& h1 = resized_row(src, r1, keep, w);
    blend_resized_rows(h0.data(), h1.data(), w.y.w0[di], w.y.w1[di], dst.cols, dst.ptr<std::uint8_t>(d));
  }
}

}  // namespace detail
}  // namespace affine_orb
