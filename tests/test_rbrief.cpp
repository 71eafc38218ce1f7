// rBRIEF-256 and the intensity-centroid angle against plain reference implementations of their
// definitions (Rublee et al., ICCV 2011), on real photos.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include "affine_orb/descriptors/detail/gaussian_q8.hpp"
#include "affine_orb/descriptors/detail/moment_lanes.hpp"
#include "affine_orb/descriptors/detail/orb_pattern.hpp"
#include "affine_orb/descriptors/detail/rbrief_tests.hpp"
#include "affine_orb/descriptors/detail/rotated_offsets.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/orientation.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "test_data.hpp"
#include "test_simd.hpp"

namespace {

// ORB's disc by its definition, formulated as transpose symmetry: rows |v| <= r/√2 have half-width
// round(√(r² − v²)); a higher row v reaches every column u whose own (rounded) column reaches v,
// i.e. max{u : round(√(r² − u²)) >= v}.
std::vector<int> naive_orb_disc(int r) {
  std::vector<int> w(static_cast<std::size_t>(r) + 1);
  for (int v = 0; v <= r; ++v) {
    if (v <= r / std::sqrt(2.0)) {
      w[static_cast<std::size_t>(v)] = static_cast<int>(std::lround(std::sqrt(r * r - v * v)));
      continue;
    }
    int reach = 0;
    for (int u = 0; u <= r; ++u) {
      if (std::lround(std::sqrt(r * r - u * u)) >= v) reach = u;
    }
    w[static_cast<std::size_t>(v)] = reach;
  }
  return w;
}

// m10 = Σ u I, m01 = Σ v I over ORB's disc, angle = fastAtan2(m01, m10) degrees times the float
// π/180, as ORB (OpenCV, ORB-SLAM2) steers its pattern.
float naive_centroid_angle(const cv::Mat& image, int x, int y, int r) {
  const std::vector<int> w = naive_orb_disc(r);
  long long m10 = 0;
  long long m01 = 0;
  for (int v = -r; v <= r; ++v) {
    for (int u = -r; u <= r; ++u) {
      if (std::abs(u) > w[static_cast<std::size_t>(std::abs(v))]) continue;
      const int value = image.at<uchar>(y + v, x + u);
      m10 += u * value;
      m01 += v * value;
    }
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10)) * static_cast<float>(CV_PI / 180.0);
}

// Bit i = [I_s(c + R a_i) < I_s(c + R b_i)], byte i / 8, bit i % 8 (OpenCV's byte layout).
std::vector<uchar> naive_rbrief(const cv::Mat& smoothed, cv::Point2f pt, float angle) {
  const float a = std::cos(angle);
  const float b = std::sin(angle);
  const int cx = cvRound(pt.x);
  const int cy = cvRound(pt.y);
  std::vector<uchar> bytes(32, 0);
  for (int i = 0; i < 256; ++i) {
    const auto& p = affine_orb::detail::kOrbTestPairs[static_cast<std::size_t>(i)];
    const int ax = cx + cvRound(p.xa * a - p.ya * b);
    const int ay = cy + cvRound(p.xa * b + p.ya * a);
    const int bx = cx + cvRound(p.xb * a - p.yb * b);
    const int by = cy + cvRound(p.xb * b + p.yb * a);
    if (smoothed.at<uchar>(ay, ax) < smoothed.at<uchar>(by, bx))
      bytes[static_cast<std::size_t>(i / 8)] |= 1u << (i % 8);
  }
  return bytes;
}

}  // namespace

TEST_CASE("ORB's published pair table is the one in the ORB paper's distribution") {
  const auto& pairs = affine_orb::detail::kOrbTestPairs;
  // Spot checks against the published table (first, second and last rows) and its range.
  CHECK(pairs[0].xa == 8);
  CHECK(pairs[0].ya == -3);
  CHECK(pairs[0].xb == 9);
  CHECK(pairs[0].yb == 5);
  CHECK(pairs[1].xa == 4);
  CHECK(pairs[1].yb == -12);
  CHECK(pairs[255].xa == -1);
  CHECK(pairs[255].ya == -6);
  CHECK(pairs[255].xb == 0);
  CHECK(pairs[255].yb == -11);
  for (const auto& p : pairs) {
    for (int c : {p.xa, p.ya, p.xb, p.yb}) {
      CHECK(c >= -13);
      CHECK(c <= 12);
    }
  }
}

