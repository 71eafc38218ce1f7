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
/// Each stage has a scalar reference, an SSE2 path (where the target has SSE2) and an AVX2 path
/// (where the CPU has AVX2, chosen per row: core/detail/simd.hpp) that give the same bytes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/simd.hpp"

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
/// The bilinear weights [128 − f | f] (16-bit halves of each 32-bit lane) of four positions from
/// `flipped`, whose lanes hold [~lo | lo], lo the position's low 16 bits: f = (lo + 2^8) >> 9 as in
/// the file comment, and 128 − f(lo) = f(~lo) = f(65535 − lo). _mm_avg_epu16(v, 255) = (v + 256) >> 1
/// without overflow.
inline __m128i fraction_pairs_sse2(__m128i flipped) {
  static_assert(kFractionBits == 7, "the weights below are in 1/128 px");
  return _mm_srli_epi16(_mm_avg_epu16(flipped, _mm_set1_epi16(255)), 8);
}

/// [~lo | lo] (see fraction_pairs_sse2()) of four 32-bit positions.
inline __m128i flipped_low_halves_sse2(__m128i pos) {
  return _mm_xor_si128(_mm_shufflehi_epi16(_mm_shufflelo_epi16(pos, 0xA0), 0xA0), _mm_set1_epi32(0xFFFF));
}

/// [−d | d] in 16 bits: what flipped_low_halves_sse2() of positions advances by when they advance by d.
inline __m128i flipped_step_sse2(std::int32_t d) {
  return _mm_set1_epi32(
      static_cast<std::int32_t>((static_cast<std::uint32_t>(-d) & 0xFFFFu) | (static_cast<std::uint32_t>(d) << 16)));
}

/// Four interpolated pixels, rounded, in the 32-bit lanes: from the pairs (p, p + 1) of the four
/// pixels in words 0-3 of `top`, those one row below in `bottom`, and the weights [128 − f | f] of x
/// (wx) and y (wy). Rows first, R = (128 − f_x)·p + f_x·p' < 2^15 for both rows, then (128 − f_y)·R_top
/// + f_y·R_bottom: the same integer as the file comment's sum, with 2^13 = 128·64 added as 64 to each R.
inline __m128i interpolate_four_sse2(__m128i top, __m128i bottom, __m128i wx, __m128i wy) {
  const __m128i zero = _mm_setzero_si128();
  const __m128i r_top = _mm_madd_epi16(_mm_unpacklo_epi8(top, zero), wx);
  const __m128i r_bottom = _mm_madd_epi16(_mm_unpacklo_epi8(bottom, zero), wx);
  const __m128i rows = _mm_add_epi16(_mm_or_si128(r_top, _mm_slli_epi32(r_bottom, 16)), _mm_set1_epi16(64));
  return _mm_srli_epi32(_mm_madd_epi16(rows, wy), 14);
}

