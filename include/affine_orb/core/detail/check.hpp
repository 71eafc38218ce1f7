#pragma once
/// \file
/// Argument checking shared by every public entry point: a failed check throws
/// std::invalid_argument with a message that names the function and the offending value.

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace affine_orb::detail {

/// Throws std::invalid_argument(`what`) unless `condition` holds.
inline void require(bool condition, const std::string& what) {
  if (!condition) throw std::invalid_argument("affine_orb: " + what);
}

/// require() for a fixed message: nothing is built or allocated when `condition` holds, so hot
/// paths can check their arguments on every frame.
inline void require(bool condition, const char* what) {
  if (!condition) throw std::invalid_argument(std::string("affine_orb: ") + what);
}

/// An interval of allowed values for require_range(): [lo, hi] with each end open on request.
/// Infinite ends are allowed; NaN lies in no range.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();  ///< lower end
  double hi = std::numeric_limits<double>::infinity();   ///< upper end
  bool lo_open = false;                                  ///< excludes lo
  bool hi_open = false;                                  ///< excludes hi

  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
};

/// (0, inf): a positive finite value.
inline constexpr Range kPositive{0.0, std::numeric_limits<double>::infinity(), true, true};
/// [0, inf): a non-negative finite value.
inline constexpr Range kNonNegative{0.0, std::numeric_limits<double>::infinity(), false, true};

/// Throws std::invalid_argument("affine_orb: <what> must be in [lo, hi], got <value>") unless
/// `value` lies in `range`; `what` names the option ("TwoViewOptions: min_inliers"). The message
/// is built only on failure.
inline void require_range(double value, Range range, const char* what) {
  if (range.contains(value)) return;
  std::ostringstream message;
  message.precision(12);
  message << what << " must be in " << (range.lo_open ? '(' : '[') << range.lo << ", " << range.hi
          << (range.hi_open ? ')' : ']') << ", got " << value;
  require(false, message.str());
}

/// Name of an OpenCV matrix type ("CV_8UC3") for error messages.
inline std::string type_name(int type) { return cv::typeToString(type); }

/// Checks that `image` is a non-empty single-channel 8-bit image (CV_8UC1); `who` names the caller.
/// The message is built only on failure (no allocation otherwise).
inline void require_gray8(const cv::Mat& image, const char* who) {
  if (image.empty()) require(false, std::string(who) + ": the image is empty");
  if (image.type() != CV_8UC1) {
    require(false, std::string(who) + ": the image must be CV_8UC1 (grey, 8-bit), got " + type_name(image.type()) +
                       "; convert colour images with cv::cvtColor");
  }
}

/// Checks that `mask` is empty (no mask) or a CV_8UC1 matrix of exactly `size`. The message is
/// built only on failure.
inline void require_mask(const cv::Mat& mask, cv::Size size, const char* who) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1)
    require(false, std::string(who) + ": the mask must be CV_8UC1, got " + type_name(mask.type()));
  if (mask.size() != size) {
    require(false, std::string(who) + ": the mask is " + std::to_string(mask.cols) + "x" + std::to_string(mask.rows) +
                       " but the image is " + std::to_string(size.width) + "x" + std::to_string(size.height));
  }
}

}  // namespace affine_orb::detail