TEST_CASE("ORB's disc: the published radius-15 rows, and symmetric under transposition for every radius") {
  CHECK(affine_orb::orb_disc_half_widths(15) ==
        std::vector<int>{15, 15, 15, 15, 14, 14, 14, 13, 13, 12, 11, 10, 9, 8, 6, 3});
  for (int r = 1; r <= 64; ++r) {
    CAPTURE(r);
    const std::vector<int> w = affine_orb::orb_disc_half_widths(r);
    CHECK(w == naive_orb_disc(r));
    int asymmetric = 0;
    for (int v = 0; v <= r; ++v) {
      for (int u = 0; u <= r; ++u)
        asymmetric += (u <= w[static_cast<std::size_t>(v)]) != (v <= w[static_cast<std::size_t>(u)]);
    }
    CHECK(asymmetric == 0);
  }
}

TEST_CASE("rBRIEF bits and centroid angles equal the naive definitions on every level") {
  const cv::Mat image = affine_orb::test::textured_photo();
  affine_orb::ExtractorOptions options;
  options.features = 1500;
  options.views.max_tilt = 1.0;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  std::vector<cv::Mat> pyramid;
  const auto features = extractor.extract(image, cv::Mat(), pyramid);
  REQUIRE(features.size() == 1500);
  const cv::Mat mat = affine_orb::descriptors_to_mat(features.descriptors);
  REQUIRE(mat.rows == 1500);
  REQUIRE(mat.cols == 32);

  std::vector<cv::Mat> smoothed(pyramid.size());
  for (std::size_t l = 0; l < pyramid.size(); ++l) {
    cv::GaussianBlur(pyramid[l], smoothed[l], cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  }
  int angle_mismatch = 0;
  int bit_mismatch = 0;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const cv::KeyPoint& kp = features.keypoints[i];
    const int level = kp.octave;
    // Back to the integer level position the keypoint was detected at.
    const cv::Mat& level_image = pyramid[static_cast<std::size_t>(level)];
    const float sx = static_cast<float>(image.cols) / static_cast<float>(level_image.cols);
    const float sy = static_cast<float>(image.rows) / static_cast<float>(level_image.rows);
    const cv::Point2f p((kp.pt.x + 0.5f) / sx - 0.5f, (kp.pt.y + 0.5f) / sy - 0.5f);
    const int x = cvRound(p.x);
    const int y = cvRound(p.y);
    CHECK(std::abs(p.x - static_cast<float>(x)) < 1e-3f);
    CHECK(std::abs(p.y - static_cast<float>(y)) < 1e-3f);
    const float angle = naive_centroid_angle(level_image, x, y, 15);
    angle_mismatch += affine_orb::radians_to_degrees_0_360(angle) != kp.angle;
    const std::vector<uchar> expected = naive_rbrief(smoothed[static_cast<std::size_t>(level)],
                                                     cv::Point2f(static_cast<float>(x), static_cast<float>(y)), angle);
    for (int b = 0; b < 32; ++b)
      bit_mismatch += expected[static_cast<std::size_t>(b)] != mat.at<uchar>(static_cast<int>(i), b);
  }
  CHECK(angle_mismatch == 0);
  CHECK(bit_mismatch == 0);
}