/// sample_canvas_row_sse2() on columns [c0, c1), four at a time; kClamp = false where the
/// positions are known to lie inside the clamping range (their fractions are then stepped in 16
/// bits rather than taken from the positions).
template <bool kClamp>
inline int sample_canvas_columns_sse2(const std::uint8_t* base, std::ptrdiff_t step, const CanvasSampler& s,
                                      std::int32_t x_row, std::int32_t y_row, int c0, int c1, std::uint8_t* out) {
  const int end = c0 + std::max(0, c1 - c0) / 4 * 4;
  if (c0 >= end) return c0;
  const __m128i x_step4 = _mm_set1_epi32(4 * s.x_step);
  const __m128i y_step4 = _mm_set1_epi32(4 * s.y_step);
  const __m128i x_max = _mm_set1_epi32(s.x_max);
  const __m128i y_max = _mm_set1_epi32(s.y_max);
  const __m128i x_flip_step = flipped_step_sse2(4 * s.x_step);
  const __m128i y_flip_step = flipped_step_sse2(4 * s.y_step);
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
  __m128i x_flip = flipped_low_halves_sse2(xs);
  __m128i y_flip = flipped_low_halves_sse2(ys);
  for (int c = c0; c < end; c += 4) {
    const __m128i x = kClamp ? clamp(xs, x_max) : xs;
    const __m128i yv = kClamp ? clamp(ys, y_max) : ys;
    xs = _mm_add_epi32(xs, x_step4);
    ys = _mm_add_epi32(ys, y_step4);
    if (kClamp) {
      x_flip = flipped_low_halves_sse2(x);
      y_flip = flipped_low_halves_sse2(yv);
    }
    const __m128i wx = fraction_pairs_sse2(x_flip);
    const __m128i wy = fraction_pairs_sse2(y_flip);
    if (!kClamp) {
      x_flip = _mm_add_epi16(x_flip, x_flip_step);
      y_flip = _mm_add_epi16(y_flip, y_flip_step);
    }
    // Row offset y0·step with one 16x16 multiply-add per lane (y0, step < 2^15, high halves zero).
    const __m128i off = _mm_add_epi32(_mm_madd_epi16(_mm_srli_epi32(yv, 16), step16), _mm_srai_epi32(x, 16));
    const std::int64_t off01 = _mm_cvtsi128_si64(off);
    const std::int64_t off23 = _mm_cvtsi128_si64(_mm_unpackhi_epi64(off, off));
    const std::uint8_t* p0 = base + static_cast<std::int32_t>(off01);
    const std::uint8_t* p1 = base + (off01 >> 32);
    const std::uint8_t* p2 = base + static_cast<std::int32_t>(off23);
    const std::uint8_t* p3 = base + (off23 >> 32);
    // Words 0-3: the pairs (p, p + 1) of the four pixels, and one row below (two chains of inserts).
    __m128i top = _mm_cvtsi32_si128(load16(p0));
    __m128i bottom = _mm_cvtsi32_si128(load16(p0 + step));
    top = _mm_insert_epi16(top, load16(p1), 1);
    bottom = _mm_insert_epi16(bottom, load16(p1 + step), 1);
    top = _mm_insert_epi16(top, load16(p2), 2);
    bottom = _mm_insert_epi16(bottom, load16(p2 + step), 2);
    top = _mm_insert_epi16(top, load16(p3), 3);
    bottom = _mm_insert_epi16(bottom, load16(p3 + step), 3);
    const __m128i v = interpolate_four_sse2(top, bottom, wx, wy);
    const std::int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(v, v), zero));
    std::memcpy(out + (c - c0), &bytes, sizeof(bytes));
  }
  return end;
}

/// The columns of canvas row y in [c0, c1) whose positions need no clamping, [first, last) (empty
/// unless at least 8 columns).
inline std::pair<int, int> unclamped_columns(const CanvasSampler& s, int y, int c0, int c1) {
  const auto [ax, bx] = columns_within(s.x_row(y), s.x_step, s.x_max, c0, c1);
  const auto [ay, by] = columns_within(s.y_row(y), s.y_step, s.y_max, c0, c1);
  const int first = std::max(ax, ay);
  const int last = std::min(bx, by);
  return last - first < 8 ? std::make_pair(c1, c1) : std::make_pair(first, last);
}

