// Every wrong or extreme input of the public API, one test case per row of docs/robustness.md.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "affine_orb/matching/matcher.hpp"
#include "test_data.hpp"

namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

/// Both descriptors, plain and with the default 18 affine views.
template <class Check>
void for_each_extractor(Check check) {
  for (double max_tilt : {1.0, 2.0 * std::sqrt(2.0)}) {
    affine_orb::ExtractorOptions options;
    options.features = 300;
    options.views.max_tilt = max_tilt;
    options.threads = 2;
    CAPTURE(max_tilt);
    affine_orb::Extractor<affine_orb::Rbrief> rbrief(options);
    check(rbrief);
    affine_orb::Extractor<affine_orb::Brisk> brisk(options);
    check(brisk);
  }
}

/// The message of the std::invalid_argument `fn` throws ("" when it throws nothing).
template <class Fn>
std::string invalid_argument_message(Fn fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

cv::Mat noise(int width, int height, unsigned seed) {
  cv::Mat image(height, width, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

void rejects_options(void (*mutate)(affine_orb::ExtractorOptions&)) {
  affine_orb::ExtractorOptions options;
  mutate(options);
  CHECK_THROWS_AS(affine_orb::Extractor<affine_orb::Rbrief>{options}, std::invalid_argument);
}

}  // namespace

TEST_CASE("empty image: std::invalid_argument naming the problem") {
  for_each_extractor([](auto& extractor) {
    CHECK(invalid_argument_message([&] { extractor.extract(cv::Mat()); }).find("empty") != std::string::npos);
  });
}

TEST_CASE("wrong pixel types (CV_8UC3, CV_16U, CV_32F, CV_8UC4): std::invalid_argument naming the type") {
  for_each_extractor([](auto& extractor) {
    for (int type : {CV_8UC3, CV_16UC1, CV_32FC1, CV_8UC4, CV_8SC1}) {
      const std::string message =
          invalid_argument_message([&] { extractor.extract(cv::Mat(64, 64, type, cv::Scalar::all(1))); });
      CHECK(message.find(cv::typeToString(type)) != std::string::npos);
    }
  });
}

TEST_CASE("masks of the wrong size or type: std::invalid_argument") {
  const cv::Mat image = affine_orb::test::textured_photo();
  for_each_extractor([&](auto& extractor) {
    CHECK_THROWS_AS(extractor.extract(image, cv::Mat(10, 10, CV_8UC1, cv::Scalar(1))), std::invalid_argument);
    CHECK_THROWS_AS(extractor.extract(image, cv::Mat(image.cols, image.rows, CV_8UC1, cv::Scalar(1))),
                    std::invalid_argument);
    CHECK_THROWS_AS(extractor.extract(image, cv::Mat(image.size(), CV_32FC1, cv::Scalar(1))), std::invalid_argument);
    CHECK_THROWS_AS(extractor.extract(image, cv::Mat(image.size(), CV_8UC3, cv::Scalar::all(1))),
                    std::invalid_argument);
  });
}

TEST_CASE("1x1, 10x10, 10x10000 and 10000x10 images: empty result") {
  for_each_extractor([](auto& extractor) {
    CHECK(extractor.extract(cv::Mat(1, 1, CV_8UC1, cv::Scalar(7))).empty());
    CHECK(extractor.extract(noise(10, 10, 1)).empty());
    CHECK(extractor.extract(noise(10000, 10, 2)).empty());
    CHECK(extractor.extract(noise(10, 10000, 3)).empty());
  });
}

TEST_CASE("image smaller than the descriptor patch: empty result") {
  const cv::Mat photo = affine_orb::test::graf(1);
  for_each_extractor([&](auto& extractor) {
    const int side = 2 * extractor.descriptor().border();
    CHECK(extractor.extract(photo(cv::Rect(300, 300, side, side)).clone()).empty());
  });
}

TEST_CASE("all-black and all-white images: empty result") {
  for_each_extractor([](auto& extractor) {
    CHECK(extractor.extract(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0))).empty());
    CHECK(extractor.extract(cv::Mat(480, 640, CV_8UC1, cv::Scalar(255))).empty());
  });
}

