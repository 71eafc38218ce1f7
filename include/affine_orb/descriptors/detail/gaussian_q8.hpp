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

#include "affine_orb/core/detail/simd.hpp"

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

/// Rows [y0, y1) whose pixels to smooth are the column runs [x0, x1) of RunBands::runs[begin, end).
struct RunBand {
  int y0 = 0;
  int y1 = 0;
  int begin = 0;
  int end = 0;
};

/// Column runs of the union of squares, band by band: disjoint bands by y, in each band disjoint
/// runs by x.
struct RunBands {
  std::vector<RunBand> bands;
  std::vector<cv::Vec2i> runs;  ///< [x0, x1)
};

/// Buffers of the smoothing functions below, reused across calls (a caller-owned workspace).
struct GaussianQ8Work {
  std::vector<cv::Rect> squares;     ///< the squares of smooth_squares_q8(), clipped to the level
  RunBands out;                      ///< the pixels to smooth
  std::vector<cv::Vec2i> active;     ///< intervals of the squares crossing the current band, by x0
  std::vector<int> order;            ///< square indices by first row, then by end row
  std::vector<std::int16_t> column;  ///< the y pass of one run with r columns each side, and one more
};

// The smoothing of the file comment is computed y pass first (the sums are the same integers in
// either order): v(x) = Σ_j k_j·I(x, y + j − r) < 2^16, kept as v − 2^15 in int16 so that the x
// pass can use signed 16-bit multiply-adds, then out(x) = (Σ_i k_i·v(x + i − r) + 2^15) >> 16
// = (Σ_i k_i·(v − 2^15)(x + i − r) + 2^23 + 2^15) >> 16 since the kernel sums to 256.

/// The y pass of one run: v(x) − 2^15 for x in [0, width), from rows[j][x0 + x] (rows[j]: source
/// row y + j − r): the scalar reference.
template <int kTaps>
inline void gaussian_q8_v_scalar(const std::uint8_t* const* rows, int x0, int width, const std::uint16_t* k,
                                 int n_runtime, std::int16_t* v) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  for (int x = 0; x < width; ++x) {
    std::int32_t sum = 0;
    for (int j = 0; j < n; ++j) sum += k[j] * rows[j][x0 + x];
    v[x] = static_cast<std::int16_t>(sum - 32768);
  }
}

/// The x pass of one run: out(x) for x in [0, width) from v[x .. x + n − 1] (v − 2^15 of
/// gaussian_q8_v_scalar(), starting r columns left of the run): the scalar reference.
template <int kTaps>
inline void gaussian_q8_h_scalar(const std::int16_t* v, int width, const std::uint16_t* k, int n_runtime,
                                 std::uint8_t* out) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  for (int x = 0; x < width; ++x) {
    std::int32_t sum = (1 << 23) + (1 << 15);
    for (int i = 0; i < n; ++i) sum += k[i] * v[x + i];
    out[x] = static_cast<std::uint8_t>(sum >> 16);
  }
}

#if AFFINE_ORB_SIMD128
/// The lane operations of gaussian_q8_v_128(): eight 16-bit lanes of SSE2 or NEON, whose products
/// and sums wrap modulo 2^16 alike.
struct Q8Lanes {
#if AFFINE_ORB_NEON
  using V = uint16x8_t;
  /// The eight bytes at p, zero-extended.
  static V load8(const std::uint8_t* p) { return vmovl_u8(vld1_u8(p)); }
  static V broadcast(std::uint16_t k) { return vdupq_n_u16(k); }
  static V add(V a, V b) { return vaddq_u16(a, b); }
  static V multiply(V a, V b) { return vmulq_u16(a, b); }
  /// Stores sum − 2^15 (the top bit flipped) as eight int16.
  static void store_offset(std::int16_t* v, V sum) {
    vst1q_s16(v, vreinterpretq_s16_u16(veorq_u16(sum, vdupq_n_u16(0x8000))));
  }
#else
  using V = __m128i;
  static V load8(const std::uint8_t* p) {
    return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128());
  }
  static V broadcast(std::uint16_t k) { return _mm_set1_epi16(static_cast<short>(k)); }
  static V add(V a, V b) { return _mm_add_epi16(a, b); }
  static V multiply(V a, V b) { return _mm_mullo_epi16(a, b); }
  static void store_offset(std::int16_t* v, V sum) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(v), _mm_xor_si128(sum, _mm_set1_epi16(static_cast<short>(0x8000))));
  }