/// sample_canvas_row_scalar() four pixels at a time, identical bytes: the columns whose positions
/// need no clamping take a path without it.
inline void sample_canvas_row_sse2(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const std::uint8_t* base = image.ptr<std::uint8_t>(0);
  const std::int32_t x_row = s.x_row(y);
  const std::int32_t y_row = s.y_row(y);
  const auto [inner0, inner1] = unclamped_columns(s, y, c0, c1);
  // [c0, inner0) clamped, [inner0, inner1) not, [inner1, c1) clamped; remainders of 4 scalar.
  auto run = [&](auto clamped, int a, int b) {
    const int c =
        sample_canvas_columns_sse2<decltype(clamped)::value>(base, step, s, x_row, y_row, a, b, out + (a - c0));
    sample_canvas_row_scalar(image, s, y, c, b, out + (c - c0));
  };
  run(std::true_type{}, c0, inner0);
  run(std::false_type{}, inner0, inner1);
  run(std::true_type{}, inner1, c1);
}

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// sample_canvas_row_avx2() on columns [c0, c1), eight at a time, each 128-bit half as in
/// sample_canvas_columns_sse2(); returns where it stopped. (Reading the pairs with
/// _mm256_i32gather_epi32 instead of 16-bit loads and inserts measured slower on an AMD EPYC.)
template <bool kClamp>
inline int sample_canvas_columns_avx2(const std::uint8_t* base, std::ptrdiff_t step, const CanvasSampler& s,
                                      std::int32_t x_row, std::int32_t y_row, int c0, int c1, std::uint8_t* out) {
  const int end = c0 + std::max(0, c1 - c0) / 8 * 8;
  if (c0 >= end) return c0;
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  __m256i xs =
      _mm256_add_epi32(_mm256_set1_epi32(x_row + c0 * s.x_step), _mm256_mullo_epi32(lane, _mm256_set1_epi32(s.x_step)));
  __m256i ys =
      _mm256_add_epi32(_mm256_set1_epi32(y_row + c0 * s.y_step), _mm256_mullo_epi32(lane, _mm256_set1_epi32(s.y_step)));
  const __m256i x_step8 = _mm256_set1_epi32(8 * s.x_step);
  const __m256i y_step8 = _mm256_set1_epi32(8 * s.y_step);
  const __m256i x_max = _mm256_set1_epi32(s.x_max);
  const __m256i y_max = _mm256_set1_epi32(s.y_max);
  const __m256i zero = _mm256_setzero_si256();
  const __m256i c255 = _mm256_set1_epi16(255);
  const __m256i c64 = _mm256_set1_epi16(64);
  const __m256i step16 = _mm256_set1_epi32(static_cast<std::int32_t>(step));
  // As flipped_low_halves_sse2() and flipped_step_sse2().
  auto flipped = [](__m256i pos) {
    return _mm256_xor_si256(_mm256_shufflehi_epi16(_mm256_shufflelo_epi16(pos, 0xA0), 0xA0), _mm256_set1_epi32(0xFFFF));
  };
  const __m256i x_flip_step = _mm256_broadcastsi128_si256(flipped_step_sse2(8 * s.x_step));
  const __m256i y_flip_step = _mm256_broadcastsi128_si256(flipped_step_sse2(8 * s.y_step));
  __m256i x_flip = flipped(xs);
  __m256i y_flip = flipped(ys);
  alignas(32) std::int32_t offset[8];
  auto load16 = [](const std::uint8_t* p) {
    std::uint16_t v;
    std::memcpy(&v, p, sizeof(v));
    return static_cast<int>(v);
  };
  // Four chains of inserts: the pairs of pixels o[0..3], `below` bytes further.
  auto quarter = [&](const std::int32_t* o, std::ptrdiff_t below) {
    __m128i v = _mm_cvtsi32_si128(load16(base + o[0] + below));
    v = _mm_insert_epi16(v, load16(base + o[1] + below), 1);
    v = _mm_insert_epi16(v, load16(base + o[2] + below), 2);
    return _mm_insert_epi16(v, load16(base + o[3] + below), 3);
  };
  for (int c = c0; c < end; c += 8) {
    const __m256i x = kClamp ? _mm256_min_epi32(_mm256_max_epi32(xs, zero), x_max) : xs;
    const __m256i yv = kClamp ? _mm256_min_epi32(_mm256_max_epi32(ys, zero), y_max) : ys;
    xs = _mm256_add_epi32(xs, x_step8);
    ys = _mm256_add_epi32(ys, y_step8);
    if (kClamp) {
      x_flip = flipped(x);
      y_flip = flipped(yv);
    }
    const __m256i wx = _mm256_srli_epi16(_mm256_avg_epu16(x_flip, c255), 8);
    const __m256i wy = _mm256_srli_epi16(_mm256_avg_epu16(y_flip, c255), 8);
    if (!kClamp) {
      x_flip = _mm256_add_epi16(x_flip, x_flip_step);
      y_flip = _mm256_add_epi16(y_flip, y_flip_step);
    }
    const __m256i off =
        _mm256_add_epi32(_mm256_madd_epi16(_mm256_srli_epi32(yv, 16), step16), _mm256_srai_epi32(x, 16));
    _mm256_store_si256(reinterpret_cast<__m256i*>(offset), off);
    // Per half: words 0-3 the pairs (p, p + 1) of four pixels, words 4-7 those one row below.
    const __m256i pairs =
        _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_unpacklo_epi64(quarter(offset, 0), quarter(offset, step))),
                                _mm_unpacklo_epi64(quarter(offset + 4, 0), quarter(offset + 4, step)), 1);
    // interpolate_four_sse2() on both halves.
    const __m256i top = _mm256_madd_epi16(_mm256_unpacklo_epi8(pairs, zero), wx);
    const __m256i bottom = _mm256_madd_epi16(_mm256_unpackhi_epi8(pairs, zero), wx);
    const __m256i rows = _mm256_add_epi16(_mm256_or_si256(top, _mm256_slli_epi32(bottom, 16)), c64);
    const __m256i v = _mm256_srli_epi32(_mm256_madd_epi16(rows, wy), 14);
    const __m256i bytes = _mm256_packus_epi16(_mm256_packs_epi32(v, v), zero);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + (c - c0)),
                     _mm_unpacklo_epi32(_mm256_castsi256_si128(bytes), _mm256_extracti128_si256(bytes, 1)));
  }
  return end;
}

