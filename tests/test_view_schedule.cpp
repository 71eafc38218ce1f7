// The Extractor's view scheduling (detail/view_schedule.hpp): turn-taking, the repeat grids and the
// budgets with carried shortfalls, each against a naive reference or its definition.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/detail/view_schedule.hpp"

namespace {

/// The repeat test by its definition: p of level l repeats an entered point e of level l' when
/// |l − l'| <= reach and |p − e| < merge_radius · s^max(l, l').
struct NaiveRepeats {
  struct Entry {
    cv::Point2f p;
    int level;
  };
  std::vector<Entry> entries;
  double merge_radius;
  double scale_factor;
  int reach;
  bool repeats(cv::Point2f p, int l) const {
    for (const Entry& e : entries) {
      if (std::abs(e.level - l) > reach) continue;
      const double r = merge_radius * std::pow(scale_factor, std::max(l, e.level));
      const double dx = static_cast<double>(e.p.x) - p.x;
      const double dy = static_cast<double>(e.p.y) - p.y;
      if (dx * dx + dy * dy < r * r) return true;
    }
    return false;
  }
};

}  // namespace

TEST_CASE("repeat grids answer exactly as the definition, for every reach") {
  affine_orb::PyramidOptions pyramid;  // 8 levels, scale 1.2
  const cv::Size size(320, 240);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> x(-0.5f, 319.49f);
  std::uniform_real_distribution<float> y(-0.5f, 239.49f);
  std::uniform_int_distribution<int> level(0, pyramid.levels - 1);
  for (int reach : {0, 1, 2, 4}) {
    for (double merge_radius : {1.0, 2.0, 5.5}) {
      CAPTURE(reach);
      CAPTURE(merge_radius);
      affine_orb::detail::RepeatGrids grids;
      grids.reset(size, pyramid, merge_radius, reach);
      NaiveRepeats naive{{}, merge_radius, pyramid.scale_factor, reach};
      int disagreements = 0;
      int repeats = 0;
      for (int i = 0; i < 3000; ++i) {
        const cv::Point2f p(x(rng), y(rng));
        const int l = level(rng);
        const bool expected = naive.repeats(p, l);
        disagreements += grids.repeats(p, l) != expected;
        repeats += expected;
        if (i % 2 == 0) {  // half of the points are entered, as a view's chosen keypoints are
          grids.enter(p, l);
          naive.entries.push_back({p, l});
        }
      }
      CHECK(disagreements == 0);
      CHECK(repeats > 50);  // the test sees both answers
      CHECK(grids.size() == naive.entries.size());
      grids.reset(size, pyramid, merge_radius, reach);
      CHECK(grids.size() == 0);
      CHECK_FALSE(grids.repeats(naive.entries.front().p, naive.entries.front().level));
    }
  }
  affine_orb::detail::RepeatGrids grids;
  CHECK_THROWS_AS(grids.reset(cv::Size(0, 10), pyramid, 2.0, 0), std::invalid_argument);
  CHECK_THROWS_AS(grids.reset(size, pyramid, 0.0, 0), std::invalid_argument);
  CHECK_THROWS_AS(grids.reset(size, pyramid, 2.0, -1), std::invalid_argument);
}

namespace {

/// The tilts of seven views (one untilted, two pairs and a triple of equal tilt), the levels and
/// the scale of the view-budget tests.
const std::vector<double> kBudgetTilts = {1.0, std::sqrt(2.0), std::sqrt(2.0), 2.0, 2.0, 2.0, 2.0 * std::sqrt(2.0)};
constexpr int kBudgetLevels = 8;
constexpr double kBudgetScale = 1.2;

/// Checks the shares of views 1 … 6 of `budgets` after share(…, total, exponent): each its exact
/// share rounded down or up, summing to `total`, equal tilts at most one apart (the earlier the
/// larger), and each view's level budgets those of level_budgets().
void check_shares(const affine_orb::detail::ViewBudgets& budgets, int total, double exponent) {
  const std::vector<double>& tilts = kBudgetTilts;
  double weight = 0.0;
  for (std::size_t v = 1; v < tilts.size(); ++v) weight += std::pow(tilts[v], exponent);
  int sum = 0;
  for (int v = 1; v < static_cast<int>(tilts.size()); ++v) {
    const double exact = total * std::pow(tilts[static_cast<std::size_t>(v)], exponent) / weight;
    // Largest remainders: every share is its exact value rounded down or up.
    CHECK(budgets.view(v) >= std::floor(exact) - 1e-9);
    CHECK(budgets.view(v) <= std::ceil(exact) + 1e-9);
    sum += budgets.view(v);
    // Views of equal tilt get shares at most one apart, the earlier one the larger.
    if (tilts[static_cast<std::size_t>(v)] == tilts[static_cast<std::size_t>(v - 1)] && v > 1) {
      CHECK(budgets.view(v - 1) - budgets.view(v) >= 0);
      CHECK(budgets.view(v - 1) - budgets.view(v) <= 1);
    }
    const std::vector<int> per_level = affine_orb::level_budgets(budgets.view(v), kBudgetScale, kBudgetLevels);
    for (int l = 0; l < kBudgetLevels; ++l) {
      CHECK(budgets.group(v * kBudgetLevels + l) == per_level[static_cast<std::size_t>(l)]);
    }
  }
  CHECK(sum == total);
}

}  // namespace