#endif
};

/// gaussian_q8_v_scalar() eight columns at a time (the last eight overlapping), identical values,
/// on SSE2 or NEON (Q8Lanes). The kernel is symmetric, so rows j and n − 1 − j are added before
/// multiplying; 16-bit products and sums wrap, and the total is below 2^16, so it is exact.
template <int kTaps>
inline void gaussian_q8_v_128(const std::uint8_t* const* rows, int x0, int width, const std::uint16_t* k, int n_runtime,
                              std::int16_t* v) {
  using L = Q8Lanes;
  const int n = kTaps > 0 ? kTaps : n_runtime;
  if (width < 8) {
    gaussian_q8_v_scalar<kTaps>(rows, x0, width, k, n, v);
    return;
  }
  const int half = n / 2;
  L::V weight[16];
  for (int j = 0; j <= half; ++j) weight[j] = L::broadcast(k[j]);
  for (int x = 0;; x = std::min(x + 8, width - 8)) {
    auto at = [&](int j) { return L::load8(rows[j] + x0 + x); };
    L::V sum = L::multiply(at(half), weight[half]);
    for (int j = 0; j < half; ++j) sum = L::add(sum, L::multiply(L::add(at(j), at(n - 1 - j)), weight[j]));
    L::store_offset(v + x, sum);
    if (x + 8 >= width) break;
  }
}
#endif

#if defined(__SSE2__)
/// gaussian_q8_h_scalar() eight columns at a time (the last eight overlapping), identical bytes,
/// with 32-bit multiply-adds of column pairs: for the even columns 2m, Σ_p k_2p·v(2m + 2p) +
/// k_2p+1·v(2m + 2p + 1) from the vectors loaded at 2p; for the odd ones from those loaded at 2p + 1
/// (k_n = 0, so v must have one readable element past v[width + n − 2]).
template <int kTaps>
inline void gaussian_q8_h_sse2(const std::int16_t* v, int width, const std::uint16_t* k, int n_runtime,
                               std::uint8_t* out) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  if (width < 8) {
    gaussian_q8_h_scalar<kTaps>(v, width, k, n, out);
    return;
  }
  const int pairs = (n + 1) / 2;
  __m128i weight[16];
  for (int p = 0; p < pairs; ++p) {
    const int high = 2 * p + 1 < n ? k[2 * p + 1] : 0;
    weight[p] = _mm_set1_epi32(static_cast<int>(k[2 * p] | (high << 16)));
  }
  const __m128i bias = _mm_set1_epi32((1 << 23) + (1 << 15));
  const __m128i odd_mask = _mm_set1_epi32(static_cast<int>(0xFFFF0000u));
  for (int x = 0;; x = std::min(x + 8, width - 8)) {
    auto at = [&](int i) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(v + x + i)); };
    __m128i even = bias;
    __m128i odd = bias;
    for (int p = 0; p < pairs; ++p) {
      even = _mm_add_epi32(even, _mm_madd_epi16(at(2 * p), weight[p]));
      odd = _mm_add_epi32(odd, _mm_madd_epi16(at(2 * p + 1), weight[p]));
    }
    // out(2m) in the low half of lane m, out(2m + 1) in the high half: the columns in order.
    const __m128i value = _mm_or_si128(_mm_srli_epi32(even, 16), _mm_and_si128(odd, odd_mask));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(value, value));
    if (x + 8 >= width) break;
  }
}
#endif