/// sample_canvas_row_scalar() eight pixels at a time, identical bytes; the last columns of each
/// stretch four at a time (sample_canvas_columns_sse2()) and one at a time.
inline void sample_canvas_row_avx2(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const std::uint8_t* base = image.ptr<std::uint8_t>(0);
  const std::int32_t x_row = s.x_row(y);
  const std::int32_t y_row = s.y_row(y);
  const auto [inner0, inner1] = unclamped_columns(s, y, c0, c1);
  auto run = [&](auto clamped, int a, int b) {
    constexpr bool kClamp = decltype(clamped)::value;
    int c = sample_canvas_columns_avx2<kClamp>(base, step, s, x_row, y_row, a, b, out + (a - c0));
    c = sample_canvas_columns_sse2<kClamp>(base, step, s, x_row, y_row, c, b, out + (c - c0));
    sample_canvas_row_scalar(image, s, y, c, b, out + (c - c0));
  };
  run(std::true_type{}, c0, inner0);
  run(std::false_type{}, inner0, inner1);
  run(std::true_type{}, inner1, c1);
}
AFFINE_ORB_TARGET_AVX2_END
#endif
#endif

#if AFFINE_ORB_NEON
/// sample_canvas_row_scalar() four pixels at a time on NEON, identical bytes: the file comment's
/// integers in 32-bit lanes (weights and sums below 2^23), the positions clamped as there.
inline void sample_canvas_row_neon(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(image.step[0]);
  const std::uint8_t* base = image.ptr<std::uint8_t>(0);
  const std::int32_t x_row = s.x_row(y);
  const std::int32_t y_row = s.y_row(y);
  const int end = c0 + std::max(0, c1 - c0) / 4 * 4;
  const int32x4_t lane = {0, 1, 2, 3};
  int32x4_t xs = vmlaq_n_s32(vdupq_n_s32(x_row + c0 * s.x_step), lane, s.x_step);
  int32x4_t ys = vmlaq_n_s32(vdupq_n_s32(y_row + c0 * s.y_step), lane, s.y_step);
  const int32x4_t zero = vdupq_n_s32(0);
  const int32x4_t x_max = vdupq_n_s32(s.x_max);
  const int32x4_t y_max = vdupq_n_s32(s.y_max);
  const uint32x4_t low16 = vdupq_n_u32(0xFFFF);
  const uint32x4_t half = vdupq_n_u32(1u << (15 - kFractionBits));
  const uint32x4_t one = vdupq_n_u32(1u << kFractionBits);
  auto fraction = [&](int32x4_t v) {
    return vshrq_n_u32(vaddq_u32(vandq_u32(vreinterpretq_u32_s32(v), low16), half), 16 - kFractionBits);
  };
  for (int c = c0; c < end; c += 4) {
    const int32x4_t x = vminq_s32(vmaxq_s32(xs, zero), x_max);
    const int32x4_t yv = vminq_s32(vmaxq_s32(ys, zero), y_max);
    xs = vaddq_s32(xs, vdupq_n_s32(4 * s.x_step));
    ys = vaddq_s32(ys, vdupq_n_s32(4 * s.y_step));
    const uint32x4_t fx = fraction(x);
    const uint32x4_t fy = fraction(yv);
    const uint32x4_t gx = vsubq_u32(one, fx);
    const uint32x4_t gy = vsubq_u32(one, fy);
    std::int32_t offset[4];
    vst1q_s32(offset, vmlaq_n_s32(vshrq_n_s32(x, 16), vshrq_n_s32(yv, 16), static_cast<std::int32_t>(step)));
    std::uint32_t p00[4], p01[4], p10[4], p11[4];
    for (int i = 0; i < 4; ++i) {
      const std::uint8_t* p = base + offset[i];
      p00[i] = p[0];
      p01[i] = p[1];
      p10[i] = p[step];
      p11[i] = p[step + 1];
    }
    uint32x4_t sum = vmulq_u32(vld1q_u32(p00), vmulq_u32(gx, gy));
    sum = vmlaq_u32(sum, vld1q_u32(p01), vmulq_u32(fx, gy));
    sum = vmlaq_u32(sum, vld1q_u32(p10), vmulq_u32(gx, fy));
    sum = vmlaq_u32(sum, vld1q_u32(p11), vmulq_u32(fx, fy));
    const uint16x4_t v = vmovn_u32(vshrq_n_u32(vaddq_u32(sum, vdupq_n_u32(1u << 13)), 14));
    const std::uint32_t bytes = vget_lane_u32(vreinterpret_u32_u8(vmovn_u16(vcombine_u16(v, v))), 0);
    std::memcpy(out + (c - c0), &bytes, sizeof(bytes));
  }
  sample_canvas_row_scalar(image, s, y, std::max(c0, end), c1, out + (std::max(c0, end) - c0));
}
#endif