TEST_CASE("rBRIEF describe() matches the definition at arbitrary angles") {
  const cv::Mat image = affine_orb::test::textured_photo();
  affine_orb::Rbrief rbrief;
  affine_orb::Rbrief::LevelData data;
  rbrief.prepare(image, data);
  cv::Mat smoothed;
  cv::GaussianBlur(image, smoothed, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> angle(-3.2f, 3.2f);
  std::uniform_int_distribution<int> px(rbrief.border(), image.cols - 1 - rbrief.border());
  std::uniform_int_distribution<int> py(rbrief.border(), image.rows - 1 - rbrief.border());
  int mismatches = 0;
  for (int k = 0; k < 500; ++k) {
    const cv::Point2f pt(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
    const float theta = angle(rng);
    const auto descriptor = rbrief.describe(data, pt, theta);
    const cv::Mat row = affine_orb::descriptors_to_mat(std::vector<affine_orb::BinaryDescriptor<256>>{descriptor});
    const auto expected = naive_rbrief(smoothed, pt, theta);
    for (int b = 0; b < 32; ++b) mismatches += expected[static_cast<std::size_t>(b)] != row.at<uchar>(0, b);
  }
  CHECK(mismatches == 0);
  // Corner reads stay inside: the farthest rotated test point plus rounding is the border.
  CHECK(rbrief.border() == 18);
}

TEST_CASE("rBRIEF rotated test offsets: the SSE2 and AVX2 paths give the scalar reference's integers") {
  MESSAGE(affine_orb::test::avx2_paths_message());
  namespace d = affine_orb::detail;
  std::vector<float> x, y;
  for (const auto& pair : d::kOrbTestPairs) {
    x.insert(x.end(), {static_cast<float>(pair.xa), static_cast<float>(pair.xb)});
    y.insert(y.end(), {static_cast<float>(pair.ya), static_cast<float>(pair.yb)});
  }
  // Angles on a fine grid, the quarter and eighth turns (products at exact halves: rounding ties)
  // and random ones, each at three row steps.
  std::vector<float> angles;
  for (int i = -1800; i <= 1800; ++i) angles.push_back(static_cast<float>(i * CV_PI / 1800.0));
  for (int i = -8; i <= 8; ++i) angles.push_back(static_cast<float>(i * CV_PI / 4.0));
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> any(-4.0f, 4.0f);
  for (int i = 0; i < 500; ++i) angles.push_back(any(rng));
  int mismatches = 0;
  int ties = 0;
  std::vector<std::int32_t> expected(x.size()), out(x.size());
  for (const float angle : angles) {
    const float a = std::cos(angle);
    const float b = std::sin(angle);
    for (const std::int32_t step : {41, 704, 4096}) {
      d::rotated_offsets_scalar(x.data(), y.data(), x.size(), a, b, step, expected.data());
      for (std::size_t i = 0; i < x.size(); ++i) {
        const float u = x[i] * a - y[i] * b;
        ties += u - std::floor(u) == 0.5f;
      }
      auto check = [&](auto path) {
        std::fill(out.begin(), out.end(), -1);
        path(x.data(), y.data(), x.size(), a, b, step, out.data());
        mismatches += out != expected;
      };
      check(d::rotated_offsets);
#if defined(__SSE2__)
      check(d::rotated_offsets_sse2);
#endif
#if AFFINE_ORB_AVX2
      if (d::cpu_has_avx2()) check(d::rotated_offsets_avx2);
#endif
    }
  }
  CHECK(ties > 0);
  CHECK(mismatches == 0);
}

TEST_CASE("rBRIEF options are checked") {
  affine_orb::RbriefOptions options;
  options.blur_kernel = 6;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.blur_sigma = std::nan("");
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.blur_sigma = -1;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  options = {};
  options.orientation_radius = 0;
  CHECK_THROWS_AS(affine_orb::Rbrief{options}, std::invalid_argument);
  affine_orb::Rbrief rbrief;
  affine_orb::Rbrief::LevelData data;
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(), data), std::invalid_argument);
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(40, 40, CV_8UC3), data), std::invalid_argument);
  CHECK_THROWS_AS(rbrief.prepare(cv::Mat(40, 40, CV_32F), data), std::invalid_argument);
}

