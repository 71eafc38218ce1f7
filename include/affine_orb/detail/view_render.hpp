#pragma once
/// \file
/// The arithmetic of render_view() (affine_views.hpp): a view is rendered row by row, each row from
/// one row of the rotated canvas, blurred and subsampled along x in a single pass.
///
/// Canvas row y, column c (integers) samples the original image at
///   X = x_row(y) + c·x_step,  Y = y_row(y) + c·y_step   (fixed point, 16 fractional bits)
/// where x_row(y) = round(2^16·(m01·y + m02)), x_step = round(2^16·m00) (likewise for Y) from the
/// canvas-to-original map m; this is within (1 + c)·2^-17 px of the exact position. X and Y are
/// clamped to the image (the border replicated), then interpolated bilinearly with the fractions
/// rounded to 1/128 px:
///   f = ((X mod 2^16) + 2^8) >> 9 in [0, 128],
///   v = (Σ w_ab · I(x0 + a, y0 + b) + 2^13) >> 14,  w_ab = (a ? f_x : 128 − f_x)(b ? f_y : 128 − f_y).
/// View column x of that row is Σ_j w_j(x) · C(first(x) + j) with the canvas columns clamped to the
/// canvas (border replicated) and weights in units of 2^-14 that sum to 2^14: the Gaussian of σ
/// (radius max(1, ⌈3σ⌉), none for σ = 0) followed by the bilinear resampling from the canvas width
/// to the view width (pixel centres: x_c = (x + 0.5)·W_c/W_v − 0.5).
///
/// Each stage has a scalar reference and an SSE2 path (where the target has SSE2) that gives the
/// same bytes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace affine_orb::detail {

/// Bilinear fractions are multiples of 2^-kFractionBits pixel.
inline constexpr int kFractionBits = 7;
/// Resampling weights are multiples of 2^-kWeightBits.
inline constexpr int kWeightBits = 14;

/// Where the canvas rows sample the original image (see the file comment).
struct CanvasSampler {
  double m[6] = {1, 0, 0, 0, 1, 0};  ///< canvas -> original, row-major 2x3
  std::int32_t x_step = 0;
  std::int32_t y_step = 0;
  std::int32_t x_max = 0;  ///< largest X: just below the last column, so that x0 + 1 stays inside
  std::int32_t y_max = 0;
  int width = 0;
  int height = 0;

  /// For an image of `size` (at least 2x2) and the canvas-to-original map `to_original`.
  CanvasSampler(const cv::Matx23d& to_original, cv::Size size) : width(size.width), height(size.height) {
    for (int i = 0; i < 6; ++i) m[i] = to_original.val[i];
    x_step = static_cast<std::int32_t>(std::llround(65536.0 * m[0]));
    y_step = static_cast<std::int32_t>(std::llround(65536.0 * m[3]));
    x_max = (width - 1) * 65536 - 1;
    y_max = (height - 1) * 65536 - 1;
  }

  std::int32_t x_row(int y) const { return static_cast<std::int32_t>(std::llround(65536.0 * (m[1] * y + m[2]))); }
  std::int32_t y_row(int y) const { return static_cast<std::int32_t>(std::llround(65536.0 * (m[4] * y + m[5]))); }
};

/// Canvas row y, columns [c0, c1), into out[0, c1 − c0): the scalar reference.
inline void sample_canvas_row_scalar(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                     std::uint8_t* out) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const std::uint8_t* base = image.ptr<std::uint8_t>(0);
  const std::int32_t x_row = s.x_row(y);
  const std::int32_t y_row = s.y_row(y);
  constexpr int one = 1 << kFractionBits;
  for (int c = c0; c < c1; ++c) {
    const std::int32_t x = std::clamp(x_row + c * s.x_step, 0, s.x_max);
    const std::int32_t yy = std::clamp(y_row + c * s.y_step, 0, s.y_max);
    const int fx = ((x & 0xFFFF) + (1 << (15 - kFractionBits))) >> (16 - kFractionBits);
    const int fy = ((yy & 0xFFFF) + (1 << (15 - kFractionBits))) >> (16 - kFractionBits);
    const std::uint8_t* p = base + static_cast<std::ptrdiff_t>(yy >> 16) * step + (x >> 16);
    const int sum = p[0] * ((one - fx) * (one - fy)) + p[1] * (fx * (one - fy)) + p[step] * ((one - fx) * fy) +
                    p[step + 1] * (fx * fy);
    out[c - c0] = static_cast<std::uint8_t>((sum + (1 << 13)) >> 14);
  }
}