/// sample_canvas_row_avx2() where the CPU has AVX2, else sample_canvas_row_sse2() where the target
/// has SSE2, sample_canvas_row_neon() on AArch64, else the scalar reference.
inline void sample_canvas_row(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1, std::uint8_t* out) {
#if defined(__SSE2__)
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    sample_canvas_row_avx2(image, s, y, c0, c1, out);
    return;
  }
#endif
  sample_canvas_row_sse2(image, s, y, c0, c1, out);
#elif AFFINE_ORB_NEON
  sample_canvas_row_neon(image, s, y, c0, c1, out);
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

/// Calls fn(std::integral_constant<int, R>{}) with R the number of 16-tap rounds of a resampler of
/// `stride` (a multiple of 16) as a compile-time constant for strides 16 and 32, else R = 0 (the
/// resampler's own count at run time): the resamplers' loops unrolled for the common strides.
template <class Fn>
inline void with_rounds(int stride, Fn fn) {
  switch (stride) {
    case 16:
      fn(std::integral_constant<int, 1>{});
      break;
    case 32:
      fn(std::integral_constant<int, 2>{});
      break;
    default:
      fn(std::integral_constant<int, 0>{});
      break;
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
  if (r.stride == 8) {
    resample_row_sse2_8(r, row, row_first, x0, x1, out);
    return;
  }
  with_rounds(r.stride,
              [&](auto rounds) { resample_row_sse2_rounds<decltype(rounds)::value>(r, row, row_first, x0, x1, out); });
}
#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// Rounds eight columns' dot products (lane i of `sum` holds column i's) to bytes, Q kWeightBits
/// fixed point, and stores them at out[0..7].
inline void store_eight_columns_avx2(__m256i sum, std::uint8_t* out) {
  const __m256i v = _mm256_srai_epi32(_mm256_add_epi32(sum, _mm256_set1_epi32(1 << (kWeightBits - 1))), kWeightBits);
  const __m256i bytes = _mm256_packus_epi16(_mm256_packs_epi32(v, v), _mm256_setzero_si256());
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out),
                   _mm_unpacklo_epi32(_mm256_castsi256_si128(bytes), _mm256_extracti128_si256(bytes, 1)));
}

/// resample_row_avx2() for a compile-time number of 16-tap rounds (0: the resampler's own): one
/// 16-lane multiply-add per column and round, eight columns at a time.
template <int kRounds>
inline void resample_row_avx2_rounds(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                                     std::uint8_t* out) {
  const int rounds = kRounds > 0 ? kRounds : r.stride / 16;
  const int* first = r.first.data();
  const std::int16_t* weights = r.weights.data();
  const std::size_t stride = static_cast<std::size_t>(r.stride);
  auto dot = [&](int x) {
    const std::uint8_t* p = row + (first[x] - row_first);
    const std::int16_t* w = weights + static_cast<std::size_t>(x) * stride;
    __m256i sum = _mm256_setzero_si256();
    for (int j = 0; j < rounds; ++j, p += 16, w += 16) {
      const __m256i v = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
      sum = _mm256_add_epi32(sum, _mm256_madd_epi16(v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w))));
    }
    return sum;
  };
  int x = x0;
  for (; x + 8 <= x1; x += 8) {
    // Horizontal adds: lane i of each half holds the half-sums of columns x + i and x + 4 + i.
    const __m256i a =
        _mm256_hadd_epi32(_mm256_hadd_epi32(dot(x), dot(x + 1)), _mm256_hadd_epi32(dot(x + 2), dot(x + 3)));
    const __m256i b =
        _mm256_hadd_epi32(_mm256_hadd_epi32(dot(x + 4), dot(x + 5)), _mm256_hadd_epi32(dot(x + 6), dot(x + 7)));
    store_eight_columns_avx2(
        _mm256_add_epi32(_mm256_permute2x128_si256(a, b, 0x20), _mm256_permute2x128_si256(a, b, 0x31)), out + x);
  }
  if (x < x1) resample_row_sse2(r, row, row_first, x, x1, out);
}

