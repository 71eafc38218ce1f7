// Tests of the spreading (detection/distribution.hpp): level budgets, allocation with carried
// shortfalls, the quadtree against its first implementation, the strongest corners.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "test_data.hpp"
#include "test_regions.hpp"

namespace {

// The quadtree spreading as first written (a vector of members per cell), the reference for the
// in-place version: root_cells(), then split_round() until there are `target` cells or none can be
// split, then the strongest member of each cell, topped up or cut to `target` by response.
struct QuadCell {
  cv::Rect2f box;
  std::vector<int> members;
};

// Square-ish root cells across `region`, each point in the one its x falls in; empty ones dropped.
std::vector<QuadCell> root_cells(const std::vector<cv::Point2f>& points, cv::Rect2f region) {
  const int roots = std::max(1, static_cast<int>(std::lround(region.width / std::max(region.height, 1.0f))));
  const float root_width = region.width / static_cast<float>(roots);
  std::vector<QuadCell> cells(static_cast<std::size_t>(roots));
  for (int r = 0; r < roots; ++r) {
    cells[static_cast<std::size_t>(r)].box = {region.x + r * root_width, region.y, root_width, region.height};
  }
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const cv::Point2f& p = points[static_cast<std::size_t>(i)];
    const int r = std::clamp(static_cast<int>((p.x - region.x) / root_width), 0, roots - 1);
    cells[static_cast<std::size_t>(r)].members.push_back(i);
  }
  cells.erase(std::remove_if(cells.begin(), cells.end(), [](const QuadCell& c) { return c.members.empty(); }),
              cells.end());
  return cells;
}

// Appends the non-empty quarters of `cell` to `children`; returns how many there are.
int split_cell(const QuadCell& cell, const std::vector<cv::Point2f>& points, std::vector<QuadCell>& children) {
  const float hw = cell.box.width * 0.5f;
  const float hh = cell.box.height * 0.5f;
  const float cx = cell.box.x + hw;
  const float cy = cell.box.y + hh;
  QuadCell quad[4] = {{{cell.box.x, cell.box.y, hw, hh}, {}},
                      {{cx, cell.box.y, hw, hh}, {}},
                      {{cell.box.x, cy, hw, hh}, {}},
                      {{cx, cy, hw, hh}, {}}};
  for (int m : cell.members) {
    const cv::Point2f& p = points[static_cast<std::size_t>(m)];
    quad[(p.x >= cx ? 1 : 0) + (p.y >= cy ? 2 : 0)].members.push_back(m);
  }
  int nonempty = 0;
  for (QuadCell& q : quad) {
    if (!q.members.empty()) {
      children.push_back(std::move(q));
      ++nonempty;
    }
  }
  return nonempty;
}

// One round: the splittable cells, most members first, are split while there are fewer than
// `target` cells; the unsplit cells come first, then the children. False when none can be split.
bool split_round(std::vector<QuadCell>& cells, const std::vector<cv::Point2f>& points, int target) {
  auto splittable = [](const QuadCell& c) {
    return c.members.size() > 1 && c.box.width >= 1.0f && c.box.height >= 1.0f;
  };
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (splittable(cells[i])) order.push_back(i);
  }
  if (order.empty()) return false;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return cells[a].members.size() > cells[b].members.size(); });
  std::vector<bool> split(cells.size(), false);
  int count = static_cast<int>(cells.size());
  std::vector<QuadCell> children;
  for (std::size_t idx : order) {
    if (count >= target) break;
    count += split_cell(cells[idx], points, children) - 1;
    split[idx] = true;
  }
  std::vector<QuadCell> next;
  next.reserve(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (!split[i]) next.push_back(std::move(cells[i]));
  }
  for (QuadCell& c : children) next.push_back(std::move(c));
  cells = std::move(next);
  return true;
}

std::vector<int> reference_quadtree(const std::vector<cv::Point2f>& points, const std::vector<float>& responses,
                                    cv::Rect2f region, int target) {
  const int n = static_cast<int>(points.size());
  std::vector<int> kept;
  if (target == 0 || n == 0) return kept;
  auto stronger = [&](int a, int b) {
    return responses[static_cast<std::size_t>(a)] > responses[static_cast<std::size_t>(b)] ||
           (responses[static_cast<std::size_t>(a)] == responses[static_cast<std::size_t>(b)] && a < b);
  };
  if (n <= target) {
    kept.resize(static_cast<std::size_t>(n));
    std::iota(kept.begin(), kept.end(), 0);
    return kept;
  }
  std::vector<QuadCell> cells = root_cells(points, region);
  bool splittable = true;
  while (splittable && static_cast<int>(cells.size()) < target) splittable = split_round(cells, points, target);
  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  for (const QuadCell& cell : cells) {
    const int best = *std::min_element(cell.members.begin(), cell.members.end(), stronger);
    kept.push_back(best);
    taken[static_cast<std::size_t>(best)] = 1;
  }
  std::sort(kept.begin(), kept.end(), stronger);
  if (static_cast<int>(kept.size()) > target) {
    kept.resize(static_cast<std::size_t>(target));
  } else if (static_cast<int>(kept.size()) < target) {
    std::vector<int> rest;
    for (int i = 0; i < n; ++i) {
      if (!taken[static_cast<std::size_t>(i)]) rest.push_back(i);
    }
    const std::size_t missing = static_cast<std::size_t>(target) - kept.size();
    std::partial_sort(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(missing), rest.end(), stronger);
    kept.insert(kept.end(), rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(missing));
  }
  std::sort(kept.begin(), kept.end());
  return kept;
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
      const int spread = affine_orb::test::occupied_cells(points, kept, region, 16);
      const int greedy = affine_orb::test::occupied_cells(points, strongest, region, 16);
      CHECK(greedy <= 4);    // the strongest-N all sit in the cluster
      CHECK(spread >= 150);  // of 256 cells; the uniform points occupy about 244
    }
  }
  CHECK(affine_orb::distribute_quadtree(points, responses, region, 0).empty());
  CHECK(affine_orb::distribute_quadtree({}, {}, region, 10).empty());
  CHECK(affine_orb::distribute_quadtree(points, responses, region, 5000).size() == points.size());
  CHECK_THROWS_AS(affine_orb::distribute_quadtree(points, {}, region, 10), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::distribute_quadtree(points, responses, region, -1), std::invalid_argument);
}