namespace {

// The bytes of the union of `squares` in `a` and `b` that differ.
int union_mismatches(const cv::Mat& a, const cv::Mat& b, const std::vector<cv::Rect>& squares) {
  cv::Mat mask(a.size(), CV_8UC1, cv::Scalar(0));
  for (const cv::Rect& s : squares) mask(s).setTo(255);
  cv::Mat differ = a != b;
  differ &= mask;
  return cv::countNonZero(differ);
}

// Random points in [−margin, size + margin), some in tight clusters so that squares overlap heavily.
std::vector<cv::Point2f> random_points(cv::Size size, int count, int margin, std::mt19937& rng) {
  std::uniform_real_distribution<float> px(static_cast<float>(-margin), static_cast<float>(size.width + margin - 1));
  std::uniform_real_distribution<float> py(static_cast<float>(-margin), static_cast<float>(size.height + margin - 1));
  std::uniform_real_distribution<float> jitter(-4.0f, 4.0f);
  std::vector<cv::Point2f> points;
  for (int i = 0; i < count; ++i) {
    if (i % 3 == 2) {
      points.emplace_back(points.back().x + jitter(rng), points.back().y + jitter(rng));
    } else {
      points.emplace_back(px(rng), py(rng));
    }
  }
  return points;
}

/// The squares of side 2 `border` + 1 around `points` (rounded), cut to an image of `size`, the
/// empty ones left out.
std::vector<cv::Rect> squares_around(const std::vector<cv::Point2f>& points, int border, cv::Size size) {
  const int side = 2 * border + 1;
  std::vector<cv::Rect> squares;
  for (const cv::Point2f& p : points) {
    const cv::Rect s =
        cv::Rect(cvRound(p.x) - border, cvRound(p.y) - border, side, side) & cv::Rect(0, 0, size.width, size.height);
    if (!s.empty()) squares.push_back(s);
  }
  return squares;
}

/// Pixels where the runs of `work` break their definition: each pixel once, the runs disjoint and
/// covering the union of `squares` and the gaps of fewer than 8 columns between its pixels in a
/// row, nothing else.
int run_coverage_errors(const affine_orb::detail::GaussianQ8Work& work, const std::vector<cv::Rect>& squares,
                        cv::Size size) {
  cv::Mat covered(size, CV_8UC1, cv::Scalar(0));
  for (const affine_orb::detail::RunBand& band : work.out.bands) {
    for (int i = band.begin; i < band.end; ++i) {
      const cv::Vec2i run = work.out.runs[static_cast<std::size_t>(i)];
      covered(cv::Range(band.y0, band.y1), cv::Range(run[0], run[1])) += 1;
    }
  }
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  for (const cv::Rect& s : squares) mask(s).setTo(1);
  int bad = 0;
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const int c = covered.at<uchar>(y, x);
      if (c > 1 || (c == 0 && mask.at<uchar>(y, x) == 1)) ++bad;
      if (c == 0 || mask.at<uchar>(y, x) == 1) continue;
      int left = x;
      while (left >= 0 && mask.at<uchar>(y, left) == 0) --left;
      int right = x;
      while (right < size.width && mask.at<uchar>(y, right) == 0) ++right;
      if (left < 0 || right == size.width || right - left - 1 >= 8) ++bad;
    }
  }
  return bad;
}

/// Where the scalar passes' outputs `v` (the y pass of `rows` from column x0) and `h` (the x pass
/// of `column`) differ from the formulas of detail/gaussian_q8.hpp with kernel `k` of `size` taps.
int formula_mismatches(const std::vector<const std::uint8_t*>& rows, int x0, int width, const std::uint16_t* k,
                       int size, const std::vector<std::int16_t>& column, const std::vector<std::int16_t>& v,
                       const std::vector<std::uint8_t>& h) {
  int mismatches = 0;
  for (int x = 0; x < width; ++x) {
    std::uint32_t sum = 0;
    for (int j = 0; j < size; ++j) sum += k[j] * static_cast<std::uint32_t>(rows[static_cast<std::size_t>(j)][x0 + x]);
    mismatches += v[static_cast<std::size_t>(x)] + 32768 != static_cast<int>(sum);
    std::uint32_t out = 1u << 15;
    for (int i = 0; i < size; ++i) {
      out += k[i] * static_cast<std::uint32_t>(column[static_cast<std::size_t>(x + i)] + 32768);
    }
    mismatches += h[static_cast<std::size_t>(x)] != (out >> 16);
  }
  return mismatches;
}

}  // namespace