/// resample_row_avx2() for a stride of 8: the windows of two neighbouring columns share one vector.
inline void resample_row_avx2_8(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                                std::uint8_t* out) {
  const int* first = r.first.data();
  const std::int16_t* weights = r.weights.data();
  // Columns x and x + 1: the low half holds x's window times its weights, the high half x + 1's.
  auto dot2 = [&](int x) {
    const __m128i windows =
        _mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row + (first[x] - row_first))),
                           _mm_loadl_epi64(reinterpret_cast<const __m128i*>(row + (first[x + 1] - row_first))));
    return _mm256_madd_epi16(_mm256_cvtepu8_epi16(windows),
                             _mm256_loadu_si256(reinterpret_cast<const __m256i*>(weights + 8 * x)));
  };
  int x = x0;
  for (; x + 8 <= x1; x += 8) {
    // Lane i of the low half: column x + 2i; of the high half: column x + 2i + 1.
    const __m256i sum =
        _mm256_hadd_epi32(_mm256_hadd_epi32(dot2(x), dot2(x + 2)), _mm256_hadd_epi32(dot2(x + 4), dot2(x + 6)));
    const __m256i v = _mm256_srai_epi32(_mm256_add_epi32(sum, _mm256_set1_epi32(1 << (kWeightBits - 1))), kWeightBits);
    const __m256i words = _mm256_packs_epi32(v, v);
    const __m128i ordered = _mm_unpacklo_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(ordered, ordered));
  }
  if (x < x1) resample_row_sse2(r, row, row_first, x, x1, out);
}

/// resample_row_scalar() with 16 taps per multiply-add (two columns' 8 for a stride of 8), eight
/// columns at a time, identical bytes; the last columns through resample_row_sse2().
inline void resample_row_avx2(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                              std::uint8_t* out) {
  if (r.stride == 8) {
    resample_row_avx2_8(r, row, row_first, x0, x1, out);
    return;
  }
  with_rounds(r.stride,
              [&](auto rounds) { resample_row_avx2_rounds<decltype(rounds)::value>(r, row, row_first, x0, x1, out); });
}
AFFINE_ORB_TARGET_AVX2_END
#endif
#endif

#if AFFINE_ORB_NEON
/// resample_row_scalar() on NEON, identical bytes: each column's dot product over the whole
/// `stride` (the padding weights are zero) by widening multiply-accumulates, eight taps a step.
inline void resample_row_neon(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                              std::uint8_t* out) {
  const std::size_t stride = static_cast<std::size_t>(r.stride);
  for (int x = x0; x < x1; ++x) {
    const std::uint8_t* p = row + (r.first[static_cast<std::size_t>(x)] - row_first);
    const std::int16_t* w = r.weights.data() + static_cast<std::size_t>(x) * stride;
    int32x4_t sum = vdupq_n_s32(0);
    for (std::size_t j = 0; j < stride; j += 8) {
      const int16x8_t v = vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p + j)));
      const int16x8_t k = vld1q_s16(w + j);
      sum = vmlal_high_s16(vmlal_s16(sum, vget_low_s16(v), vget_low_s16(k)), v, k);
    }
    out[x] = static_cast<std::uint8_t>((vaddvq_s32(sum) + (1 << (kWeightBits - 1))) >> kWeightBits);
  }
}
#endif

/// resample_row_avx2() where the CPU has AVX2, else resample_row_sse2() where the target has SSE2,
/// resample_row_neon() on AArch64, else the scalar reference.
inline void resample_row(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                         std::uint8_t* out) {
#if defined(__SSE2__)
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    resample_row_avx2(r, row, row_first, x0, x1, out);
    return;
  }
#endif
  resample_row_sse2(r, row, row_first, x0, x1, out);
#elif AFFINE_ORB_NEON
  resample_row_neon(r, row, row_first, x0, x1, out);
#else
  resample_row_scalar(r, row, row_first, x0, x1, out);
#endif
}

}  // namespace affine_orb::detail
