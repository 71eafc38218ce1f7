// FAST-9 against a brute-force segment test written from the definition, pixel for pixel.
#include <doctest/doctest.h>

#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/detection/fast.hpp"
#include "affine_orb/extraction/detail/cell_maxima.hpp"
#include "affine_orb/extraction/detail/fork_image.hpp"
#include "affine_orb/extraction/detail/stella_image.hpp"
#include "test_data.hpp"
#include "test_simd.hpp"

namespace {

// The 16 circle pixels listed independently of the library (Rosten & Drummond 2006, fig. 1).
const int kCircleX[16] = {0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1};
const int kCircleY[16] = {-3, -3, -2, -1, 0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3};

bool naive_is_corner(const cv::Mat& image, int x, int y, int t) {
  const int c = image.at<uchar>(y, x);
  for (int start = 0; start < 16; ++start) {
    bool all_bright = true;
    bool all_dark = true;
    for (int k = 0; k < 9; ++k) {
      const int i = (start + k) % 16;
      const int v = image.at<uchar>(y + kCircleY[i], x + kCircleX[i]);
      all_bright = all_bright && v > c + t;
      all_dark = all_dark && v < c - t;
    }
    if (all_bright || all_dark) return true;
  }
  return false;
}

// Largest t in [0, 255] at which the pixel is a corner, 0 if it is not one at t = 0; found by a
// linear scan from the top so that no assumption about monotonicity is needed.
int naive_score(const cv::Mat& image, int x, int y) {
  for (int t = 255; t >= 0; --t) {
    if (naive_is_corner(image, x, y, t)) return t;
  }
  return 0;
}

void check_score_map(const cv::Mat& image, int threshold) {
  cv::Mat scores;
  affine_orb::fast_score_map(image, cv::Rect(0, 0, image.cols, image.rows), threshold, scores);
  REQUIRE(scores.size() == image.size());
  int mismatches = 0;
  int corners = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      int expected = 0;
      if (x >= 3 && y >= 3 && x < image.cols - 3 && y < image.rows - 3) {
        const int s = naive_score(image, x, y);
        if (s >= threshold && naive_is_corner(image, x, y, threshold)) expected = s;
      }
      corners += expected > 0;
      mismatches += scores.at<uchar>(y, x) != expected;
    }
  }
  CHECK(mismatches == 0);
  CHECK(corners > 0);
}

std::vector<affine_orb::Corner> naive_nms(const cv::Mat& image, int threshold) {
  cv::Mat score(image.size(), CV_32S, cv::Scalar(0));
  for (int y = 3; y < image.rows - 3; ++y) {
    for (int x = 3; x < image.cols - 3; ++x) {
      if (naive_is_corner(image, x, y, threshold)) score.at<int>(y, x) = naive_score(image, x, y);
    }
  }
  std::vector<affine_orb::Corner> out;
  for (int y = 1; y < image.rows - 1; ++y) {
    for (int x = 1; x < image.cols - 1; ++x) {
      const int s = score.at<int>(y, x);
      if (s == 0) continue;
      // Strictly above the neighbours that come earlier in raster order, at least equal to the later ones.
      bool is_max = true;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy) continue;
          const bool earlier = dy < 0 || (dy == 0 && dx < 0);
          const int n = score.at<int>(y + dy, x + dx);
          if (earlier ? n >= s : n > s) is_max = false;
        }
      }
      if (is_max) out.push_back({x, y, s});
    }
  }
  return out;
}

cv::Mat random_image(int width, int height, std::uint64_t seed, int levels) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> value(0, levels - 1);
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at<uchar>(y, x) = static_cast<uchar>(value(rng) * (255 / (levels - 1)));
  }
  return image;
}

}  // namespace

TEST_CASE("FAST score map equals the brute-force segment test on random images") {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    // Few grey levels make many exact ties with the threshold, the case strict inequalities decide.
    const cv::Mat coarse = random_image(61, 47, seed, 4);
    const cv::Mat fine = random_image(53, 41, seed + 100, 256);
    for (int threshold : {1, 7, 20, 60}) {
      CAPTURE(seed);
      CAPTURE(threshold);
      check_score_map(coarse, threshold);
      check_score_map(fine, threshold);
    }
  }
}