TEST_CASE("pure noise: the full budget, every keypoint inside the image") {
  const cv::Mat image = noise(320, 240, 9);
  for_each_extractor([&](auto& extractor) {
    const auto f = extractor.extract(image);
    // 300 of the image, and with the views on as many again from them (the additive budget).
    CHECK(f.size() == (extractor.options().views.max_tilt > 1.0 ? 600u : 300u));
    for (const auto& kp : f.keypoints) {
      CHECK(kp.pt.x >= 0);
      CHECK(kp.pt.y >= 0);
      CHECK(kp.pt.x <= image.cols - 1);
      CHECK(kp.pt.y <= image.rows - 1);
    }
  });
}

TEST_CASE("non-continuous ROI of a larger image: the same result as its copy") {
  const cv::Mat big = affine_orb::test::textured_photo();
  const cv::Mat roi = big(cv::Rect(37, 41, 400, 300));
  REQUIRE_FALSE(roi.isContinuous());
  for_each_extractor([&](auto& extractor) {
    const auto a = extractor.extract(roi);
    const auto b = extractor.extract(roi.clone());
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      CHECK(a.keypoints[i].pt == b.keypoints[i].pt);
      CHECK(a.descriptors[i] == b.descriptors[i]);
    }
  });
}

TEST_CASE("zero, negative, NaN and huge options: std::invalid_argument") {
  rejects_options([](auto& o) { o.features = 0; });
  rejects_options([](auto& o) { o.features = -1; });
  rejects_options([](auto& o) { o.features = std::numeric_limits<int>::max(); });
  rejects_options([](auto& o) { o.pyramid.scale_factor = kNan; });
  rejects_options([](auto& o) { o.pyramid.scale_factor = kInf; });
  rejects_options([](auto& o) { o.pyramid.scale_factor = 0.0; });
  rejects_options([](auto& o) { o.pyramid.scale_factor = 1.0; });
  rejects_options([](auto& o) { o.pyramid.levels = 0; });
  rejects_options([](auto& o) { o.pyramid.levels = 1000; });
  rejects_options([](auto& o) { o.detector.initial_threshold = 0; });
  rejects_options([](auto& o) { o.detector.initial_threshold = 1000; });
  rejects_options([](auto& o) { o.detector.min_threshold = -5; });
  rejects_options([](auto& o) { o.detector.min_threshold = 50; });
  rejects_options([](auto& o) { o.detector.cell_size = 0; });
  rejects_options([](auto& o) { o.detector.harris_k = static_cast<float>(kNan); });
  rejects_options([](auto& o) { o.detector.score = static_cast<affine_orb::ScoreType>(9); });
  rejects_options([](auto& o) { o.views.max_tilt = 0.0; });
  rejects_options([](auto& o) { o.views.max_tilt = kNan; });
  rejects_options([](auto& o) { o.views.max_tilt = 1e9; });
  rejects_options([](auto& o) { o.views.tilt_ratio = 1.0; });
  rejects_options([](auto& o) { o.views.rotation_base_degrees = -72.0; });
  rejects_options([](auto& o) { o.views.antialias = kInf; });
  rejects_options([](auto& o) { o.threads = 0; });
  rejects_options([](auto& o) { o.threads = 100000; });
  rejects_options([](auto& o) { o.merge_duplicates->radius = kNan; });
  rejects_options([](auto& o) { o.merge_duplicates->repeat_levels = 5; });
  rejects_options([](auto& o) { o.snap_to_corners = affine_orb::CornerSnapOptions{-1}; });
  rejects_options([](auto& o) { std::get<affine_orb::AdditiveBudget>(o.view_budget).view_features = kInf; });
  affine_orb::RbriefOptions rbrief;
  rbrief.blur_sigma = kNan;
  CHECK_THROWS_AS(affine_orb::Rbrief{rbrief}, std::invalid_argument);
  affine_orb::BriskOptions brisk;
  brisk.pattern_scale = 0.0;
  CHECK_THROWS_AS(affine_orb::Brisk{brisk}, std::invalid_argument);
}

