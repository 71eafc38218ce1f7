// Feature budget and spatial spreading (SPEC §2).
#include <doctest/doctest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/distribution.hpp"
#include "affine_orb/extractor.hpp"
#include "affine_orb/rbrief.hpp"
#include "test_data.hpp"

namespace {

// Number of cells of a g x g grid over `region` that hold at least one of the chosen points.
int occupied_cells(const std::vector<cv::Point2f>& points, const std::vector<int>& chosen, cv::Rect2f region, int g) {
  std::set<int> cells;
  for (int i : chosen) {
    const cv::Point2f& p = points[static_cast<std::size_t>(i)];
    const int cx = std::min(g - 1, static_cast<int>((p.x - region.x) / region.width * static_cast<float>(g)));
    const int cy = std::min(g - 1, static_cast<int>((p.y - region.y) / region.height * static_cast<float>(g)));
    cells.insert(cy * g + cx);
  }
  return static_cast<int>(cells.size());
}

}  // namespace

TEST_CASE("level budgets are geometric and sum to the total") {
  const std::vector<int> budgets = affine_orb::level_budgets(1000, 1.2, 8);
  REQUIRE(budgets.size() == 8);
  CHECK(std::accumulate(budgets.begin(), budgets.end(), 0) == 1000);
  // N (1 − 1/s) / (1 − s^-L) for N = 1000, s = 1.2, L = 8: 217.2 → 217.
  const double first = 1000 * (1 - 1 / 1.2) / (1 - std::pow(1 / 1.2, 8));
  CHECK(budgets[0] == static_cast<int>(std::lround(first)));
  for (int l = 1; l + 1 < 8; ++l) {
    CHECK(std::abs(budgets[static_cast<std::size_t>(l)] - first * std::pow(1 / 1.2, l)) <= 1.0);
  }
  for (int total : {0, 1, 7, 2000, 12345}) {
    for (int levels : {1, 3, 8, 12}) {
      const auto b = affine_orb::level_budgets(total, 1.3, levels);
      CHECK(std::accumulate(b.begin(), b.end(), 0) == total);
      for (int n : b) CHECK(n >= 0);
    }
  }
  CHECK_THROWS_AS(affine_orb::level_budgets(-1, 1.2, 8), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::level_budgets(10, 1.0, 8), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::level_budgets(10, std::nan(""), 8), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::level_budgets(10, 1.2, 0), std::invalid_argument);
}

TEST_CASE("allocation carries shortfalls and never exceeds what is available") {
  const std::vector<int> take = affine_orb::allocate_with_carry({50, 30, 20}, {10, 100, 5});
  // Level 0 is 40 short: carried to level 1 (70); level 2 is 15 short: taken from level 1 after
  // the last level (85).
  CHECK(take == std::vector<int>{10, 85, 5});
  const std::vector<int> wrap = affine_orb::allocate_with_carry({10, 10, 80}, {100, 5, 0});
  CHECK(std::accumulate(wrap.begin(), wrap.end(), 0) == 100);
  CHECK(wrap[1] == 5);
  CHECK(wrap[2] == 0);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(0, 60);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<int> budgets(6);
    std::vector<int> available(6);
    for (int i = 0; i < 6; ++i) {
      budgets[static_cast<std::size_t>(i)] = value(rng);
      available[static_cast<std::size_t>(i)] = value(rng);
    }
    const auto t = affine_orb::allocate_with_carry(budgets, available);
    const int want = std::accumulate(budgets.begin(), budgets.end(), 0);
    const int have = std::accumulate(available.begin(), available.end(), 0);
    CHECK(std::accumulate(t.begin(), t.end(), 0) == std::min(want, have));
    for (int i = 0; i < 6; ++i) CHECK(t[static_cast<std::size_t>(i)] <= available[static_cast<std::size_t>(i)]);
  }
}

