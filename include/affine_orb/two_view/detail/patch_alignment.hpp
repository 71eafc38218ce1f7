#pragma once
/// \file
/// Internals of align_correspondences() (two_view/alignment.hpp): bilinear sampling of a grey
/// image and the inverse-compositional Lucas–Kanade alignment of one patch under a fixed local
/// affine map, translation only (Baker & Matthews, "Lucas-Kanade 20 Years On: A Unifying
/// Framework", IJCV 56(3), 2004, section 3.2), with the patch's mean and contrast normalised so
/// that a change of light between the images does not bias it.

#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/detail/homography.hpp"

namespace affine_orb::detail {

/// Bilinear interpolation at fractions (ax, ay) of a pixel between r0[0], r0[1] (one image row)
/// and r1[0], r1[1] (the next).
inline double interpolate(const std::uint8_t* r0, const std::uint8_t* r1, double ax, double ay) {
  const double top = r0[0] + ax * (r0[1] - r0[0]);
  const double bottom = r1[0] + ax * (r1[1] - r1[0]);
  return top + ay * (bottom - top);
}

/// Grey level of a CV_8UC1 image at (x, y), bilinear between the four pixel centres around it.
/// The caller keeps 0 <= x < cols − 1 and 0 <= y < rows − 1.
inline double sample_bilinear(const cv::Mat& image, double x, double y) {
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);
  const std::uint8_t* r0 = image.ptr<std::uint8_t>(iy) + ix;
  return interpolate(r0, r0 + image.step[0], x - ix, y - iy);
}

/// True when the parallelogram centre + A·[−half, half]² lies where sample_bilinear() may read.
inline bool samplable(const cv::Mat& image, const Eigen::Vector2d& centre, const Eigen::Matrix2d& a, double half) {
  const double ex = half * (std::abs(a(0, 0)) + std::abs(a(0, 1)));
  const double ey = half * (std::abs(a(1, 0)) + std::abs(a(1, 1)));
  return centre.x() - ex >= 0.0 && centre.y() - ey >= 0.0 && centre.x() + ex < image.cols - 1 &&
         centre.y() + ey < image.rows - 1;
}

/// Buffers of align_patch(), reused across correspondences.
struct PatchAlignmentWork {
  std::vector<double> bordered;  ///< image 1's patch with a one-sample border, for the gradients
  std::vector<double> templ;     ///< image 1's patch, mean-free
  std::vector<double> gx, gy;    ///< its gradients
  std::vector<double> warped;    ///< image 2 sampled on the patch's grid
};

/// What align_patch() found.
struct PatchAlignment {
  Eigen::Vector2d point2;    ///< image-2 point aligned with the patch centre, pixels
  double correlation = 0.0;  ///< normalised cross-correlation of the aligned patches, [-1, 1]
};

/// Image 1's patch, as align_patch() aligns it: the patch itself is in the PatchAlignmentWork.
struct PatchTemplate {
  Eigen::Matrix2d inverse_hessian;  ///< inverse of the structure tensor Σ ∇T ∇Tᵀ of the patch
  double norm = 0.0;                ///< norm of the mean-free patch
};

/// Samples the (2·radius + 1)² patch of image1 centred on `point1` into work.templ (mean-free) and
/// its central-difference gradients into work.gx and work.gy. nullopt when a sample (or a gradient's
/// neighbour) would fall outside image1, or when the patch is too weakly textured (see
/// align_patch()) or flat.
inline std::optional<PatchTemplate> patch_template(const cv::Mat& image1, const Eigen::Vector2d& point1, int radius,
                                                   double min_texture, PatchAlignmentWork& work) {
  const int side = 2 * radius + 1;
  const int bside = side + 2;
  const std::size_t n = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  if (!samplable(image1, point1, Eigen::Matrix2d::Identity(), radius + 1.0)) return std::nullopt;
  work.bordered.resize(static_cast<std::size_t>(bside) * static_cast<std::size_t>(bside));
  // The samples lie a whole number of pixels apart, so all share the bilinear weights of the
  // first: the values sample_bilinear() gives at each, without its per-sample conversions.
  const double x0 = point1.x() - radius - 1, y0 = point1.y() - radius - 1;
  const int ix = static_cast<int>(x0), iy = static_cast<int>(y0);
  const double ax = x0 - ix, ay = y0 - iy;
  for (int j = 0; j < bside; ++j) {
    const std::uint8_t* r0 = image1.ptr<std::uint8_t>(iy + j) + ix;
    const std::uint8_t* r1 = r0 + image1.step[0];
    double* out = work.bordered.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(bside);
    for (int i = 0; i < bside; ++i) out[i] = interpolate(r0 + i, r1 + i, ax, ay);
  }
  work.templ.resize(n);
  work.gx.resize(n);
  work.gy.resize(n);
  double mean = 0.0;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) mean += work.bordered[static_cast<std::size_t>((j + 1) * bside + i + 1)];
  mean /= static_cast<double>(n);
  Eigen::Matrix2d hessian = Eigen::Matrix2d::Zero();
  double energy = 0.0;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const std::size_t b = static_cast<std::size_t>((j + 1) * bside + i + 1);
      const std::size_t k = static_cast<std::size_t>(j * side + i);
      work.templ[k] = work.bordered[b] - mean;
      // Central differences, per pixel of image 1.
      work.gx[k] = 0.5 * (work.bordered[b + 1] - work.bordered[b - 1]);
      work.gy[k] = 0.5 * (work.bordered[b + static_cast<std::size_t>(bside)] -
                          work.bordered[b - static_cast<std::size_t>(bside)]);
      hessian(0, 0) += work.gx[k] * work.gx[k];
      hessian(0, 1) += work.gx[k] * work.gy[k];
      hessian(1, 1) += work.gy[k] * work.gy[k];
      energy += work.templ[k] * work.templ[k];
    }
  }
  hessian(1, 0) = hessian(0, 1);
  const double trace = hessian.trace(), det = hessian.determinant();
  const double smaller = 0.5 * (trace - std::sqrt(std::max(0.0, trace * trace - 4.0 * det)));
  if (!(smaller >= min_texture * static_cast<double>(n)) || !(energy > 0.0)) return std::nullopt;
  return PatchTemplate{hessian.inverse(), std::sqrt(energy)};
}