TEST_CASE("FAST score map equals the brute-force segment test on a real photo") {
  const cv::Mat graf = affine_orb::test::graf(1)(cv::Rect(300, 250, 120, 90)).clone();
  for (int threshold : {7, 20}) {
    CAPTURE(threshold);
    check_score_map(graf, threshold);
  }
  const cv::Mat photo = affine_orb::test::textured_photo()(cv::Rect(100, 100, 100, 80));
  check_score_map(photo, 20);  // a non-continuous ROI of a larger image
}

TEST_CASE("non-maximum suppression keeps exactly the local maxima, ties broken in raster order") {
  const cv::Mat graf = affine_orb::test::graf(1)(cv::Rect(200, 300, 150, 100)).clone();
  const cv::Mat noise = random_image(70, 50, 7, 256);
  for (const cv::Mat* image : {&graf, &noise}) {
    for (int threshold : {7, 20}) {
      const auto expected = naive_nms(*image, threshold);
      const auto got = affine_orb::detect_fast(*image, threshold, true);
      REQUIRE(got.size() == expected.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        CHECK(got[i].x == expected[i].x);
        CHECK(got[i].y == expected[i].y);
        CHECK(got[i].score == expected[i].score);
      }
      CHECK_FALSE(got.empty());
    }
  }
}

TEST_CASE("scoring a rectangle touches only that rectangle and equals the portable scalar path") {
  const cv::Mat image = random_image(97, 40, 5, 256);
  const auto offset = affine_orb::detail::circle_offsets(static_cast<std::ptrdiff_t>(image.step[0]));
  std::mt19937 rng(9);
  for (int width = 1; width <= 60; ++width) {
    for (int threshold : {3, 20}) {
      const int x0 = 3 + static_cast<int>(rng() % static_cast<unsigned>(97 - 6 - width + 1));
      cv::Mat scores(image.size(), CV_8UC1, cv::Scalar(77));
      affine_orb::fast_score_rect(image, cv::Rect(x0, 10, width, 5), threshold, scores);
      std::vector<std::uint8_t> expected(static_cast<std::size_t>(image.cols), 77);
      for (int y = 0; y < image.rows; ++y) {
        std::fill(expected.begin(), expected.end(), 77);
        if (y >= 10 && y < 15) {
          affine_orb::detail::score_row_scalar(image.ptr<std::uint8_t>(y), offset, x0, x0 + width, threshold,
                                               expected.data());
        }
        int mismatches = 0;
        for (int x = 0; x < image.cols; ++x)
          mismatches += scores.at<uchar>(y, x) != expected[static_cast<std::size_t>(x)];
        CAPTURE(width);
        CAPTURE(y);
        CHECK(mismatches == 0);
      }
    }
  }
}

TEST_CASE("a plateau of equal scores keeps exactly one corner") {
  // A dark 16x16 square on a flat background: neighbouring corner pixels have equal scores.
  cv::Mat image(40, 40, CV_8UC1, cv::Scalar(200));
  image(cv::Rect(12, 12, 16, 16)).setTo(40);
  const auto corners = affine_orb::detect_fast(image, 20);
  CHECK(corners.size() == 4);  // one per square corner
}

TEST_CASE("FAST rejects bad input") {
  cv::Mat scores;
  const cv::Mat ok(20, 20, CV_8UC1, cv::Scalar(0));
  CHECK_THROWS_AS(affine_orb::fast_score_map(cv::Mat(), cv::Rect(0, 0, 1, 1), 20, scores), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::fast_score_map(cv::Mat(20, 20, CV_8UC3), cv::Rect(0, 0, 20, 20), 20, scores),
                  std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::fast_score_map(cv::Mat(20, 20, CV_16UC1), cv::Rect(0, 0, 20, 20), 20, scores),
                  std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::fast_score_map(ok, cv::Rect(0, 0, 20, 20), 0, scores), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::fast_score_map(ok, cv::Rect(0, 0, 20, 20), 256, scores), std::invalid_argument);
  // Smaller than the circle: a valid image with no corners.
  CHECK(affine_orb::detect_fast(cv::Mat(5, 5, CV_8UC1, cv::Scalar(9)), 20).empty());
  CHECK(affine_orb::detect_fast(ok, 20).empty());
}