TEST_CASE("the quadtree returns exactly the budget and spreads better than the strongest-N") {
  // A dense cluster of strong corners in one corner and weaker ones spread uniformly.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> cluster(0.0f, 60.0f);
  std::uniform_real_distribution<float> wide(0.0f, 640.0f);
  std::uniform_real_distribution<float> tall(0.0f, 480.0f);
  std::vector<cv::Point2f> points;
  std::vector<float> responses;
  for (int i = 0; i < 1500; ++i) {
    points.emplace_back(cluster(rng), cluster(rng));
    responses.push_back(100.0f + static_cast<float>(i % 50));
  }
  for (int i = 0; i < 800; ++i) {
    points.emplace_back(wide(rng), tall(rng));
    responses.push_back(20.0f + static_cast<float>(i % 30));
  }
  const cv::Rect2f region(0, 0, 640, 480);
  for (int target : {1, 10, 300, 1000, 2299}) {
    CAPTURE(target);
    const auto kept = affine_orb::distribute_quadtree(points, responses, region, target);
    REQUIRE(static_cast<int>(kept.size()) == target);
    CHECK(std::set<int>(kept.begin(), kept.end()).size() == kept.size());
    CHECK(std::is_sorted(kept.begin(), kept.end()));
    if (target >= 300 && target < 1500) {
      std::vector<int> strongest(points.size());
      std::iota(strongest.begin(), strongest.end(), 0);
      std::stable_sort(strongest.begin(), strongest.end(), [&](int a, int b) {
        return responses[static_cast<std::size_t>(a)] > responses[static_cast<std::size_t>(b)];
      });
      strongest.resize(static_cast<std::size_t>(target));
      const int spread = occupied_cells(points, kept, region, 16);
      const int greedy = occupied_cells(points, strongest, region, 16);
      CHECK(greedy <= 4);   // the strongest-N all sit in the cluster
      CHECK(spread >= 150);  // of 256 cells; the uniform points occupy about 244
    }
  }
  CHECK(affine_orb::distribute_quadtree(points, responses, region, 0).empty());
  CHECK(affine_orb::distribute_quadtree({}, {}, region, 10).empty());
  CHECK(affine_orb::distribute_quadtree(points, responses, region, 5000).size() == points.size());
  CHECK_THROWS_AS(affine_orb::distribute_quadtree(points, {}, region, 10), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::distribute_quadtree(points, responses, region, -1), std::invalid_argument);
}

TEST_CASE("the extractor returns exactly the budget, geometric per level, spread over a real image") {
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1);
  for (int n : {500, 1000, 2000}) {
    CAPTURE(n);
    affine_orb::ExtractorOptions options;
    options.features = n;
    options.views.max_tilt = 1.0;
    affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
    const auto features = extractor.extract(image);
    REQUIRE(static_cast<int>(features.size()) == n);
    std::vector<int> per_level(8, 0);
    for (const auto& kp : features.keypoints) ++per_level[static_cast<std::size_t>(kp.octave)];
    const auto budgets = affine_orb::level_budgets(n, 1.2, 8);
    // graf is richly textured: every level fills its own budget.
    CHECK(per_level == budgets);

    // Spread at level 0 against the strongest-N selection of the same candidates.
    affine_orb::Pyramid pyramid;
    pyramid.build(image);
    cv::Mat scores;
    const int border = extractor.descriptor().border();
    const cv::Rect roi(border, border, image.cols - 2 * border, image.rows - 2 * border);
    const auto candidates = affine_orb::detect_candidates(image, roi, options.detector, scores);
    std::vector<cv::Point2f> points;
    for (const auto& c : candidates.corners) points.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y));
    std::vector<int> strongest(points.size());
    std::iota(strongest.begin(), strongest.end(), 0);
    std::stable_sort(strongest.begin(), strongest.end(), [&](int a, int b) {
      return candidates.responses[static_cast<std::size_t>(a)] > candidates.responses[static_cast<std::size_t>(b)];
    });
    strongest.resize(static_cast<std::size_t>(budgets[0]));
    std::vector<cv::Point2f> ours;
    for (const auto& kp : features.keypoints) {
      if (kp.octave == 0) ours.push_back(kp.pt);
    }
    std::vector<int> all(ours.size());
    std::iota(all.begin(), all.end(), 0);
    const cv::Rect2f region(roi);
    const int spread = occupied_cells(ours, all, region, 10);
    const int greedy = occupied_cells(points, strongest, region, 10);
    CAPTURE(spread);
    CAPTURE(greedy);
    CHECK(spread >= greedy + 5);
    CHECK(spread >= std::min(100, budgets[0]) * 6 / 10);
  }
}

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
