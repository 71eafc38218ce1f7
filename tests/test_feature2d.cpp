// affine_orb behind cv::Feature2D (opencv_feature2d.hpp): the same bytes as Extractor::extract(),
// compute() on given keypoints, interplay with cv::BFMatcher and cv::drawMatches, and the library's
// errors for bad input.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/extraction/opencv_feature2d.hpp"
#include "test_data.hpp"

namespace {

bool same_keypoints(const std::vector<cv::KeyPoint>& a, const std::vector<cv::KeyPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].pt != b[i].pt || a[i].angle != b[i].angle || a[i].size != b[i].size || a[i].octave != b[i].octave ||
        a[i].response != b[i].response)
      return false;
  }
  return true;
}

}  // namespace

TEST_CASE("detectAndCompute and detect give exactly Extractor::extract's keypoints and rows") {
  for (const double max_tilt : {1.0, 2.0 * std::sqrt(2.0)}) {
    for (const auto kind : {affine_orb::DescriptorKind::kRbrief, affine_orb::DescriptorKind::kBrisk}) {
      CAPTURE(max_tilt);
      CAPTURE(static_cast<int>(kind));
      affine_orb::ExtractorOptions options;
      options.features = 800;
      options.views.max_tilt = max_tilt;
      options.threads = 2;
      const cv::Ptr<cv::Feature2D> f2d = affine_orb::create_feature2d(options, kind);
      CHECK(f2d->descriptorSize() == (kind == affine_orb::DescriptorKind::kRbrief ? 32 : 64));
      CHECK(f2d->descriptorType() == CV_8U);
      CHECK(f2d->defaultNorm() == cv::NORM_HAMMING);
      CHECK(f2d->getDefaultName() == "Feature2D.AffineORB");
      for (const cv::Mat& image : {affine_orb::test::graf(1), affine_orb::test::textured_photo()}) {
        cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(255));
        mask(cv::Rect(0, 0, image.cols / 3, image.rows)).setTo(0);
        std::vector<cv::KeyPoint> keypoints;
        cv::Mat descriptors;
        f2d->detectAndCompute(image, mask, keypoints, descriptors);
        cv::Mat direct;
        std::vector<cv::KeyPoint> direct_keypoints;
        if (kind == affine_orb::DescriptorKind::kRbrief) {
          const auto f = affine_orb::Extractor<affine_orb::Rbrief>(options).extract(image, mask);
          direct = affine_orb::descriptors_to_mat(f.descriptors);
          direct_keypoints = f.keypoints;
        } else {
          const auto f = affine_orb::Extractor<affine_orb::Brisk>(options).extract(image, mask);
          direct = affine_orb::descriptors_to_mat(f.descriptors);
          direct_keypoints = f.keypoints;
        }
        REQUIRE(!keypoints.empty());
        CHECK(same_keypoints(keypoints, direct_keypoints));
        REQUIRE(descriptors.size() == direct.size());
        CHECK(descriptors.type() == CV_8UC1);
        CHECK(cv::norm(descriptors, direct, cv::NORM_HAMMING) == 0.0);
        std::vector<cv::KeyPoint> detected;
        f2d->detect(image, detected, mask);
        CHECK(same_keypoints(detected, direct_keypoints));
      }
    }
  }
}

TEST_CASE("compute on the extractor's own image keypoints reproduces their rows; bad keypoints are removed") {
  const cv::Mat image = affine_orb::test::textured_photo();
  affine_orb::ExtractorOptions options;
  options.views.max_tilt = 1.0;
  const cv::Ptr<cv::Feature2D> f2d = affine_orb::create_feature2d(options);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  f2d->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
  REQUIRE(keypoints.size() == 1000);
  std::vector<cv::KeyPoint> given = keypoints;
  // Two the compute cannot describe (outside the image, support beyond the border) and one without
  // an angle, which gets the orientation there.
  given.emplace_back(-20.0f, 5.0f, 31.0f, 10.0f, 0.0f, 0);
  given.emplace_back(2.0f, 2.0f, 31.0f, 10.0f, 0.0f, 0);
  cv::KeyPoint unoriented = keypoints.front();
  unoriented.angle = -1.0f;
  given.push_back(unoriented);
  cv::Mat computed;
  f2d->compute(image, given, computed);
  REQUIRE(given.size() == 1001);
  REQUIRE(computed.rows == 1001);
  CHECK(cv::norm(computed.rowRange(0, 1000), descriptors, cv::NORM_HAMMING) == 0.0);
  CHECK(given.back().angle == keypoints.front().angle);
  CHECK(cv::norm(computed.row(1000), descriptors.row(0), cv::NORM_HAMMING) == 0.0);
}