/// The columns c in [c0, c1) with 0 <= base + c·step <= max, as [first, last) (possibly empty).
inline std::pair<int, int> columns_within(std::int64_t base, std::int64_t step, std::int64_t max, int c0, int c1) {
  if (step == 0) return base >= 0 && base <= max ? std::make_pair(c0, c1) : std::make_pair(c0, c0);
  // Smallest c with base + c·step >= 0 (step > 0) or <= max (step < 0), and the largest with the other.
  auto ceil_div = [](std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return q + ((a % b != 0) && ((a < 0) == (b < 0)) ? 1 : 0);
  };
  auto floor_div = [](std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return q - ((a % b != 0) && ((a < 0) != (b < 0)) ? 1 : 0);
  };
  std::int64_t lo = 0;
  std::int64_t hi = 0;
  if (step > 0) {
    lo = ceil_div(-base, step);
    hi = floor_div(max - base, step);
  } else {
    lo = ceil_div(max - base, step);
    hi = floor_div(-base, step);
  }
  const std::int64_t first = std::max<std::int64_t>(lo, c0);
  const std::int64_t last = std::min<std::int64_t>(hi + 1, c1);
  if (first >= last) return {c0, c0};
  return {static_cast<int>(first), static_cast<int>(last)};
}

#if defined(__SSE2__)
/// sample_canvas_row_sse2() on columns [c0, c1), four at a time; kClamp = false where the
/// positions are known to lie inside the clamping range.
template <bool kClamp>
inline void sample_canvas_columns_sse2(const std::uint8_t* base, std::ptrdiff_t step, const CanvasSampler& s,
                                       std::int32_t x_row, std::int32_t y_row, int c0, int c1, std::uint8_t* out) {
  const __m128i x_step4 = _mm_set1_epi32(4 * s.x_step);
  const __m128i y_step4 = _mm_set1_epi32(4 * s.y_step);
  const __m128i x_max = _mm_set1_epi32(s.x_max);
  const __m128i y_max = _mm_set1_epi32(s.y_max);
  const __m128i low16 = _mm_set1_epi32(0xFFFF);
  const __m128i half = _mm_set1_epi32(1 << (15 - kFractionBits));
  const __m128i one = _mm_set1_epi32(1 << kFractionBits);
  const __m128i round = _mm_set1_epi32(1 << 13);
  const __m128i step16 = _mm_set1_epi32(static_cast<std::int32_t>(step));
  const __m128i zero = _mm_setzero_si128();
  auto clamp = [&](__m128i v, __m128i hi) {
    v = _mm_and_si128(v, _mm_cmpgt_epi32(v, zero));
    const __m128i above = _mm_cmpgt_epi32(v, hi);
    return _mm_or_si128(_mm_and_si128(above, hi), _mm_andnot_si128(above, v));
  };
  auto load16 = [](const std::uint8_t* p) {
    std::uint16_t v;
    std::memcpy(&v, p, sizeof(v));
    return static_cast<int>(v);
  };
  __m128i xs = _mm_setr_epi32(x_row + c0 * s.x_step, x_row + (c0 + 1) * s.x_step, x_row + (c0 + 2) * s.x_step,
                              x_row + (c0 + 3) * s.x_step);
  __m128i ys = _mm_setr_epi32(y_row + c0 * s.y_step, y_row + (c0 + 1) * s.y_step, y_row + (c0 + 2) * s.y_step,
                              y_row + (c0 + 3) * s.y_step);
  alignas(16) std::int32_t offset[4];
  for (int c = c0; c + 4 <= c1; c += 4) {
    const __m128i x = kClamp ? clamp(xs, x_max) : xs;
    const __m128i yv = kClamp ? clamp(ys, y_max) : ys;
    xs = _mm_add_epi32(xs, x_step4);
    ys = _mm_add_epi32(ys, y_step4);
    const __m128i fx = _mm_srli_epi32(_mm_add_epi32(_mm_and_si128(x, low16), half), 16 - kFractionBits);
    const __m128i fy = _mm_srli_epi32(_mm_add_epi32(_mm_and_si128(yv, low16), half), 16 - kFractionBits);
    // Row offset y0·step with one 16x16 multiply-add per lane (y0, step < 2^15, high halves zero).
    const __m128i off = _mm_add_epi32(_mm_madd_epi16(_mm_srli_epi32(yv, 16), step16), _mm_srai_epi32(x, 16));
    _mm_store_si128(reinterpret_cast<__m128i*>(offset), off);
    const std::uint8_t* p0 = base + offset[0];
    const std::uint8_t* p1 = base + offset[1];
    const std::uint8_t* p2 = base + offset[2];
    const std::uint8_t* p3 = base + offset[3];
    // Words 0-3: the pairs (p, p + 1) of the four pixels; words 4-7: the pairs one row below.
    __m128i pairs = _mm_cvtsi32_si128(load16(p0));
    pairs = _mm_insert_epi16(pairs, load16(p1), 1);
    pairs = _mm_insert_epi16(pairs, load16(p2), 2);
    pairs = _mm_insert_epi16(pairs, load16(p3), 3);
    pairs = _mm_insert_epi16(pairs, load16(p0 + step), 4);
    pairs = _mm_insert_epi16(pairs, load16(p1 + step), 5);
    pairs = _mm_insert_epi16(pairs, load16(p2 + step), 6);
    pairs = _mm_insert_epi16(pairs, load16(p3 + step), 7);
    const __m128i gx = _mm_sub_epi32(one, fx);
    const __m128i gy = _mm_sub_epi32(one, fy);
    // Products of values <= 128 fit the low 16-bit half of each lane.
    const __m128i w_top = _mm_or_si128(_mm_mullo_epi16(gx, gy), _mm_slli_epi32(_mm_mullo_epi16(fx, gy), 16));
    const __m128i w_bottom = _mm_or_si128(_mm_mullo_epi16(gx, fy), _mm_slli_epi32(_mm_mullo_epi16(fx, fy), 16));
    const __m128i sum = _mm_add_epi32(_mm_add_epi32(_mm_madd_epi16(_mm_unpacklo_epi8(pairs, zero), w_top),
                                                    _mm_madd_epi16(_mm_unpackhi_epi8(pairs, zero), w_bottom)),
                                      round);
    const __m128i v = _mm_srai_epi32(sum, 14);
    const std::int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(v, v), zero));
    std::memcpy(out + (c - c0), &bytes, sizeof(bytes));
  }
}