TEST_CASE("view budgets share a total in proportion to t^e, levels geometric") {
  const std::vector<double>& tilts = kBudgetTilts;
  for (double exponent : {-1.0, 0.0, 1.0, 2.5}) {
    for (int total : {0, 1, 7, 999, 1000}) {
      CAPTURE(exponent);
      CAPTURE(total);
      affine_orb::detail::ViewBudgets budgets;
      budgets.resize(tilts.size(), kBudgetLevels);
      budgets.set_view(0, 123, kBudgetScale);
      budgets.share(tilts, 1, static_cast<int>(tilts.size()), total, exponent, kBudgetScale);
      CHECK(budgets.view(0) == 123);  // views outside the range keep theirs
      check_shares(budgets, total, exponent);
    }
  }
  affine_orb::detail::ViewBudgets budgets;
  budgets.resize(tilts.size(), kBudgetLevels);
  CHECK_THROWS_AS(budgets.share(tilts, 3, 2, 10, 1.0, kBudgetScale), std::invalid_argument);
  CHECK_THROWS_AS(budgets.share(tilts, 0, 8, 10, 1.0, kBudgetScale), std::invalid_argument);
  CHECK_THROWS_AS(budgets.share(tilts, 0, 7, -1, 1.0, kBudgetScale), std::invalid_argument);
}

TEST_CASE("view budgets: allocate carries shortfalls within the range only, as allocate_with_carry defines") {
  const int levels = kBudgetLevels;
  affine_orb::detail::ViewBudgets budgets;
  budgets.resize(kBudgetTilts.size(), levels);
  budgets.share(kBudgetTilts, 0, static_cast<int>(kBudgetTilts.size()), 2000, -1.0, kBudgetScale);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> offered(0, 60);
  const int begin = 1 * levels;
  const int end = 5 * levels;
  std::vector<int> available(static_cast<std::size_t>(end - begin));
  std::vector<int> range_budgets;
  for (int& a : available) a = offered(rng);
  for (int g = begin; g < end; ++g) range_budgets.push_back(budgets.group(g));
  budgets.allocate(begin, end, available, true);
  const std::vector<int> expected = affine_orb::allocate_with_carry(range_budgets, available);
  int carried = 0;
  for (int g = begin; g < end; ++g) {
    CHECK(budgets.take(g) == expected[static_cast<std::size_t>(g - begin)]);
    CHECK(budgets.take(g) <= available[static_cast<std::size_t>(g - begin)]);
    carried += budgets.take(g) > budgets.group(g);
  }
  CHECK(carried > 0);  // some group took a shortfall carried from another

  // Without carrying, every group takes what it can of its own budget and nothing more, and
  // the groups outside the range keep what the carrying allocation gave them.
  const int outside = budgets.take(0);
  budgets.allocate(begin, end, available, false);
  int short_groups = 0;
  for (int g = begin; g < end; ++g) {
    const int offered_here = available[static_cast<std::size_t>(g - begin)];
    CHECK(budgets.take(g) == std::min(budgets.group(g), offered_here));
    short_groups += offered_here < budgets.group(g);
  }
  CHECK(short_groups > 0);  // the shortfalls the carrying allocation passed on are lost here
  CHECK(budgets.take(0) == outside);
  CHECK_THROWS_AS(budgets.allocate(begin, end + 1, available, false), std::invalid_argument);
}

TEST_CASE("a shortlist is ceil(factor x budget), at most the candidates") {
  CHECK(affine_orb::detail::shortlist_size(100, 40, 1.25) == 50);
  CHECK(affine_orb::detail::shortlist_size(100, 41, 1.25) == 52);  // 51.25 rounded up
  CHECK(affine_orb::detail::shortlist_size(30, 40, 1.25) == 30);
  CHECK(affine_orb::detail::shortlist_size(100, 0, 1.25) == 0);
  CHECK(affine_orb::detail::shortlist_size(0, 10, 2.0) == 0);
}

TEST_CASE("views take their turns in index order whatever the threads, and a failure ends the turns") {
  for (int threads : {1, 2, 4, 8}) {
    CAPTURE(threads);
    affine_orb::detail::ViewTurns turns;
    const int first = 3;
    const int n = 40;
    turns.reset(first);
    std::vector<int> order;
    std::mutex mutex;
    std::atomic<int> next_view{first};
    std::vector<std::thread> workers;
    for (int t = 0; t < threads; ++t) {
      workers.emplace_back([&] {
        // Views are handed out in increasing order, as WorkerPool does.
        for (int v = next_view++; v < first + n; v = next_view++) {
          REQUIRE(turns.wait(v));
          {
            const std::lock_guard<std::mutex> lock(mutex);
            order.push_back(v);
          }
          turns.pass(v);
        }
      });
    }
    for (std::thread& w : workers) w.join();
    std::vector<int> expected(n);
    std::iota(expected.begin(), expected.end(), first);
    CHECK(order == expected);
  }
  affine_orb::detail::ViewTurns turns;
  turns.reset(0);
  std::atomic<bool> released{false};
  std::thread waiter([&] { released = !turns.wait(5); });  // view 5's turn never comes
  turns.fail();
  waiter.join();
  CHECK(released);
  CHECK_FALSE(turns.wait(0));  // no turn after a failure until the next reset
  turns.reset(0);
  CHECK(turns.wait(0));
}