namespace {

// Random runs per row, some empty, some touching the image border (where the circle is outside).
affine_orb::RowSpans random_spans(cv::Size size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  affine_orb::RowSpans spans;
  spans.reset(0, size.height);
  for (int y = 0; y < size.height; ++y) {
    if (rng() % 7 == 0) continue;
    int a = static_cast<int>(rng() % static_cast<unsigned>(size.width + 1));
    int b = static_cast<int>(rng() % static_cast<unsigned>(size.width + 1));
    if (a > b) std::swap(a, b);
    spans.begin[static_cast<std::size_t>(y)] = a;
    spans.end[static_cast<std::size_t>(y)] = b;
  }
  return spans;
}

bool in_spans(const affine_orb::RowSpans& spans, int x, int y) {
  const auto [b, e] = spans.run(y);
  return x >= b && x < e;
}

}  // namespace

TEST_CASE("scoring row spans writes the scalar scores on the spans and nothing else") {
  const cv::Mat noise = random_image(83, 61, 21, 256);
  const cv::Mat graf = affine_orb::test::graf(1)(cv::Rect(250, 200, 90, 70));
  for (const cv::Mat* image : {&noise, &graf}) {
    const auto offset = affine_orb::detail::circle_offsets(static_cast<std::ptrdiff_t>(image->step[0]));
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      for (int threshold : {7, 20}) {
        const affine_orb::RowSpans spans = random_spans(image->size(), seed);
        cv::Mat scores(image->size(), CV_8UC1, cv::Scalar(77));
        affine_orb::fast_score_spans(*image, spans, threshold, scores);
        std::vector<std::uint8_t> row(static_cast<std::size_t>(image->cols));
        int mismatches = 0;
        int corners = 0;
        for (int y = 0; y < image->rows; ++y) {
          const bool circle_rows = y >= 3 && y < image->rows - 3;
          if (circle_rows) {
            affine_orb::detail::score_row_scalar(image->ptr<std::uint8_t>(y), offset, 3, image->cols - 3, threshold,
                                                 row.data());
          }
          for (int x = 0; x < image->cols; ++x) {
            int expected = 77;
            if (in_spans(spans, x, y)) {
              expected = circle_rows && x >= 3 && x < image->cols - 3 ? row[static_cast<std::size_t>(x)] : 0;
            }
            corners += expected != 77 && expected > 0;
            mismatches += scores.at<uchar>(y, x) != expected;
          }
        }
        CAPTURE(seed);
        CAPTURE(threshold);
        CHECK(mismatches == 0);
        CHECK(corners > 0);
      }
    }
  }
}

TEST_CASE("suppression on row spans keeps the rectangle's maxima that lie on the spans") {
  const cv::Mat graf = affine_orb::test::graf(1)(cv::Rect(120, 340, 140, 90)).clone();
  for (int threshold : {7, 20}) {
    cv::Mat scores;
    affine_orb::fast_score_map(graf, cv::Rect(0, 0, graf.cols, graf.rows), threshold, scores);
    const auto all = affine_orb::non_max_suppression(scores, cv::Rect(0, 0, graf.cols, graf.rows), threshold);
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const affine_orb::RowSpans spans = random_spans(graf.size(), seed + 50);
      std::vector<affine_orb::Corner> expected;
      for (const auto& c : all) {
        if (in_spans(spans, c.x, c.y)) expected.push_back(c);
      }
      std::vector<affine_orb::Corner> got{{-1, -1, 0}};  // appended to, not replaced
      affine_orb::non_max_suppression(scores, spans, threshold, got);
      REQUIRE(got.size() == expected.size() + 1);
      for (std::size_t i = 0; i < expected.size(); ++i) {
        CHECK(got[i + 1].x == expected[i].x);
        CHECK(got[i + 1].y == expected[i].y);
        CHECK(got[i + 1].score == expected[i].score);
      }
      CHECK_FALSE(expected.empty());
    }
  }
}