/// sample_canvas_row_scalar() four pixels at a time, identical bytes: the columns whose positions
/// need no clamping take a path without it.
inline void sample_canvas_row_sse2(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const std::uint8_t* base = image.ptr<std::uint8_t>(0);
  const std::int32_t x_row = s.x_row(y);
  const std::int32_t y_row = s.y_row(y);
  const auto [ax, bx] = columns_within(x_row, s.x_step, s.x_max, c0, c1);
  const auto [ay, by] = columns_within(y_row, s.y_step, s.y_max, c0, c1);
  int inner0 = std::max(ax, ay);
  int inner1 = std::min(bx, by);
  if (inner1 - inner0 < 8) inner0 = inner1 = c1;
  // [c0, inner0) clamped, [inner0, inner1) not, [inner1, c1) clamped; remainders of 4 scalar.
  int c = c0;
  const int head = c0 + (inner0 - c0) / 4 * 4;
  sample_canvas_columns_sse2<true>(base, step, s, x_row, y_row, c, head, out);
  sample_canvas_row_scalar(image, s, y, head, inner0, out + (head - c0));
  c = inner0;
  const int body = c + (inner1 - c) / 4 * 4;
  sample_canvas_columns_sse2<false>(base, step, s, x_row, y_row, c, body, out + (c - c0));
  c = body;
  const int tail = c + (c1 - c) / 4 * 4;
  sample_canvas_columns_sse2<true>(base, step, s, x_row, y_row, c, tail, out + (c - c0));
  sample_canvas_row_scalar(image, s, y, tail, c1, out + (tail - c0));
}
#endif

/// sample_canvas_row_sse2() where the target has SSE2, else the scalar reference.
inline void sample_canvas_row(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1, std::uint8_t* out) {
#if defined(__SSE2__)
  sample_canvas_row_sse2(image, s, y, c0, c1, out);
#else
  sample_canvas_row_scalar(image, s, y, c0, c1, out);
#endif
}

/// The x resampling of one view (see the file comment): for view column x the weights
/// weights[x·stride, x·stride + taps) apply to canvas columns first[x], first[x] + 1, ...; the
/// weights are padded with zeros to `stride`: 8 for at most 8 taps, else a multiple of 16.
struct ViewResampler {
  int taps = 0;
  int stride = 0;
  std::vector<int> first;
  std::vector<std::int16_t> weights;

