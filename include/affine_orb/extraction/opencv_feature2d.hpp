#pragma once
/// \file
/// affine_orb behind OpenCV's cv::Feature2D interface (detect, compute, detectAndCompute), for code
/// that already feeds cv::BFMatcher, cv::drawMatches or cv::findHomography. The only header of the
/// library that needs OpenCV's features2d module (link opencv_features2d to use it); the core
/// never includes it.
///
/// The object wraps one Extractor: detectAndCompute() and detect() return exactly its keypoints and
/// descriptor rows (descriptors_to_mat()), so the bytes are those of Extractor::extract(). Like
/// every cv::Feature2D, one object must not be used by two threads at once.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/opencv_feature2d.hpp"
#include "affine_orb/extraction/extractor.hpp"

namespace affine_orb {

/// The descriptor a Feature2D (or the Python module) computes.
enum class DescriptorKind {
  kRbrief,  ///< rBRIEF, 256 bits = 32 bytes a row; ORB's bits for the same keypoint and angle.
  kBrisk,   ///< BRISK, 512 bits = 64 bytes a row.
};

/// A cv::Feature2D that extracts with `options` and describes with `kind`: detectAndCompute() and
/// detect() return exactly Extractor::extract()'s keypoints and descriptor rows (CV_8U, 32 bytes
/// for rBRIEF, 64 for BRISK; defaultNorm() NORM_HAMMING); compute() describes given keypoints in
/// the original image (see detail::Feature2DExtractor). Throws std::invalid_argument for invalid
/// options, and its detect/compute calls throw it for empty images, types other than CV_8UC1 and
/// masks of the wrong size or type.
inline cv::Ptr<cv::Feature2D> create_feature2d(const ExtractorOptions& options = {},
                                               DescriptorKind kind = DescriptorKind::kRbrief) {
  detail::require(kind == DescriptorKind::kRbrief || kind == DescriptorKind::kBrisk,
                  "create_feature2d: the descriptor kind is invalid");
  if (kind == DescriptorKind::kBrisk) return cv::makePtr<detail::Feature2DExtractor<Brisk>>(options);
  return cv::makePtr<detail::Feature2DExtractor<Rbrief>>(options);
}

}  // namespace affine_orb
