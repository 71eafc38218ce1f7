// rBRIEF-256 and the intensity-centroid angle against plain reference implementations of their
// definitions (Rublee et al., ICCV 2011), on real photos.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/detail/orb_pattern.hpp"
#include "affine_orb/extractor.hpp"
#include "affine_orb/rbrief.hpp"
#include "test_data.hpp"

namespace {

// m10 = Σ u I, m01 = Σ v I over the disc u² + v² <= r², angle = atan2(m01, m10).
float naive_centroid_angle(const cv::Mat& image, int x, int y, int r) {
  double m10 = 0.0;
  double m01 = 0.0;
  for (int v = -r; v <= r; ++v) {
    for (int u = -r; u <= r; ++u) {
      if (u * u + v * v > r * r) continue;
      const double value = image.at<uchar>(y + v, x + u);
      m10 += u * value;
      m01 += v * value;
    }
  }
  return std::atan2(static_cast<float>(m01), static_cast<float>(m10));
}

// Bit i = [I_s(c + R a_i) < I_s(c + R b_i)], byte i / 8, bit i % 8 (OpenCV's byte layout).
std::vector<uchar> naive_rbrief(const cv::Mat& smoothed, cv::Point2f pt, float angle) {
  const float a = std::cos(angle);
  const float b = std::sin(angle);
  const int cx = cvRound(pt.x);
  const int cy = cvRound(pt.y);
  std::vector<uchar> bytes(32, 0);
  for (int i = 0; i < 256; ++i) {
    const auto& p = affine_orb::detail::kOrbTestPairs[static_cast<std::size_t>(i)];
    const int ax = cx + cvRound(p.xa * a - p.ya * b);
    const int ay = cy + cvRound(p.xa * b + p.ya * a);
    const int bx = cx + cvRound(p.xb * a - p.yb * b);
    const int by = cy + cvRound(p.xb * b + p.yb * a);
    if (smoothed.at<uchar>(ay, ax) < smoothed.at<uchar>(by, bx)) bytes[static_cast<std::size_t>(i / 8)] |= 1u << (i % 8);
  }
  return bytes;
}

}  // namespace

TEST_CASE("ORB's published pair table is the one in the ORB paper's distribution") {
  const auto& pairs = affine_orb::detail::kOrbTestPairs;
  // Spot checks against the published table (first, second and last rows) and its range.
  CHECK(pairs[0].xa == 8);
  CHECK(pairs[0].ya == -3);
  CHECK(pairs[0].xb == 9);
  CHECK(pairs[0].yb == 5);
  CHECK(pairs[1].xa == 4);
  CHECK(pairs[1].yb == -12);
  CHECK(pairs[255].xa == -1);
  CHECK(pairs[255].ya == -6);
  CHECK(pairs[255].xb == 0);
  CHECK(pairs[255].yb == -11);
  for (const auto& p : pairs) {
    for (int c : {p.xa, p.ya, p.xb, p.yb}) {
      CHECK(c >= -13);
      CHECK(c <= 12);
    }
  }
}

TEST_CASE("rBRIEF bits and centroid angles equal the naive definitions on every level") {
  const cv::Mat image = affine_orb::test::oxford_image("boat", 1);
  affine_orb::ExtractorOptions options;
  options.features = 1500;
  options.views.max_tilt = 1.0;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  const auto features = extractor.extract(image);
  REQUIRE(features.size() == 1500);
  const cv::Mat mat = affine_orb::descriptors_to_mat(features.descriptors);
  REQUIRE(mat.rows == 1500);
  REQUIRE(mat.cols == 32);

  std::vector<cv::Mat> smoothed(static_cast<std::size_t>(extractor.pyramid().levels()));
  for (int l = 0; l < extractor.pyramid().levels(); ++l) {
    cv::GaussianBlur(extractor.pyramid().level(l), smoothed[static_cast<std::size_t>(l)], cv::Size(7, 7), 2, 2,
                     cv::BORDER_REFLECT_101);
  }
  int angle_mismatch = 0;
  int bit_mismatch = 0;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const cv::KeyPoint& kp = features.keypoints[i];
    const int level = kp.octave;
    // Back to the integer level position the keypoint was detected at.
    const cv::Mat& level_image = extractor.pyramid().level(level);
    const float sx = static_cast<float>(image.cols) / static_cast<float>(level_image.cols);
    const float sy = static_cast<float>(image.rows) / static_cast<float>(level_image.rows);
    const cv::Point2f p((kp.pt.x + 0.5f) / sx - 0.5f, (kp.pt.y + 0.5f) / sy - 0.5f);
    const int x = cvRound(p.x);
    const int y = cvRound(p.y);
    CHECK(std::abs(p.x - static_cast<float>(x)) < 1e-3f);
    CHECK(std::abs(p.y - static_cast<float>(y)) < 1e-3f);
    const float angle = naive_centroid_angle(level_image, x, y, 15);
    float degrees = angle * static_cast<float>(180.0 / CV_PI);
    if (degrees < 0) degrees += 360.0f;
    const float diff = std::abs(degrees - kp.angle);
    angle_mismatch += std::min(diff, 360.0f - diff) > 1e-3f;
    const std::vector<uchar> expected =
        naive_rbrief(smoothed[static_cast<std::size_t>(level)], cv::Point2f(static_cast<float>(x), static_cast<float>(y)),
                     angle);
    for (int b = 0; b < 32; ++b) bit_mismatch += expected[static_cast<std::size_t>(b)] != mat.at<uchar>(static_cast<int>(i), b);
  }
  CHECK(angle_mismatch == 0);
  CHECK(bit_mismatch == 0);
}

TEST_CASE("rBRIEF describe() matches the definition at arbitrary angles") {
  const cv::Mat image = affine_orb::test::oxford_image("bark", 1);
  affine_orb::Rbrief rbrief;
  affine_orb::Rbrief::LevelData data;
  rbrief.prepare(image, data);
  cv::Mat smoothed;
  cv::GaussianBlur(image, smoothed, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> angle(-3.2f, 3.2f);
  std::uniform_int_distribution<int> px(rbrief.border(), image.cols - 1 - rbrief.border());
  std::uniform_int_distribution<int> py(rbrief.border(), image.rows - 1 - rbrief.border());
  int mismatches = 0;
  for (int k = 0; k < 500; ++k) {
    const cv::Point2f pt(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
    const float theta = angle(rng);
    const auto descriptor = rbrief.describe(data, pt, theta);
    const cv::Mat row = affine_orb::descriptors_to_mat(std::vector<affine_orb::BinaryDescriptor<256>>{descriptor});
    const auto expected = naive_rbrief(smoothed, pt, theta);
    for (int b = 0; b < 32; ++b) mismatches += expected[static_cast<std::size_t>(b)] != row.at<uchar>(0, b);
  }
  CHECK(mismatches == 0);
  // Corner reads stay inside: the farthest rotated test point plus rounding is the border.
  CHECK(rbrief.border() == 18);
}

TEST_CASE("rBRIEF options are checked") {
  affine_orb::RbriefOptions options;
  options.blur_kernel = 6;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.blur_sigma = std::nan("");
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.blur_sigma = -1;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.orientation_radius = 0;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  affine_orb::Rbrief rbrief;
  affine_orb::Rbrief::LevelData data;
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(), data), std::invalid_argument);
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(40, 40, CV_8UC3), data), std::invalid_argument);
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(40, 40, CV_32F), data), std::invalid_argument);
}