TEST_CASE("more views than pixels: a 24x24 image with max tilt 16 gives a valid, possibly empty, result") {
  affine_orb::ExtractorOptions options;
  options.views.max_tilt = 16.0;
  options.features = 50;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  const auto f = extractor.extract(noise(24, 24, 4));
  CHECK(extractor.views().size() > 24 * 24 / 8);
  CHECK(f.size() <= 50);
}

TEST_CASE("matcher inputs of different descriptor widths, wrong types or zero rows") {
  const cv::Mat a(10, 32, CV_8U, cv::Scalar(1));
  const cv::Mat b(10, 64, CV_8U, cv::Scalar(1));
  CHECK_THROWS_AS(affine_orb::match(a, b), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::match(cv::Mat(10, 32, CV_32F), cv::Mat(10, 32, CV_32F)), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::match(cv::Mat(10, 12, CV_8U), cv::Mat(10, 12, CV_8U)), std::invalid_argument);
  CHECK(affine_orb::match(cv::Mat(0, 32, CV_8U), a).empty());
  CHECK(affine_orb::match(a, cv::Mat()).empty());
  affine_orb::MatcherOptions options;
  options.ratio = static_cast<float>(kNan);
  CHECK_THROWS_AS(affine_orb::match(a, a, options), std::invalid_argument);
  options = {};
  options.max_distance = -1;
  CHECK_THROWS_AS(affine_orb::match(a, a, options), std::invalid_argument);
  // Feature sets: empty ones match nothing; inconsistent ones are rejected.
  affine_orb::Features<256> empty;
  affine_orb::Features<256> broken;
  broken.keypoints.resize(3);
  CHECK(affine_orb::match_features(empty, empty).empty());
  CHECK_THROWS_AS(affine_orb::match_features(broken, broken), std::invalid_argument);
}

TEST_CASE("model selection inputs: mismatched sizes, NaN, too few, identical and collinear points") {
  std::vector<cv::Point2f> p(20), q(20);
  for (int i = 0; i < 20; ++i) {
    p[static_cast<std::size_t>(i)] = {static_cast<float>(i * 13 % 97), static_cast<float>(i * 29 % 89)};
    q[static_cast<std::size_t>(i)] = p[static_cast<std::size_t>(i)] + cv::Point2f(3, 1);
  }
  CHECK_THROWS_AS(affine_orb::select_model(p, std::vector<cv::Point2f>(q.begin(), q.end() - 1)), std::invalid_argument);
  auto nan_points = p;
  nan_points[5].x = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(affine_orb::select_model(nan_points, q), std::invalid_argument);
  CHECK_FALSE(affine_orb::select_model(std::vector<cv::Point2f>(p.begin(), p.begin() + 5),
                                       std::vector<cv::Point2f>(q.begin(), q.begin() + 5))
                  .success);
  CHECK_FALSE(
      affine_orb::select_model(std::vector<cv::Point2f>(20, {5, 5}), std::vector<cv::Point2f>(20, {7, 7})).success);
  std::vector<cv::Point2f> line1, line2;
  for (int i = 0; i < 30; ++i) {
    line1.emplace_back(static_cast<float>(i), static_cast<float>(2 * i));
    line2.emplace_back(static_cast<float>(i + 1), static_cast<float>(2 * i + 1));
  }
  CHECK_FALSE(affine_orb::select_model(line1, line2).success);
  affine_orb::ModelSelectionOptions options;
  options.sigma = -1.0;
  CHECK_THROWS_AS(affine_orb::select_model(p, q, options), std::invalid_argument);
}
