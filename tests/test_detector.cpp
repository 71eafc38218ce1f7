// Tests of the detector (detection/detector.hpp): candidates in a region of row spans, the
// fallback to the minimum threshold, against definitions written from scratch.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/detection/detector.hpp"
#include "test_data.hpp"
#include "test_regions.hpp"

namespace {

// Candidates by definition: the suppressed corners of whole-image score maps at both thresholds;
// a grid cell keeps its strong corners in the region, or its weak ones if it has none.
std::vector<affine_orb::Corner> reference_candidates(const cv::Mat& image, const affine_orb::RowSpans& region,
                                                     cv::Point origin, const affine_orb::DetectorOptions& options) {
  const cv::Rect all(0, 0, image.cols, image.rows);
  auto corners_at = [&](int threshold) {
    cv::Mat scores;
    affine_orb::fast_score_map(image, all, threshold, scores);
    std::vector<affine_orb::Corner> out;
    for (const auto& c : affine_orb::non_max_suppression(scores, all, threshold)) {
      if (affine_orb::test::in_region(region, c.x, c.y)) out.push_back(c);
    }
    return out;
  };
  auto cell_of = [&](const affine_orb::Corner& c) {
    auto index = [&](int v, int o) {
      return static_cast<int>(std::floor(static_cast<double>(v - o) / options.cell_size));
    };
    return std::make_pair(index(c.x, origin.x), index(c.y, origin.y));
  };
  std::vector<affine_orb::Corner> out = corners_at(options.initial_threshold);
  std::set<std::pair<int, int>> strong;
  for (const auto& c : out) strong.insert(cell_of(c));
  for (const auto& c : corners_at(options.min_threshold)) {
    if (!strong.count(cell_of(c))) out.push_back(c);
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.y < b.y || (a.y == b.y && a.x < b.x); });
  return out;
}

}  // namespace

TEST_CASE("cells without corners at the initial threshold fall back to the minimum threshold") {
  // Dark 6x6 squares on a grey background (their corners are FAST corners): high contrast on the
  // left half, contrast 12 on the right (between min_threshold 7 and initial_threshold 20).
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(100));
  for (int y = 8; y + 6 < image.rows; y += 16) {
    for (int x = 8; x + 6 < image.cols; x += 16) {
      image(cv::Rect(x, y, 6, 6)).setTo(x < 160 ? 30 : 88);
    }
  }
  cv::Mat scores;
  affine_orb::DetectorOptions options;
  const cv::Rect roi(20, 20, 280, 200);
  const auto with_retry = affine_orb::detect_candidates(image, roi, options, scores);
  options.min_threshold = options.initial_threshold;
  const auto without_retry = affine_orb::detect_candidates(image, roi, options, scores);
  auto right_half = [](const affine_orb::Candidates& c) {
    return std::count_if(c.corners.begin(), c.corners.end(), [](const affine_orb::Corner& k) { return k.x >= 190; });
  };
  CHECK(right_half(without_retry) == 0);
  CHECK(right_half(with_retry) > 20);
  // The strong half is unaffected by the retry.
  CHECK(without_retry.corners.size() + right_half(with_retry) <= with_retry.corners.size());
}

TEST_CASE("candidates in a region equal whole-image corners filtered by region and grid cell") {
  const cv::Mat graf = affine_orb::test::graf(1)(cv::Rect(100, 80, 400, 300)).clone();
  // Low contrast in the right half, so that many cells have no corner at the initial threshold.
  cv::Mat image = graf.clone();
  image(cv::Rect(200, 0, 200, 300)) = graf(cv::Rect(200, 0, 200, 300)) * 0.15 + 100;
  affine_orb::DetectorWorkspace work;
  affine_orb::Candidates got;
  for (double angle : {0.0, 27.0, 61.0}) {
    for (const cv::Point origin : {cv::Point(18, 18), cv::Point(5, 40)}) {
      CAPTURE(angle);
      CAPTURE(origin);
      const affine_orb::RowSpans region = affine_orb::test::quad_region(image.size(), angle, 18);
      affine_orb::DetectorOptions options;
      const auto expected = reference_candidates(image, region, origin, options);
      affine_orb::detect_candidates(image, region, origin, options, work, got);
      REQUIRE(got.corners.size() == expected.size());
      REQUIRE(got.responses.size() == expected.size());
      int mismatches = 0;
      for (std::size_t i = 0; i < expected.size(); ++i) {
        mismatches += got.corners[i].x != expected[i].x || got.corners[i].y != expected[i].y ||
                      got.corners[i].score != expected[i].score ||
                      got.responses[i] != static_cast<float>(expected[i].score);
      }
      CHECK(mismatches == 0);
      const auto weak = std::count_if(expected.begin(), expected.end(),
                                      [&](const auto& c) { return c.score < options.initial_threshold; });
      CHECK(weak > 20);  // the fallback is exercised
      // Harris ranking: same corners, responses from harris_response().
      options.score = affine_orb::ScoreType::kHarris;
      affine_orb::detect_candidates(image, region, origin, options, work, got);
      REQUIRE(got.corners.size() == expected.size());
      for (std::size_t i = 0; i < expected.size(); i += 17) {
        CHECK(got.responses[i] == affine_orb::harris_response(image, expected[i].x, expected[i].y));
      }
    }
  }
  // A rectangle region is the rectangle overload.
  cv::Mat scores;
  const cv::Rect roi(18, 18, 300, 200);
  const auto rect = affine_orb::detect_candidates(image, roi, affine_orb::DetectorOptions{}, scores);
  const auto expected = reference_candidates(image, affine_orb::RowSpans::rectangle(roi), roi.tl(), {});
  REQUIRE(rect.corners.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) CHECK(rect.corners[i].x == expected[i].x);
}
