#pragma once
/// \file
/// rBRIEF-256, ORB's steered BRIEF descriptor (Rublee et al., ICCV 2011, section 4.3), as a
/// descriptor policy for Extractor<Rbrief> (see descriptor.hpp).
///
/// Definition, for a keypoint at level pixel p (rounded to the nearest integer pixel c) with
/// orientation θ, on the level image smoothed by a 7x7 Gaussian of σ = 2 (border reflected, 101):
/// test i of ORB's published pair table (detail/orb_pattern.hpp) rotates both points by θ,
/// (x', y') = (round(x cos θ − y sin θ), round(x sin θ + y cos θ)), and bit i is 1 iff
/// I_s(c + a'_i) < I_s(c + b'_i). Rounding is OpenCV's cvRound (round half to even), as in ORB.
/// With the default options the bits are those of ORB for the same keypoint and angle, so DBoW2
/// vocabularies trained on ORB (ORB-SLAM2's ORBvoc.txt) remain valid.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/descriptors/detail/gaussian_q8.hpp"
#include "affine_orb/descriptors/detail/moment_lanes.hpp"
#include "affine_orb/descriptors/detail/orb_pattern.hpp"
#include "affine_orb/descriptors/detail/rbrief_tests.hpp"
#include "affine_orb/descriptors/detail/rotated_offsets.hpp"
#include "affine_orb/detection/orientation.hpp"

namespace affine_orb {

/// rBRIEF parameters. Changing any of them breaks bit compatibility with ORB.
struct RbriefOptions {
  /// Radius in level pixels of the intensity-centroid disc, in [3, 64]; 15, half ORB's 31-pixel
  /// patch, is ORB's.
  int orientation_radius = 15;
  /// Side of the Gaussian smoothing kernel in pixels, odd, in [1, 31]; 7 is ORB's and ORB-SLAM2's.
  int blur_kernel = 7;
  /// σ of the Gaussian smoothing in pixels, in (0, 16]; 2 is ORB's and ORB-SLAM2's. With these
  /// three defaults the bits equal cv::ORB's (bench/bench_extract counts the equal rows).
  double blur_sigma = 2.0;

  void check() const {
    detail::require_range(orientation_radius, {3, 64}, "RbriefOptions::orientation_radius");
    detail::require_range(blur_kernel, {1, 31}, "RbriefOptions::blur_kernel");
    detail::require(blur_kernel % 2 == 1, "RbriefOptions::blur_kernel must be odd, got " + std::to_string(blur_kernel));
    detail::require_range(blur_sigma, {0, 16, true}, "RbriefOptions::blur_sigma");
  }
};

/// The rBRIEF-256 descriptor policy.
class Rbrief {
 public:
  static constexpr int kBits = detail::kRbriefTests;
  /// Diameter in level pixels of ORB's patch; cv::KeyPoint::size is this times the keypoint scale.
  static constexpr float kPatchSize = 31.0f;
  using Options = RbriefOptions;

  /// Per-level data: the level image (shallow) for the orientation and its smoothed copy for the
  /// tests. One LevelData serves levels of any size in turn without reallocating once it has held
  /// the largest.
  struct LevelData {
    cv::Mat image;
    cv::Mat smoothed;                ///< the top-left part of `storage`
    cv::Mat storage;                 ///< grown to the largest level seen, never shrunk
    detail::GaussianQ8Work squares;  ///< scratch of the integer smoothing
  };

  explicit Rbrief(const Options& options = {})
      : options_(options), disc_((options.check(), options.orientation_radius)) {
    int extent = 0;
    for (const auto& pair : detail::kOrbTestPairs) {
      const double ra = std::hypot(pair.xa, pair.ya);
      const double rb = std::hypot(pair.xb, pair.yb);
      extent = std::max(extent, static_cast<int>(std::lround(std::max(ra, rb))));
    }
    // A rotated test point has |x'|, |y'| <= round(|(x, y)|), the rounded radius.
    border_ = std::max(extent, options_.orientation_radius);
    // The default smoothing's kernel is read and checked once per process (an immutable
    // function-local static); other kernels at construction.
    const RbriefOptions defaults;
    kernel_q8_ = options_.blur_kernel == defaults.blur_kernel && options_.blur_sigma == defaults.blur_sigma
                     ? default_kernel_q8()
                     : detail::gaussian_kernel_q8(options_.blur_kernel, options_.blur_sigma);
#if AFFINE_ORB_SIMD128
    const std::vector<int> half_widths = orb_disc_half_widths(options_.orientation_radius);
    disc_chunks_ = detail::disc_chunks<8>(half_widths);
#if AFFINE_ORB_AVX2
    if (detail::cpu_has_avx2() && options_.orientation_radius <= detail::kCentroidAvx2MaxRadius)
      disc_chunks32_ = detail::disc_chunks<32, std::int8_t>(half_widths);
#endif
#endif
  }

