#pragma once
/// \file
/// Bilinear resizing of CV_8UC1 images in fixed point, the step between pyramid levels
/// (pyramid.hpp), optionally only on a region of the output.
///
/// Output pixel (x, y) of a W_d x H_d image from a W_s x H_s source (pixel centres at integers):
/// u = (x + 0.5)·W_s/W_d − 0.5, i = ⌊u⌋, f = u − i; at the left edge (i < 0) i = 0, f = 0; at the
/// right edge (i >= W_s − 1) i = W_s − 1, f = 0 (likewise for y, giving j and g). With the
/// fractions rounded to 1/128, a = round(128·f), b = round(128·g), and the neighbour index i + 1
/// clamped to the image,
///   out = ((128 − a)·R(i) + a·R(i + 1) + 2^13) >> 14,  R(k) = (128 − b)·I(k, j) + b·I(k, j + 1).
/// The scalar reference, the SSE2 path (where the target has SSE2) and the AVX2 path (where the CPU
/// has AVX2, chosen per row: core/detail/simd.hpp) give the same bytes.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/core/row_spans.hpp"

namespace affine_orb::detail {

/// The source index and 1/128 fraction of every output index along one axis (see the file comment).
struct ResizeAxis {
  std::vector<int> index;
  std::vector<std::int16_t> fraction;

  /// Fills the tables for `source` -> `target` pixels, reusing the vectors' capacity.
  void set(int source, int target) {
    index.resize(static_cast<std::size_t>(target));
    fraction.resize(static_cast<std::size_t>(target));
    const double scale = static_cast<double>(source) / target;
    for (int d = 0; d < target; ++d) {
      const double u = (d + 0.5) * scale - 0.5;
      int i = static_cast<int>(std::floor(u));
      double f = u - i;
      if (i < 0) {
        i = 0;
        f = 0.0;
      } else if (i >= source - 1) {
        i = source - 1;
        f = 0.0;
      }
      index[static_cast<std::size_t>(d)] = i;
      fraction[static_cast<std::size_t>(d)] = static_cast<std::int16_t>(std::lround(f * 128.0));
    }
  }
};

/// Buffers and tables of resize_bilinear(), recomputed when the sizes change (in the vectors'
/// capacity: no allocation once they have held the largest sizes).
struct ResizeWork {
  /// Output columns per block of the AVX2 column blend.
  static constexpr int kBlock = 8;
  /// 16-bit entries of a window: each half of a block reads its four pairs from one 16-byte load.
  static constexpr int kWindow = 8;
  cv::Size source;
  cv::Size target;
  ResizeAxis x;
  ResizeAxis y;
  std::vector<std::int32_t> x_weights;  ///< per output column: (128 − a) | a << 16
  /// Per block of kBlock output columns (columns 8b .. 8b + 7): whether both its halves find their
  /// pairs (row[i], row[i + 1]) within the kWindow entries from the half's first index, and the
  /// vpshufb mask that moves each pair's four bytes from its half's window into the column's
  /// 32-bit lane.
  std::vector<std::uint8_t> windowed;
  std::vector<std::array<std::uint8_t, 32>> spread;
  /// One vertically interpolated source row, plus one column, plus kWindow entries that a window
  /// may cover beyond the row (loaded, never selected).
  std::vector<std::int16_t> row;

  void prepare(cv::Size from, cv::Size to) {
    if (from == source && to == target && !x.index.empty()) return;
    source = from;
    target = to;
    x.set(from.width, to.width);
    y.set(from.height, to.height);
    x_weights.resize(static_cast<std::size_t>(to.width));
    for (std::size_t d = 0; d < x_weights.size(); ++d) {
      const std::int32_t a = x.fraction[d];
      x_weights[d] = (128 - a) | (a << 16);
    }
    set_windows();
    row.assign(static_cast<std::size_t>(from.width) + 1 + kWindow, 0);
  }

