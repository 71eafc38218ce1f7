#pragma once
/// \file
/// Image buffers that images of varying sizes share without reallocating.

#include <algorithm>

#include <opencv2/core.hpp>

namespace affine_orb::detail {

/// A `size` x `type` matrix in the top-left corner of `storage` (a ROI: its step is storage's row
/// step), reallocating `storage` only when it is too small or of another type: grown to the
/// largest size asked for, never shrunk. An empty size gives an empty matrix.
inline cv::Mat fit_buffer(cv::Mat& storage, cv::Size size, int type) {
  if (size.width <= 0 || size.height <= 0) return cv::Mat();
  if (storage.type() != type || storage.rows < size.height || storage.cols < size.width) {
    storage.create(std::max(storage.rows, size.height), std::max(storage.cols, size.width), type);
  }
  return storage(cv::Rect(0, 0, size.width, size.height));
}

}  // namespace affine_orb::detail
