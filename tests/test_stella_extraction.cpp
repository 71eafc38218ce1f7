// StellaVslamKeypoints against stella_vslam's own orb_extractor, compiled from
// ../shared/slam/stock_extractors (tests/stock): the same keypoints (position, octave, angle, size,
// response), in the same order, with the same descriptor rows and the same pyramid, on the frames
// and photos of test_fork_extraction at several min_size, with its mask rectangles and with a mask.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "stock_stella.hpp"
#include "test_data.hpp"

namespace {

using affine_orb::Extractor;
using affine_orb::ExtractorOptions;
using affine_orb::MaskRectangle;
using affine_orb::Rbrief;
using affine_orb::StellaVslamKeypoints;
using affine_orb::stock::StockFrame;
using affine_orb::stock::StockStellaExtractor;

/// Keypoints of two outputs equal field by field at the same index, with equal descriptor rows.
struct Agreement {
  std::size_t stock = 0;
  std::size_t ours = 0;
  std::size_t identical = 0;
};

bool same_keypoint(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return a.pt.x == b.pt.x && a.pt.y == b.pt.y && a.octave == b.octave && a.angle == b.angle && a.size == b.size &&
         a.response == b.response;
}

Agreement compare(const StockFrame& stock, const affine_orb::Features<256>& ours) {
  Agreement a;
  a.stock = stock.keypoints.size();
  a.ours = ours.size();
  const cv::Mat rows = affine_orb::descriptors_to_mat(ours.descriptors);
  for (std::size_t i = 0; i < std::min(a.stock, a.ours); ++i) {
    if (!same_keypoint(stock.keypoints[i], ours.keypoints[i])) continue;
    if (std::memcmp(stock.descriptors.ptr(static_cast<int>(i)), rows.ptr(static_cast<int>(i)), 32) != 0) continue;
    ++a.identical;
  }
  return a;
}

/// Whether two pyramids have the same levels, byte for byte.
bool same_pyramid(const std::vector<cv::Mat>& a, const std::vector<cv::Mat>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t l = 0; l < a.size(); ++l) {
    if (a[l].size() != b[l].size() || cv::norm(a[l], b[l], cv::NORM_INF) != 0.0) return false;
  }
  return true;
}

/// A mask of `size` that hides a disc and a slanted band, edges at no cell boundary.
cv::Mat sample_mask(cv::Size size) {
  cv::Mat mask(size, CV_8UC1, cv::Scalar(255));
  cv::circle(mask, cv::Point(size.width / 3, size.height / 2), size.height / 5, cv::Scalar(0), cv::FILLED);
  cv::line(mask, cv::Point(0, size.height - 1), cv::Point(size.width - 1, size.height / 3), cv::Scalar(0), 25);
  return mask;
}

struct Case {
  unsigned min_size = 800;
  std::vector<MaskRectangle> rectangles;
  bool masked = false;  ///< extract() gets sample_mask()
};

/// stella's and our keypoints for `c` on `images`: the same keypoints in the same order with the
/// same rows and the same pyramid, every keypoint.
void check_identical(const std::vector<cv::Mat>& images, const Case& c) {
  ExtractorOptions options;
  options.views.max_tilt = 1.0;
  StellaVslamKeypoints stella;
  stella.min_size = static_cast<int>(c.min_size);
  stella.mask_rectangles = c.rectangles;
  options.image_keypoints = stella;
  Extractor<Rbrief> extractor(options);
  std::vector<std::vector<float>> rectangles;
  for (const MaskRectangle& r : c.rectangles) rectangles.push_back({r.x_min, r.x_max, r.y_min, r.y_max});
  std::size_t total = 0;
  std::size_t identical = 0;
  for (const cv::Mat& image : images) {
    // stella builds its rectangle mask for the first image size only: one extractor per image.
    StockStellaExtractor stock(1.2f, 8, 20, 7, c.min_size, rectangles);
    const cv::Mat mask = c.masked ? sample_mask(image.size()) : cv::Mat();
    std::vector<cv::Mat> levels;
    const affine_orb::Features<256> ours = extractor.extract(image, mask, levels);
    const StockFrame expected = stock.extract(image, mask);
    const Agreement a = compare(expected, ours);
    CHECK(a.ours == a.stock);
    CHECK(same_pyramid(expected.pyramid, levels));
    total += a.stock;
    identical += a.identical;
  }
  MESSAGE("min_size " << c.min_size << ", " << c.rectangles.size() << " rectangles, mask " << c.masked << ": "
                      << identical << " of " << total << " keypoints identical");
  CHECK(total > 100 * images.size());
  CHECK(identical == total);
}

void check_cases(const std::vector<cv::Mat>& images) {
  for (const unsigned min_size : {800u, 400u, 200u, 100u, 50u}) check_identical(images, {min_size, {}, false});
  const std::vector<MaskRectangle> rectangles = {{0.0f, 1.0f, 0.0f, 0.1f}, {0.313f, 0.547f, 0.61f, 1.0f}};
  check_identical(images, {800, rectangles, false});
  check_identical(images, {200, rectangles, false});
  check_identical(images, {800, {}, true});
  check_identical(images, {200, rectangles, true});  // the caller's mask wins over the rectangles
}

}  // namespace

TEST_CASE(
    "stella_vslam's image keypoints equal its own extractor's, in order and bit for bit, on opencv-doc's photos") {
  check_cases(affine_orb::test::conformance_sample_frames());
}

TEST_CASE("the same on KITTI and Oxford frames" * doctest::test_suite("data")) {
  check_cases(affine_orb::test::conformance_data_frames());
}

TEST_CASE("stella_vslam's options are checked") {
  ExtractorOptions options;
  StellaVslamKeypoints stella;
  stella.min_size = 0;
  options.image_keypoints = stella;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  stella.min_size = 800;
  stella.mask_rectangles = {{0.5f, 0.4f, 0.0f, 1.0f}};
  options.image_keypoints = stella;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  stella.mask_rectangles = {{0.0f, 1.0f, -0.1f, 1.0f}};
  options.image_keypoints = stella;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  stella.mask_rectangles = {{0.0f, 1.0f, 0.2f, 0.3f}};
  options.image_keypoints = stella;
  CHECK_NOTHROW(options.check());
  options.view_budget = affine_orb::AreaSplitBudget{};
  CHECK_THROWS_AS(options.check(), std::invalid_argument);  // a fork's keypoints need the additive budget
}
