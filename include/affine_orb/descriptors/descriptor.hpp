#pragma once
/// \file
/// The descriptor policy concept that Extractor<Descriptor> is templated on.
///
/// A descriptor policy `D` describes keypoints on one pyramid level image (of the original image or
/// of a simulated view). It provides:
///
/// - `static constexpr int kBits;` descriptor length, a multiple of 64;
/// - `static constexpr float kPatchSize;` diameter of the described support in level pixels, reported
///   as cv::KeyPoint::size (times the keypoint scale);
/// - `using Options = ...;` a plain options struct with `void check() const` (throws
///   std::invalid_argument);
/// - `using LevelData = ...;` what the policy precomputes once per level image (a smoothed copy, an
///   integral image, ...); default-constructible; one LevelData is prepared for levels of varying
///   sizes in turn (every level of every view, on one thread), so it should keep its buffers and
///   allocate only for a level larger than any it held (detail::fit_buffer());
/// - `explicit D(const Options& options = {});` checks the options, builds the sampling pattern;
/// - `int border() const;` the radius, in level pixels, of the support of orientation and descriptor
///   around a keypoint: a keypoint at integer position (x, y) must satisfy
///   border() <= x < width − border() (likewise y) so that nothing is read outside the level image;
/// - `void prepare(const cv::Mat& level, LevelData& data) const;` fills `data` for a CV_8UC1 level
///   image (reusing its buffers); `data` may keep a shallow reference to `level`;
/// - `void prepare(const cv::Mat& level, const std::vector<cv::Point2f>& points, LevelData& data)
///   const;` the same, for describing only keypoints at `points` (level pixels): a policy may then
///   prepare just what those keypoints read, but must give the same results for them;
/// - `float orientation(const LevelData& data, cv::Point2f pt) const;` the keypoint orientation in
///   radians, level pixel coordinates (x right, y down, angle from +x towards +y);
/// - `BinaryDescriptor<kBits> describe(const LevelData& data, cv::Point2f pt, float angle) const;`
///   the descriptor of the keypoint at `pt` (level pixels) steered by `angle` (radians).
///
/// orientation() and describe() are const and touch no shared mutable state, so one policy object
/// may be used from several threads at once as long as each thread has its own LevelData.

#include <cmath>

#include "affine_orb/core/features.hpp"

namespace affine_orb {

/// Degrees in [0, 360) from an angle in radians.
inline float radians_to_degrees_0_360(float radians) {
  float degrees = radians * static_cast<float>(180.0 / CV_PI);
  degrees = std::fmod(degrees, 360.0f);
  if (degrees < 0.0f) degrees += 360.0f;
  return degrees >= 360.0f ? 0.0f : degrees;
}

}  // namespace affine_orb