  ViewResampler() = default;

  /// Anti-aliasing Gaussian of `sigma` canvas pixels, then bilinear from canvas_width to view_width.
  ViewResampler(int canvas_width, int view_width, double sigma) {
    const int radius = sigma > 0.0 ? std::max(1, static_cast<int>(std::ceil(3.0 * sigma))) : 0;
    std::vector<double> gauss(static_cast<std::size_t>(2 * radius + 1), 1.0);
    double total = 0.0;
    for (int j = -radius; j <= radius; ++j) {
      const double g = sigma > 0.0 ? std::exp(-0.5 * j * j / (sigma * sigma)) : 1.0;
      gauss[static_cast<std::size_t>(j + radius)] = g;
      total += g;
    }
    for (double& g : gauss) g /= total;
    taps = 2 * radius + 2;
    stride = taps <= 8 ? 8 : (taps + 15) / 16 * 16;
    first.resize(static_cast<std::size_t>(view_width));
    weights.assign(static_cast<std::size_t>(view_width) * static_cast<std::size_t>(stride), 0);
    const double scale = static_cast<double>(canvas_width) / view_width;
    std::vector<double> w(static_cast<std::size_t>(taps));
    for (int x = 0; x < view_width; ++x) {
      const double sx = (x + 0.5) * scale - 0.5;
      int x0 = static_cast<int>(std::floor(sx));
      double f = sx - x0;
      if (x0 < 0) {
        x0 = 0;
        f = 0.0;
      } else if (x0 >= canvas_width - 1) {
        x0 = canvas_width - 1;
        f = 0.0;
      }
      // Tap j (canvas column x0 − radius + j) weighs (1 − f)·g(j − radius) + f·g(j − radius − 1).
      for (int j = 0; j < taps; ++j) {
        const double a = j < 2 * radius + 1 ? gauss[static_cast<std::size_t>(j)] : 0.0;
        const double b = j >= 1 ? gauss[static_cast<std::size_t>(j - 1)] : 0.0;
        w[static_cast<std::size_t>(j)] = (1.0 - f) * a + f * b;
      }
      std::int16_t* q = weights.data() + static_cast<std::size_t>(x) * static_cast<std::size_t>(stride);
      int sum = 0;
      int largest = 0;
      for (int j = 0; j < taps; ++j) {
        q[j] = static_cast<std::int16_t>(std::lround(w[static_cast<std::size_t>(j)] * (1 << kWeightBits)));
        sum += q[j];
        if (q[j] > q[largest]) largest = j;
      }
      q[largest] = static_cast<std::int16_t>(q[largest] + ((1 << kWeightBits) - sum));
      first[static_cast<std::size_t>(x)] = x0 - radius;
    }
  }
};

/// View columns [x0, x1) of one row from `row`, which holds canvas columns starting at `row_first`
/// and covers first[x] .. first[x] + stride − 1 for every x in [x0, x1): the scalar reference.
inline void resample_row_scalar(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                                std::uint8_t* out) {
  for (int x = x0; x < x1; ++x) {
    const std::uint8_t* p = row + (r.first[static_cast<std::size_t>(x)] - row_first);
    const std::int16_t* w = r.weights.data() + static_cast<std::size_t>(x) * static_cast<std::size_t>(r.stride);
    int sum = 0;
    for (int j = 0; j < r.taps; ++j) sum += p[j] * w[j];
    out[x] = static_cast<std::uint8_t>((sum + (1 << (kWeightBits - 1))) >> kWeightBits);
  }
}

#if defined(__SSE2__)
/// Rounds four columns' partial dot products (s_i holds column i's four 32-bit partial sums) to
/// bytes, Q kWeightBits fixed point, and stores them at out[0..3].
inline void store_four_columns(__m128i s0, __m128i s1, __m128i s2, __m128i s3, std::uint8_t* out) {
  const __m128i t0 = _mm_add_epi32(_mm_unpacklo_epi32(s0, s1), _mm_unpackhi_epi32(s0, s1));
  const __m128i t1 = _mm_add_epi32(_mm_unpacklo_epi32(s2, s3), _mm_unpackhi_epi32(s2, s3));
  const __m128i sum = _mm_add_epi32(_mm_unpacklo_epi64(t0, t1), _mm_unpackhi_epi64(t0, t1));
  const __m128i v = _mm_srai_epi32(_mm_add_epi32(sum, _mm_set1_epi32(1 << (kWeightBits - 1))), kWeightBits);
  const std::int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(v, v), _mm_setzero_si128()));
  std::memcpy(out, &bytes, sizeof(bytes));
}

