// Tests of the pyramid (detection/pyramid.hpp): resizing against its per-pixel definition, cv::resize
// and the scalar references of every SIMD path.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/detection/detail/opencv_resize.hpp"
#include "affine_orb/detection/detail/resize.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "test_data.hpp"
#include "test_simd.hpp"

TEST_CASE("pyramid resizing equals its per-pixel definition and stays within a grey level of cv::resize") {
  const cv::Mat image = affine_orb::test::textured_photo()(cv::Rect(13, 7, 611, 433));  // a ROI
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

namespace {

/// Columns [c0, c1) of rows `top` and `bottom` blended with weight b by every row-blend path of
/// this build and CPU: how many differ from the scalar reference.
int row_blend_mismatches(const std::vector<std::uint8_t>& top, const std::vector<std::uint8_t>& bottom, int b, int c0,
                         int c1) {
  std::vector<std::int16_t> rows_a(top.size() + 1, 0);
  std::vector<std::int16_t> rows_b(rows_a.size(), 0);
  affine_orb::detail::blend_rows_scalar(top.data(), bottom.data(), b, c0, c1, rows_a.data());
  int mismatches = 0;
#if defined(__SSE2__)
  affine_orb::detail::blend_rows_sse2(top.data(), bottom.data(), b, c0, c1, rows_b.data());
  mismatches += rows_a != rows_b;
#endif
#if AFFINE_ORB_NEON
  std::fill(rows_b.begin(), rows_b.end(), 0);
  affine_orb::detail::blend_rows_neon(top.data(), bottom.data(), b, c0, c1, rows_b.data());
  mismatches += rows_a != rows_b;
#endif
#if AFFINE_ORB_AVX2
  if (affine_orb::detail::cpu_has_avx2()) {
    std::fill(rows_b.begin(), rows_b.end(), 0);
    affine_orb::detail::blend_rows_avx2(top.data(), bottom.data(), b, c0, c1, rows_b.data());
    mismatches += rows_a != rows_b;
  }
#endif
  return mismatches;
}

/// Output columns [x0, x1) of a row of `to` columns from the blended row `blended` by every
/// column-blend path of this build and CPU: how many differ from the scalar reference.
int column_blend_mismatches(const affine_orb::detail::ResizeWork& work, const std::vector<std::int16_t>& blended,
                            int x0, int x1, int to) {
  std::vector<std::uint8_t> out_a(static_cast<std::size_t>(to), 0);
  std::vector<std::uint8_t> out_b(out_a.size(), 0);
  affine_orb::detail::blend_columns_scalar(work, blended.data(), x0, x1, out_a.data());
  int mismatches = 0;
#if defined(__SSE2__)
  affine_orb::detail::blend_columns_sse2(work, blended.data(), x0, x1, out_b.data());
  mismatches += out_a != out_b;
#endif
#if AFFINE_ORB_NEON
  std::fill(out_b.begin(), out_b.end(), 0);
  affine_orb::detail::blend_columns_neon(work, blended.data(), x0, x1, out_b.data());
  mismatches += out_a != out_b;
#endif
#if AFFINE_ORB_AVX2
  if (affine_orb::detail::cpu_has_avx2()) {
    std::fill(out_b.begin(), out_b.end(), 0);
    affine_orb::detail::blend_columns_avx2(work, blended.data(), x0, x1, out_b.data());
    mismatches += out_a != out_b;
  }
#endif
  return mismatches;
}

}  // namespace

TEST_CASE("every resize row and column blend path gives the scalar references' values") {
  MESSAGE(affine_orb::test::avx2_paths_message());
  // Random source rows (extremes included) and column tables of several ratios; column ranges of
  // every remainder modulo 8.
  std::mt19937 rng(34);
  std::size_t windowed = 0;  // blocks of the AVX2 column blend with a window, and without
  std::size_t unwindowed = 0;
  // 640 -> 200 spans more than a window per half block: the AVX2 blend's loads without one.
  for (const auto& widths : {std::pair<int, int>(640, 533), {533, 444}, {37, 31}, {100, 100}, {90, 200}, {640, 200}}) {
    const int from = widths.first;  // not a structured binding: CAPTURE's lambda captures it
    const int to = widths.second;
    CAPTURE(from);
    CAPTURE(to);
    affine_orb::detail::ResizeWork work;
    work.prepare(cv::Size(from, 4), cv::Size(to, 3));
    const auto with_window = static_cast<std::size_t>(std::count(work.windowed.begin(), work.windowed.end(), 1));
    windowed += with_window;
    unwindowed += work.windowed.size() - with_window;
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
      mismatches += row_blend_mismatches(top, bottom, b, c0, c1);
      // The column blend reads the whole blended row (plus the repeated last column, plus the
      // entries a window may load beyond it, which no column may use).
      std::vector<std::int16_t> blended(static_cast<std::size_t>(from) + 1 + affine_orb::detail::ResizeWork::kWindow,
                                        -1);
      affine_orb::detail::blend_rows_scalar(top.data(), bottom.data(), b, 0, from, blended.data());
      blended[static_cast<std::size_t>(from)] = blended[static_cast<std::size_t>(from) - 1];
      const int x0 = static_cast<int>(rng() % static_cast<unsigned>(to));
      const int x1 = x0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(to - x0));
      mismatches += column_blend_mismatches(work, blended, x0, x1, to);
    }
    CHECK(mismatches == 0);
  }
  CHECK(windowed > 0);
  CHECK(unwindowed > 0);
}