TEST_CASE("every compiled suppression row path equals the scalar reference, ties included") {
  MESSAGE(affine_orb::test::avx2_paths_message());
  using Row = void (*)(const cv::Mat&, int, int, int, int, std::vector<affine_orb::Corner>&);
  std::vector<std::pair<const char*, Row>> paths = {{"dispatch", &affine_orb::detail::non_max_row}};
#if AFFINE_ORB_SIMD128
  paths.emplace_back("128-bit (SSE2 or NEON)", &affine_orb::detail::non_max_row_128);
#endif
#if AFFINE_ORB_AVX2
  if (affine_orb::detail::cpu_has_avx2()) paths.emplace_back("avx2", &affine_orb::detail::non_max_row_avx2);
#endif
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    // Score maps with few distinct values (many ties) and with mostly zeros.
    cv::Mat scores = random_image(101, 23, seed, seed % 2 ? 3 : 9);
    if (seed > 3) scores.setTo(0, random_image(101, 23, seed + 7, 2) == 0);
    for (int threshold : {1, 40, 200}) {
      for (int y = 1; y < scores.rows - 1; ++y) {
        // Runs of 99, 33, 16, 17, 47, 32, 15 and 1 pixels: every path's last chunk overlapping the
        // previous one, and runs shorter than a chunk.
        for (const auto& [x0, x1] :
             {std::pair<int, int>(1, 100), {5, 38}, {17, 33}, {3, 20}, {2, 49}, {60, 92}, {60, 75}, {40, 41}}) {
          std::vector<affine_orb::Corner> expected;
          affine_orb::detail::non_max_row_scalar(scores, y, x0, x1, threshold, expected);
          for (const auto& path : paths) {
            const auto& name = path.first;  // not a structured binding: CAPTURE's lambda captures it
            const auto& row = path.second;
            CAPTURE(name);
            std::vector<affine_orb::Corner> got;
            row(scores, y, x0, x1, threshold, got);
            REQUIRE(got.size() == expected.size());
            for (std::size_t i = 0; i < got.size(); ++i) {
              CHECK(got[i].x == expected[i].x);
              CHECK(got[i].score == expected[i].score);
            }
          }
        }
      }
    }
  }
}

