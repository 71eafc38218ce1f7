// Matching of affine feature sets (matching/affine_matching.hpp, SPEC §4) against naive references
// written here: the removal of duplicate correspondences, the location-aware ratio test of
// match_features() and the gated search of match_guided().
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/affine_matching.hpp"

namespace {

/// The four combinations of the location-aware ratio test (exclusion radius 0 or 4 px) and the
/// cross-check that the matching tests try, duplicates kept.
std::vector<affine_orb::AffineMatchOptions> exclusion_and_cross_check() {
  std::vector<affine_orb::AffineMatchOptions> out;
  for (double radius : {0.0, 4.0}) {
    for (bool cross : {false, true}) {
      affine_orb::AffineMatchOptions options;
      options.ratio_exclusion_radius = radius;
      options.matcher.cross_check = cross;
      options.duplicate_radius = 0.0;
      out.push_back(options);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("the point grid visits every point within the radius, each once, cell by cell") {
  // Clustered points (cells widen to one point per cell on average) and a point 1e30 px away (the
  // cell count per side is bounded); queries inside, on cell borders and outside the points' box.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> wide(-20.0f, 120.0f), near(40.0f, 44.0f);
  for (const bool far : {false, true}) {
    CAPTURE(far);
    std::vector<cv::Point2f> points(400);
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i] = i % 2 == 0 ? cv::Point2f(wide(rng), wide(rng)) : cv::Point2f(near(rng), near(rng));
    }
    points[7] = {std::numeric_limits<float>::quiet_NaN(), 3.0f};
    if (far) points[9] = {1e30f, 1e30f};
    for (const double side : {2.0, 7.5, 40.0}) {
      affine_orb::detail::PointGrid grid;
      grid.build(points, side);
      for (int q = 0; q < 300; ++q) {
        const cv::Point2f p = q % 3 == 0 ? points[static_cast<std::size_t>(q)] : cv::Point2f(wide(rng), wide(rng));
        const double radius = side * (q % 4 + 1) / 4.0;
        std::vector<int> visited;
        grid.for_each_near(p, radius, [&](int i) { visited.push_back(i); });
        std::vector<int> sorted = visited;
        std::sort(sorted.begin(), sorted.end());
        CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
        for (std::size_t i = 0; i < points.size(); ++i) {
          const double dx = points[i].x - p.x, dy = points[i].y - p.y;
          if (!(dx * dx + dy * dy <= radius * radius)) continue;
          CAPTURE(i);
          CHECK(std::binary_search(sorted.begin(), sorted.end(), static_cast<int>(i)));
        }
      }
    }
  }
}

TEST_CASE("duplicate correspondences are removed exactly as defined") {
  // Points in a 40 px square (many duplicates), then the same spread over 4e6 px with a few points
  // at ±1e30 and NaN (the grid's cells widen; a NaN point is never within the radius).
  for (const float scale : {1.0f, 1e5f}) {
    CAPTURE(scale);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> coord(0.0f, 40.0f);
    std::vector<cv::Point2f> p1(60);
    std::vector<cv::Point2f> p2(60);
    for (auto& p : p1) p = {coord(rng) * scale, coord(rng) * scale};
    for (auto& p : p2) p = {coord(rng) * scale, coord(rng) * scale};
    if (scale > 1.0f) {
      p1[3] = {1e30f, -1e30f};
      p1[4] = {std::numeric_limits<float>::quiet_NaN(), 0.0f};
      p2[5] = {-1e30f, 1e30f};
    }
    std::vector<affine_orb::Match> matches;
    for (int k = 0; k < 300; ++k) {
      matches.push_back({static_cast<int>(rng() % 60), static_cast<int>(rng() % 60), static_cast<int>(rng() % 20)});
    }
    const auto kept = affine_orb::remove_duplicate_matches(matches, p1, p2, 3.0);
    // Naive reference: greedy by (distance, query, train), O(n²).
    auto order = matches;
    std::sort(order.begin(), order.end(), [](const affine_orb::Match& a, const affine_orb::Match& b) {
      return std::tie(a.distance, a.query, a.train) < std::tie(b.distance, b.query, b.train);
    });
    std::vector<affine_orb::Match> expected;
    for (const auto& m : order) {
      bool duplicate = false;
      for (const auto& k : expected) {
        const auto& a = p1[static_cast<std::size_t>(m.query)];
        const auto& b = p1[static_cast<std::size_t>(k.query)];
        const auto& c = p2[static_cast<std::size_t>(m.train)];
        const auto& d = p2[static_cast<std::size_t>(k.train)];
        duplicate = duplicate || (std::hypot(a.x - b.x, a.y - b.y) < 3.0 && std::hypot(c.x - d.x, c.y - d.y) < 3.0);
      }
      if (!duplicate) expected.push_back(m);
    }
    std::sort(expected.begin(), expected.end(), [](const affine_orb::Match& a, const affine_orb::Match& b) {
      return std::tie(a.query, a.train) < std::tie(b.query, b.train);
    });
    CHECK(expected.size() < matches.size());  // the case has duplicates to remove
    REQUIRE(kept.size() == expected.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
      CHECK(kept[i].query == expected[i].query);
      CHECK(kept[i].train == expected[i].train);
      CHECK(kept[i].distance == expected[i].distance);
    }
    CHECK_THROWS_AS(affine_orb::remove_duplicate_matches(matches, p1, p2, -1.0), std::invalid_argument);
  }
}

namespace {

/// Features with planted near-duplicates: each image-1 descriptor has one to three copies in
/// image 2, more bits off each, at nearly the same image-2 location, and every fourth a confuser
/// elsewhere; image 2 holds about 450, more than the rescans of the location-aware ratio
/// test read at a time (256).
std::pair<affine_orb::Features<256>, affine_orb::Features<256>> planted_copies() {
  std::mt19937_64 rng(23);
  affine_orb::Features<256> a;
  affine_orb::Features<256> b;
  for (int i = 0; i < 200; ++i) {
    affine_orb::BinaryDescriptor<256> d{rng(), rng(), rng(), rng()};
    a.descriptors.push_back(d);
    a.keypoints.emplace_back(cv::Point2f(static_cast<float>(rng() % 1000), static_cast<float>(rng() % 1000)), 31.0f);
    a.views.push_back(0);
    const cv::Point2f at(static_cast<float>(rng() % 1000), static_cast<float>(rng() % 1000));
    for (int copy = 0; copy < 1 + i % 3; ++copy) {
      affine_orb::BinaryDescriptor<256> e = d;
      for (int flip = 0; flip < 20 + (i % 4 == 0 ? 1 : 15) * copy; ++flip) {
        const unsigned bit = static_cast<unsigned>(rng() % 256);
        e[bit / 64] ^= 1ull << (bit % 64);
      }
      b.descriptors.push_back(e);
      b.keypoints.emplace_back(at + cv::Point2f(static_cast<float>(copy), 0.5f * copy), 31.0f);
      b.views.push_back(copy);
    }
  }
  // After all of them, for every fourth image-1 descriptor (whose copies are one bit apart) a
  // confuser elsewhere in image 2, a little farther than its copies: the runner-up outside the
  // radius that decides the ratio test, last in the train set.
  for (std::size_t i = 0; i < a.size(); i += 4) {
    affine_orb::BinaryDescriptor<256> e = a.descriptors[i];
    for (int flip = 0; flip < 22 + static_cast<int>(i % 3); ++flip) {
      const unsigned bit = static_cast<unsigned>(rng() % 256);
      e[bit / 64] ^= 1ull << (bit % 64);
    }
    b.descriptors.push_back(e);
    b.keypoints.emplace_back(cv::Point2f(static_cast<float>(rng() % 1000), static_cast<float>(rng() % 1000)), 31.0f);
    b.views.push_back(0);
  }
  return {a, b};
}

/// Index of the descriptor of `set` nearest to `d` (the first on ties) and its distance.
std::pair<std::size_t, int> nearest(const affine_orb::BinaryDescriptor<256>& d, const affine_orb::Features<256>& set) {
  int best = 1 << 30;
  std::size_t at = 0;
  for (std::size_t j = 0; j < set.size(); ++j) {
    const int distance = affine_orb::hamming_distance(d, set.descriptors[j]);
    if (distance < best) {
      best = distance;
      at = j;
    }
  }
  return {at, best};
}

/// The location-aware ratio test by brute force: the nearest descriptor of `b`, against the nearest
/// farther than `radius` px from it (ratio 0.8), and with `cross` the nearest of `a` back.
std::vector<affine_orb::Match> naive_ratio_matches(const affine_orb::Features<256>& a,
                                                   const affine_orb::Features<256>& b, double radius, bool cross) {
  std::vector<affine_orb::Match> expected;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto [j1, best] = nearest(a.descriptors[i], b);
    int second = 1 << 30;
    for (std::size_t j = 0; j < b.size(); ++j) {
      if (j == j1) continue;
      const auto& p = b.keypoints[j].pt;
      const auto& q = b.keypoints[j1].pt;
      if (std::hypot(p.x - q.x, p.y - q.y) <= radius) continue;
      second = std::min(second, affine_orb::hamming_distance(a.descriptors[i], b.descriptors[j]));
    }
    if (!(best < static_cast<double>(0.8f) * second)) continue;  // the ratio as MatcherOptions holds it
    if (cross && nearest(b.descriptors[j1], a).first != i) continue;
    expected.push_back({static_cast<int>(i), static_cast<int>(j1), best});
  }
  return expected;
}

}  // namespace

TEST_CASE("the location-aware ratio test equals a naive reference") {
  const auto [a, b] = planted_copies();
  for (const affine_orb::AffineMatchOptions& options : exclusion_and_cross_check()) {
    const double radius = options.ratio_exclusion_radius;
    const bool cross = options.matcher.cross_check;
    CAPTURE(radius);
    CAPTURE(cross);
    const auto got = affine_orb::match_features(a, b, options);
    const std::vector<affine_orb::Match> expected = naive_ratio_matches(a, b, radius, cross);
    REQUIRE(got.size() == expected.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      CHECK(got[k].query == expected[k].query);
      CHECK(got[k].train == expected[k].train);
    }
    if (radius > 0.0) CHECK(got.size() > 60);  // the planted copies no longer veto their originals
  }
  affine_orb::AffineMatchOptions bad;
  bad.ratio_exclusion_radius = -1.0;
  CHECK_THROWS_AS(affine_orb::match_features(a, b, bad), std::invalid_argument);
  bad = {};
  bad.matcher.ratio = 0.0f;
  CHECK_THROWS_AS(affine_orb::match_features(a, b, bad), std::invalid_argument);
  CHECK(affine_orb::match_features(affine_orb::Features<256>{}, b).empty());
}

namespace {

/// `n` features whose descriptors are a few bits off one of `kinds` prototypes (the same ones on
/// every call), so that many distances tie, at positions in a 300 x 300 image, some in clusters
/// within the exclusion radius.
affine_orb::Features<256> tied_features(std::mt19937_64& rng, int n, int kinds) {
  std::mt19937_64 r(5);
  std::vector<affine_orb::BinaryDescriptor<256>> prototypes;
  for (int k = 0; k < kinds; ++k) prototypes.push_back({r(), r(), r(), r()});
  affine_orb::Features<256> f;
  for (int i = 0; i < n; ++i) {
    affine_orb::BinaryDescriptor<256> d = prototypes[rng() % prototypes.size()];
    for (int flip = static_cast<int>(rng() % 4); flip > 0; --flip) {
      const unsigned bit = static_cast<unsigned>(rng() % 256);
      d[bit / 64] ^= 1ull << (bit % 64);
    }
    f.descriptors.push_back(d);
    const float x = static_cast<float>(rng() % 60) * 5.0f, y = static_cast<float>(rng() % 60) * 5.0f;
    f.keypoints.emplace_back(cv::Point2f(x, y) + cv::Point2f(static_cast<float>(rng() % 3), 0.0f), 31.0f);
    f.views.push_back(static_cast<int>(rng() % 3));
  }
  return f;
}

/// The first `n` features of `f`.
affine_orb::Features<256> first(const affine_orb::Features<256>& f, std::size_t n) {
  affine_orb::Features<256> out;
  out.keypoints.assign(f.keypoints.begin(), f.keypoints.begin() + static_cast<std::ptrdiff_t>(n));
  out.descriptors.assign(f.descriptors.begin(), f.descriptors.begin() + static_cast<std::ptrdiff_t>(n));
  out.views.assign(f.views.begin(), f.views.begin() + static_cast<std::ptrdiff_t>(n));
  return out;
}

}  // namespace

TEST_CASE("searches extended to grown sets equal the searches of the whole sets, ties included") {
  std::mt19937_64 rng(41);
  const affine_orb::Features<256> a = tied_features(rng, 150, 8);
  const affine_orb::Features<256> b = tied_features(rng, 170, 8);
  // The reference: every distance, sorted by (distance, train index).
  auto naive = [&](std::size_t i) {
    std::vector<std::pair<int, int>> all;
    for (std::size_t j = 0; j < b.size(); ++j) {
      all.push_back({affine_orb::hamming_distance(a.descriptors[i], b.descriptors[j]), static_cast<int>(j)});
    }
    std::sort(all.begin(), all.end());
    return all;
  };
  int ties = 0;
  for (std::size_t known_query : {std::size_t{0}, std::size_t{1}, std::size_t{77}, a.size()}) {
    for (std::size_t known_train : {std::size_t{0}, std::size_t{1}, std::size_t{90}, b.size()}) {
      CAPTURE(known_query);
      CAPTURE(known_train);
      const std::vector<affine_orb::BinaryDescriptor<256>> old_query(
          a.descriptors.begin(), a.descriptors.begin() + static_cast<std::ptrdiff_t>(known_query));
      const std::vector<affine_orb::BinaryDescriptor<256>> old_train(
          b.descriptors.begin(), b.descriptors.begin() + static_cast<std::ptrdiff_t>(known_train));
      const auto got = affine_orb::detail::extend_knn2(affine_orb::knn2(old_query, old_train), known_train,
                                                       a.descriptors, b.descriptors);
      REQUIRE(got.size() == a.size());
      for (std::size_t i = 0; i < a.size(); ++i) {
        const auto all = naive(i);
        REQUIRE(got[i].count == 2);
        CHECK(got[i].query == static_cast<int>(i));
        CHECK(got[i].best.distance == all[0].first);
        CHECK(got[i].best.train == all[0].second);
        CHECK(got[i].second.distance == all[1].first);
        CHECK(got[i].second.train == all[1].second);
        ties += all[0].first == all[1].first || all[1].first == all[2].first;
      }
    }
  }
  CHECK(ties > 500);  // the ties the order of the merge decides are there to be decided
  // Train sets of one descriptor: count 1, the second left at Neighbour's defaults.
  const std::vector<affine_orb::BinaryDescriptor<256>> one(b.descriptors.begin(), b.descriptors.begin() + 1);
  const auto single = affine_orb::detail::extend_knn2(affine_orb::knn2(a.descriptors, {}), 0, a.descriptors, one);
  for (const affine_orb::KnnMatch& k : single) {
    CHECK(k.count == 1);
    CHECK(k.best.train == 0);
    CHECK(k.second.distance == affine_orb::Neighbour{}.distance);
  }
}

TEST_CASE("matching sets stage by stage equals matching each stage's sets whole") {
  std::mt19937_64 rng(43);
  const affine_orb::Features<256> a = tied_features(rng, 160, 100);
  const affine_orb::Features<256> b = tied_features(rng, 140, 100);
  const std::vector<std::pair<std::size_t, std::size_t>> stages = {
      {0, 60}, {40, 60}, {100, 90}, {100, 140}, {160, 140}};
  for (affine_orb::AffineMatchOptions options : exclusion_and_cross_check()) {
    CAPTURE(options.ratio_exclusion_radius);
    CAPTURE(options.matcher.cross_check);
    options.matcher.ratio = 0.95f;
    affine_orb::detail::KnnSearches searches;
    std::size_t matched = 0;
    for (const auto& [na, nb] : stages) {
      CAPTURE(na);
      const affine_orb::Features<256> fa = first(a, na), fb = first(b, nb);
      const auto grown = affine_orb::detail::match_growing_features(fa, fb, options, searches);
      const auto whole = affine_orb::match_features(fa, fb, options);
      REQUIRE(grown.size() == whole.size());
      for (std::size_t k = 0; k < grown.size(); ++k) {
        CHECK(grown[k].query == whole[k].query);
        CHECK(grown[k].train == whole[k].train);
        CHECK(grown[k].distance == whole[k].distance);
      }
      matched += whole.size();
    }
    CHECK(matched > 50);
  }
}

namespace {

/// Image 1's keypoints, their predictions in image 2 and image 2's keypoints for the guided
/// matching test.
struct GuidedScene {
  affine_orb::Features<256> a, b;
  std::vector<cv::Point2f> predicted;
};

/// Image-2 partners near each prediction (shifted by up to 3 px, some with near-duplicates one
/// pixel apart), random distractors all over; some predictions are not finite.
GuidedScene guided_scene() {
  std::mt19937_64 rng(31);
  GuidedScene s;
  const auto flipped = [&](affine_orb::BinaryDescriptor<256> d, int bits) {
    for (int flip = 0; flip < bits; ++flip) {
      const unsigned bit = static_cast<unsigned>(rng() % 256);
      d[bit / 64] ^= 1ull << (bit % 64);
    }
    return d;
  };
  for (int i = 0; i < 120; ++i) {
    const affine_orb::BinaryDescriptor<256> d{rng(), rng(), rng(), rng()};
    const cv::Point2f p(static_cast<float>(rng() % 300), static_cast<float>(rng() % 300));
    s.a.descriptors.push_back(d);
    s.a.keypoints.emplace_back(p, 31.0f);
    s.a.views.push_back(0);
    s.predicted.push_back(i % 17 == 0 ? cv::Point2f(std::numeric_limits<float>::quiet_NaN(), 0.0f)
                                      : p + cv::Point2f(20.0f, -10.0f));
    const cv::Point2f at =
        p + cv::Point2f(20.0f + static_cast<float>(rng() % 7) - 3.0f, -10.0f + static_cast<float>(rng() % 7) - 3.0f);
    for (int copy = 0; copy < 1 + i % 2; ++copy) {
      s.b.descriptors.push_back(flipped(d, 10 + 30 * copy + static_cast<int>(rng() % 60)));
      s.b.keypoints.emplace_back(at + cv::Point2f(static_cast<float>(copy), 0.0f), 31.0f);
      s.b.views.push_back(copy);
    }
    s.b.descriptors.push_back({rng(), rng(), rng(), rng()});
    s.b.keypoints.emplace_back(cv::Point2f(static_cast<float>(rng() % 340), static_cast<float>(rng() % 340)), 31.0f);
    s.b.views.push_back(0);
  }
  return s;
}

/// match_guided() by brute force over every keypoint of `train`: the nearest descriptor within the
/// gate, at most max_distance bits, against the nearest in the gate farther than the exclusion
/// radius from it (ratio 0.8); duplicates kept.
std::vector<affine_orb::Match> naive_guided_matches(const affine_orb::Features<256>& a,
                                                    const affine_orb::Features<256>& train,
                                                    const std::vector<cv::Point2f>& predicted,
                                                    const affine_orb::GuidedMatchOptions& options) {
  const double gate = options.gate_radius, exclusion = options.ratio_exclusion_radius;
  const auto squared = [](cv::Point2f p, cv::Point2f q) {
    return static_cast<double>(p.x - q.x) * (p.x - q.x) + static_cast<double>(p.y - q.y) * (p.y - q.y);
  };
  std::vector<affine_orb::Match> expected;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(predicted[i].x)) continue;
    int best = 1 << 30;
    std::size_t j1 = 0;
    for (std::size_t j = 0; j < train.size(); ++j) {
      if (squared(predicted[i], train.keypoints[j].pt) > gate * gate) continue;
      const int d = affine_orb::hamming_distance(a.descriptors[i], train.descriptors[j]);
      if (d < best) {
        best = d;
        j1 = j;
      }
    }
    if (best > options.max_distance) continue;
    int second = 1 << 30;
    for (std::size_t j = 0; j < train.size(); ++j) {
      if (squared(predicted[i], train.keypoints[j].pt) > gate * gate) continue;
      if (squared(train.keypoints[j].pt, train.keypoints[j1].pt) <= exclusion * exclusion) continue;
      second = std::min(second, affine_orb::hamming_distance(a.descriptors[i], train.descriptors[j]));
    }
    if (second != 1 << 30 && !(best < static_cast<double>(0.8f) * second)) continue;
    expected.push_back({static_cast<int>(i), static_cast<int>(j1), best});
  }
  return expected;
}

}  // namespace