TEST_CASE("cv::resize's row pass: the SSE2 and AVX2 kernels give the scalar reference's sums") {
  // Downscales by 1.2 (ORB-SLAM's), 1.5 and 1.9 (sources of a block more than 16 bytes apart: no
  // window), upscales, equal sizes, rows shorter than a window; random rows with extremes.
  std::mt19937 rng(55);
  int windows = 0;
  for (const auto& widths : {std::pair<int, int>(1241, 1034),
                             {1034, 862},
                             {640, 533},
                             {600, 400},
                             {190, 100},
                             {100, 190},
                             {77, 77},
                             {15, 12},
                             {9, 20},
                             {31, 26}}) {
    const int from = widths.first;  // not a structured binding: CAPTURE's lambda captures it
    const int to = widths.second;
    CAPTURE(from);
    CAPTURE(to);
    affine_orb::detail::CvResizeAxis axis;
    axis.set(from, to, true);
    for (const int w : axis.window) windows += w >= 0;
    std::vector<std::uint8_t> row(static_cast<std::size_t>(from));
    for (int trial = 0; trial < 20; ++trial) {
      for (std::uint8_t& v : row) v = static_cast<std::uint8_t>(trial % 4 == 0 ? 255 * (rng() % 2) : rng() % 256);
      std::vector<int> expected(static_cast<std::size_t>(to), -1);
      affine_orb::detail::resize_row_x_scalar(row.data(), axis, 0, to, expected.data());
      std::vector<int> got(expected.size(), -1);
      affine_orb::detail::resize_row_x_sse2(row.data(), axis, got.data());
      CHECK(got == expected);
#if AFFINE_ORB_AVX2
      if (affine_orb::detail::cpu_has_avx2()) {
        std::fill(got.begin(), got.end(), -1);
        affine_orb::detail::resize_row_x_avx2(row.data(), axis, got.data());
        CHECK(got == expected);
      }
#endif
    }
  }
  CHECK(windows > 300);  // the AVX2 kernel's vector path runs, not only its fallback
}