TEST_CASE("every compiled path of the cells' maxima rows equals the scalar reference") {
  using Row = void (*)(const cv::Mat&, int, bool, bool, int, int, const std::uint8_t*, const std::uint8_t*, int, int,
                       std::uint64_t*, std::uint64_t*);
  std::vector<std::pair<const char*, Row>> paths = {{"dispatch", &affine_orb::detail::mark_row}};
#if AFFINE_ORB_SIMD128
  paths.emplace_back("128-bit (SSE2 or NEON)",
                     &affine_orb::detail::maxima128::mark_row_run<affine_orb::detail::Lanes128>);
#endif
#if AFFINE_ORB_AVX2
  if (affine_orb::detail::cpu_has_avx2()) paths.emplace_back("avx2", &affine_orb::detail::mark_row_avx2);
#endif
  // Cells of 99, 35 and 29, 1 and 34, one column, 33, 16 and 16 pixels: runs that end inside a chunk
  // and cells narrower than the lanes.
  const std::vector<std::vector<int>> tilings = {{1, 100}, {1, 36, 71, 100}, {5, 6, 40, 41, 80},         {2, 3, 4, 50},
                                                 {10, 43}, {1, 17},          {3, 19, 35, 51, 67, 83, 99}};
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    // Score maps with few distinct values (many ties, which no maximum may win) and mostly zeros; the
    // padding past the map is random too, so a lane that reads it and is not cleared shows.
    cv::Mat padded = random_image(101 + affine_orb::detail::kCellMaximaPadding, 23, seed, seed % 2 ? 3 : 9);
    if (seed > 3) padded.setTo(0, random_image(padded.cols, 23, seed + 7, 2) == 0);
    const cv::Mat scores = padded.colRange(0, 101);
    for (const std::vector<int>& edges : tilings) {
      affine_orb::detail::CellMaximaWork work;
      work.edges = edges;
      affine_orb::detail::set_cell_columns(work);
      const std::size_t words = static_cast<std::size_t>(work.words_per_row);
      for (const auto& [strong_floor, weak_floor] : {std::pair<int, int>(1, 1), {5, 3}, {100, 1}, {255, 7}}) {
        for (int y = 1; y < scores.rows - 1; ++y) {
          for (const int edge_rows : {0, 1, 2, 3}) {
            const bool top = (edge_rows & 1) != 0;
            const bool bottom = (edge_rows & 2) != 0;
            std::vector<std::uint64_t> strong(words, 0), weak(words, 0);
            affine_orb::detail::mark_row_scalar(scores, y, top, bottom, edges.front(), edges.back(),
                                                work.drop_left.data(), work.drop_right.data(), strong_floor, weak_floor,
                                                strong.data(), weak.data());
            for (const auto& path : paths) {
              const auto& name = path.first;  // not a structured binding: CAPTURE's lambda captures it
              CAPTURE(name);
              CAPTURE(y);
              std::vector<std::uint64_t> got_strong(words, 0), got_weak(words, 0);
              path.second(scores, y, top, bottom, edges.front(), edges.back(), work.drop_left.data(),
                          work.drop_right.data(), strong_floor, weak_floor, got_strong.data(), got_weak.data());
              CHECK(got_strong == strong);
              CHECK(got_weak == weak);
            }
          }
        }
      }
    }
  }
}

namespace {

/// What the forks' extractors do in one cell: cv::FAST with non-maximum suppression on the cell's
/// image at `initial`, at `minimum` where that finds nothing; positions relative to `origin`.
void fast_in_cell(const cv::Mat& level, const cv::Rect& image, cv::Point origin, int initial, int minimum,
                  std::vector<cv::Point2f>& points, std::vector<float>& responses) {
  std::vector<cv::KeyPoint> found;
  cv::FAST(level(image), found, initial, true);
  if (found.empty()) cv::FAST(level(image), found, minimum, true);
  for (const cv::KeyPoint& k : found) {
    points.emplace_back(k.pt.x + static_cast<float>(image.x - origin.x),
                        k.pt.y + static_cast<float>(image.y - origin.y));
    responses.push_back(k.response);
  }
}

}  // namespace

TEST_CASE("the forks' cells keep the corners cv::FAST finds on each cell's image, in its order") {
  const cv::Mat photo = affine_orb::test::textured_photo();
  const cv::Mat graf = affine_orb::test::graf(1);
  // Whole images and crops whose last column or row of cells the forks skip or cut.
  const std::vector<cv::Mat> levels = {graf, photo, graf(cv::Rect(0, 0, 293, 211)), photo(cv::Rect(7, 3, 140, 77)),
                                       graf(cv::Rect(100, 100, 40, 40))};
  for (std::size_t n = 0; n < levels.size(); ++n) {
    const cv::Mat& level = levels[n];
    CAPTURE(n);
    for (const int cell_size : {30, 35}) {
      const affine_orb::detail::ForkCells cells(level.size(), cell_size);
      std::vector<cv::Point2f> expected_points;
      std::vector<float> expected_responses;
      const cv::Point origin(affine_orb::detail::kForkRegionBorder, affine_orb::detail::kForkRegionBorder);
      for (int i = 0; i < cells.rows; ++i) {
        for (int j = 0; j < cells.columns; ++j) {
          const cv::Rect scored = cells.scored(i, j);
          if (scored.width <= 0 || scored.height <= 0) continue;
          const int r = affine_orb::kFastRadius;
          const cv::Rect image(scored.x - r, scored.y - r, scored.width + 2 * r, scored.height + 2 * r);
          fast_in_cell(level, image, origin, 20, 7, expected_points, expected_responses);
        }
      }
      cv::Mat storage;
      affine_orb::detail::CellMaximaWork work;
      std::vector<cv::Point2f> points;
      std::vector<float> responses;
      affine_orb::detail::detect_in_fork_cells(level, cells, 20, 7, storage, work, points, responses);
      CAPTURE(cell_size);
      CHECK(points.size() >= (n + 1 < levels.size() ? 20u : 0u));  // the last level holds no whole cell
      CHECK(points == expected_points);
      CHECK(responses == expected_responses);
    }
  }
}