 private:
  void set_windows() {
    const std::size_t blocks = x.index.size() / kBlock;
    windowed.assign(blocks, 0);
    spread.resize(blocks);
    for (std::size_t b = 0; b < blocks; ++b) {
      bool fits = true;
      for (std::size_t k = 0; k < kBlock; ++k) {
        const std::size_t d = b * kBlock + k;
        const int offset = x.index[d] - x.index[d & ~std::size_t{3}];  // from its half's first index
        fits = fits && offset + 2 <= kWindow;
        for (int byte = 0; byte < 4; ++byte) {
          spread[b][4 * k + static_cast<std::size_t>(byte)] = static_cast<std::uint8_t>(2 * offset + byte);
        }
      }
      windowed[b] = fits;
    }
  }
};

/// Source row j blended with row j + 1 (clamped) by b/128, columns [c0, c1), into row[c0, c1): the
/// scalar reference.
inline void blend_rows_scalar(const std::uint8_t* top, const std::uint8_t* bottom, int b, int c0, int c1,
                              std::int16_t* row) {
  for (int c = c0; c < c1; ++c) row[c] = static_cast<std::int16_t>((128 - b) * top[c] + b * bottom[c]);
}

/// Output columns [x0, x1) from the blended row (ResizeWork::row: its source columns, the last one
/// repeated, then kWindow more entries for the AVX2 path's windows): the scalar reference.
inline void blend_columns_scalar(const ResizeWork& w, const std::int16_t* row, int x0, int x1, std::uint8_t* out) {
  for (int x = x0; x < x1; ++x) {
    const int i = w.x.index[static_cast<std::size_t>(x)];
    const int a = w.x.fraction[static_cast<std::size_t>(x)];
    out[x] = static_cast<std::uint8_t>(((128 - a) * row[i] + a * row[i + 1] + (1 << 13)) >> 14);
  }
}

#if defined(__SSE2__)
/// blend_rows_scalar(), 16 columns at a time, identical values; the last 16 end at c1, overlapping
/// the previous ones (a column computed twice gets the same value), and rows shorter than 16 go
/// through the reference.
inline void blend_rows_sse2(const std::uint8_t* top, const std::uint8_t* bottom, int b, int c0, int c1,
                            std::int16_t* row) {
  const __m128i wt = _mm_set1_epi16(static_cast<short>(128 - b));
  const __m128i wb = _mm_set1_epi16(static_cast<short>(b));
  const __m128i zero = _mm_setzero_si128();
  if (c1 - c0 < 16) {
    blend_rows_scalar(top, bottom, b, c0, c1, row);
    return;
  }
  for (int c = c0;; c = std::min(c + 16, c1 - 16)) {
    const __m128i t = _mm_loadu_si128(reinterpret_cast<const __m128i*>(top + c));
    const __m128i u = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bottom + c));
    const __m128i lo =
        _mm_add_epi16(_mm_mullo_epi16(_mm_unpacklo_epi8(t, zero), wt), _mm_mullo_epi16(_mm_unpacklo_epi8(u, zero), wb));
    const __m128i hi =
        _mm_add_epi16(_mm_mullo_epi16(_mm_unpackhi_epi8(t, zero), wt), _mm_mullo_epi16(_mm_unpackhi_epi8(u, zero), wb));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(row + c), lo);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(row + c + 8), hi);
    if (c + 16 >= c1) break;
  }
}

/// blend_columns_scalar(), eight and then four columns at a time, identical bytes.
inline void blend_columns_sse2(const ResizeWork& w, const std::int16_t* row, int x0, int x1, std::uint8_t* out) {
  const __m128i round = _mm_set1_epi32(1 << 13);
  const __m128i zero = _mm_setzero_si128();
  const int* index = w.x.index.data();
  auto pair = [&](int x) {
    std::int32_t v;
    std::memcpy(&v, row + index[x], sizeof(v));
    return v;
  };
  // Columns x .. x + 3, rounded, in 32-bit lanes.
  auto four = [&](int x) {
    const __m128i pairs = _mm_setr_epi32(pair(x), pair(x + 1), pair(x + 2), pair(x + 3));
    const __m128i weights = _mm_loadu_si128(reinterpret_cast<const __m128i*>(w.x_weights.data() + x));
    return _mm_srai_epi32(_mm_add_epi32(_mm_madd_epi16(pairs, weights), round), 14);
  };
  int x = x0;
  for (; x + 8 <= x1; x += 8) {
    const __m128i words = _mm_packs_epi32(four(x), four(x + 4));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(words, words));
  }
  for (; x + 4 <= x1; x += 4) {
    const __m128i v = four(x);
    const std::int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(v, v), zero));
    std::memcpy(out + x, &bytes, sizeof(bytes));
  }
  blend_columns_scalar(w, row, x, x1, out);
}
#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// blend_rows_sse2() with 16 columns in one 256-bit vector, identical values.
inline void blend_rows_avx2(const std::uint8_t* top, const std::uint8_t* bottom, int b, int c0, int c1,
                            std::int16_t* row) {
  const __m256i wt = _mm256_set1_epi16(static_cast<short>(128 - b));
  const __m256i wb = _mm256_set1_epi16(static_cast<short>(b));
  if (c1 - c0 < 16) {
    blend_rows_scalar(top, bottom, b, c0, c1, row);
    return;
  }
  for (int c = c0;; c = std::min(c + 16, c1 - 16)) {
    const __m256i t = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(top + c)));
    const __m256i u = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bottom + c)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(row + c),
                        _mm256_add_epi16(_mm256_mullo_epi16(t, wt), _mm256_mullo_epi16(u, wb)));
    if (c + 16 >= c1) break;
  }
}

