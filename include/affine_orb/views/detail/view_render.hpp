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
/// (where the CPU has AVX2, chosen per row: core/detail/simd.hpp) that give the same bytes: the
/// kernels of render_lanes.inc on RenderLanes128 and RenderLanes256. NEON has its own.

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

/// The columns of canvas row y in [c0, c1) whose positions need no clamping, [first, last) (empty
/// unless at least 8 columns).
inline std::pair<int, int> unclamped_columns(const CanvasSampler& s, int y, int c0, int c1) {
  const auto [ax, bx] = columns_within(s.x_row(y), s.x_step, s.x_max, c0, c1);
  const auto [ay, by] = columns_within(s.y_row(y), s.y_step, s.y_max, c0, c1);
  const int first = std::max(ax, ay);
  const int last = std::min(bx, by);
  return last - first < 8 ? std::make_pair(c1, c1) : std::make_pair(first, last);
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
/// [−d | d] in 16 bits: what flipped_low_halves() of positions (render_lanes.inc) advances by when
/// the positions advance by d.
inline std::int32_t flipped_step(std::int32_t d) {
  return static_cast<std::int32_t>((static_cast<std::uint32_t>(-d) & 0xFFFFu) | (static_cast<std::uint32_t>(d) << 16));
}

/// The renderer's operations on four 32-bit lanes (SSE2), for the kernels of render_lanes.inc.
struct RenderLanes128 {
  using V = __m128i;
  static constexpr int kLanes = 4;
  static V zero() { return _mm_setzero_si128(); }
  static V set1_32(std::int32_t a) { return _mm_set1_epi32(a); }
  static V set1_16(std::int16_t a) { return _mm_set1_epi16(a); }
  /// Lane i: start + i·step.
  static V positions(std::int32_t start, std::int32_t step) {
    return _mm_setr_epi32(start, start + step, start + 2 * step, start + 3 * step);
  }
  static V add32(V a, V b) { return _mm_add_epi32(a, b); }
  static V add16(V a, V b) { return _mm_add_epi16(a, b); }
  static V or_(V a, V b) { return _mm_or_si128(a, b); }
  static V xor_(V a, V b) { return _mm_xor_si128(a, b); }
  static V madd16(V a, V b) { return _mm_madd_epi16(a, b); }
  static V avg_u16(V a, V b) { return _mm_avg_epu16(a, b); }
  static V srli16(V a, int bits) { return _mm_srli_epi16(a, bits); }
  static V srli32(V a, int bits) { return _mm_srli_epi32(a, bits); }
  static V srai32(V a, int bits) { return _mm_srai_epi32(a, bits); }
  static V slli32(V a, int bits) { return _mm_slli_epi32(a, bits); }
  /// Each 32-bit lane's low 16 bits copied to its high 16 bits.
  static V dup_low_halves(V a) { return _mm_shufflehi_epi16(_mm_shufflelo_epi16(a, 0xA0), 0xA0); }
  /// min(max(v, 0), hi) per 32-bit lane (SSE2 has no 32-bit min and max).
  static V clamp(V v, V hi) {
    v = _mm_and_si128(v, _mm_cmpgt_epi32(v, _mm_setzero_si128()));
    const V above = _mm_cmpgt_epi32(v, hi);
    return _mm_or_si128(_mm_and_si128(above, hi), _mm_andnot_si128(above, v));
  }
  /// Bytes 0-7 (widen_lo8) or 8-15 (widen_hi8) zero-extended to 16 bits.
  static V widen_lo8(V a) { return _mm_unpacklo_epi8(a, _mm_setzero_si128()); }
  static V widen_hi8(V a) { return _mm_unpackhi_epi8(a, _mm_setzero_si128()); }
  static void store(std::int32_t* p, V a) { _mm_store_si128(reinterpret_cast<__m128i*>(p), a); }
  /// Bytes 0-7: the pairs (p, p + 1) at base + o[0..3]; bytes 8-15: those `step` bytes further
  /// (two chains of 16-bit loads and inserts).
  static V load_pairs(const std::uint8_t* base, const std::int32_t* o, std::ptrdiff_t step) {
    auto load16 = [](const std::uint8_t* p) {
      std::uint16_t v;
      std::memcpy(&v, p, sizeof(v));
      return static_cast<int>(v);
    };
    __m128i top = _mm_cvtsi32_si128(load16(base + o[0]));
    __m128i bottom = _mm_cvtsi32_si128(load16(base + o[0] + step));
    top = _mm_insert_epi16(top, load16(base + o[1]), 1);
    bottom = _mm_insert_epi16(bottom, load16(base + o[1] + step), 1);
    top = _mm_insert_epi16(top, load16(base + o[2]), 2);
    bottom = _mm_insert_epi16(bottom, load16(base + o[2] + step), 2);
    top = _mm_insert_epi16(top, load16(base + o[3]), 3);
    bottom = _mm_insert_epi16(bottom, load16(base + o[3] + step), 3);
    return _mm_unpacklo_epi64(top, bottom);
  }
  /// The 32-bit lanes saturated to bytes, stored at out[0, 4).
  static void store_bytes(std::uint8_t* out, V v) {
    const std::int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(v, v), _mm_setzero_si128()));
    std::memcpy(out, &bytes, sizeof(bytes));
  }
  /// Partial sums (four 32-bit lanes) of the dot product of the 16 bytes at p with the 16 weights at w.
  static V dot16(const std::uint8_t* p, const std::int16_t* w) {
    const V v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
    return _mm_add_epi32(_mm_madd_epi16(widen_lo8(v), _mm_loadu_si128(reinterpret_cast<const __m128i*>(w))),
                         _mm_madd_epi16(widen_hi8(v), _mm_loadu_si128(reinterpret_cast<const __m128i*>(w + 8))));
  }
  /// Lane i: the sum of the lanes of s[i] (four vectors of partial sums, transposed and added).
  static V sum_columns(const V* s) {
    const V t0 = _mm_add_epi32(_mm_unpacklo_epi32(s[0], s[1]), _mm_unpackhi_epi32(s[0], s[1]));
    const V t1 = _mm_add_epi32(_mm_unpacklo_epi32(s[2], s[3]), _mm_unpackhi_epi32(s[2], s[3]));
    return _mm_add_epi32(_mm_unpacklo_epi64(t0, t1), _mm_unpackhi_epi64(t0, t1));
  }
  /// Lane i: the dot product of the 8 bytes at windows[i] with the 8 weights at w + 8i.
  static V dot8_columns(const std::uint8_t* const* windows, const std::int16_t* w) {
    V s[kLanes];
    for (int i = 0; i < kLanes; ++i) {
      s[i] = _mm_madd_epi16(widen_lo8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(windows[i]))),
                            _mm_loadu_si128(reinterpret_cast<const __m128i*>(w + 8 * i)));
    }
    return sum_columns(s);
  }
};