#if AFFINE_ORB_NEON
/// gaussian_q8_h_scalar() eight columns at a time on NEON (the last eight overlapping), identical
/// bytes: each column's 32-bit sum by widening multiply-accumulates, shifted and narrowed (the sums
/// lie in [0, 2^24), so out(x) is in [0, 255]). Reads v up to v[width + n − 2].
template <int kTaps>
inline void gaussian_q8_h_neon(const std::int16_t* v, int width, const std::uint16_t* k, int n_runtime,
                               std::uint8_t* out) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  if (width < 8) {
    gaussian_q8_h_scalar<kTaps>(v, width, k, n, out);
    return;
  }
  const int32x4_t bias = vdupq_n_s32((1 << 23) + (1 << 15));
  for (int x = 0;; x = std::min(x + 8, width - 8)) {
    int32x4_t low = bias;
    int32x4_t high = bias;
    for (int i = 0; i < n; ++i) {
      const int16x8_t column = vld1q_s16(v + x + i);
      const int16x8_t weight = vdupq_n_s16(static_cast<std::int16_t>(k[i]));
      low = vmlal_s16(low, vget_low_s16(column), vget_low_s16(weight));
      high = vmlal_high_s16(high, column, weight);
    }
    vst1_u8(out + x, vqmovun_s16(vcombine_s16(vshrn_n_s32(low, 16), vshrn_n_s32(high, 16))));
    if (x + 8 >= width) break;
  }
}
#endif

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// gaussian_q8_v_128() sixteen columns at a time, identical values.
template <int kTaps>
inline void gaussian_q8_v_avx2(const std::uint8_t* const* rows, int x0, int width, const std::uint16_t* k,
                               int n_runtime, std::int16_t* v) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  if (width < 16) {
    gaussian_q8_v_128<kTaps>(rows, x0, width, k, n, v);
    return;
  }
  const int half = n / 2;
  const __m256i offset = _mm256_set1_epi16(static_cast<short>(0x8000));
  __m256i weight[16];
  for (int j = 0; j <= half; ++j) weight[j] = _mm256_set1_epi16(static_cast<short>(k[j]));
  for (int x = 0;; x = std::min(x + 16, width - 16)) {
    auto at = [&](int j) {
      return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(rows[j] + x0 + x)));
    };
    __m256i sum = _mm256_mullo_epi16(at(half), weight[half]);
    for (int j = 0; j < half; ++j) {
      sum = _mm256_add_epi16(sum, _mm256_mullo_epi16(_mm256_add_epi16(at(j), at(n - 1 - j)), weight[j]));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(v + x), _mm256_xor_si256(sum, offset));
    if (x + 16 >= width) break;
  }
}

/// gaussian_q8_h_sse2() sixteen columns at a time, identical bytes (one permutation puts the two
/// 128-bit halves' bytes together).
template <int kTaps>
inline void gaussian_q8_h_avx2(const std::int16_t* v, int width, const std::uint16_t* k, int n_runtime,
                               std::uint8_t* out) {
  const int n = kTaps > 0 ? kTaps : n_runtime;
  if (width < 16) {
    gaussian_q8_h_sse2<kTaps>(v, width, k, n, out);
    return;
  }
  const int pairs = (n + 1) / 2;
  __m256i weight[16];
  for (int p = 0; p < pairs; ++p) {
    const int high = 2 * p + 1 < n ? k[2 * p + 1] : 0;
    weight[p] = _mm256_set1_epi32(static_cast<int>(k[2 * p] | (high << 16)));
  }
  const __m256i bias = _mm256_set1_epi32((1 << 23) + (1 << 15));
  const __m256i odd_mask = _mm256_set1_epi32(static_cast<int>(0xFFFF0000u));
  for (int x = 0;; x = std::min(x + 16, width - 16)) {
    auto at = [&](int i) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(v + x + i)); };
    __m256i even = bias;
    __m256i odd = bias;
    for (int p = 0; p < pairs; ++p) {
      even = _mm256_add_epi32(even, _mm256_madd_epi16(at(2 * p), weight[p]));
      odd = _mm256_add_epi32(odd, _mm256_madd_epi16(at(2 * p + 1), weight[p]));
    }
    const __m256i value = _mm256_or_si256(_mm256_srli_epi32(even, 16), _mm256_and_si256(odd, odd_mask));
    const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(value, value), _MM_SHUFFLE(3, 1, 2, 0));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(bytes));
    if (x + 16 >= width) break;
  }
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// The y pass of the widest vector path the CPU has (AVX2, SSE2, NEON, else the scalar reference).
template <int kTaps>
inline void gaussian_q8_v(const std::uint8_t* const* rows, int x0, int width, const std::uint16_t* k, int n,
                          std::int16_t* v) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    gaussian_q8_v_avx2<kTaps>(rows, x0, width, k, n, v);
    return;
  }