TEST_CASE("the descriptors feed cv::BFMatcher and cv::drawMatches, and match graf 1 to 3 correctly") {
  const cv::Mat a = affine_orb::test::graf(1);
  const cv::Mat b = affine_orb::test::graf(3);
  const cv::Ptr<cv::Feature2D> f2d = affine_orb::create_feature2d();
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  f2d->detectAndCompute(a, cv::noArray(), ka, da);
  f2d->detectAndCompute(b, cv::noArray(), kb, db);
  cv::BFMatcher matcher(f2d->defaultNorm(), true);
  std::vector<cv::DMatch> matches;
  matcher.match(da, db, matches);
  REQUIRE(matches.size() > 100);
  const cv::Matx33d h = affine_orb::test::graf_homography_1to3();
  int correct = 0;
  for (const cv::DMatch& m : matches) {
    const cv::Point2f p = ka[static_cast<std::size_t>(m.queryIdx)].pt;
    const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
    const cv::Point2f r = kb[static_cast<std::size_t>(m.trainIdx)].pt;
    correct += std::hypot(q[0] / q[2] - r.x, q[1] / q[2] - r.y) < 3.0;
  }
  MESSAGE("graf 1->3 through cv::BFMatcher (cross-check): " << correct << " correct of " << matches.size());
  CHECK(correct > 100);
  cv::Mat canvas;
  cv::drawMatches(a, ka, b, kb, matches, canvas);
  CHECK(canvas.cols == a.cols + b.cols);
}

TEST_CASE("bad input through the interface gives the library's errors") {
  const cv::Ptr<cv::Feature2D> f2d = affine_orb::create_feature2d();
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  CHECK_THROWS_AS(f2d->detectAndCompute(cv::Mat(), cv::noArray(), keypoints, descriptors), std::invalid_argument);
  CHECK_THROWS_AS(f2d->detectAndCompute(cv::Mat(40, 40, CV_8UC3), cv::noArray(), keypoints, descriptors),
                  std::invalid_argument);
  CHECK_THROWS_AS(
      f2d->detectAndCompute(cv::Mat(40, 40, CV_8UC1, cv::Scalar(9)), cv::Mat(20, 40, CV_8UC1), keypoints, descriptors),
      std::invalid_argument);
  CHECK_THROWS_AS(f2d->compute(cv::Mat(40, 40, CV_32F), keypoints, descriptors), std::invalid_argument);
  affine_orb::ExtractorOptions nonsense;
  nonsense.features = 0;
  CHECK_THROWS_AS(affine_orb::create_feature2d(nonsense), std::invalid_argument);
  // A flat image: no keypoint, descriptors released.
  f2d->detectAndCompute(cv::Mat(64, 64, CV_8UC1, cv::Scalar(7)), cv::noArray(), keypoints, descriptors);
  CHECK(keypoints.empty());
  CHECK(descriptors.empty());
  // Given keypoints with a NaN or infinite angle (fuzz_describe's case): rBRIEF's rotated test
  // points would be undefined, so both descriptors reject them; −infinity is < 0, "not computed".
  const cv::Mat image = affine_orb::test::graf(1)(cv::Rect(100, 100, 120, 120)).clone();
  for (const auto kind : {affine_orb::DescriptorKind::kRbrief, affine_orb::DescriptorKind::kBrisk}) {
    const cv::Ptr<cv::Feature2D> f = affine_orb::create_feature2d({}, kind);
    for (const float angle : {std::nanf(""), std::numeric_limits<float>::infinity()}) {
      std::vector<cv::KeyPoint> given{cv::KeyPoint(60.0f, 60.0f, 31.0f, angle, 0.0f, 0)};
      CHECK_THROWS_AS(f->compute(image, given, descriptors), std::invalid_argument);
    }
    std::vector<cv::KeyPoint> given{
        cv::KeyPoint(60.0f, 60.0f, 31.0f, -std::numeric_limits<float>::infinity(), 0.0f, 0)};
    f->compute(image, given, descriptors);
    REQUIRE(given.size() == 1);
    CHECK(given[0].angle >= 0.0f);
    CHECK(given[0].angle < 360.0f);
  }
}
