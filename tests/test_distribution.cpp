// Feature budget and spatial spreading (SPEC §2), and the pieces of the extractor behind them:
// detection in the valid region of a view, the view renderer and sparse rBRIEF smoothing, each
// against a plain reference.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/detail/gaussian_q8.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/detail/resize.hpp"
#include "affine_orb/detection/detector.hpp"
#include "affine_orb/detection/distribution.hpp"
#include "affine_orb/detection/orientation.hpp"
#include "affine_orb/extraction/detail/view_regions.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/views/affine_views.hpp"
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

namespace {

bool in_region(const affine_orb::RowSpans& region, int x, int y) {
  const auto [b, e] = region.run(y);
  return x >= b && x < e;
}

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
      if (in_region(region, c.x, c.y)) out.push_back(c);
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

// A rotated quadrilateral region, at least `inset` pixels inside the image.
affine_orb::RowSpans quad_region(cv::Size size, double angle_degrees, int inset) {
  affine_orb::RowSpans region;
  region.reset(0, size.height);
  const double a = angle_degrees * CV_PI / 180.0;
  const cv::Point2d centre(size.width / 2.0, size.height / 2.0);
  const cv::Point2d u(std::cos(a), std::sin(a));
  const cv::Point2d v(-std::sin(a), std::cos(a));
  const double half_u = 0.45 * size.width;
  const double half_v = 0.3 * size.height;
  for (int y = inset; y < size.height - inset; ++y) {
    int first = -1;
    int last = -1;
    for (int x = inset; x < size.width - inset; ++x) {
      const cv::Point2d d(x - centre.x, y - centre.y);
      if (std::abs(d.dot(u)) <= half_u && std::abs(d.dot(v)) <= half_v) {
        if (first < 0) first = x;
        last = x;
      }
    }
    if (first >= 0) {
      region.begin[static_cast<std::size_t>(y)] = first;
      region.end[static_cast<std::size_t>(y)] = last + 1;
    }
  }
  return region;
}

}  // namespace