/// blend_columns_scalar(), eight columns at a time, identical bytes: the blocks of
/// ResizeWork::windowed with two 16-byte loads and one vpshufb, the others with eight scalar loads
/// of their pairs (a 32-bit gather measured much slower on an AMD EPYC); columns before the first
/// whole block and after the last through blend_columns_sse2().
inline void blend_columns_avx2(const ResizeWork& w, const std::int16_t* row, int x0, int x1, std::uint8_t* out) {
  constexpr int kBlock = ResizeWork::kBlock;
  const __m256i round = _mm256_set1_epi32(1 << 13);
  const int* index = w.x.index.data();
  auto pair = [&](int x) {
    std::int32_t v;
    std::memcpy(&v, row + index[x], sizeof(v));
    return v;
  };
  auto window = [&](int x) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + index[x])); };
  // The tables through local pointers: the stores to `out` may alias anything as far as the
  // compiler knows, so members would be reloaded per block.
  const std::uint8_t* windowed = w.windowed.data();
  const std::array<std::uint8_t, 32>* spread = w.spread.data();
  const std::int32_t* x_weights = w.x_weights.data();
  const int start = std::min((x0 + kBlock - 1) / kBlock * kBlock, x1);
  blend_columns_sse2(w, row, x0, start, out);
  int x = start;
  for (std::size_t b = static_cast<std::size_t>(start / kBlock); x + kBlock <= x1; x += kBlock, ++b) {
    __m256i pairs;
    if (windowed[b] != 0) {
      pairs = _mm256_shuffle_epi8(_mm256_inserti128_si256(_mm256_castsi128_si256(window(x)), window(x + 4), 1),
                                  _mm256_loadu_si256(reinterpret_cast<const __m256i*>(spread[b].data())));
    } else {
      pairs = _mm256_setr_epi32(pair(x), pair(x + 1), pair(x + 2), pair(x + 3), pair(x + 4), pair(x + 5), pair(x + 6),
                                pair(x + 7));
    }
    const __m256i weights = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x_weights + x));
    const __m256i v = _mm256_srai_epi32(_mm256_add_epi32(_mm256_madd_epi16(pairs, weights), round), 14);
    const __m256i bytes = _mm256_packus_epi16(_mm256_packs_epi32(v, v), _mm256_setzero_si256());
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x),
                     _mm_unpacklo_epi32(_mm256_castsi256_si128(bytes), _mm256_extracti128_si256(bytes, 1)));
  }
  blend_columns_sse2(w, row, x, x1, out);
}
AFFINE_ORB_TARGET_AVX2_END
#endif
#endif

#if AFFINE_ORB_NEON
/// blend_rows_scalar() on NEON, 16 columns at a time, identical values (each sum is below 2^15).
inline void blend_rows_neon(const std::uint8_t* top, const std::uint8_t* bottom, int b, int c0, int c1,
                            std::int16_t* row) {
  const uint8x16_t wt = vdupq_n_u8(static_cast<std::uint8_t>(128 - b));
  const uint8x16_t wb = vdupq_n_u8(static_cast<std::uint8_t>(b));
  int c = c0;
  for (; c + 16 <= c1; c += 16) {
    const uint8x16_t t = vld1q_u8(top + c);
    const uint8x16_t u = vld1q_u8(bottom + c);
    const uint16x8_t lo = vmlal_u8(vmull_u8(vget_low_u8(t), vget_low_u8(wt)), vget_low_u8(u), vget_low_u8(wb));
    const uint16x8_t hi = vmlal_high_u8(vmull_high_u8(t, wt), u, wb);
    vst1q_s16(row + c, vreinterpretq_s16_u16(lo));
    vst1q_s16(row + c + 8, vreinterpretq_s16_u16(hi));
  }
  blend_rows_scalar(top, bottom, b, c, c1, row);
}

