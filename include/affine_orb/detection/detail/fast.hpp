#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the arc-strength score (scalar reference, SSE2
/// or NEON and AVX2 lanes) and the row-wise non-maximum suppression behind detection/fast.hpp. The AVX2 rows run where
/// the CPU has AVX2, chosen per row (core/detail/simd.hpp).

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/detection/corner.hpp"

namespace affine_orb {
namespace detail {

/// Arc strength of a pixel from its 16 circle differences d_k >= 0 (saturated at 0): the largest
/// value v such that some 9 contiguous d_k are all >= v. For d_k = max(I_k − I_p, 0) (bright) or
/// max(I_p − I_k, 0) (dark), the pixel is a corner at threshold t >= 1 iff the larger of its two
/// arc strengths S exceeds t, and its FAST score is max(S − 1, 0).
inline int arc_strength(const std::array<int, 16>& d) {
  std::array<int, 16> m2{};
  std::array<int, 16> m4{};
  int best = 0;
  for (int k = 0; k < 16; ++k) m2[k] = std::min(d[k], d[(k + 1) & 15]);
  for (int k = 0; k < 16; ++k) m4[k] = std::min(m2[k], m2[(k + 2) & 15]);
  for (int k = 0; k < 16; ++k) {
    const int m8 = std::min(m4[k], m4[(k + 4) & 15]);
    best = std::max(best, std::min(m8, d[(k + 8) & 15]));
  }
  return best;
}

/// max(bright, dark) arc strength of the pixel at p; see arc_strength().
inline int pixel_strength(const std::uint8_t* p, const std::array<std::ptrdiff_t, 16>& offset) {
  const int center = p[0];
  std::array<int, 16> bright{};
  std::array<int, 16> dark{};
  for (int k = 0; k < 16; ++k) {
    const int v = p[offset[k]];
    bright[k] = std::max(v - center, 0);
    dark[k] = std::max(center - v, 0);
  }
  return std::max(arc_strength(bright), arc_strength(dark));
}

/// Scalar scoring of pixels [x0, x1) of one row (see fast_score_map()); the portable path and the
/// reference the SIMD path is tested against.
inline void score_row_scalar(const std::uint8_t* row, const std::array<std::ptrdiff_t, 16>& offset, int x0, int x1,
                             int threshold, std::uint8_t* out) {
  for (int x = x0; x < x1; ++x) {
    const std::uint8_t* p = row + x;
    const int center = p[0];
    const int hi = center + threshold;
    const int lo = center - threshold;
    // Any arc of 9 contains one of the pixels 0/8 and one of 4/12: reject early.
    const int p0 = p[offset[0]], p4 = p[offset[4]], p8 = p[offset[8]], p12 = p[offset[12]];
    const bool bright_possible = (p0 > hi || p8 > hi) && (p4 > hi || p12 > hi);
    const bool dark_possible = (p0 < lo || p8 < lo) && (p4 < lo || p12 < lo);
    if (!bright_possible && !dark_possible) {
      out[x] = 0;
      continue;
    }
    const int strength = pixel_strength(p, offset);
    out[x] = static_cast<std::uint8_t>(strength > threshold ? strength - 1 : 0);
  }
}

/// The 16 circle offsets in bytes for a row step of `step` bytes.
inline std::array<std::ptrdiff_t, 16> circle_offsets(std::ptrdiff_t step) {
  std::array<std::ptrdiff_t, 16> offset{};
  for (int i = 0; i < 16; ++i) offset[i] = kFastCircle[i][1] * step + kFastCircle[i][0];
  return offset;
}

/// The local maxima of row y, columns [x0, x1), of a score map, appended to `corners`; see
/// non_max_suppression(). The caller keeps the columns and rows one pixel inside the map. The
/// scalar reference.
inline void non_max_row_scalar(const cv::Mat& scores, int y, int x0, int x1, int threshold,
                               std::vector<Corner>& corners) {
  const std::uint8_t* above = scores.ptr<std::uint8_t>(y - 1);
  const std::uint8_t* row = scores.ptr<std::uint8_t>(y);
  const std::uint8_t* below = scores.ptr<std::uint8_t>(y + 1);
  for (int x = x0; x < x1; ++x) {
    // Score maps are mostly zero: skip 8 empty pixels at a time.
    if (x + 8 <= x1) {
      std::uint64_t word = 0;
      std::memcpy(&word, row + x, sizeof(word));
      if (word == 0) {
        x += 7;
        continue;
      }
    }
    const int s = row[x];
    if (s < threshold) continue;
    if (s > above[x - 1] && s > above[x] && s > above[x + 1] && s > row[x - 1] && s >= row[x + 1] &&
        s >= below[x - 1] && s >= below[x] && s >= below[x + 1]) {
      corners.push_back({x, y, s});
    }
  }
}

#if AFFINE_ORB_SIMD128
#if defined(__SSE2__)
/// 8-bit lane operations of SSE2 (16 lanes), for the FAST code written once for every width.
struct Lanes128 {
  using V = __m128i;
  static constexpr int kLanes = 16;
  static V load(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
  static void store(std::uint8_t* p, V v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  static V set1(int v) { return _mm_set1_epi8(static_cast<char>(v)); }
  static V zero() { return _mm_setzero_si128(); }
  static V adds(V a, V b) { return _mm_adds_epu8(a, b); }
  static V subs(V a, V b) { return _mm_subs_epu8(a, b); }
  static V min(V a, V b) { return _mm_min_epu8(a, b); }
  static V max(V a, V b) { return _mm_max_epu8(a, b); }
  static V eq(V a, V b) { return _mm_cmpeq_epi8(a, b); }
  static V or_(V a, V b) { return _mm_or_si128(a, b); }
  static V andnot(V a, V b) { return _mm_andnot_si128(a, b); }
  static bool none(V v) { return _mm_movemask_epi8(v) == 0; }
  /// Bit i set where lane i has its top bit set.
  static unsigned mask(V v) { return static_cast<unsigned>(_mm_movemask_epi8(v)); }
};
#else
/// 8-bit lane operations of NEON (16 lanes), the same operations as SSE2's.
struct Lanes128 {
  using V = uint8x16_t;
  static constexpr int kLanes = 16;
  static V load(const std::uint8_t* p) { return vld1q_u8(p); }
  static void store(std::uint8_t* p, V v) { vst1q_u8(p, v); }
  static V set1(int v) { return vdupq_n_u8(static_cast<std::uint8_t>(v)); }
  static V zero() { return vdupq_n_u8(0); }
  static V adds(V a, V b) { return vqaddq_u8(a, b); }
  static V subs(V a, V b) { return vqsubq_u8(a, b); }
  static V min(V a, V b) { return vminq_u8(a, b); }
  static V max(V a, V b) { return vmaxq_u8(a, b); }
  static V eq(V a, V b) { return vceqq_u8(a, b); }
  static V or_(V a, V b) { return vorrq_u8(a, b); }
  static V andnot(V a, V b) { return vbicq_u8(b, a); }
  static bool none(V v) { return (vmaxvq_u8(v) & 0x80) == 0; }
  /// Bit i set where lane i has its top bit set.
  static unsigned mask(V v) { return top_bits_neon(v); }
};
#endif

/// Appends the corners of the set bits of `mask` (bit i: column x + i of row y).
inline void append_corners(unsigned mask, int x, int y, const std::uint8_t* row, std::vector<Corner>& corners) {
  while (mask != 0) {
    const int i = __builtin_ctz(mask);
    corners.push_back({x + i, y, row[x + i]});
    mask &= mask - 1;
  }
}

// The kernels written once over S lanes (arc strength, score chunk, suppression chunk and run), for the
// 128-bit lanes here and for AVX2's inside the target region below, where they compile for AVX2.
namespace lanes128 {
#include "affine_orb/detection/detail/fast_lanes.inc"
}  // namespace lanes128

/// Scoring of pixels [x0, x1) of one row 16 at a time (SSE2 or NEON: Lanes128), equal to
/// score_row_scalar() bit for bit. [lo, hi) ⊇ [x0, x1) are the columns whose circle lies inside the
/// image: a run shorter than 16 is scored as the 16 pixels from clamp(x0, lo, hi − 16) and only its
/// own lanes are stored (the scalar path remains for rows narrower than 16 such columns).
inline void score_row_128(const std::uint8_t* row, const std::array<std::ptrdiff_t, 16>& offset, int x0, int x1, int lo,
                          int hi, int threshold, std::uint8_t* out) {
  using S = Lanes128;
  if (x1 <= x0) return;
  const S::V t = S::set1(threshold);
  if (x1 - x0 < S::kLanes) {
    if (hi - lo < S::kLanes) {
      score_row_scalar(row, offset, x0, x1, threshold, out);
      return;
    }
    const int c = std::clamp(x0, lo, hi - S::kLanes);
    alignas(16) std::uint8_t scores[S::kLanes];
    S::store(scores, lanes128::score_chunk_simd<S>(row + c, offset, t));
    std::memcpy(out + x0, scores + (x0 - c), static_cast<std::size_t>(x1 - x0));
    return;
  }
  // The last chunk overlaps the previous one so that it ends exactly at x1: scoring a pixel twice
  // writes the same value, and nothing outside [x0, x1) is touched.
  for (int x = x0;; x = std::min(x + S::kLanes, x1 - S::kLanes)) {
    S::store(out + x, lanes128::score_chunk_simd<S>(row + x, offset, t));
    if (x + S::kLanes >= x1) break;
  }
}

/// non_max_row_scalar() 16 pixels at a time (runs shorter than 16: the scalar reference).
inline void non_max_row_128(const cv::Mat& scores, int y, int x0, int x1, int threshold, std::vector<Corner>& corners) {
  if (x1 - x0 < Lanes128::kLanes) {
    non_max_row_scalar(scores, y, x0, x1, threshold, corners);
  } else {
    lanes128::non_max_run_simd<Lanes128>(scores, y, x0, x1, threshold, corners);
  }
}

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// 8-bit lane operations of AVX2 (32 lanes).
struct Lanes256 {
  using V = __m256i;
  static constexpr int kLanes = 32;
  static V load(const std::uint8_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
  static void store(std::uint8_t* p, V v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
  static V set1(int v) { return _mm256_set1_epi8(static_cast<char>(v)); }
  static V zero() { return _mm256_setzero_si256(); }
  static V adds(V a, V b) { return _mm256_adds_epu8(a, b); }
  static V subs(V a, V b) { return _mm256_subs_epu8(a, b); }
  static V min(V a, V b) { return _mm256_min_epu8(a, b); }
  static V max(V a, V b) { return _mm256_max_epu8(a, b); }
  static V eq(V a, V b) { return _mm256_cmpeq_epi8(a, b); }
  static V or_(V a, V b) { return _mm256_or_si256(a, b); }
  static V andnot(V a, V b) { return _mm256_andnot_si256(a, b); }
  static bool none(V v) { return _mm256_movemask_epi8(v) == 0; }
  /// Bit i set where lane i has its top bit set.
  static unsigned mask(V v) { return static_cast<unsigned>(_mm256_movemask_epi8(v)); }
};

namespace lanes256 {
#include "affine_orb/detection/detail/fast_lanes.inc"
}  // namespace lanes256

/// score_row_128() 32 pixels at a time where the run is that long (the last 32 overlapping the
/// previous ones), identical bytes; shorter runs go to score_row_128().
inline void score_row_avx2(const std::uint8_t* row, const std::array<std::ptrdiff_t, 16>& offset, int x0, int x1,
                           int lo, int hi, int threshold, std::uint8_t* out) {
  if (x1 - x0 < 32) {
    score_row_128(row, offset, x0, x1, lo, hi, threshold, out);
    return;
  }
  const __m256i t = _mm256_set1_epi8(static_cast<char>(threshold));
  for (int x = x0;; x = std::min(x + 32, x1 - 32)) {
    Lanes256::store(out + x, lanes256::score_chunk_simd<Lanes256>(row + x, offset, t));
    if (x + 32 >= x1) break;
  }
}

/// non_max_row_scalar() 32 pixels at a time (runs shorter than 32: non_max_row_128()).
inline void non_max_row_avx2(const cv::Mat& scores, int y, int x0, int x1, int threshold,
                             std::vector<Corner>& corners) {
  if (x1 - x0 < Lanes256::kLanes) {
    non_max_row_128(scores, y, x0, x1, threshold, corners);
  } else {
    lanes256::non_max_run_simd<Lanes256>(scores, y, x0, x1, threshold, corners);
  }
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// score_row_avx2() where the CPU has AVX2, score_row_128() where the target has SSE2 or NEON.
inline void score_row_simd(const std::uint8_t* row, const std::array<std::ptrdiff_t, 16>& offset, int x0, int x1,
                           int lo, int hi, int threshold, std::uint8_t* out) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    score_row_avx2(row, offset, x0, x1, lo, hi, threshold, out);
    return;
  }
#endif
  score_row_128(row, offset, x0, x1, lo, hi, threshold, out);
}
#endif

/// non_max_row_avx2() where the CPU has AVX2, non_max_row_128() where the target has SSE2 or NEON,
/// else the scalar reference.
inline void non_max_row(const cv::Mat& scores, int y, int x0, int x1, int threshold, std::vector<Corner>& corners) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    non_max_row_avx2(scores, y, x0, x1, threshold, corners);
    return;
  }
#endif
#if AFFINE_ORB_SIMD128
  non_max_row_128(scores, y, x0, x1, threshold, corners);
#else
  non_max_row_scalar(scores, y, x0, x1, threshold, corners);
#endif
}

/// fast_score_rect() without the argument checks, for callers that made them once (it builds no
/// message, so hot paths may call it every frame).
inline void score_rect(const cv::Mat& image, cv::Rect rect, int threshold, cv::Mat& scores) {
  rect &= cv::Rect(kFastRadius, kFastRadius, image.cols - 2 * kFastRadius, image.rows - 2 * kFastRadius);
  if (rect.empty()) return;
  const std::array<std::ptrdiff_t, 16> offset = circle_offsets(static_cast<std::ptrdiff_t>(image.step[0]));
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
#if AFFINE_ORB_SIMD128
    score_row_simd(image.ptr<std::uint8_t>(y), offset, rect.x, rect.x + rect.width, kFastRadius,
                   image.cols - kFastRadius, threshold, scores.ptr<std::uint8_t>(y));
#else
    score_row_scalar(image.ptr<std::uint8_t>(y), offset, rect.x, rect.x + rect.width, threshold,
                     scores.ptr<std::uint8_t>(y));
#endif
  }
}

/// fast_score_spans() without the argument checks, for callers that made them once.
inline void score_spans(const cv::Mat& image, const RowSpans& region, int threshold, cv::Mat& scores) {
  const std::array<std::ptrdiff_t, 16> offset = circle_offsets(static_cast<std::ptrdiff_t>(image.step[0]));
  const int top = std::max(region.y0, 0);
  const int bottom = std::min(region.y0 + region.rows(), image.rows);
  for (int y = top; y < bottom; ++y) {
    const auto [b, e] = region.run(y);
    const int x0 = std::max(b, 0);
    const int x1 = std::min(e, image.cols);
    if (x0 >= x1) continue;
    std::uint8_t* out = scores.ptr<std::uint8_t>(y);
    if (y < kFastRadius || y >= image.rows - kFastRadius) {
      std::memset(out + x0, 0, static_cast<std::size_t>(x1 - x0));
      continue;
    }
    const int s0 = std::max(x0, kFastRadius);
    const int s1 = std::min(x1, image.cols - kFastRadius);
    if (s0 >= s1) {
      std::memset(out + x0, 0, static_cast<std::size_t>(x1 - x0));
      continue;
    }
    std::memset(out + x0, 0, static_cast<std::size_t>(s0 - x0));
    std::memset(out + s1, 0, static_cast<std::size_t>(x1 - s1));
#if AFFINE_ORB_SIMD128
    score_row_simd(image.ptr<std::uint8_t>(y), offset, s0, s1, kFastRadius, image.cols - kFastRadius, threshold, out);
#else
    score_row_scalar(image.ptr<std::uint8_t>(y), offset, s0, s1, threshold, out);
#endif
  }
}

/// non_max_suppression() on row spans without the argument check.
inline void non_max_spans(const cv::Mat& scores, const RowSpans& region, int threshold, std::vector<Corner>& corners) {
  threshold = std::max(threshold, 1);
  const int top = std::max(region.y0, 1);
  const int bottom = std::min(region.y0 + region.rows(), scores.rows - 1);
  for (int y = top; y < bottom; ++y) {
    const auto [b, e] = region.run(y);
    const int x0 = std::max(b, 1);
    const int x1 = std::min(e, scores.cols - 1);
    if (x0 < x1) non_max_row(scores, y, x0, x1, threshold, corners);
  }
}

}  // namespace detail
}  // namespace affine_orb