TEST_CASE("rBRIEF smoothing of the union of squares equals cv::GaussianBlur on every pixel of the union") {
  const cv::Mat photo = affine_orb::test::textured_photo();
  std::mt19937 rng(7);
  affine_orb::RbriefOptions wide_kernel;
  wide_kernel.blur_kernel = 11;
  wide_kernel.blur_sigma = 2.5;
  for (const affine_orb::Rbrief& rbrief : {affine_orb::Rbrief(), affine_orb::Rbrief(wide_kernel)}) {
    const int border = rbrief.border();
    const int size = rbrief.options().blur_kernel;
    const double sigma = rbrief.options().blur_sigma;
    // Levels of several sizes, including ones smaller than a square and a ROI of a larger image.
    for (const cv::Rect roi : {cv::Rect(0, 0, 640, 480), cv::Rect(13, 7, 301, 203), cv::Rect(100, 100, 90, 40),
                               cv::Rect(5, 5, 20, 33), cv::Rect(50, 60, 7, 9)}) {
      const cv::Mat level = photo(roi);
      cv::Mat expected;
      cv::GaussianBlur(level, expected, cv::Size(size, size), sigma, sigma,
                       cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
      for (const int count : {1, 3, 10, 40, 120}) {
        CAPTURE(roi);
        CAPTURE(count);
        const std::vector<cv::Point2f> points = random_points(level.size(), count, border / 2, rng);
        const std::vector<cv::Rect> squares = squares_around(points, border, level.size());
        affine_orb::Rbrief::LevelData data;
        data.smoothed = cv::Mat(level.size(), CV_8UC1, cv::Scalar(0));
        rbrief.prepare(level, points, data);
        CHECK(union_mismatches(data.smoothed, expected, squares) == 0);
        // The union itself, whatever its area (prepare() smooths the whole level above half).
        const std::vector<std::uint16_t> kernel = affine_orb::detail::gaussian_kernel_q8(size, sigma);
        affine_orb::detail::GaussianQ8Work work;
        cv::Mat ours(level.size(), CV_8UC1, cv::Scalar(0));
        affine_orb::detail::smooth_squares_q8(level, squares, kernel, work, ours);
        CHECK(union_mismatches(ours, expected, squares) == 0);
        CHECK(run_coverage_errors(work, squares, level.size()) == 0);
      }
    }
  }
}

TEST_CASE("rBRIEF smoothing: the SSE2, AVX2 and NEON passes equal the scalar reference and the formula") {
  MESSAGE(affine_orb::test::avx2_paths_message());
  namespace d = affine_orb::detail;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  for (const auto& kernel_shape : {std::pair<int, double>(7, 2.0), {5, 1.2}, {9, 3.0}, {3, 0.5}, {1, 1.0}, {31, 8.0}}) {
    const int size = kernel_shape.first;  // not a structured binding: the lambdas below capture it
    const double sigma = kernel_shape.second;
    CAPTURE(size);
    const std::vector<std::uint16_t> kernel = d::gaussian_kernel_q8(size, sigma);
    REQUIRE(static_cast<int>(kernel.size()) == size);
    const std::uint16_t* k = kernel.data();
    for (int width = 1; width <= 70; ++width) {
      CAPTURE(width);
      // Rows of random bytes, and all 0 or all 255 (the ends of the 16-bit range) for some widths.
      auto value = [&] { return static_cast<std::uint8_t>(width % 7 == 0 ? 255 : width % 7 == 1 ? 0 : byte(rng)); };
      const int x0 = width % 5;
      std::vector<std::vector<std::uint8_t>> image(static_cast<std::size_t>(size),
                                                   std::vector<std::uint8_t>(static_cast<std::size_t>(x0 + width)));
      std::vector<const std::uint8_t*> rows;
      for (auto& row : image) {
        for (std::uint8_t& b : row) b = value();
        rows.push_back(row.data());
      }
      std::vector<std::int16_t> v_reference(static_cast<std::size_t>(width));
      d::gaussian_q8_v_scalar<0>(rows.data(), x0, width, k, size, v_reference.data());
      // The x pass input: width + size − 1 values and one more that the vector paths read.
      std::vector<std::int16_t> column(static_cast<std::size_t>(width + size));
      for (std::int16_t& c : column)
        c = static_cast<std::int16_t>(width % 7 == 0 ? 32512 : width % 7 == 1 ? -32768 : byte(rng) * 255 - 32768);
      std::vector<std::uint8_t> h_reference(static_cast<std::size_t>(width));
      d::gaussian_q8_h_scalar<0>(column.data(), width, k, size, h_reference.data());
      // The scalar passes are the formulas of detail/gaussian_q8.hpp.
      CHECK(formula_mismatches(rows, x0, width, k, size, column, v_reference, h_reference) == 0);
      std::vector<std::int16_t> v(static_cast<std::size_t>(width));
      std::vector<std::uint8_t> h(static_cast<std::size_t>(width));
      auto check = [&](auto v_pass, auto h_pass) {
        std::fill(v.begin(), v.end(), std::int16_t{0});
        std::fill(h.begin(), h.end(), std::uint8_t{0});
        v_pass(rows.data(), x0, width, k, size, v.data());
        h_pass(column.data(), width, k, size, h.data());
        CHECK(v == v_reference);
        CHECK(h == h_reference);
      };
      if (size == 7) check(d::gaussian_q8_v_scalar<7>, d::gaussian_q8_h_scalar<7>);
#if defined(__SSE2__)
      check(d::gaussian_q8_v_128<0>, d::gaussian_q8_h_sse2<0>);
      if (size == 7) check(d::gaussian_q8_v_128<7>, d::gaussian_q8_h_sse2<7>);
#endif
#if AFFINE_ORB_NEON
      check(d::gaussian_q8_v_128<0>, d::gaussian_q8_h_neon<0>);
      if (size == 7) check(d::gaussian_q8_v_128<7>, d::gaussian_q8_h_neon<7>);
#endif
#if AFFINE_ORB_AVX2
      if (affine_orb::detail::cpu_has_avx2()) {
        check(d::gaussian_q8_v_avx2<0>, d::gaussian_q8_h_avx2<0>);
        if (size == 7) check(d::gaussian_q8_v_avx2<7>, d::gaussian_q8_h_avx2<7>);
      }
#endif
    }
  }
}

TEST_CASE("the integer Gaussian reproduces cv::GaussianBlur bit for bit on whole photos") {
  const cv::Mat graf = affine_orb::test::graf(1);
  const cv::Mat photo = affine_orb::test::textured_photo()(cv::Rect(0, 0, 333, 222));
  for (const auto& kernel_shape : {std::pair<int, double>(7, 2.0), {5, 1.2}, {9, 3.0}, {3, 0.5}, {1, 1.0}}) {
    const int size = kernel_shape.first;  // not a structured binding: CAPTURE's lambda captures it
    const double sigma = kernel_shape.second;
    CAPTURE(size);
    CAPTURE(sigma);
    const std::vector<std::uint16_t> kernel = affine_orb::detail::gaussian_kernel_q8(size, sigma);
    REQUIRE(static_cast<int>(kernel.size()) == size);
    int sum = 0;
    for (std::uint16_t k : kernel) sum += k;
    CHECK(sum == 256);
    for (const cv::Mat* image : {&graf, &photo}) {
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
  cv::GaussianBlur(photo, expected, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
  affine_orb::detail::GaussianQ8Work work;
  cv::Mat ours(photo.size(), CV_8UC1, cv::Scalar(0));
  for (int width = 1; width <= 12; ++width) {
    for (const cv::Point corner :
         {cv::Point(0, 0), cv::Point(100, 50), cv::Point(photo.cols - width, photo.rows - 9)}) {
      const cv::Rect square(corner, cv::Size(width, 9));
      affine_orb::detail::smooth_square_q8(photo, square, kernel, work, ours);
      CAPTURE(width);
      CHECK(cv::countNonZero(ours(square) != expected(square)) == 0);
    }
  }
  // σ = 2, 7 taps (ORB's smoothing): the kernel is the one OpenCV measures to.
  CHECK(affine_orb::detail::gaussian_kernel_q8(7, 2.0) == std::vector<std::uint16_t>{18, 34, 48, 56, 48, 34, 18});
}

TEST_CASE("rBRIEF smoothing, whole level or sparse squares, equals cv::GaussianBlur") {
  const cv::Mat image = affine_orb::test::textured_photo()(cv::Rect(10, 20, 500, 400));
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

TEST_CASE("the intensity-test kernels give the scalar reference's bits") {
  namespace d = affine_orb::detail;
  MESSAGE(affine_orb::test::avx2_paths_message());
  std::mt19937 rng(31);
  cv::Mat noise(120, 130, CV_8UC1);
  cv::randu(noise, 0, 256);
  // Ties (I_a == I_b) must give 0: a flat image and one of two grey levels.
  const cv::Mat flat(120, 130, CV_8UC1, cv::Scalar(77));
  cv::Mat two_levels(120, 130, CV_8UC1);
  cv::randu(two_levels, 0, 2);
  two_levels *= 255;
  std::uniform_int_distribution<int> coordinate(-18, 18);
  using Words = std::array<std::uint64_t, 4>;
  const auto run = [](auto kernel, const std::uint8_t* center, const std::int32_t* offset) {
    Words words{};
    kernel(center, offset, words.data());
    return words;
  };
  for (const cv::Mat& image : {noise, flat, two_levels}) {
    const std::uint8_t* center = image.ptr<std::uint8_t>(60) + 65;
    int mismatches = 0, ones = 0;
    for (int k = 0; k < 100; ++k) {
      std::array<std::int32_t, 2 * d::kRbriefTests> offset;
      for (std::int32_t& o : offset) o = coordinate(rng) * static_cast<std::int32_t>(image.step[0]) + coordinate(rng);
      const Words expected = run(d::rbrief_tests_scalar, center, offset.data());
      for (std::uint64_t w : expected) ones += __builtin_popcountll(w);
      mismatches += run(d::rbrief_tests, center, offset.data()) != expected;
#if AFFINE_ORB_SIMD128
      mismatches += run(d::rbrief_tests_128, center, offset.data()) != expected;
#endif
#if AFFINE_ORB_AVX2
      if (d::cpu_has_avx2()) mismatches += run(d::rbrief_tests_avx2, center, offset.data()) != expected;
#endif
    }
    CHECK(mismatches == 0);
    if (image.data == flat.data) CHECK(ones == 0);              // ties give 0
    if (image.data == noise.data) CHECK(ones > 100 * 256 / 3);  // about half the bits set
  }
}

#if AFFINE_ORB_SIMD128
TEST_CASE("the centroid moment kernels give the moments of a naive sum over the disc") {
  namespace d = affine_orb::detail;
  MESSAGE(affine_orb::test::avx2_paths_message());
  std::mt19937 rng(21);
  cv::Mat noise(200, 220, CV_8UC1);
  cv::randu(noise, 0, 256);
  const cv::Mat white(200, 220, CV_8UC1, cv::Scalar(255));
  for (int radius : {3, 7, 8, 9, 15, 16, 22, 31, 32, 64}) {
    const std::vector<int> half = affine_orb::orb_disc_half_widths(radius);
    const d::DiscChunks<8> chunks8 = d::disc_chunks<8>(half);
#if AFFINE_ORB_AVX2
    const d::DiscChunks<32, std::int8_t> chunks32 = d::disc_chunks<32, std::int8_t>(half);
#endif
    for (const cv::Mat& image : {noise, white}) {
      std::uniform_int_distribution<int> px(radius + 16, image.cols - 1 - radius - 16);
      std::uniform_int_distribution<int> py(radius, image.rows - 1 - radius);
      int mismatches = 0;
      for (int k = 0; k < 200; ++k) {
        const int x = px(rng);
        const int y = py(rng);
        std::int64_t m01 = 0, m10 = 0;
        for (int v = -radius; v <= radius; ++v) {
          const int w = half[static_cast<std::size_t>(std::abs(v))];
          for (int u = -w; u <= w; ++u) {
            const int i = image.at<std::uint8_t>(y + v, x + u);
            m01 += static_cast<std::int64_t>(v) * i;
            m10 += static_cast<std::int64_t>(u) * i;
          }
        }
        const std::uint8_t* center = image.ptr<std::uint8_t>(y) + x;
        const std::size_t step = image.step[0];
        const d::CentroidMoments a = d::centroid_moments_128(center, step, chunks8);
        mismatches += a.m01 != m01 || a.m10 != m10;
#if AFFINE_ORB_AVX2
        if (d::cpu_has_avx2() && radius <= d::kCentroidAvx2MaxRadius) {
          const d::CentroidMoments b = d::centroid_moments_avx2(center, step, chunks32);
          mismatches += b.m01 != m01 || b.m10 != m10;
        }
#endif
      }
      CAPTURE(radius);
      CHECK(mismatches == 0);
    }
  }
}
#endif

TEST_CASE("rBRIEF orientation equals the intensity-centroid angle of the scalar disc") {
  const cv::Mat image = affine_orb::test::graf(1)(cv::Rect(30, 40, 600, 500));
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
