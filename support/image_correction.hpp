#pragma once
/// \file
/// Image correction ("restoration", paper Sec. on model selection, docs/algorithm.md §5): when the homography
/// was chosen, image 2 is warped into image 1's frame so that the two can be compared pixel by
/// pixel.

#include <cmath>
#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/model_selection.hpp"

namespace affine_orb {

/// Resampling of warp_to_first_image().
struct ImageCorrectionOptions {
  /// cv::INTER_NEAREST, cv::INTER_LINEAR (default: bilinear, what ORB-SLAM-style pipelines use for
  /// image warps), cv::INTER_CUBIC or cv::INTER_LANCZOS4.
  int interpolation = cv::INTER_LINEAR;
  /// Value of output pixels whose source lies outside image 2 (cv::BORDER_CONSTANT).
  double border_value = 0.0;

  /// Throws std::invalid_argument for an unsupported interpolation or a non-finite border value.
  void check() const {
    detail::require(interpolation == cv::INTER_NEAREST || interpolation == cv::INTER_LINEAR ||
                        interpolation == cv::INTER_CUBIC || interpolation == cv::INTER_LANCZOS4,
                    "ImageCorrectionOptions: interpolation must be INTER_NEAREST, INTER_LINEAR, INTER_CUBIC or "
                    "INTER_LANCZOS4, got " +
                        std::to_string(interpolation));
    detail::require(std::isfinite(border_value), "ImageCorrectionOptions: border_value must be finite");
  }
};

/// Image 2 resampled in image 1's frame.
struct CorrectedImage {
  /// False when there was no homography to correct with (select_model() chose F or failed).
  bool success = false;
  /// Size of image 1, type of image 2: image(x1) = image2(H x1).
  cv::Mat image;
  /// CV_8UC1 of the same size: 255 where `image` was interpolated from image-2 pixels only (H x1
  /// inside [r, w − 1 − r] x [r, h − 1 − r] of image 2, r = 0 for nearest and bilinear, 1 for
  /// bicubic, 3 for Lanczos-4 interpolation), 0 elsewhere (border value or blended with it).
  cv::Mat valid;
};

/// Warps `image2` into the frame of an image 1 of size `size1` through x2 ~ h x1 (pixels):
/// output(x1) = image2(h x1), i.e. cv::warpPerspective with WARP_INVERSE_MAP.
///
/// Throws std::invalid_argument when image2 is empty, size1 is not positive, h is not finite or is
/// singular, or the options fail check().
inline CorrectedImage warp_to_first_image(const cv::Mat& image2, const Eigen::Matrix3d& h, cv::Size size1,
                                          const ImageCorrectionOptions& options = {}) {
  options.check();
  detail::require(!image2.empty(), "warp_to_first_image: image2 is empty");
  detail::require(size1.width > 0 && size1.height > 0, "warp_to_first_image: size1 must be positive, got " +
                                                           std::to_string(size1.width) + "x" +
                                                           std::to_string(size1.height));
  detail::require(h.allFinite(), "warp_to_first_image: the homography has a non-finite entry");
  const Eigen::Matrix3d unit = h / h.norm();
  detail::require(unit.allFinite() && std::abs(unit.determinant()) > 1e-15,
                  "warp_to_first_image: the homography is singular");

  cv::Matx33d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = h(r, c);
  }
  CorrectedImage out;
  cv::warpPerspective(image2, out.image, cv::Mat(m), size1, options.interpolation | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar::all(options.border_value));

  out.valid.create(size1, CV_8UC1);
  const double margin = options.interpolation == cv::INTER_CUBIC      ? 1.0
                        : options.interpolation == cv::INTER_LANCZOS4 ? 3.0
                                                                      : 0.0;
  const double max_x = image2.cols - 1 - margin, max_y = image2.rows - 1 - margin;
  for (int y = 0; y < size1.height; ++y) {
    std::uint8_t* row = out.valid.ptr<std::uint8_t>(y);
    for (int x = 0; x < size1.width; ++x) {
      const double w = unit(2, 0) * x + unit(2, 1) * y + unit(2, 2);
      const double u = (unit(0, 0) * x + unit(0, 1) * y + unit(0, 2)) / w;
      const double v = (unit(1, 0) * x + unit(1, 1) * y + unit(1, 2)) / w;
      const bool inside = u >= margin && u <= max_x && v >= margin && v <= max_y;  // false for NaN
      row[x] = inside ? 255 : 0;
    }
  }
  out.success = true;
  return out;
}

/// Corrects image 2 with the homography of `selection` when select_model() chose it; returns
/// success = false (empty images) when it chose F or failed. Throws as warp_to_first_image().
inline CorrectedImage correct_image(const cv::Mat& image2, cv::Size size1, const ModelSelectionResult& selection,
                                    const ImageCorrectionOptions& options = {}) {
  options.check();
  detail::require(!image2.empty(), "correct_image: image2 is empty");
  detail::require(size1.width > 0 && size1.height > 0, "correct_image: size1 must be positive");
  if (!selection.success || selection.model != GeometricModel::kHomography) return {};
  return warp_to_first_image(image2, selection.homography, size1, options);
}

}  // namespace affine_orb