/// resample_row_sse2() for a compile-time number of 16-tap rounds (0: the resampler's own).
template <int kRounds>
inline void resample_row_sse2_rounds(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                                     std::uint8_t* out) {
  const int rounds = kRounds > 0 ? kRounds : r.stride / 16;
  const __m128i zero = _mm_setzero_si128();
  const int* first = r.first.data();
  const std::int16_t* weights = r.weights.data();
  const std::size_t stride = static_cast<std::size_t>(r.stride);
  auto dot = [&](int x) {
    const std::uint8_t* p = row + (first[x] - row_first);
    const __m128i* w = reinterpret_cast<const __m128i*>(weights + static_cast<std::size_t>(x) * stride);
    __m128i sum = zero;
    for (int j = 0; j < rounds; ++j, p += 16, w += 2) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
      sum = _mm_add_epi32(sum, _mm_madd_epi16(_mm_unpacklo_epi8(v, zero), _mm_loadu_si128(w)));
      sum = _mm_add_epi32(sum, _mm_madd_epi16(_mm_unpackhi_epi8(v, zero), _mm_loadu_si128(w + 1)));
    }
    return sum;
  };
  int x = x0;
  for (; x + 4 <= x1; x += 4) {
    // Four partial-sum vectors transposed and added: lane i is the dot product of column x + i.
    const __m128i s0 = dot(x), s1 = dot(x + 1), s2 = dot(x + 2), s3 = dot(x + 3);
    store_four_columns(s0, s1, s2, s3, out + x);
  }
  if (x < x1) resample_row_scalar(r, row, row_first, x, x1, out);
}

/// resample_row_sse2() for a stride of 8: the windows of two columns share one vector.
inline void resample_row_sse2_8(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                                std::uint8_t* out) {
  const __m128i zero = _mm_setzero_si128();
  const int* first = r.first.data();
  const std::int16_t* weights = r.weights.data();
  auto window = [&](int x) { return _mm_loadl_epi64(reinterpret_cast<const __m128i*>(row + (first[x] - row_first))); };
  auto weight = [&](int x) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(weights + 8 * x)); };
  int x = x0;
  for (; x + 4 <= x1; x += 4) {
    const __m128i ab = _mm_unpacklo_epi64(window(x), window(x + 1));
    const __m128i cd = _mm_unpacklo_epi64(window(x + 2), window(x + 3));
    const __m128i s0 = _mm_madd_epi16(_mm_unpacklo_epi8(ab, zero), weight(x));
    const __m128i s1 = _mm_madd_epi16(_mm_unpackhi_epi8(ab, zero), weight(x + 1));
    const __m128i s2 = _mm_madd_epi16(_mm_unpacklo_epi8(cd, zero), weight(x + 2));
    const __m128i s3 = _mm_madd_epi16(_mm_unpackhi_epi8(cd, zero), weight(x + 3));
    store_four_columns(s0, s1, s2, s3, out + x);
  }
  if (x < x1) resample_row_scalar(r, row, row_first, x, x1, out);
}

/// resample_row_scalar() with 8 or 16 taps per multiply-add round, identical bytes (the padding
/// weights are zero, so reading `stride` canvas columns adds nothing).
inline void resample_row_sse2(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                              std::uint8_t* out) {
  switch (r.stride) {
    case 8:
      resample_row_sse2_8(r, row, row_first, x0, x1, out);
      break;
    case 16:
      resample_row_sse2_rounds<1>(r, row, row_first, x0, x1, out);
      break;
    case 32:
      resample_row_sse2_rounds<2>(r, row, row_first, x0, x1, out);
      break;
    default:
      resample_row_sse2_rounds<0>(r, row, row_first, x0, x1, out);
      break;
  }
}
#endif

/// resample_row_sse2() where the target has SSE2, else the scalar reference.
inline void resample_row(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                         std::uint8_t* out) {
#if defined(__SSE2__)
  resample_row_sse2(r, row, row_first, x0, x1, out);
#else
  resample_row_scalar(r, row, row_first, x0, x1, out);
#endif
}

}  // namespace affine_orb::detail