/// Image 2's patch at one alignment: its samples are in work.warped, mean-free.
struct WarpedPatch {
  double norm = 0.0;   ///< norm of the mean-free samples
  double cross = 0.0;  ///< their dot product with the mean-free template
};

/// Samples image2 at x2 = c + A·(i − r, j − r) for the patch's grid (r = radius) into work.warped,
/// mean-free. nullopt when a sample would fall outside image2 or all samples are equal.
inline std::optional<WarpedPatch> warp_patch(const cv::Mat& image2, const Eigen::Vector2d& c, const Eigen::Matrix2d& a,
                                             int radius, PatchAlignmentWork& work) {
  const int side = 2 * radius + 1;
  const std::size_t n = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  if (!samplable(image2, c, a, radius)) return std::nullopt;
  work.warped.resize(n);
  double wmean = 0.0;
  double* out = work.warped.data();
  for (int j = 0; j < side; ++j) {
    // x2 = c + A·(i − r, j − r), stepped along the row.
    double x = c.x() + (a(0, 0) * -radius + a(0, 1) * (j - radius));
    double y = c.y() + (a(1, 0) * -radius + a(1, 1) * (j - radius));
    for (int i = 0; i < side; ++i, x += a(0, 0), y += a(1, 0)) {
      const double v = sample_bilinear(image2, x, y);
      *out++ = v;
      wmean += v;
    }
  }
  wmean /= static_cast<double>(n);
  double wenergy = 0.0, cross = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    work.warped[k] -= wmean;
    wenergy += work.warped[k] * work.warped[k];
    cross += work.warped[k] * work.templ[k];
  }
  if (!(wenergy > 0.0)) return std::nullopt;
  return WarpedPatch{std::sqrt(wenergy), cross};
}

/// The inverse-compositional update (pixels of image 1): image 2's patch scaled by `gain` to the
/// template's contrast, minus the template, projected on the template's gradients.
inline Eigen::Vector2d alignment_step(const PatchAlignmentWork& work, double gain,
                                      const Eigen::Matrix2d& inverse_hessian) {
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < work.templ.size(); ++k) {
    const double e = gain * work.warped[k] - work.templ[k];
    b.x() += work.gx[k] * e;
    b.y() += work.gy[k] * e;
  }
  return inverse_hessian * b;
}

/// Aligns the (2·radius + 1)² patch of image1 centred on `point1` (one sample per pixel) with
/// image2 sampled through x2 = c + A·u (u the patch offset from point1, pixels of image 1), starting
/// from c = `start`: translation-only inverse-compositional Lucas–Kanade on mean- and
/// contrast-normalised patches, until an update is below 0.01 pixels of image 1 or `iterations`
/// updates. The correlation is measured on the last patch sampled: after a converged update, the
/// one before it (the update moves c by less than 0.01 pixels of image 1, so the patch is not
/// sampled again). nullopt when a sample would fall outside either image, the patch is too weakly
/// textured in one direction (the smaller eigenvalue of its structure tensor below `min_texture`
/// grey levels² per sample), an update is not finite or moves c further than `max_shift` pixels of
/// image 2 from `start` (the alignment stops there: it slides along an edge or onto a neighbour).
inline std::optional<PatchAlignment> align_patch(const cv::Mat& image1, const cv::Mat& image2,
                                                 const Eigen::Vector2d& point1, const Eigen::Vector2d& start,
                                                 const Eigen::Matrix2d& a, int radius, int iterations,
                                                 double min_texture, double max_shift, PatchAlignmentWork& work) {
  const std::optional<PatchTemplate> templ = patch_template(image1, point1, radius, min_texture, work);
  if (!templ) return std::nullopt;
  Eigen::Vector2d c = start;
  for (int it = 0;; ++it) {
    const std::optional<WarpedPatch> warped = warp_patch(image2, c, a, radius, work);
    if (!warped) return std::nullopt;
    const double correlation = warped->cross / (warped->norm * templ->norm);
    if (it == iterations) return PatchAlignment{c, correlation};
    const Eigen::Vector2d delta = alignment_step(work, templ->norm / warped->norm, templ->inverse_hessian);
    if (!delta.allFinite()) return std::nullopt;
    c -= a * delta;
    if (!((c - start).norm() <= max_shift)) return std::nullopt;
    if (delta.norm() < 0.01) return PatchAlignment{c, correlation};
  }
}

}  // namespace affine_orb::detail