TEST_CASE("stella_vslam's cells keep the corners cv::FAST finds on each cell's image, in its order") {
  const cv::Mat photo = affine_orb::test::textured_photo();
  const cv::Mat graf = affine_orb::test::graf(1);
  // Crops whose last column and row of cells stella skips (297 x 168: regions of 4·64 + 3 and 2·64 + 2
  // pixels) or cuts.
  for (const cv::Mat& level : {graf, photo, graf(cv::Rect(0, 0, 297, 168)), photo(cv::Rect(5, 9, 90, 90))}) {
    const affine_orb::detail::StellaCells cells(level.size());
    const cv::Point origin(affine_orb::detail::kStellaRegionBorder, affine_orb::detail::kStellaRegionBorder);
    std::vector<cv::Point2f> expected_points;
    std::vector<float> expected_responses;
    for (int i = 0; i < cells.rows; ++i) {
      for (int j = 0; j < cells.columns; ++j) {
        const cv::Rect image = cells.image(i, j);
        if (image.width <= 2 * affine_orb::kFastRadius || image.height <= 2 * affine_orb::kFastRadius) continue;
        fast_in_cell(level, image, origin, 20, 7, expected_points, expected_responses);
      }
    }
    cv::Mat storage;
    affine_orb::detail::CellMaximaWork work;
    std::vector<cv::Point2f> points;
    std::vector<float> responses;
    affine_orb::DetectorOptions detector;
    detector.initial_threshold = 20;
    detector.min_threshold = 7;
    affine_orb::detail::detect_in_stella_cells(level, cells, 1.0f, detector, cv::Mat(), storage, work, points,
                                               responses);
    CHECK(points.size() >= 20u);
    CHECK(points == expected_points);
    CHECK(responses == expected_responses);
  }
}

TEST_CASE("every compiled SIMD row path of FAST equals the scalar reference") {
  MESSAGE(affine_orb::test::avx2_paths_message());
  const cv::Mat noise = random_image(150, 12, 33, 256);
  const cv::Mat coarse = random_image(150, 12, 34, 3);
  for (const cv::Mat* image : {&noise, &coarse}) {
    const auto offset = affine_orb::detail::circle_offsets(static_cast<std::ptrdiff_t>(image->step[0]));
    const std::uint8_t* row = image->ptr<std::uint8_t>(6);
    const int lo = 3;
    const int hi = image->cols - 3;
    for (int threshold : {1, 9, 30}) {
      for (int x0 = lo; x0 < hi; x0 += 7) {
        for (int x1 = x0; x1 <= hi; x1 += 5) {
          std::vector<std::uint8_t> expected(static_cast<std::size_t>(image->cols), 99);
          affine_orb::detail::score_row_scalar(row, offset, x0, x1, threshold, expected.data());
          std::vector<std::vector<std::uint8_t>> paths;
#if AFFINE_ORB_SIMD128
          paths.emplace_back(static_cast<std::size_t>(image->cols), 99);
          affine_orb::detail::score_row_128(row, offset, x0, x1, lo, hi, threshold, paths.back().data());
#endif
#if AFFINE_ORB_AVX2
          if (affine_orb::detail::cpu_has_avx2()) {
            paths.emplace_back(static_cast<std::size_t>(image->cols), 99);
            affine_orb::detail::score_row_avx2(row, offset, x0, x1, lo, hi, threshold, paths.back().data());
          }
#endif
          for (const auto& got : paths) {
            CAPTURE(x0);
            CAPTURE(x1);
            CHECK(got == expected);
          }
        }
      }
    }
  }
}
