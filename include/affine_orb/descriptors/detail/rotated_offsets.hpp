#pragma once
/// \file
/// The rotated test points of rBRIEF (rbrief.hpp) as byte offsets into the smoothed level: for test
/// point (x, y) and the angle's cosine a and sine b, offset = round(x·b + y·a)·step + round(x·a − y·b),
/// each product and sum in float and rounded half to even (cvRound's rule, which cvtps2dq applies
/// under the default rounding mode), as ORB rotates its pattern. The scalar reference, SSE2 four
/// points at a time and AVX2 eight at a time (chosen at run time) give the same integers.

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/simd.hpp"

namespace affine_orb::detail {

/// out[i] for the n test points (x[i], y[i]): the scalar reference.
inline void rotated_offsets_scalar(const float* x, const float* y, std::size_t n, float a, float b, std::int32_t step,
                                   std::int32_t* out) {
  for (std::size_t i = 0; i < n; ++i) out[i] = cvRound(x[i] * b + y[i] * a) * step + cvRound(x[i] * a - y[i] * b);
}

#if defined(__SSE2__)
/// rotated_offsets_scalar() four points at a time (n a multiple of 4), identical integers.
inline void rotated_offsets_sse2(const float* x, const float* y, std::size_t n, float a, float b, std::int32_t step,
                                 std::int32_t* out) {
  const __m128 va = _mm_set1_ps(a);
  const __m128 vb = _mm_set1_ps(b);
  const __m128i vstep = _mm_set1_epi32(step);
  for (std::size_t i = 0; i < n; i += 4) {
    const __m128 px = _mm_loadu_ps(x + i);
    const __m128 py = _mm_loadu_ps(y + i);
    const __m128i rx = _mm_cvtps_epi32(_mm_sub_ps(_mm_mul_ps(px, va), _mm_mul_ps(py, vb)));
    const __m128i ry = _mm_cvtps_epi32(_mm_add_ps(_mm_mul_ps(px, vb), _mm_mul_ps(py, va)));
    // ry·step with SSE2 only: the low 32 bits of the unsigned 32x32 products are the signed
    // products modulo 2^32, exact since |ry·step| < 2^31.
    const __m128i lo = _mm_mul_epu32(ry, vstep);
    const __m128i hi = _mm_mul_epu32(_mm_srli_si128(ry, 4), _mm_srli_si128(vstep, 4));
    const __m128i product = _mm_unpacklo_epi32(_mm_shuffle_epi32(lo, _MM_SHUFFLE(0, 0, 2, 0)),
                                               _mm_shuffle_epi32(hi, _MM_SHUFFLE(0, 0, 2, 0)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_add_epi32(product, rx));
  }
}
#endif

#if AFFINE_ORB_AVX2
AFFINE_ORB_TARGET_AVX2_BEGIN
/// rotated_offsets_scalar() eight points at a time (n a multiple of 8), identical integers: the
/// same float operations and a 32-bit multiply for ry·step. The region enables AVX2, not FMA; a
/// translation unit compiled with FMA (-march=native, as ORB-SLAM builds) lets GCC fuse a product
/// with the sum here and in the scalar code, not necessarily the same one, so that about one angle
/// in 20,000 moves a test point by a pixel (docs/slam.md, "ORB-SLAM3: the default").
inline void rotated_offsets_avx2(const float* x, const float* y, std::size_t n, float a, float b, std::int32_t step,
                                 std::int32_t* out) {
  const __m256 va = _mm256_set1_ps(a);
  const __m256 vb = _mm256_set1_ps(b);
  const __m256i vstep = _mm256_set1_epi32(step);
  for (std::size_t i = 0; i < n; i += 8) {
    const __m256 px = _mm256_loadu_ps(x + i);
    const __m256 py = _mm256_loadu_ps(y + i);
    const __m256i rx = _mm256_cvtps_epi32(_mm256_sub_ps(_mm256_mul_ps(px, va), _mm256_mul_ps(py, vb)));
    const __m256i ry = _mm256_cvtps_epi32(_mm256_add_ps(_mm256_mul_ps(px, vb), _mm256_mul_ps(py, va)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), _mm256_add_epi32(_mm256_mullo_epi32(ry, vstep), rx));
  }
}
AFFINE_ORB_TARGET_AVX2_END
#endif

/// rotated_offsets_scalar() on the widest path the CPU has (AVX2, SSE2, else the scalar reference);
/// n a multiple of 8.
inline void rotated_offsets(const float* x, const float* y, std::size_t n, float a, float b, std::int32_t step,
                            std::int32_t* out) {
#if AFFINE_ORB_AVX2
  if (cpu_has_avx2()) {
    rotated_offsets_avx2(x, y, n, a, b, step, out);
    return;
  }
#endif
#if defined(__SSE2__)
  rotated_offsets_sse2(x, y, n, a, b, step, out);
#else
  rotated_offsets_scalar(x, y, n, a, b, step, out);
#endif
}

}  // namespace affine_orb::detail