TEST_CASE("cv::resize's column pass: the SSE2 and AVX2 kernels give the scalar reference's bytes") {
  // Rows as the row pass makes them (0 to 255 · 2048, extremes included) and weight pairs as the
  // column axis gives them (summing to 2048, one of them 0 at a clamped edge), widths around the
  // kernels' 8 and 16 pixels and a KITTI level's.
  std::mt19937 rng(56);
  std::uniform_int_distribution<int> sum(0, 255 * 2048);
  std::uniform_int_distribution<int> weight(0, 2048);
  for (const int width : {1, 7, 8, 15, 16, 17, 31, 33, 862, 1034}) {
    CAPTURE(width);
    std::vector<int> h0(static_cast<std::size_t>(width)), h1(h0.size());
    for (int trial = 0; trial < 20; ++trial) {
      for (std::size_t i = 0; i < h0.size(); ++i) {
        h0[i] = trial % 5 == 0 ? 255 * 2048 * static_cast<int>(rng() % 2) : sum(rng);
        h1[i] = trial % 5 == 1 ? 255 * 2048 : sum(rng);
      }
      const int b0 = trial % 7 == 0 ? 2048 : weight(rng);
      const int b1 = 2048 - b0;
      std::vector<std::uint8_t> expected(h0.size(), 7), got(h0.size(), 9);
      affine_orb::detail::blend_resized_rows_scalar(h0.data(), h1.data(), b0, b1, 0, width, expected.data());
      affine_orb::detail::blend_resized_rows_sse2(h0.data(), h1.data(), b0, b1, width, got.data());
      CHECK(got == expected);
#if AFFINE_ORB_AVX2
      if (affine_orb::detail::cpu_has_avx2()) {
        std::fill(got.begin(), got.end(), 9);
        affine_orb::detail::blend_resized_rows_avx2(h0.data(), h1.data(), b0, b1, width, got.data());
        CHECK(got == expected);
      }
#endif
    }
  }
}

TEST_CASE("build_resized: every level is what cv::resize makes of the level before, byte for byte") {
  // cv::resize itself is the reference: random images and sizes (downscales by ORB-SLAM's 1.2 and
  // others, upscales, exactly half, the same size, one-pixel edges), and a ROI source.
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> side(1, 260);
  std::uniform_int_distribution<int> byte(0, 255);
  affine_orb::detail::OpenCvResizeWork work;
  int cases = 0;
  for (int t = 0; t < 300; ++t) {
    cv::Mat big(side(rng) + 4, side(rng) + 4, CV_8UC1);
    for (int y = 0; y < big.rows; ++y) {
      for (int x = 0; x < big.cols; ++x) big.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(byte(rng));
    }
    const cv::Mat src = big(cv::Rect(2, 2, big.cols - 4, big.rows - 4));
    cv::Size size(side(rng), side(rng));
    if (t % 4 == 0) size = cv::Size(cvRound(src.cols / 1.2f), cvRound(src.rows / 1.2f));
    if (t % 17 == 0) size = cv::Size(src.cols / 2, src.rows / 2);
    if (t % 19 == 0) size = src.size();
    if (size.width < 1 || size.height < 1) continue;
    CAPTURE(src.size());
    CAPTURE(size);
    cv::Mat expected;
    cv::resize(src, expected, size, 0.0, 0.0, cv::INTER_LINEAR);
    cv::Mat got(size, CV_8UC1);
    affine_orb::detail::resize_linear_8u(src, got, work);
    CHECK(cv::norm(expected, got, cv::NORM_INF) == 0.0);
    ++cases;
  }
  CHECK(cases > 250);
  // The pyramid of a real photo at ORB-SLAM's sizes.
  const cv::Mat image = affine_orb::test::textured_photo();
  std::vector<cv::Size> sizes = {image.size()};
  float factor = 1.0f;
  for (int l = 1; l < 8; ++l) {
    factor *= 1.2f;
    sizes.emplace_back(cvRound(static_cast<float>(image.cols) * (1.0f / factor)),
                       cvRound(static_cast<float>(image.rows) * (1.0f / factor)));
  }
  affine_orb::Pyramid pyramid;
  pyramid.build_resized(image, sizes);
  cv::Mat previous = image;
  for (int l = 1; l < 8; ++l) {
    cv::Mat expected;
    cv::resize(previous, expected, sizes[static_cast<std::size_t>(l)], 0.0, 0.0, cv::INTER_LINEAR);
    CHECK(cv::norm(expected, pyramid.level(l), cv::NORM_INF) == 0.0);
    previous = expected;
  }
}