/// blend_columns_scalar() on NEON, eight columns at a time, identical bytes: each column's pair
/// (row[i], row[i + 1]) times its weights (128 − a, a), the products of a pair added, rounded,
/// shifted and narrowed with saturation as SSE2's pack instructions do.
inline void blend_columns_neon(const ResizeWork& w, const std::int16_t* row, int x0, int x1, std::uint8_t* out) {
  const int* index = w.x.index.data();
  const int32x4_t round = vdupq_n_s32(1 << 13);
  // Columns x .. x + 3, rounded, in 32-bit lanes.
  auto four = [&](int x) {
    std::int32_t pairs[4];
    for (int i = 0; i < 4; ++i) std::memcpy(&pairs[i], row + index[x + i], sizeof(pairs[i]));
    const int16x8_t p = vreinterpretq_s16_s32(vld1q_s32(pairs));
    const int16x8_t q = vreinterpretq_s16_s32(vld1q_s32(w.x_weights.data() + x));
    const int32x4_t sums = vpaddq_s32(vmull_s16(vget_low_s16(p), vget_low_s16(q)), vmull_high_s16(p, q));
    return vshrq_n_s32(vaddq_s32(sums, round), 14);
  };
  int x = x0;
  for (; x + 8 <= x1; x += 8) {
    vst1_u8(out + x, vqmovun_s16(vcombine_s16(vqmovn_s32(four(x)), vqmovn_s32(four(x + 4)))));
  }
  blend_columns_scalar(w, row, x, x1, out);
}
#endif

/// Resizes `src` (CV_8UC1) to `size` into `dst` (its buffer reused). With `region`, only the
/// columns of each row's run are computed (the whole row where the run is empty) and the other
/// pixels of the row repeat the nearest computed one.
inline void resize_bilinear(const cv::Mat& src, cv::Mat& dst, cv::Size size, const RowSpans* region, ResizeWork& w) {
  w.prepare(src.size(), size);
  dst.create(size, CV_8UC1);
  std::int16_t* row = w.row.data();
  [[maybe_unused]] const bool avx2 = cpu_has_avx2();
  for (int y = 0; y < size.height; ++y) {
    int x0 = 0;
    int x1 = size.width;
    if (region != nullptr) {
      const auto [b, e] = region->run(y);
      if (b < e) {
        x0 = std::max(b, 0);
        x1 = std::min(e, size.width);
      }
    }
    const int j = w.y.index[static_cast<std::size_t>(y)];
    const std::uint8_t* top = src.ptr<std::uint8_t>(j);
    const std::uint8_t* bottom = src.ptr<std::uint8_t>(std::min(j + 1, src.rows - 1));
    const int c0 = w.x.index[static_cast<std::size_t>(x0)];
    const int c1 = std::min(w.x.index[static_cast<std::size_t>(x1 - 1)] + 2, src.cols);
    const int b = w.y.fraction[static_cast<std::size_t>(y)];
    std::uint8_t* out = dst.ptr<std::uint8_t>(y);
#if defined(__SSE2__)
#if AFFINE_ORB_AVX2
    if (avx2) {
      blend_rows_avx2(top, bottom, b, c0, c1, row);
      row[src.cols] = row[src.cols - 1];
      blend_columns_avx2(w, row, x0, x1, out);
    } else
#endif
    {
      blend_rows_sse2(top, bottom, b, c0, c1, row);
      row[src.cols] = row[src.cols - 1];
      blend_columns_sse2(w, row, x0, x1, out);
    }
#elif AFFINE_ORB_NEON
    blend_rows_neon(top, bottom, b, c0, c1, row);
    row[src.cols] = row[src.cols - 1];
    blend_columns_neon(w, row, x0, x1, out);
#else
    blend_rows_scalar(top, bottom, b, c0, c1, row);
    row[src.cols] = row[src.cols - 1];
    blend_columns_scalar(w, row, x0, x1, out);
#endif
    std::memset(out, out[x0], static_cast<std::size_t>(x0));
    std::memset(out + x1, out[x1 - 1], static_cast<std::size_t>(size.width - x1));
  }
}

/// The definition in the file comment evaluated pixel by pixel: the reference resize_bilinear()
/// is tested against.
inline void resize_bilinear_reference(const cv::Mat& src, cv::Mat& dst, cv::Size size) {
  ResizeAxis ax;
  ResizeAxis ay;
  ax.set(src.cols, size.width);
  ay.set(src.rows, size.height);
  dst.create(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y) {
    const int j = ay.index[static_cast<std::size_t>(y)];
    const int b = ay.fraction[static_cast<std::size_t>(y)];
    const int j1 = std::min(j + 1, src.rows - 1);
    for (int x = 0; x < size.width; ++x) {
      const int i = ax.index[static_cast<std::size_t>(x)];
      const int a = ax.fraction[static_cast<std::size_t>(x)];
      const int i1 = std::min(i + 1, src.cols - 1);
      auto r = [&](int k) { return (128 - b) * src.at<std::uint8_t>(j, k) + b * src.at<std::uint8_t>(j1, k); };
      dst.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(((128 - a) * r(i) + a * r(i1) + (1 << 13)) >> 14);
    }
  }
}

}  // namespace affine_orb::detail
