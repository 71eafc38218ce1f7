// ExtractorOptions::subpixel against an independent reference: a pattern rendered at 8x and
// reduced by area averaging, once as it is and once warped by a known homography, so that the
// scene point under a keypoint of the first image lands at a known sub-pixel position of the
// second. Sub-pixel keypoints land closer to it than integer ones; only the positions change.
#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "test_data.hpp"

namespace {

using affine_orb::test::apply_homography;

constexpr int kSupersampling = 8;

/// Random filled triangles and rectangles of random grey levels on a grey background, at
/// kSupersampling times `size`.
cv::Mat fine_pattern(cv::Size size, unsigned seed) {
  const int s = kSupersampling;
  cv::Mat fine(size.height * s, size.width * s, CV_8UC1, cv::Scalar(128));
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  std::uniform_int_distribution<int> x(0, fine.cols - 1);
  std::uniform_int_distribution<int> y(0, fine.rows - 1);
  std::uniform_int_distribution<int> extent(6 * s, 30 * s);
  for (int i = 0; i < 600; ++i) {
    const cv::Point a(x(random), y(random));
    if (i % 2 == 0) {
      cv::rectangle(fine, cv::Rect(a.x, a.y, extent(random), extent(random)), cv::Scalar(grey(random)), cv::FILLED);
    } else {
      const cv::Point triangle[] = {a, a + cv::Point(extent(random), extent(random) / 3),
                                    a + cv::Point(extent(random) / 4, extent(random))};
      cv::fillConvexPoly(fine, triangle, 3, cv::Scalar(grey(random)));
    }
  }
  return fine;
}

/// The fine pattern warped by `h` (x' ~ h·x, pixels of the reduced image) and reduced by area
/// averaging.
cv::Mat render(const cv::Mat& fine, const cv::Matx33d& h) {
  const double s = kSupersampling;
  // Reduced pixel x covers fine pixels s·x .. s·x + s − 1: its centre is s·x + (s − 1) / 2.
  const cv::Matx33d to_fine(s, 0, (s - 1) / 2, 0, s, (s - 1) / 2, 0, 0, 1);
  cv::Mat warped;
  cv::warpPerspective(fine, warped, to_fine * h * to_fine.inv(), fine.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::Mat image;
  cv::resize(warped, image, cv::Size(fine.cols / kSupersampling, fine.rows / kSupersampling), 0, 0, cv::INTER_AREA);
  return image;
}

affine_orb::Features<256> extract(const cv::Mat& image, bool subpixel, double max_tilt = 1.0) {
  affine_orb::ExtractorOptions options;
  options.features = 1500;
  options.spreading = affine_orb::Spreading::kStrongest;
  options.views.max_tilt = max_tilt;
  options.subpixel = subpixel;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  return extractor.extract(image);
}

/// Mean distance, pixels of image 2, between H·x1 and x2 over the pairs of keypoints of the same
/// octave whose integer positions (`integer1`, `integer2`) lie within 1.5 level pixels of each
/// other under H; the positions compared are those of `f1` and `f2`, and `pairs` counts them.
double mean_residual(const affine_orb::Features<256>& integer1, const affine_orb::Features<256>& integer2,
                     const affine_orb::Features<256>& f1, const affine_orb::Features<256>& f2, const cv::Matx33d& h,
                     int& pairs) {
  double sum = 0.0;
  pairs = 0;
  for (std::size_t i = 0; i < integer1.size(); ++i) {
    const cv::KeyPoint& a = integer1.keypoints[i];
    const cv::Point2d p = apply_homography(h, a.pt);
    const double reach = 1.5 * std::pow(1.2, a.octave);
    for (std::size_t j = 0; j < integer2.size(); ++j) {
      const cv::KeyPoint& b = integer2.keypoints[j];
      if (b.octave != a.octave || std::hypot(p.x - b.pt.x, p.y - b.pt.y) > reach) continue;
      const cv::Point2d q = apply_homography(h, f1.keypoints[i].pt);
      sum += std::hypot(q.x - f2.keypoints[j].pt.x, q.y - f2.keypoints[j].pt.y);
      ++pairs;
      break;
    }
  }
  return pairs > 0 ? sum / pairs : 0.0;
}

}  // namespace

TEST_CASE("sub-pixel keypoints land nearer the ground truth than integer ones under a known homography") {
  const cv::Mat fine = fine_pattern(cv::Size(640, 480), 7);
  const cv::Mat image1 = render(fine, cv::Matx33d::eye());
  // A small rotation, zoom and sub-pixel shift, with a little perspective.
  const double angle = 0.05;
  const cv::Matx33d h(1.03 * std::cos(angle), -1.03 * std::sin(angle), 9.37, 1.03 * std::sin(angle),
                      1.03 * std::cos(angle), -6.61, 2e-5, -1e-5, 1.0);
  const cv::Mat image2 = render(fine, h);

  const auto integer1 = extract(image1, false);
  const auto integer2 = extract(image2, false);
  const auto refined1 = extract(image1, true);
  const auto refined2 = extract(image2, true);
  int pairs_integer = 0, pairs_refined = 0;
  const double integer = mean_residual(integer1, integer2, integer1, integer2, h, pairs_integer);
  const double refined = mean_residual(integer1, integer2, refined1, refined2, h, pairs_refined);
  CAPTURE(integer);
  CAPTURE(refined);
  REQUIRE(pairs_integer >= 200);
  CHECK(pairs_refined == pairs_integer);
  CHECK(refined < 0.85 * integer);
}

TEST_CASE("sub-pixel positions change only the positions, by at most half a level pixel per axis") {
  const cv::Mat image = affine_orb::test::graf(1);
  for (const double max_tilt : {1.0, 2.0}) {
    CAPTURE(max_tilt);
    const auto integer = extract(image, false, max_tilt);
    const auto refined = extract(image, true, max_tilt);
    REQUIRE(integer.size() == refined.size());
    REQUIRE(integer.size() > 1000);
    int moved = 0;
    for (std::size_t i = 0; i < integer.size(); ++i) {
      const cv::KeyPoint& a = integer.keypoints[i];
      const cv::KeyPoint& b = refined.keypoints[i];
      CHECK(a.octave == b.octave);
      CHECK(a.angle == b.angle);
      CHECK(a.size == b.size);
      CHECK(a.response == b.response);
      CHECK(integer.views[i] == refined.views[i]);
      CHECK(integer.descriptors[i] == refined.descriptors[i]);
      if (integer.views[i] == 0) {
        // Half a pixel of the keypoint's level per axis (1.2^octave original pixels, to the
        // rounding of the level size).
        const double bound = 0.5 * std::pow(1.2, a.octave) * 1.01 + 1e-3;
        CHECK(std::abs(a.pt.x - b.pt.x) <= bound);
        CHECK(std::abs(a.pt.y - b.pt.y) <= bound);
      } else {
        // Half a level pixel per axis of a view level of scale at most 1.2^7, stretched by at most
        // the tilt on its way back.
        CHECK(std::hypot(a.pt.x - b.pt.x, a.pt.y - b.pt.y) <= std::sqrt(0.5) * max_tilt * std::pow(1.2, 7) * 1.01);
      }
      moved += a.pt != b.pt;
    }
    CHECK(moved > static_cast<int>(integer.size()) / 2);
  }
}

TEST_CASE("without sub-pixel positions every image keypoint lies on a pixel of its level") {
  const cv::Mat image = affine_orb::test::textured_photo();
  const auto f = extract(image, false);
  REQUIRE(f.size() > 1000);
  for (const cv::KeyPoint& k : f.keypoints) {
    // The inverse of Pyramid::to_level0.
    const cv::Size level = affine_orb::pyramid_level_size(image.size(), affine_orb::PyramidOptions{}, k.octave);
    const double x = (k.pt.x + 0.5) * level.width / image.cols - 0.5;
    const double y = (k.pt.y + 0.5) * level.height / image.rows - 0.5;
    CHECK(std::abs(x - std::round(x)) < 1e-3);
    CHECK(std::abs(y - std::round(y)) < 1e-3);
  }
}