namespace render128 {
#include "affine_orb/views/detail/render_lanes.inc"
}  // namespace render128

/// sample_canvas_row_scalar() four pixels at a time, identical bytes (render_lanes.inc).
inline void sample_canvas_row_sse2(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  render128::sample_canvas_row_simd<RenderLanes128>(image, s, y, c0, c1, out);
}

/// resample_row_scalar() four columns at a time, identical bytes (render_lanes.inc).
inline void resample_row_sse2(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                              std::uint8_t* out) {
  render128::resample_row_simd<RenderLanes128>(r, row, row_first, x0, x1, out);
}

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// RenderLanes128's operations on eight 32-bit lanes (AVX2): each 128-bit half as there, except
/// dot16() (16 taps in one multiply-add) and dot8_columns() (two columns' windows in one vector).
struct RenderLanes256 {
  using V = __m256i;
  static constexpr int kLanes = 8;
  static V zero() { return _mm256_setzero_si256(); }
  static V set1_32(std::int32_t a) { return _mm256_set1_epi32(a); }
  static V set1_16(std::int16_t a) { return _mm256_set1_epi16(a); }
  static V positions(std::int32_t start, std::int32_t step) {
    return _mm256_add_epi32(_mm256_set1_epi32(start),
                            _mm256_mullo_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(step)));
  }
  static V add32(V a, V b) { return _mm256_add_epi32(a, b); }
  static V add16(V a, V b) { return _mm256_add_epi16(a, b); }
  static V or_(V a, V b) { return _mm256_or_si256(a, b); }
  static V xor_(V a, V b) { return _mm256_xor_si256(a, b); }
  static V madd16(V a, V b) { return _mm256_madd_epi16(a, b); }
  static V avg_u16(V a, V b) { return _mm256_avg_epu16(a, b); }
  static V srli16(V a, int bits) { return _mm256_srli_epi16(a, bits); }
  static V srli32(V a, int bits) { return _mm256_srli_epi32(a, bits); }
  static V srai32(V a, int bits) { return _mm256_srai_epi32(a, bits); }
  static V slli32(V a, int bits) { return _mm256_slli_epi32(a, bits); }
  static V dup_low_halves(V a) { return _mm256_shufflehi_epi16(_mm256_shufflelo_epi16(a, 0xA0), 0xA0); }
  static V clamp(V v, V hi) { return _mm256_min_epi32(_mm256_max_epi32(v, _mm256_setzero_si256()), hi); }
  static V widen_lo8(V a) { return _mm256_unpacklo_epi8(a, _mm256_setzero_si256()); }
  static V widen_hi8(V a) { return _mm256_unpackhi_epi8(a, _mm256_setzero_si256()); }
  static void store(std::int32_t* p, V a) { _mm256_store_si256(reinterpret_cast<__m256i*>(p), a); }
  /// RenderLanes128::load_pairs() of o[0..3] in the low half, of o[4..7] in the high half. (Reading
  /// the pairs with _mm256_i32gather_epi32 instead measured slower on an AMD EPYC.)
  static V load_pairs(const std::uint8_t* base, const std::int32_t* o, std::ptrdiff_t step) {
    return _mm256_inserti128_si256(_mm256_castsi128_si256(RenderLanes128::load_pairs(base, o, step)),
                                   RenderLanes128::load_pairs(base, o + 4, step), 1);
  }
  static void store_bytes(std::uint8_t* out, V v) {
    const V bytes = _mm256_packus_epi16(_mm256_packs_epi32(v, v), _mm256_setzero_si256());
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out),
                     _mm_unpacklo_epi32(_mm256_castsi256_si128(bytes), _mm256_extracti128_si256(bytes, 1)));
  }
  static V dot16(const std::uint8_t* p, const std::int16_t* w) {
    return _mm256_madd_epi16(_mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))),
                             _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w)));
  }
  /// Horizontal adds: lane i of each half of a and b holds the half-sums of columns i and 4 + i.
  static V sum_columns(const V* s) {
    const V a = _mm256_hadd_epi32(_mm256_hadd_epi32(s[0], s[1]), _mm256_hadd_epi32(s[2], s[3]));
    const V b = _mm256_hadd_epi32(_mm256_hadd_epi32(s[4], s[5]), _mm256_hadd_epi32(s[6], s[7]));
    return _mm256_add_epi32(_mm256_permute2x128_si256(a, b, 0x20), _mm256_permute2x128_si256(a, b, 0x31));
  }
  /// Columns 2j and 2j + 1 share one multiply-add (the low half holds 2j's window times its
  /// weights, the high half 2j + 1's); the adds leave column 2i in lane i, 2i + 1 in lane 4 + i.
  static V dot8_columns(const std::uint8_t* const* windows, const std::int16_t* w) {
    auto dot2 = [&](int i) {
      const __m128i pair = _mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(windows[i])),
                                              _mm_loadl_epi64(reinterpret_cast<const __m128i*>(windows[i + 1])));
      return _mm256_madd_epi16(_mm256_cvtepu8_epi16(pair),
                               _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w + 8 * i)));
    };
    const V sum = _mm256_hadd_epi32(_mm256_hadd_epi32(dot2(0), dot2(2)), _mm256_hadd_epi32(dot2(4), dot2(6)));
    return _mm256_permutevar8x32_epi32(sum, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
  }
};

namespace render256 {
#include "affine_orb/views/detail/render_lanes.inc"
}  // namespace render256

/// sample_canvas_row_scalar() eight pixels at a time, identical bytes (render_lanes.inc).
inline void sample_canvas_row_avx2(const cv::Mat& image, const CanvasSampler& s, int y, int c0, int c1,
                                   std::uint8_t* out) {
  render256::sample_canvas_row_simd<RenderLanes256>(image, s, y, c0, c1, out);
}

/// resample_row_scalar() eight columns at a time, identical bytes (render_lanes.inc).
inline void resample_row_avx2(const ViewResampler& r, const std::uint8_t* row, int row_first, int x0, int x1,
                              std::uint8_t* out) {
  render256::resample_row_simd<RenderLanes256>(r, row, row_first, x0, x1, out);
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