  const Options& options() const { return options_; }

  /// Minimal distance in level pixels between a keypoint and the level border (18 by default).
  int border() const { return border_; }

  /// Smooths the whole level. The border is reflected about the level's own edge even when the
  /// level is a ROI of a larger image (BORDER_ISOLATED), as the definition says. Uses
  /// cv::GaussianBlur's integer arithmetic (detail/gaussian_q8.hpp) when it was confirmed at
  /// construction, cv::GaussianBlur itself otherwise: the same bytes.
  void prepare(const cv::Mat& level, LevelData& data) const {
    detail::require_gray8(level, "Rbrief::prepare");
    data.image = level;
    data.smoothed = detail::fit_buffer(data.storage, level.size(), CV_8UC1);
    if (kernel_q8_.empty()) {
      cv::GaussianBlur(level, data.smoothed, cv::Size(options_.blur_kernel, options_.blur_kernel), options_.blur_sigma,
                       options_.blur_sigma, cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
      return;
    }
    detail::smooth_square_q8(level, cv::Rect(0, 0, level.cols, level.rows), kernel_q8_, data.squares, data.smoothed);
  }

  /// Smooths only the union of the squares of side 2·border()+1 around `points` (level pixels,
  /// rounded) when it covers less than half of the level, else the whole level (at once, without
  /// forming the union, when the squares' areas add up to twice the level's or more). The union is
  /// smoothed row run by row run, each pixel once, with cv::GaussianBlur's own integer arithmetic
  /// (detail/gaussian_q8.hpp, reflecting about the level edges), so its pixels equal those of the
  /// full smoothing; when that arithmetic could not be confirmed at construction, the whole level is
  /// smoothed. Pixels outside the squares are left undefined.
  void prepare(const cv::Mat& level, const std::vector<cv::Point2f>& points, LevelData& data) const {
    detail::require_gray8(level, "Rbrief::prepare");
    if (kernel_q8_.empty()) {
      prepare(level, data);
      return;
    }
    const int side = 2 * border_ + 1;
    if (static_cast<double>(points.size()) * side * side >= 2.0 * static_cast<double>(level.total())) {
      prepare(level, data);
      return;
    }
    const cv::Rect bounds(0, 0, level.cols, level.rows);
    data.squares.squares.clear();
    for (const cv::Point2f& p : points) {
      const cv::Rect square = cv::Rect(cvRound(p.x) - border_, cvRound(p.y) - border_, side, side) & bounds;
      if (!square.empty()) data.squares.squares.push_back(square);
    }
    const std::int64_t area = detail::union_runs_q8(data.squares);
    if (2 * area >= static_cast<std::int64_t>(level.total())) {
      prepare(level, data);
      return;
    }
    data.image = level;
    data.smoothed = detail::fit_buffer(data.storage, level.size(), CV_8UC1);
    detail::smooth_runs_q8(level, kernel_q8_, data.squares, data.smoothed);
  }

  /// Intensity-centroid orientation in radians on the unsmoothed level image, as ORB computes it:
  /// degrees_to_steering(orientation_degrees()).
  float orientation(const LevelData& data, cv::Point2f pt) const {
    return degrees_to_steering(orientation_degrees(data, pt));
  }

  /// The same orientation in degrees, the keypoint angle ORB and ORB-SLAM store:
  /// CentroidDisc::degrees(), whose integer moments are summed 8 columns at a time where the target
  /// has SSE2 or NEON, 32 on CPUs with AVX2 (the same sums, so the same angle).
  float orientation_degrees(const LevelData& data, cv::Point2f pt) const {
#if AFFINE_ORB_SIMD128
    const std::uint8_t* center = data.image.ptr<std::uint8_t>(cvRound(pt.y)) + cvRound(pt.x);
#if AFFINE_ORB_AVX2
    if (!disc_chunks32_.x.empty()) {
      const detail::CentroidMoments m = detail::centroid_moments_avx2(center, data.image.step[0], disc_chunks32_);
      return orb_angle_degrees(m.m01, m.m10);
    }
#endif
    const detail::CentroidMoments m = detail::centroid_moments_128(center, data.image.step[0], disc_chunks_);
    return orb_angle_degrees(m.m01, m.m10);
#else
    return disc_.degrees(data.image, cvRound(pt.x), cvRound(pt.y));
#endif
  }

  /// The 256-bit descriptor of the keypoint at integer level position `pt` (border() <= x <
  /// width − border(), likewise y) with the test pattern rotated by `angle` (radians, the frame of
  /// orientation()). Throws std::invalid_argument for a non-finite angle (its rotated test points
  /// would be undefined).
  BinaryDescriptor<kBits> describe(const LevelData& data, cv::Point2f pt, float angle) const {
    detail::require(std::isfinite(angle), "Rbrief::describe: the angle is not finite");
    return describe_rotated(data, pt, std::cos(angle), std::sin(angle));
  }

  /// describe() with the rotation given by its cosine `a` and sine `b` (finite), for callers whose
  /// reference computes them otherwise than std::cos and std::sin (stella_vslam's approximations).
  BinaryDescriptor<kBits> describe_rotated(const LevelData& data, cv::Point2f pt, float a, float b) const {
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(data.smoothed.step[0]);
    const std::uint8_t* center = data.smoothed.ptr<std::uint8_t>(cvRound(pt.y)) + cvRound(pt.x);
    // Byte offsets of the rotated test points: offset = round(x sin + y cos)·step + round(x cos − y sin).
    alignas(16) std::array<std::int32_t, 2 * kBits> offset;
    const PatternPoints& points = pattern_points();
    detail::rotated_offsets(points.x.data(), points.y.data(), offset.size(), a, b, static_cast<std::int32_t>(step),
                            offset.data());
    BinaryDescriptor<kBits> descriptor{};
    detail::rbrief_tests(center, offset.data(), descriptor.data());
    return descriptor;
  }

 private:
  // gaussian_kernel_q8() of the default blur_kernel and blur_sigma, computed at the first call.
  static const std::vector<std::uint16_t>& default_kernel_q8() {
    static const std::vector<std::uint16_t> kernel =
        detail::gaussian_kernel_q8(RbriefOptions{}.blur_kernel, RbriefOptions{}.blur_sigma);
    return kernel;
  }

  /// The test points of the pattern as floats, interleaved a_0, b_0, a_1, b_1, ... (x and y apart).
  struct PatternPoints {
    alignas(16) std::array<float, 2 * kBits> x{};
    alignas(16) std::array<float, 2 * kBits> y{};
  };

  static const PatternPoints& pattern_points() {
    static const PatternPoints points = [] {
      PatternPoints p;
      for (std::size_t i = 0; i < detail::kOrbTestPairs.size(); ++i) {
        const auto& pair = detail::kOrbTestPairs[i];
        p.x[2 * i] = pair.xa;
        p.y[2 * i] = pair.ya;
        p.x[2 * i + 1] = pair.xb;
        p.y[2 * i + 1] = pair.yb;
      }
      return p;
    }();
    return points;
  }

  Options options_;
  CentroidDisc disc_;
#if AFFINE_ORB_SIMD128
  detail::DiscChunks<8> disc_chunks_;
#if AFFINE_ORB_AVX2
  /// Empty without AVX2 or for a radius above kCentroidAvx2MaxRadius: the 8-column chunks serve.
  detail::DiscChunks<32, std::int8_t> disc_chunks32_;
#endif
#endif
  int border_ = 0;
  /// cv::GaussianBlur's integer kernel for the options (empty: not reproduced, see prepare()).
  std::vector<std::uint16_t> kernel_q8_;
};

}  // namespace affine_orb