TEST_CASE("candidates in a region equal whole-image corners filtered by region and grid cell") {
  const cv::Mat graf = affine_orb::test::oxford_image("graf", 1)(cv::Rect(100, 80, 400, 300)).clone();
  // Low contrast in the right half, so that many cells have no corner at the initial threshold.
  cv::Mat image = graf.clone();
  image(cv::Rect(200, 0, 200, 300)) = graf(cv::Rect(200, 0, 200, 300)) * 0.15 + 100;
  affine_orb::DetectorWorkspace work;
  affine_orb::Candidates got;
  for (double angle : {0.0, 27.0, 61.0}) {
    for (const cv::Point origin : {cv::Point(18, 18), cv::Point(5, 40)}) {
      CAPTURE(angle);
      CAPTURE(origin);
      const affine_orb::RowSpans region = quad_region(image.size(), angle, 18);
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

TEST_CASE("the support region of a view level is exactly the set of pixels whose support maps inside") {
  const cv::Size size(320, 240);
  const int border = 18;
  affine_orb::PyramidOptions pyramid;
  for (const auto& view : affine_orb::make_views(affine_orb::AffineViewOptions{}, size)) {
    for (int level : {0, 2, 5}) {
      CAPTURE(view.tilt);
      CAPTURE(view.rotation_degrees);
      CAPTURE(level);
      const cv::Size level_size = affine_orb::pyramid_level_size(view.size, pyramid, level);
      const affine_orb::RowSpans region = affine_orb::detail::support_region(view, size, level_size, border);
      const cv::Matx23d& m = view.to_original;
      const double radius = border * static_cast<double>(view.size.width) / level_size.width;
      const double ex = radius * std::hypot(m(0, 0), m(0, 1));
      const double ey = radius * std::hypot(m(1, 0), m(1, 1));
      int mismatches = 0;
      long inside = 0;
      for (int y = 0; y < level_size.height; ++y) {
        for (int x = 0; x < level_size.width; ++x) {
          const cv::Point2f p0 = affine_orb::Pyramid::to_level0(
              cv::Point2f(static_cast<float>(x), static_cast<float>(y)), view.size, level_size);
          const cv::Point2d q = affine_orb::apply_affine(m, p0);
          const bool expected =
              x >= border && y >= border && x < level_size.width - border && y < level_size.height - border &&
              (view.is_identity() ||
               (q.x - ex >= 0.0 && q.y - ey >= 0.0 && q.x + ex <= size.width - 1.0 && q.y + ey <= size.height - 1.0));
          inside += expected;
          mismatches += expected != in_region(region, x, y);
        }
      }
      CHECK(mismatches == 0);
      if (level == 0) CHECK(inside > 0);
    }
  }
}

namespace {

// A view pixel by its definition in double precision: the canvas sampled bilinearly at the exact
// original position (clamped to the image), blurred along x by the normalised Gaussian (radius
// max(1, ⌈3σ⌉), canvas border replicated), then resampled bilinearly to the view width.
double exact_view_pixel(const cv::Mat& image, const affine_orb::AffineView& view, double antialias, int x, int y) {
  const cv::Matx23d m = view.to_original_canvas();
  auto canvas = [&](int c) {
    c = std::clamp(c, 0, view.canvas_size.width - 1);
    const double sx = std::clamp(m(0, 0) * c + m(0, 1) * y + m(0, 2), 0.0, image.cols - 1.0);
    const double sy = std::clamp(m(1, 0) * c + m(1, 1) * y + m(1, 2), 0.0, image.rows - 1.0);
    const int x0 = std::min(static_cast<int>(sx), image.cols - 2);
    const int y0 = std::min(static_cast<int>(sy), image.rows - 2);
    const double fx = sx - x0;
    const double fy = sy - y0;
    auto at = [&](int u, int v) { return static_cast<double>(image.at<uchar>(v, u)); };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
  };
  const double sigma = antialias * std::sqrt(view.tilt * view.tilt - 1.0);
  const int radius = sigma > 0.0 ? std::max(1, static_cast<int>(std::ceil(3.0 * sigma))) : 0;
  auto blurred = [&](int c) {
    double sum = 0.0;
    double weight = 0.0;
    for (int k = -radius; k <= radius; ++k) {
      const double g = sigma > 0.0 ? std::exp(-0.5 * k * k / (sigma * sigma)) : 1.0;
      sum += g * canvas(c + k);
      weight += g;
    }
    return sum / weight;
  };
  const double sx = (x + 0.5) * view.canvas_size.width / view.size.width - 0.5;
  int x0 = static_cast<int>(std::floor(sx));
  double f = sx - x0;
  if (x0 < 0) {
    x0 = 0;
    f = 0.0;
  } else if (x0 >= view.canvas_size.width - 1) {
    x0 = view.canvas_size.width - 1;
    f = 0.0;
  }
  return (1 - f) * blurred(x0) + f * blurred(x0 + 1);
}

}  // namespace

TEST_CASE("the view renderer is within a grey level of the exact definition and 3 of OpenCV's pipeline") {
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1);
  cv::Mat small;
  cv::resize(image, small, cv::Size(400, 320), 0, 0, cv::INTER_AREA);
  affine_orb::AffineViewOptions options;
  options.max_tilt = 4.0;  // 10 views: tilts 1, √2, 2, 2√2, 4
  for (const auto& view : affine_orb::make_views(options, small.size())) {
    CAPTURE(view.tilt);
    CAPTURE(view.rotation_degrees);
    cv::Mat scratch, ours, reference;
    affine_orb::render_view(small, view, 0.8, scratch, ours);
    affine_orb::render_view_reference(small, view, 0.8, scratch, reference);
    REQUIRE(ours.size() == view.size);
    REQUIRE(reference.size() == view.size);
    cv::Mat difference;
    cv::absdiff(ours, reference, difference);
    double worst = 0.0;
    cv::minMaxLoc(difference, nullptr, &worst);
    // OpenCV's warpAffine interpolates at 1/32 pixel, so it differs more than our 1/128.
    CHECK(worst <= 3.0);
    CHECK(cv::mean(difference)[0] < 0.4);
    std::mt19937 rng(static_cast<unsigned>(view.rotation_degrees * 10 + view.tilt));
    int far = 0;
    for (int k = 0; k < 1500; ++k) {
      const int x = static_cast<int>(rng() % static_cast<unsigned>(view.size.width));
      const int y = static_cast<int>(rng() % static_cast<unsigned>(view.size.height));
      far += std::abs(ours.at<uchar>(y, x) - exact_view_pixel(small, view, 0.8, x, y)) > 1.0;
    }
    CHECK(far == 0);

    // Rendering a region computes its pixels exactly as the whole view; the rest of each row
    // repeats the row's nearest computed pixel.
    const affine_orb::RowSpans region = affine_orb::detail::render_region(view, small.size(), 4.0);
    const affine_orb::ViewRenderer renderer(view, 0.8);
    cv::Mat partial;
    renderer.render(small, &region, scratch, partial);
    int mismatches = 0;
    for (int y = 0; y < view.size.height; ++y) {
      const auto [b, e] = region.run(y);
      const int x0 = b < e ? b : 0;
      const int x1 = b < e ? e : view.size.width;
      for (int x = 0; x < view.size.width; ++x) {
        const int source = std::clamp(x, x0, x1 - 1);
        mismatches += partial.at<uchar>(y, x) != ours.at<uchar>(y, source);
      }
    }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("the SSE2 canvas sampler and resampler give the scalar references' bytes") {
  const cv::Mat image = affine_orb::test::oxford_image("boat", 1)(cv::Rect(40, 30, 300, 200));  // a ROI
  // Tilts √2, 2, 2√2, 4√2: 8, 12, 16 and 30 resampling taps (strides 8, 16, 16, 32).
  for (const auto& [tilt, phi] : {std::pair<double, double>(2.0 * std::sqrt(2.0), 0.0),
                                  {2.0 * std::sqrt(2.0), 17.0},
                                  {std::sqrt(2.0), 50.9},
                                  {2.0, 101.8},
                                  {4.0 * std::sqrt(2.0), 178.2}}) {
    const affine_orb::AffineView view = affine_orb::make_view(tilt, phi, image.size());
    const affine_orb::detail::CanvasSampler sampler(view.to_original_canvas(), image.size());
    const affine_orb::detail::ViewResampler resampler(view.canvas_size.width, view.size.width,
                                                      0.8 * std::sqrt(tilt * tilt - 1.0));
    std::vector<std::uint8_t> a(static_cast<std::size_t>(view.canvas_size.width) + 64);
    std::vector<std::uint8_t> b(a.size());
    std::vector<std::uint8_t> out_a(static_cast<std::size_t>(view.size.width));
    std::vector<std::uint8_t> out_b(out_a.size());
    int mismatches = 0;
    for (int y = 0; y < view.canvas_size.height; y += 7) {
      // Columns beyond the canvas on both sides too: the sampler clamps to the image.
      const int c0 = -20 + y % 5;
      const int c1 = view.canvas_size.width + 20 - y % 3;
      affine_orb::detail::sample_canvas_row_scalar(image, sampler, y, c0, c1, a.data());
      std::fill(b.begin(), b.end(), 0);
#if defined(__SSE2__)
      affine_orb::detail::sample_canvas_row_sse2(image, sampler, y, c0, c1, b.data());
#else
      affine_orb::detail::sample_canvas_row_scalar(image, sampler, y, c0, c1, b.data());
#endif
      for (int i = 0; i < c1 - c0; ++i) mismatches += a[static_cast<std::size_t>(i)] != b[static_cast<std::size_t>(i)];
      // The resampler reads canvas columns first[0] .. first[W − 1] + stride − 1 of this row.
      const int first = resampler.first.front();
      const int last = resampler.first.back() + resampler.stride - 1;
      std::vector<std::uint8_t> row(static_cast<std::size_t>(last - first + 1));
      affine_orb::detail::sample_canvas_row_scalar(image, sampler, y, first, last + 1, row.data());
      affine_orb::detail::resample_row_scalar(resampler, row.data(), first, 0, view.size.width, out_a.data());
#if defined(__SSE2__)
      affine_orb::detail::resample_row_sse2(resampler, row.data(), first, 0, view.size.width, out_b.data());
#else
      affine_orb::detail::resample_row_scalar(resampler, row.data(), first, 0, view.size.width, out_b.data());
#endif
      mismatches += out_a != out_b;
    }
    CAPTURE(tilt);
    CAPTURE(phi);
    CHECK(mismatches == 0);
  }
}

TEST_CASE("every canvas sampler and resampler path gives the scalar references' bytes on any column range") {
  // The paths of this build (AVX2 eight at a time, SSE2 four at a time, clamped or not) against the
  // scalar references, on column ranges of every remainder modulo 8 and on images taller and
  // wider than the canvas.
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1)(cv::Rect(17, 9, 283, 211));  // a ROI
  std::mt19937 rng(21);
  int checked = 0;
  for (const auto& [tilt, phi] : {std::pair<double, double>(std::sqrt(2.0), 33.3),
                                  {2.0, 0.0},
                                  {2.0, 72.0},
                                  {2.0 * std::sqrt(2.0), 127.3},
                                  {4.0 * std::sqrt(2.0), 251.0}}) {
    const affine_orb::AffineView view = affine_orb::make_view(tilt, phi, image.size());
    const affine_orb::detail::CanvasSampler sampler(view.to_original_canvas(), image.size());
    const affine_orb::detail::ViewResampler resampler(view.canvas_size.width, view.size.width,
                                                      0.8 * std::sqrt(tilt * tilt - 1.0));
    const int first = resampler.first.front();
    const int last = resampler.first.back() + resampler.stride - 1;
    std::vector<std::uint8_t> row(static_cast<std::size_t>(last - first + 1));
    int mismatches = 0;
    for (int y = -3; y < view.canvas_size.height + 3; y += 5) {
      const int c0 = -30 + static_cast<int>(rng() % 40);
      const int c1 = c0 + static_cast<int>(rng() % static_cast<unsigned>(view.canvas_size.width + 40));
      std::vector<std::uint8_t> a(static_cast<std::size_t>(c1 - c0) + 1, 0);
      std::vector<std::uint8_t> b(a.size(), 0);
      affine_orb::detail::sample_canvas_row_scalar(image, sampler, y, c0, c1, a.data());
      affine_orb::detail::sample_canvas_row(image, sampler, y, c0, c1, b.data());
      mismatches += a != b;
#if defined(__SSE2__)
      std::fill(b.begin(), b.end(), 0);
      affine_orb::detail::sample_canvas_row_sse2(image, sampler, y, c0, c1, b.data());
      mismatches += a != b;
#endif
#if defined(__AVX2__)
      std::fill(b.begin(), b.end(), 0);
      affine_orb::detail::sample_canvas_row_avx2(image, sampler, y, c0, c1, b.data());
      mismatches += a != b;
#endif
      affine_orb::detail::sample_canvas_row_scalar(image, sampler, y, first, last + 1, row.data());
      const int x0 = static_cast<int>(rng() % static_cast<unsigned>(view.size.width));
      const int x1 = x0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(view.size.width - x0));
      std::vector<std::uint8_t> out_a(static_cast<std::size_t>(view.size.width), 0);
      std::vector<std::uint8_t> out_b(out_a.size(), 0);
      affine_orb::detail::resample_row_scalar(resampler, row.data(), first, x0, x1, out_a.data());
      affine_orb::detail::resample_row(resampler, row.data(), first, x0, x1, out_b.data());
      mismatches += out_a != out_b;
#if defined(__SSE2__)
      std::fill(out_b.begin(), out_b.end(), 0);
      affine_orb::detail::resample_row_sse2(resampler, row.data(), first, x0, x1, out_b.data());
      mismatches += out_a != out_b;
#endif
#if defined(__AVX2__)
      std::fill(out_b.begin(), out_b.end(), 0);
      affine_orb::detail::resample_row_avx2(resampler, row.data(), first, x0, x1, out_b.data());
      mismatches += out_a != out_b;
#endif
      ++checked;
    }
    CAPTURE(tilt);
    CAPTURE(phi);
    CHECK(mismatches == 0);
  }
  CHECK(checked > 100);
}

TEST_CASE("the integer Gaussian reproduces cv::GaussianBlur bit for bit on whole photos") {
  const cv::Mat graf = affine_orb::test::oxford_image("graf", 1);
  const cv::Mat boat = affine_orb::test::oxford_image("boat", 1)(cv::Rect(0, 0, 333, 222));
  for (const auto& [size, sigma] : {std::pair<int, double>(7, 2.0), {5, 1.2}, {9, 3.0}, {3, 0.5}, {1, 1.0}}) {
    CAPTURE(size);
    CAPTURE(sigma);
    const std::vector<std::uint16_t> kernel = affine_orb::detail::gaussian_kernel_q8(size, sigma);
    REQUIRE(static_cast<int>(kernel.size()) == size);
    int sum = 0;
    for (std::uint16_t k : kernel) sum += k;
    CHECK(sum == 256);
    for (const cv::Mat* image : {&graf, &boat}) {
      const cv::Mat copy = image->clone();
      cv::Mat expected;
      cv::GaussianBlur(copy, expected, cv::Size(size, size), sigma, sigma, cv::BORDER_REFLECT_101);
      cv::Mat ours(copy.size(), CV_8UC1, cv::Scalar(0));
      affine_orb::detail::GaussianQ8Work work;
      affine_orb::detail::smooth_square_q8(copy, cv::Rect(0, 0, copy.cols, copy.rows), kernel, work, ours);
      CHECK(cv::countNonZero(ours != expected) == 0);
    }
  }
  // Squares of every small width (the narrow ones take the scalar path), some at the image edges.
  const std::vector<std::uint16_t> kernel = affine_orb::detail::gaussian_kernel_q8(7, 2.0);
  cv::Mat expected;
  cv::GaussianBlur(boat, expected, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
  affine_orb::detail::GaussianQ8Work work;
  cv::Mat ours(boat.size(), CV_8UC1, cv::Scalar(0));
  for (int width = 1; width <= 12; ++width) {
    for (const cv::Point corner : {cv::Point(0, 0), cv::Point(100, 50), cv::Point(boat.cols - width, boat.rows - 9)}) {
      const cv::Rect square(corner, cv::Size(width, 9));
      affine_orb::detail::smooth_square_q8(boat, square, kernel, work, ours);
      CAPTURE(width);
      CHECK(cv::countNonZero(ours(square) != expected(square)) == 0);
    }
  }
  // σ = 2, 7 taps (ORB's smoothing): the kernel is the one OpenCV measures to.
  CHECK(affine_orb::detail::gaussian_kernel_q8(7, 2.0) == std::vector<std::uint16_t>{18, 34, 48, 56, 48, 34, 18});
}

TEST_CASE("rBRIEF smoothing, whole level or sparse squares, equals cv::GaussianBlur") {
  const cv::Mat image = affine_orb::test::oxford_image("bark", 1)(cv::Rect(10, 20, 500, 400));
  affine_orb::RbriefOptions small_kernel;
  small_kernel.blur_kernel = 5;
  small_kernel.blur_sigma = 1.3;
  for (const affine_orb::Rbrief& rbrief : {affine_orb::Rbrief(), affine_orb::Rbrief(small_kernel)}) {
    const int border = rbrief.border();
    const int size = rbrief.options().blur_kernel;
    const double sigma = rbrief.options().blur_sigma;
    cv::Mat expected;
    cv::GaussianBlur(image, expected, cv::Size(size, size), sigma, sigma, cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
    affine_orb::Rbrief::LevelData full;
    rbrief.prepare(image, full);
    CHECK(cv::countNonZero(full.smoothed != expected) == 0);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> px(static_cast<float>(border), static_cast<float>(image.cols - 1 - border));
    std::uniform_real_distribution<float> py(static_cast<float>(border), static_cast<float>(image.rows - 1 - border));
    std::vector<cv::Point2f> points;
    for (int i = 0; i < 60; ++i) points.emplace_back(px(rng), py(rng));
    // At the border distance exactly, so that the smoothing reflects at the level border.
    points.emplace_back(static_cast<float>(border), static_cast<float>(border));
    points.emplace_back(static_cast<float>(image.cols - 1 - border), static_cast<float>(image.rows - 1 - border));
    points.emplace_back(static_cast<float>(border) + 0.4f, static_cast<float>(image.rows - 1 - border));
    affine_orb::Rbrief::LevelData sparse;
    rbrief.prepare(image, points, sparse);
    int mismatches = 0;
    for (const cv::Point2f& p : points) {
      const cv::Rect square(cvRound(p.x) - border, cvRound(p.y) - border, 2 * border + 1, 2 * border + 1);
      mismatches += cv::countNonZero(expected(square) != sparse.smoothed(square));
      CHECK(rbrief.describe(sparse, p, 0.7f) == rbrief.describe(full, p, 0.7f));
    }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("the area split's merge keeps exactly what a brute-force merge keeps") {
  // With an unbounded budget every candidate is returned, so kKeepAll lists all of them (by
  // octave, view, level, then raster order in the view) and kMerge the ones the merge kept.
  cv::Mat image;
  cv::resize(affine_orb::test::oxford_image("graf", 1), image, cv::Size(320, 256), 0, 0, cv::INTER_AREA);
  for (const auto score : {affine_orb::ScoreType::kFast, affine_orb::ScoreType::kHarris}) {
    affine_orb::ExtractorOptions options;
    options.features = 1000000;
    options.pyramid.levels = 3;
    options.detector.score = score;
    options.duplicates = affine_orb::DuplicatePolicy::kKeepAll;
    options.view_budget = affine_orb::ViewBudget::kAreaSplit;
    affine_orb::Extractor<affine_orb::Rbrief> keep_all(options);
    const auto all = keep_all.extract(image);
    const std::vector<affine_orb::AffineView> views = keep_all.views();
    options.duplicates = affine_orb::DuplicatePolicy::kMerge;
    const auto merged = affine_orb::Extractor<affine_orb::Rbrief>(options).extract(image);
    // The level a keypoint was detected at in its view, from its size 31·s^l·√t.
    auto level_of = [&](std::size_t i) {
      const double tilt = views[static_cast<std::size_t>(all.views[i])].tilt;
      return static_cast<int>(std::lround(std::log(all.keypoints[i].size / (31.0 * std::sqrt(tilt))) /
                                          std::log(options.pyramid.scale_factor)));
    };

    // Views in index order; a candidate is dropped when a survivor of an earlier view of its
    // level lies within the merge radius (repeat_levels 0).
    std::vector<std::size_t> expected;
    for (int view = 0; view < static_cast<int>(views.size()); ++view) {
      std::vector<std::size_t> survivors;
      for (std::size_t i = 0; i < all.size(); ++i) {
        if (all.views[i] != view) continue;
        const int level = level_of(i);
        const double radius = options.merge_radius * std::pow(options.pyramid.scale_factor, level);
        bool duplicate = false;
        for (std::size_t k : expected) {
          if (level_of(k) != level) continue;
          const cv::Point2f d = all.keypoints[k].pt - all.keypoints[i].pt;
          duplicate = duplicate || std::hypot(d.x, d.y) < radius;
        }
        if (!duplicate) survivors.push_back(i);
      }
      expected.insert(expected.end(), survivors.begin(), survivors.end());
    }
    // The merged output is the kept subset in the output order of all candidates.
    std::sort(expected.begin(), expected.end());
    CAPTURE(static_cast<int>(score));
    REQUIRE(merged.size() == expected.size());
    CHECK(merged.size() < all.size());
    int mismatches = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      const std::size_t j = expected[i];
      mismatches += merged.keypoints[i].pt != all.keypoints[j].pt || merged.views[i] != all.views[j] ||
                    merged.descriptors[i] != all.descriptors[j];
    }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("pyramid resizing equals its per-pixel definition and stays within a grey level of cv::resize") {
  const cv::Mat image = affine_orb::test::oxford_image("boat", 1)(cv::Rect(13, 7, 611, 433));  // a ROI
  std::mt19937 rng(8);
  for (const cv::Size size : {cv::Size(509, 361), cv::Size(424, 301), cv::Size(611, 433), cv::Size(700, 500),
                              cv::Size(1, 1), cv::Size(3, 200), cv::Size(17, 2)}) {
    CAPTURE(size);
    cv::Mat reference;
    affine_orb::detail::resize_bilinear_reference(image, reference, size);
    affine_orb::detail::ResizeWork work;
    cv::Mat ours;
    affine_orb::detail::resize_bilinear(image, ours, size, nullptr, work);
    CHECK(cv::countNonZero(ours != reference) == 0);
    cv::Mat opencv;
    cv::resize(image, opencv, size, 0, 0, cv::INTER_LINEAR);
    cv::Mat difference;
    cv::absdiff(ours, opencv, difference);
    double worst = 0.0;
    cv::minMaxLoc(difference, nullptr, &worst);
    CHECK(worst <= 1.0);
    // A region: its runs as the whole image, the rest of each row its nearest computed pixel.
    affine_orb::RowSpans region;
    region.reset(0, size.height);
    for (int y = 0; y < size.height; ++y) {
      if (rng() % 5 == 0) continue;  // empty run: the whole row
      int a = static_cast<int>(rng() % static_cast<unsigned>(size.width));
      int b = static_cast<int>(rng() % static_cast<unsigned>(size.width));
      if (a > b) std::swap(a, b);
      region.begin[static_cast<std::size_t>(y)] = a;
      region.end[static_cast<std::size_t>(y)] = b + 1;
    }
    cv::Mat partial;
    affine_orb::detail::resize_bilinear(image, partial, size, &region, work);
    int mismatches = 0;
    for (int y = 0; y < size.height; ++y) {
      const auto [b, e] = region.run(y);
      for (int x = 0; x < size.width; ++x) {
        const int source = b < e ? std::clamp(x, b, e - 1) : x;
        mismatches += partial.at<uchar>(y, x) != reference.at<uchar>(y, source);
      }
    }
    CHECK(mismatches == 0);
  }
  // The pyramid chains the resizes.
  affine_orb::Pyramid pyramid;
  pyramid.build(image);
  cv::Mat level = image.clone();
  for (int l = 1; l < pyramid.levels(); ++l) {
    cv::Mat next;
    affine_orb::detail::resize_bilinear_reference(level, next, affine_orb::pyramid_level_size(image.size(), {}, l));
    CHECK(cv::countNonZero(pyramid.level(l) != next) == 0);
    level = next;
  }
}

TEST_CASE("every resize row and column blend path gives the scalar references' values") {
  // Random source rows (extremes included) and column tables of several ratios; column ranges of
  // every remainder modulo 8.
  std::mt19937 rng(34);
  for (const auto& [from, to] : {std::pair<int, int>(640, 533), {533, 444}, {37, 31}, {100, 100}, {90, 200}}) {
    CAPTURE(from);
    CAPTURE(to);
    affine_orb::detail::ResizeWork work;
    work.prepare(cv::Size(from, 4), cv::Size(to, 3));
    std::vector<std::uint8_t> top(static_cast<std::size_t>(from));
    std::vector<std::uint8_t> bottom(top.size());
    int mismatches = 0;
    for (int trial = 0; trial < 40; ++trial) {
      for (std::size_t i = 0; i < top.size(); ++i) {
        top[i] = static_cast<std::uint8_t>(trial % 3 == 0 ? 255 * (rng() % 2) : rng() % 256);
        bottom[i] = static_cast<std::uint8_t>(rng() % 256);
      }
      const int b = trial % 5 == 0 ? 128 * (trial % 2) : static_cast<int>(rng() % 129);
      const int c0 = static_cast<int>(rng() % static_cast<unsigned>(from));
      const int c1 = c0 + static_cast<int>(rng() % static_cast<unsigned>(from - c0 + 1));
      std::vector<std::int16_t> rows_a(static_cast<std::size_t>(from) + 1, 0);
      std::vector<std::int16_t> rows_b(rows_a.size(), 0);
      affine_orb::detail::blend_rows_scalar(top.data(), bottom.data(), b, c0, c1, rows_a.data());
#if defined(__SSE2__)
      affine_orb::detail::blend_rows_sse2(top.data(), bottom.data(), b, c0, c1, rows_b.data());
      mismatches += rows_a != rows_b;
#endif
#if AFFINE_ORB_NEON
      std::fill(rows_b.begin(), rows_b.end(), 0);
      affine_orb::detail::blend_rows_neon(top.data(), bottom.data(), b, c0, c1, rows_b.data());
      mismatches += rows_a != rows_b;
#endif
#if defined(__AVX2__)
      std::fill(rows_b.begin(), rows_b.end(), 0);
      affine_orb::detail::blend_rows_avx2(top.data(), bottom.data(), b, c0, c1, rows_b.data());
      mismatches += rows_a != rows_b;
#endif
      // The column blend reads the whole blended row (plus the repeated last column).
      affine_orb::detail::blend_rows_scalar(top.data(), bottom.data(), b, 0, from, rows_a.data());
      rows_a[static_cast<std::size_t>(from)] = rows_a[static_cast<std::size_t>(from) - 1];
      const int x0 = static_cast<int>(rng() % static_cast<unsigned>(to));
      const int x1 = x0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(to - x0));
      std::vector<std::uint8_t> out_a(static_cast<std::size_t>(to), 0);
      std::vector<std::uint8_t> out_b(out_a.size(), 0);
      affine_orb::detail::blend_columns_scalar(work, rows_a.data(), x0, x1, out_a.data());
#if defined(__SSE2__)
      affine_orb::detail::blend_columns_sse2(work, rows_a.data(), x0, x1, out_b.data());
      mismatches += out_a != out_b;
#endif
#if AFFINE_ORB_NEON
      std::fill(out_b.begin(), out_b.end(), 0);
      affine_orb::detail::blend_columns_neon(work, rows_a.data(), x0, x1, out_b.data());
      mismatches += out_a != out_b;
#endif
#if defined(__AVX2__)
      std::fill(out_b.begin(), out_b.end(), 0);
      affine_orb::detail::blend_columns_avx2(work, rows_a.data(), x0, x1, out_b.data());
      mismatches += out_a != out_b;
#endif
    }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("rBRIEF orientation equals the intensity-centroid angle of the scalar disc") {
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1)(cv::Rect(30, 40, 600, 500));
  std::mt19937 rng(12);
  for (int radius : {3, 8, 15, 22, 64}) {
    affine_orb::RbriefOptions options;
    options.orientation_radius = radius;
    const affine_orb::Rbrief rbrief(options);
    const affine_orb::CentroidDisc disc(radius);
    affine_orb::Rbrief::LevelData data;
    rbrief.prepare(image, {}, data);
    const int border = rbrief.border();
    std::uniform_int_distribution<int> px(border, image.cols - 1 - border);
    std::uniform_int_distribution<int> py(border, image.rows - 1 - border);
    int mismatches = 0;
    for (int k = 0; k < 300; ++k) {
      const int x = px(rng);
      const int y = py(rng);
      mismatches += rbrief.orientation(data, cv::Point2f(static_cast<float>(x), static_cast<float>(y))) !=
                    disc.angle(image, x, y);
    }
    CAPTURE(radius);
    CHECK(mismatches == 0);
  }
}

namespace {

// The quadtree spreading as first written (a vector of members per cell), the reference for the
// in-place version.
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

  struct Cell {
    cv::Rect2f box;
    std::vector<int> members;
  };
  std::vector<Cell> cells;
  const int roots = std::max(1, static_cast<int>(std::lround(region.width / std::max(region.height, 1.0f))));
  const float root_width = region.width / static_cast<float>(roots);
  cells.resize(static_cast<std::size_t>(roots));
  for (int r = 0; r < roots; ++r) {
    cells[static_cast<std::size_t>(r)].box = {region.x + r * root_width, region.y, root_width, region.height};
  }
  for (int i = 0; i < n; ++i) {
    const cv::Point2f& p = points[static_cast<std::size_t>(i)];
    int r = static_cast<int>((p.x - region.x) / root_width);
    r = std::clamp(r, 0, roots - 1);
    cells[static_cast<std::size_t>(r)].members.push_back(i);
  }
  cells.erase(std::remove_if(cells.begin(), cells.end(), [](const Cell& c) { return c.members.empty(); }), cells.end());

  auto splittable = [](const Cell& c) { return c.members.size() > 1 && c.box.width >= 1.0f && c.box.height >= 1.0f; };
  while (static_cast<int>(cells.size()) < target) {
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (splittable(cells[i])) order.push_back(i);
    }
    if (order.empty()) break;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return cells[a].members.size() > cells[b].members.size(); });
    std::vector<bool> split(cells.size(), false);
    int count = static_cast<int>(cells.size());
    std::vector<Cell> children;
    for (std::size_t idx : order) {
      if (count >= target) break;
      const Cell& cell = cells[idx];
      const float hw = cell.box.width * 0.5f;
      const float hh = cell.box.height * 0.5f;
      const float cx = cell.box.x + hw;
      const float cy = cell.box.y + hh;
      Cell quad[4] = {{{cell.box.x, cell.box.y, hw, hh}, {}},
                      {{cx, cell.box.y, hw, hh}, {}},
                      {{cell.box.x, cy, hw, hh}, {}},
                      {{cx, cy, hw, hh}, {}}};
      for (int m : cell.members) {
        const cv::Point2f& p = points[static_cast<std::size_t>(m)];
        quad[(p.x >= cx ? 1 : 0) + (p.y >= cy ? 2 : 0)].members.push_back(m);
      }
      int nonempty = 0;
      for (Cell& q : quad) {
        if (!q.members.empty()) {
          children.push_back(std::move(q));
          ++nonempty;
        }
      }
      count += nonempty - 1;
      split[idx] = true;
    }
    std::vector<Cell> next;
    next.reserve(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (!split[i]) next.push_back(std::move(cells[i]));
    }
    for (Cell& c : children) next.push_back(std::move(c));
    cells = std::move(next);
  }

  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  for (const Cell& cell : cells) {
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
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1);
  affine_orb::ExtractorOptions options;
  options.features = 1000;
  options.views.max_tilt = 1.0;
  affine_orb::ExtractorOptions strongest = options;
  strongest.spreading = affine_orb::Spreading::kStrongest;
  const auto spread = affine_orb::Extractor<affine_orb::Rbrief>(options).extract(image);
  const auto strong = affine_orb::Extractor<affine_orb::Rbrief>(strongest).extract(image);
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
}