TEST_CASE("the quadtree equals its first, per-cell-vector implementation") {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 3000);
    const cv::Rect2f region(5.0f, 7.0f, 100.0f + static_cast<float>(rng() % 900),
                            100.0f + static_cast<float>(rng() % 500));
    std::uniform_real_distribution<float> ux(region.x, region.x + region.width);
    std::uniform_real_distribution<float> uy(region.y, region.y + region.height);
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    for (int i = 0; i < n; ++i) {
      // Clusters, duplicates and few distinct responses (ties) as well as spread points.
      const bool clustered = rng() % 3 == 0;
      points.emplace_back(clustered ? region.x + static_cast<float>(rng() % 8) : ux(rng),
                          clustered ? region.y + static_cast<float>(rng() % 8) : uy(rng));
      responses.push_back(static_cast<float>(rng() % 12));
    }
    for (int target : {1, 3, n / 10 + 1, n / 2 + 1, n - 1, n}) {
      CAPTURE(trial);
      CAPTURE(target);
      CHECK(affine_orb::distribute_quadtree(points, responses, region, target) ==
            reference_quadtree(points, responses, region, target));
    }
  }
}

TEST_CASE("select_strongest keeps the target strongest, ties to the lower index") {
  const std::vector<float> responses = {5, 9, 1, 9, 7, 3, 9, 0};
  CHECK(affine_orb::select_strongest(responses, 3) == std::vector<int>{1, 3, 6});
  CHECK(affine_orb::select_strongest(responses, 2) == std::vector<int>{1, 3});
  CHECK(affine_orb::select_strongest(responses, 4) == std::vector<int>{1, 3, 4, 6});
  CHECK(affine_orb::select_strongest(responses, 0).empty());
  CHECK(affine_orb::select_strongest(responses, 100).size() == responses.size());
  CHECK_THROWS_AS(affine_orb::select_strongest(responses, -1), std::invalid_argument);
  // Against a full sort on random responses with many ties.
  std::mt19937 rng(4);
  std::vector<float> random(500);
  for (float& r : random) r = static_cast<float>(rng() % 40);
  std::vector<int> order(random.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return random[static_cast<std::size_t>(a)] > random[static_cast<std::size_t>(b)];
  });
  order.resize(123);
  std::sort(order.begin(), order.end());
  CHECK(affine_orb::select_strongest(random, 123) == order);
}

TEST_CASE("the strongest spreading gives the budget and more matches; the quadtree spreads wider") {
  const cv::Mat image = affine_orb::test::graf(1);
  affine_orb::ExtractorOptions options;
  options.features = 1000;
  options.views.max_tilt = 1.0;
  affine_orb::ExtractorOptions strongest = options;
  strongest.spreading = affine_orb::Spreading::kStrongest;
  const auto spread = affine_orb::Extractor<affine_orb::Rbrief>(options).extract(image);
  const auto strong = affine_orb::Extractor<affine_orb::Rbrief>(strongest).extract(image);
  REQUIRE(spread.size() == 1000);
  CHECK(strong.size() == 1000);
  double spread_mean = 0.0;
  double strong_mean = 0.0;
  std::set<int> spread_cells;
  std::set<int> strong_cells;
  for (std::size_t i = 0; i < 1000; ++i) {
    spread_mean += spread.keypoints[i].response;
    strong_mean += strong.keypoints[i].response;
    spread_cells.insert(static_cast<int>(spread.keypoints[i].pt.y / 64) * 16 +
                        static_cast<int>(spread.keypoints[i].pt.x / 64));
    strong_cells.insert(static_cast<int>(strong.keypoints[i].pt.y / 64) * 16 +
                        static_cast<int>(strong.keypoints[i].pt.x / 64));
  }
  CHECK(strong_mean > spread_mean);
  CHECK(spread_cells.size() > strong_cells.size());

  // More matches: graf 1 -> 3 matched (match_features()), correct within 3 px of the ground truth.
  const cv::Mat other = affine_orb::test::graf(3);
  const cv::Matx33d h = affine_orb::test::graf_homography_1to3();
  const auto correct_matches = [&](const affine_orb::ExtractorOptions& o, const affine_orb::Features<256>& a) {
    const auto b = affine_orb::Extractor<affine_orb::Rbrief>(o).extract(other);
    int correct = 0;
    for (const auto& m : affine_orb::match_features(a, b)) {
      const cv::Point2d p = affine_orb::test::apply_homography(h, a.keypoints[static_cast<std::size_t>(m.query)].pt);
      const cv::Point2f q = b.keypoints[static_cast<std::size_t>(m.train)].pt;
      correct += std::hypot(p.x - q.x, p.y - q.y) < 3.0;
    }
    return correct;
  };
  const int spread_matches = correct_matches(options, spread);
  const int strong_matches = correct_matches(strongest, strong);
  MESSAGE("graf 1->3 correct matches: quadtree " << spread_matches << ", strongest " << strong_matches);
  CHECK(strong_matches > spread_matches);
}
