#pragma once
/// \file
/// Sub-pixel correspondences under a homography: for a match x1 ↔ x2 of two images and a
/// homography H (x2 ~ H x1) that it fits, the image-2 point that corresponds to x1 found by aligning
/// image 1's patch around x1 with image 2 warped by H's local affine map (Lucas–Kanade, translation
/// only). A keypoint lies on the pixel grid of its pyramid level, so a match between two coarse
/// octaves is off by up to half a level pixel in each image (0.6–1.8 original pixels at octaves
/// 1–7), and a homography fitted to such matches extrapolates that error to the image corners
/// (bench/eval_two_view --placement measures the residuals per octave). The aligned point does not
/// depend on where either keypoint was placed.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/two_view/detail/patch_alignment.hpp"

namespace affine_orb {

/// Options of align_correspondences().
struct CorrespondenceAlignmentOptions {
  /// Half side of the aligned patch in level pixels of the image-1 keypoint's octave, at most
  /// twice this many original pixels. In [2, 32]. 5 (patch sides 11 to 21 original pixels): on
  /// graf 1 warped by a known homography, with image 2's points moved up to 1.5 px off, the aligned
  /// points lie 0.045 px from the truth on average, against 0.031 px with 7 at twice the time and
  /// 0.061 px with 4 (test_alignment measures the precision).
  int patch_radius = 5;
  /// Lucas–Kanade updates at most, in [1, 100]; an alignment that starts within 1.5 px converges
  /// in 3–5 (10 gains 0.004 px over 5 on the same warp).
  int iterations = 5;
  /// An alignment whose update moves the image-2 point further than this from where it started,
  /// pixels of image 2, stops there and is rejected (the point keeps its position): the matches
  /// handed in are inliers of H within about 2.4 px, so a longer move is a slide along an edge or
  /// onto a neighbour. In (0, 16].
  double max_shift = 2.0;
  /// An alignment whose patches correlate less than this (normalised cross-correlation after
  /// alignment, [-1, 1]) is rejected: the patches do not show the same surface (occlusion, a
  /// specularity, a different plane). In [-1, 1].
  double min_correlation = 0.8;
  /// Least texture in grey levels² per sample: the smaller eigenvalue of the patch's structure
  /// tensor over the number of samples; a patch below it (flat, or an edge without a corner) leaves
  /// the alignment undetermined along one direction and is not aligned. Image noise of σ = 1–2 grey
  /// levels gives gradients of about 1, so 4 asks for a few times the noise. In [0, 1e6].
  double min_texture = 4.0;

  /// Throws std::invalid_argument for a value outside its range.
  void check() const {
    detail::require_range(patch_radius, {2.0, 32.0}, "CorrespondenceAlignmentOptions: patch_radius");
    detail::require_range(iterations, {1.0, 100.0}, "CorrespondenceAlignmentOptions: iterations");
    detail::require_range(max_shift, {0.0, 16.0, true}, "CorrespondenceAlignmentOptions: max_shift");
    detail::require_range(min_correlation, {-1.0, 1.0}, "CorrespondenceAlignmentOptions: min_correlation");
    detail::require_range(min_texture, {0.0, 1e6}, "CorrespondenceAlignmentOptions: min_texture");
  }
};

/// The outcome of align_correspondences(), one entry per correspondence.
struct AlignedCorrespondences {
  /// Image 2's point of each correspondence, pixels of image 2: the aligned one where `aligned`,
  /// else the point handed in.
  std::vector<cv::Point2f> points2;
  std::vector<std::uint8_t> aligned;  ///< 1 where the alignment was accepted
  int aligned_count = 0;
};

/// Aligns image 2's side of the correspondences points1[i] ↔ points2[i] (pixels, level-0
/// coordinates) of the grey images image1 and image2 (CV_8UC1) under the homography `homography`
/// (x2 ~ H x1, pixels): for each, image 1's patch around points1[i] (side 2·r + 1 with r =
/// patch_radius · scales1[i] original pixels, at most 2·patch_radius) is aligned with image 2
/// sampled through H's first-order (affine) expansion at points1[i], starting from points2[i],
/// with mean and contrast normalised (a change of light does not move it). scales1[i] is the scale
/// of the image-1 keypoint's octave, s^octave (>= 1; 1 for level-0 points). A correspondence whose
/// patch leaves an image, is too weakly textured, moves further than max_shift or correlates less
/// than min_correlation keeps points2[i]. Throws std::invalid_argument for images that are not
/// CV_8UC1 or empty, lists of different lengths, a non-finite point or scale, a scale below 1, a
/// homography that is not finite, or invalid options.
inline AlignedCorrespondences align_correspondences(const cv::Mat& image1, const cv::Mat& image2,
                                                    const std::vector<cv::Point2f>& points1,
                                                    const std::vector<cv::Point2f>& points2,
                                                    const std::vector<float>& scales1,
                                                    const Eigen::Matrix3d& homography,
                                                    const CorrespondenceAlignmentOptions& options = {}) {
  options.check();
  detail::require(!image1.empty() && image1.type() == CV_8UC1 && !image2.empty() && image2.type() == CV_8UC1,
                  "align_correspondences: both images must be non-empty CV_8UC1");
  detail::require(points1.size() == points2.size() && points1.size() == scales1.size(),
                  "align_correspondences: points1, points2 and scales1 must have one entry per correspondence");
  detail::require(homography.allFinite(), "align_correspondences: the homography must be finite");
  AlignedCorrespondences out;
  out.points2 = points2;
  out.aligned.assign(points1.size(), 0);
  detail::PatchAlignmentWork work;
  for (std::size_t i = 0; i < points1.size(); ++i) {
    const cv::Point2f& p = points1[i];
    const cv::Point2f& q = points2[i];
    detail::require(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(q.x) && std::isfinite(q.y),
                    "align_correspondences: points must be finite");
    detail::require(std::isfinite(scales1[i]) && scales1[i] >= 1.0f,
                    "align_correspondences: scales must be finite and >= 1");
    const Eigen::Vector2d x1(p.x, p.y);
    const std::optional<Eigen::Matrix2d> jacobian = detail::homography_jacobian(homography, x1);
    if (!jacobian) continue;
    const int radius = static_cast<int>(
        std::lround(std::min(2.0 * options.patch_radius, options.patch_radius * static_cast<double>(scales1[i]))));
    const Eigen::Vector2d start(q.x, q.y);
    const std::optional<detail::PatchAlignment> patch = detail::align_patch(
        image1, image2, x1, start, *jacobian, radius, options.iterations, options.min_texture, options.max_shift, work);
    if (!patch || patch->correlation < options.min_correlation) continue;
    out.points2[i] = cv::Point2f(static_cast<float>(patch->point2.x()), static_cast<float>(patch->point2.y()));
    out.aligned[i] = 1;
    ++out.aligned_count;
  }
  return out;
}

}  // namespace affine_orb
