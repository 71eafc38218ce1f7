#pragma once
/// \file
/// Binary descriptors and the feature set every extractor returns.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"

namespace affine_orb {

/// A binary descriptor of `Bits` bits stored as 64-bit words.
///
/// Bit b is bit (b % 64) of word b / 64. On a little-endian machine the bytes of the words are
/// therefore exactly OpenCV's byte layout (byte b / 8, bit b % 8), so a row of
/// descriptors_to_mat() is what cv::ORB or cv::BRISK would write for the same bits.
template <int Bits>
using BinaryDescriptor = std::array<std::uint64_t, static_cast<std::size_t>(Bits / 64)>;

/// Keypoints and their descriptors, row i of `descriptors` belonging to `keypoints[i]`.
///
/// Keypoint fields (cv::KeyPoint):
/// - `pt`: position in pixels of the original (level-0) image, pixel centres at integer coordinates;
/// - `angle`: orientation in degrees in [0, 360), measured in the original image (x right, y down);
/// - `octave`: the level of the original image's pyramid whose scale is the keypoint's, 0 = full
///   resolution: for a keypoint of the image, the level l it was detected at; for one of a view of
///   tilt t detected at its level l, the level nearest (in log scale) to s^l·√t, at most
///   levels − 1. It also says how precisely the keypoint is located: an image keypoint lies on a
///   pixel of its level; a view keypoint's mapped position is off by up to t·s^l/2 original pixels
///   along the tilt and s^l/2 across it, s^l·√t/2 in geometric mean (RefineOptions);
/// - `response`: detector score (FAST or Harris, see DetectorOptions), larger is stronger.
///
/// `views[i]` is the index of the simulated view keypoint i was detected in (0 = the original,
/// untilted image; see affine_views.hpp).
template <int Bits>
struct Features {
  static constexpr int kBits = Bits;
  std::vector<cv::KeyPoint> keypoints;
  std::vector<BinaryDescriptor<Bits>> descriptors;
  std::vector<int> views;

  std::size_t size() const { return keypoints.size(); }
  bool empty() const { return keypoints.empty(); }
};

/// Copies descriptors into an N x (8·Words) CV_8U matrix, the layout OpenCV's matchers and
/// ORB-SLAM's ORBmatcher read. Requires a little-endian host (checked at compile time).
template <std::size_t Words>
cv::Mat descriptors_to_mat(const std::vector<std::array<std::uint64_t, Words>>& descriptors) {
#if defined(__BYTE_ORDER__) && (__BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__)
  static_assert(Words == 0, "descriptors_to_mat assumes a little-endian host");
#endif
  cv::Mat mat(static_cast<int>(descriptors.size()), static_cast<int>(8 * Words), CV_8U);
  if (!descriptors.empty()) std::memcpy(mat.data, descriptors.data(), descriptors.size() * 8 * Words);
  return mat;
}

/// The inverse of descriptors_to_mat(): the rows of an N x (8·Words) CV_8U matrix (cv::ORB's,
/// cv::BRISK's or ORB-SLAM's descriptors) as descriptors of Words 64-bit words. Throws
/// std::invalid_argument for another type or width.
template <std::size_t Words>
std::vector<std::array<std::uint64_t, Words>> descriptors_from_mat(const cv::Mat& mat) {
#if defined(__BYTE_ORDER__) && (__BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__)
  static_assert(Words == 0, "descriptors_from_mat assumes a little-endian host");
#endif
  detail::require(mat.empty() || (mat.type() == CV_8UC1 && mat.cols == static_cast<int>(8 * Words)),
                  "descriptors_from_mat: expected CV_8UC1 rows of " + std::to_string(8 * Words) + " bytes");
  std::vector<std::array<std::uint64_t, Words>> out(static_cast<std::size_t>(mat.rows));
  for (int r = 0; r < mat.rows; ++r) std::memcpy(out[static_cast<std::size_t>(r)].data(), mat.ptr(r), 8 * Words);
  return out;
}

}  // namespace affine_orb