TEST_CASE("guided matching equals a naive reference over every keypoint of image 2") {
  const GuidedScene scene = guided_scene();
  const affine_orb::Features<256>& a = scene.a;
  const affine_orb::Features<256>& b = scene.b;
  const std::vector<cv::Point2f>& predicted = scene.predicted;
  // The same with one more image-2 keypoint 1e30 px away, which widens the search grid's cells.
  affine_orb::Features<256> b_far = b;
  b_far.keypoints.emplace_back(cv::Point2f(1e30f, -1e30f), 31.0f);
  b_far.descriptors.push_back(b.descriptors.front());
  b_far.views.push_back(0);
  for (const bool far : {false, true}) {
    CAPTURE(far);
    const affine_orb::Features<256>& train = far ? b_far : b;
    for (const double gate : {4.0, 10.0, 40.0}) {
      for (const double exclusion : {0.0, 4.0}) {
        for (const int max_distance : {40, 100}) {
          CAPTURE(gate);
          CAPTURE(exclusion);
          CAPTURE(max_distance);
          affine_orb::GuidedMatchOptions options;
          options.gate_radius = gate;
          options.ratio_exclusion_radius = exclusion;
          options.max_distance = max_distance;
          options.duplicate_radius = 0.0;
          const auto got = affine_orb::match_guided(a, train, predicted, options);
          const std::vector<affine_orb::Match> expected = naive_guided_matches(a, train, predicted, options);
          REQUIRE(got.size() == expected.size());
          for (std::size_t k = 0; k < got.size(); ++k) {
            CHECK(got[k].query == expected[k].query);
            CHECK(got[k].train == expected[k].train);
            CHECK(got[k].distance == expected[k].distance);
          }
          if (gate == 10.0 && max_distance == 100) CHECK(got.size() > 60);  // the planted partners are found
        }
      }
    }
  }
  affine_orb::GuidedMatchOptions bad;
  bad.gate_radius = 0.0;
  CHECK_THROWS_AS(affine_orb::match_guided(a, b, predicted, bad), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::match_guided(a, b, std::vector<cv::Point2f>(3)), std::invalid_argument);
  CHECK(affine_orb::match_guided(a, affine_orb::Features<256>{}, predicted).empty());
}