#endif
#if AFFINE_ORB_SIMD128
  gaussian_q8_v_128<kTaps>(rows, x0, width, k, n, v);
#else
  gaussian_q8_v_scalar<kTaps>(rows, x0, width, k, n, v);
#endif
}

/// The x pass of the widest vector path the CPU has (AVX2, SSE2, NEON, else the scalar reference).
template <int kTaps>
inline void gaussian_q8_h(const std::int16_t* v, int width, const std::uint16_t* k, int n, std::uint8_t* out) {
#if defined(__SSE2__)
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    gaussian_q8_h_avx2<kTaps>(v, width, k, n, out);
    return;
  }
#endif
  gaussian_q8_h_sse2<kTaps>(v, width, k, n, out);
#elif AFFINE_ORB_NEON
  gaussian_q8_h_neon<kTaps>(v, width, k, n, out);
#else
  gaussian_q8_h_scalar<kTaps>(v, width, k, n, out);
#endif
}

/// Runs of the union of `squares`, with gaps narrower than `gap` columns filled (fewer, longer runs; a superset of
/// squares gives a superset of runs). Returns the number of pixels of the runs. The squares are swept top to bottom;
/// the band ends where a square enters or leaves.
inline std::int64_t union_run_bands(const std::vector<cv::Rect>& squares, int gap, GaussianQ8Work& work,
                                    RunBands& result) {
  result.bands.clear();
  result.runs.clear();
  const int count = static_cast<int>(squares.size());
  std::vector<int>& order = work.order;
  order.resize(2 * static_cast<std::size_t>(count));
  int* enter = order.data();
  int* leave = order.data() + count;
  for (int i = 0; i < count; ++i) enter[i] = leave[i] = i;
  std::sort(enter, enter + count, [&](int a, int b) { return squares[a].y < squares[b].y; });
  std::sort(leave, leave + count, [&](int a, int b) { return squares[a].br().y < squares[b].br().y; });
  std::vector<cv::Vec2i>& active = work.active;
  active.clear();
  std::int64_t area = 0;
  int next_enter = 0;
  int next_leave = 0;
  while (next_leave < count) {
    // The next event row: a square entering or leaving.
    int y = squares[leave[next_leave]].br().y;
    if (next_enter < count) y = std::min(y, squares[enter[next_enter]].y);
    for (; next_leave < count && squares[leave[next_leave]].br().y <= y; ++next_leave) {
      const cv::Rect& s = squares[leave[next_leave]];
      active.erase(std::find(active.begin(), active.end(), cv::Vec2i(s.x, s.br().x)));
    }
    for (; next_enter < count && squares[enter[next_enter]].y <= y; ++next_enter) {
      const cv::Rect& s = squares[enter[next_enter]];
      const cv::Vec2i interval(s.x, s.br().x);
      active.insert(std::upper_bound(active.begin(), active.end(), interval,
                                     [](const cv::Vec2i& a, const cv::Vec2i& b) { return a[0] < b[0]; }),
                    interval);
    }
    if (active.empty()) continue;
    int end = squares[leave[next_leave]].br().y;
    if (next_enter < count) end = std::min(end, squares[enter[next_enter]].y);
    RunBand band{y, end, static_cast<int>(result.runs.size()), 0};
    std::int64_t width = 0;
    for (const cv::Vec2i& interval : active) {
      if (static_cast<int>(result.runs.size()) > band.begin && interval[0] < result.runs.back()[1] + gap) {
        result.runs.back()[1] = std::max(result.runs.back()[1], interval[1]);
      } else {
        result.runs.push_back(interval);
      }
    }
    band.end = static_cast<int>(result.runs.size());
    for (int i = band.begin; i < band.end; ++i) width += result.runs[i][1] - result.runs[i][0];
    area += width * (band.y1 - band.y0);
    result.bands.push_back(band);
  }
  return area;
}

/// Writes the smoothing (file comment) of the runs of work.out into the same pixels of `out` (of
/// the level's size). Run by run: the y pass of the run and r columns each side goes into a small
/// buffer (in the L1 cache), read by the x pass. Source rows above and below the level are the
/// reflected rows, and the y pass of columns outside the level that of the reflected columns
/// (BORDER_REFLECT_101), copied within the buffer.
template <int kTaps>
inline void smooth_runs_q8(const cv::Mat& level, const std::vector<std::uint16_t>& kernel, GaussianQ8Work& work,
                           cv::Mat& out) {
  const int n = kTaps > 0 ? kTaps : static_cast<int>(kernel.size());
  const int r = n / 2;
  const int cols = level.cols;
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(level.step[0]);
  const std::uint16_t* k = kernel.data();
  int widest = 0;
  for (const cv::Vec2i& run : work.out.runs) widest = std::max(widest, run[1] - run[0]);
  work.column.resize(static_cast<std::size_t>(widest + 2 * r + 1));
  std::int16_t* column = work.column.data();
  const std::uint8_t* rows[32];
  for (const RunBand& band : work.out.bands) {
    for (int y = band.y0; y < band.y1; ++y) {
      if (y >= r && y + r < level.rows) {
        for (int j = 0; j < n; ++j) rows[j] = level.ptr<std::uint8_t>(y - r) + j * step;
      } else {
        for (int j = 0; j < n; ++j) rows[j] = level.ptr<std::uint8_t>(reflect101(y + j - r, level.rows));
      }
      std::uint8_t* o = out.ptr<std::uint8_t>(y);
      for (int i = band.begin; i < band.end; ++i) {
        const int x0 = work.out.runs[static_cast<std::size_t>(i)][0];
        const int x1 = work.out.runs[static_cast<std::size_t>(i)][1];
        // column[c] holds level column x0 − r + c; [lo, hi) is inside the level.
        const int lo = std::max(x0 - r, 0);
        const int hi = std::min(x1 + r, cols);
        gaussian_q8_v<kTaps>(rows, lo, hi - lo, k, n, column + (lo - x0 + r));
        for (int c = x0 - r; c < lo; ++c) column[c - x0 + r] = column[reflect101(c, cols) - x0 + r];
        for (int c = hi; c < x1 + r; ++c) column[c - x0 + r] = column[reflect101(c, cols) - x0 + r];
        gaussian_q8_h<kTaps>(column, x1 - x0, k, n, o + x0);
      }
    }
  }
}

/// Fills work.out with the runs of the union of work.squares (inside the level) for
/// smooth_runs_q8(), runs closer than 8 columns joined; returns their area in pixels.
inline std::int64_t union_runs_q8(GaussianQ8Work& work) {
  constexpr int kGap = 8;
  return union_run_bands(work.squares, kGap, work, work.out);
}

/// smooth_runs_q8() for a kernel of any size (at most 31 taps), unrolled for 7 taps.
inline void smooth_runs_q8(const cv::Mat& level, const std::vector<std::uint16_t>& kernel, GaussianQ8Work& work,
                           cv::Mat& out) {
  if (kernel.size() == 7) {
    smooth_runs_q8<7>(level, kernel, work, out);
  } else {
    smooth_runs_q8<0>(level, kernel, work, out);
  }
}

/// Writes the smoothing (file comment) of the pixels of the union of `squares` (inside `level`)
/// into the same pixels of `out` (of the level's size), each pixel once. The kernel has at most
/// 31 taps and sums to 256 (gaussian_kernel_q8()).
inline void smooth_squares_q8(const cv::Mat& level, const std::vector<cv::Rect>& squares,
                              const std::vector<std::uint16_t>& kernel, GaussianQ8Work& work, cv::Mat& out) {
  work.squares = squares;
  union_runs_q8(work);
  smooth_runs_q8(level, kernel, work, out);
}

/// smooth_squares_q8() of one square (work.squares reused: no allocation once it has grown).
inline void smooth_square_q8(const cv::Mat& level, cv::Rect square, const std::vector<std::uint16_t>& kernel,
                             GaussianQ8Work& work, cv::Mat& out) {
  work.squares.assign(1, square);
  union_runs_q8(work);
  smooth_runs_q8(level, kernel, work, out);
}

}  // namespace affine_orb::detail
