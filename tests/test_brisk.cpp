// Tests of the BRISK descriptor policy (brisk.hpp) against its definition: the pattern sizes, a
// second, naive implementation (explicit box sums in plain loops, explicit pair loops, exact rational
// comparisons), exact 90° rotations of a real photo, the border contract and the argument checks.

#include <doctest/doctest.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "test_data.hpp"

namespace {

using affine_orb::Brisk;
using affine_orb::BriskOptions;
using Descriptor = affine_orb::BinaryDescriptor<Brisk::kBits>;

constexpr double kPi = 3.14159265358979323846;

// ---- The naive reference: the definition of brisk.hpp written out again, independently. ----

struct NaivePoint {
  double x;
  double y;
  int side;
};

struct NaivePattern {
  std::vector<NaivePoint> points;
  std::vector<std::pair<int, int>> short_pairs;
  std::vector<std::pair<int, int>> long_pairs;
};

// The default pattern: rings {0, 2.9, 4.9, 7.4, 10.8} × 0.85 with {1, 10, 14, 15, 20} points,
// σ = 1.3 r sin(π/n) (0.65 at the centre), box side = the odd n closest to √(12σ² + 1); pairs shorter
// than 9.75·0.6 px are short, longer than 13.67·0.6 px are long.
NaivePattern naive_pattern() {
  const double radii[] = {0.0, 2.9, 4.9, 7.4, 10.8};
  const int counts[] = {1, 10, 14, 15, 20};
  NaivePattern pattern;
  for (int ring = 0; ring < 5; ++ring) {
    const double r = 0.85 * radii[ring];
    const double sigma = ring == 0 ? 0.65 : 1.3 * r * std::sin(kPi / counts[ring]);
    const double target = std::sqrt(12.0 * sigma * sigma + 1.0);
    int side = 1;
    for (int n = 3; n < 100; n += 2) {
      if (std::abs(n - target) < std::abs(side - target)) side = n;
    }
    for (int j = 0; j < counts[ring]; ++j) {
      const double a = 2.0 * kPi * j / counts[ring];
      pattern.points.push_back({r * std::cos(a), r * std::sin(a), side});
    }
  }
  const int n = static_cast<int>(pattern.points.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double dx = pattern.points[j].x - pattern.points[i].x;
      const double dy = pattern.points[j].y - pattern.points[i].y;
      const double d = std::sqrt(dx * dx + dy * dy);
      if (d < 9.75 * 0.6) pattern.short_pairs.emplace_back(i, j);
      if (d > 13.67 * 0.6) pattern.long_pairs.emplace_back(i, j);
    }
  }
  return pattern;
}

// A smoothed intensity as the exact fraction sum / (65536 · area).
struct Sample {
  std::int64_t sum;
  std::int64_t area;
};

// The side x side box mean at (cx + dx, cy + dy), interpolated bilinearly between the boxes centred
// on the four pixels around it with the position rounded to 1/256 pixel, by explicit summation of
// each box; throws when any pixel of the four boxes lies outside the image.
Sample naive_sample(const cv::Mat& image, int cx, int cy, double dx, double dy, int side) {
  const long qx = std::lround(dx * 256.0);
  const long qy = std::lround(dy * 256.0);
  const int x = cx + static_cast<int>(qx >= 0 ? qx / 256 : -((-qx + 255) / 256));
  const int y = cy + static_cast<int>(qy >= 0 ? qy / 256 : -((-qy + 255) / 256));
  const std::int64_t fx = ((qx % 256) + 256) % 256;
  const std::int64_t fy = ((qy % 256) + 256) % 256;
  const int h = side / 2;
  if (x - h < 0 || y - h < 0 || x + 1 + h >= image.cols || y + 1 + h >= image.rows) {
    throw std::out_of_range("naive_sample: the boxes leave the image");
  }
  std::int64_t sum = 0;
  for (int b = 0; b <= 1; ++b) {
    for (int a = 0; a <= 1; ++a) {
      std::int64_t box = 0;
      for (int v = y + b - h; v <= y + b + h; ++v) {
        for (int u = x + a - h; u <= x + a + h; ++u) box += image.at<std::uint8_t>(v, u);
      }
      sum += (a ? fx : 256 - fx) * (b ? fy : 256 - fy) * box;
    }
  }
  return {sum, static_cast<std::int64_t>(side) * side};
}

// Orientation by the explicit sum over the long pairs (eqs. 5–6), means as doubles.
double naive_orientation(const NaivePattern& pattern, const cv::Mat& image, int cx, int cy) {
  std::vector<double> mean;
  for (const auto& p : pattern.points) {
    const Sample sample = naive_sample(image, cx, cy, p.x, p.y, p.side);
    mean.push_back(static_cast<double>(sample.sum) / (65536.0 * static_cast<double>(sample.area)));
  }
  double gx = 0.0;
  double gy = 0.0;
  for (const auto& [i, j] : pattern.long_pairs) {
    const double dx = pattern.points[j].x - pattern.points[i].x;
    const double dy = pattern.points[j].y - pattern.points[i].y;
    const double d2 = dx * dx + dy * dy;
    gx += dx * (mean[j] - mean[i]) / d2;
    gy += dy * (mean[j] - mean[i]) / d2;
  }
  gx /= static_cast<double>(pattern.long_pairs.size());
  gy /= static_cast<double>(pattern.long_pairs.size());
  return std::atan2(gy, gx);
}

// The rotation step of an angle: nearest multiple of 2π/1024, in [0, 1024).
int naive_step(double angle) {
  const long step = std::lround(angle / (2.0 * kPi) * 1024.0) % 1024;
  return static_cast<int>(step < 0 ? step + 1024 : step);
}

// Descriptor (eq. 7) with the pattern rotated by the rotation matrix of step·2π/1024; bit b compares
// the exact means sum_j/area_j > sum_i/area_i by cross-multiplication.
std::bitset<512> naive_describe(const NaivePattern& pattern, const cv::Mat& image, int cx, int cy, int step) {
  const double theta = 2.0 * kPi * step / 1024.0;
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  std::vector<Sample> samples;
  for (const auto& p : pattern.points) {
    samples.push_back(naive_sample(image, cx, cy, c * p.x - s * p.y, s * p.x + c * p.y, p.side));
  }
  std::bitset<512> bits;
  for (std::size_t b = 0; b < pattern.short_pairs.size(); ++b) {
    const Sample& si = samples[static_cast<std::size_t>(pattern.short_pairs[b].first)];
    const Sample& sj = samples[static_cast<std::size_t>(pattern.short_pairs[b].second)];
    bits[b] = sj.sum * si.area > si.sum * sj.area;
  }
  return bits;
}

std::bitset<512> to_bits(const Descriptor& d) {
  std::bitset<512> bits;
  for (int b = 0; b < 512; ++b)
    bits[static_cast<std::size_t>(b)] = (d[static_cast<std::size_t>(b / 64)] >> (b % 64)) & 1u;
  return bits;
}

int hamming(const Descriptor& a, const Descriptor& b) {
  int distance = 0;
  for (std::size_t w = 0; w < a.size(); ++w) distance += static_cast<int>(std::bitset<64>(a[w] ^ b[w]).count());
  return distance;
}

// Absolute difference of two angles in radians, wrapped to [0, π].
double angle_difference(double a, double b) {
  const double d = std::remainder(a - b, 2.0 * kPi);
  return std::abs(d);
}

// Corners (cv::goodFeaturesToTrack, integer positions) at least `margin` px inside the image.
std::vector<cv::Point> corners(const cv::Mat& image, int margin, int count) {
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(margin, margin, image.cols - 2 * margin, image.rows - 2 * margin)).setTo(255);
  std::vector<cv::Point2f> found;
  cv::goodFeaturesToTrack(image, found, count, 0.01, 6.0, mask);
  std::vector<cv::Point> points;
  for (const auto& p : found) points.emplace_back(cvRound(p.x), cvRound(p.y));
  return points;
}

}  // namespace

TEST_CASE("the default pattern has 60 points on the published rings, 1770 pairs, 512 short and 870 long") {
  const Brisk brisk;
  const auto& pattern = brisk.pattern();
  REQUIRE(pattern.points.size() == 60);
  CHECK(pattern.pair_count == 1770);
  CHECK(pattern.short_pairs.size() == 512);
  CHECK(pattern.long_pairs.size() == 870);
  CHECK(Brisk::kBits == 512);

  const double radii[] = {0.0, 2.9, 4.9, 7.4, 10.8};
  const int counts[] = {1, 10, 14, 15, 20};
  for (int ring = 0; ring < 5; ++ring) {
    CHECK(pattern.ring_radius[static_cast<std::size_t>(ring)] == doctest::Approx(0.85 * radii[ring]));
    int on_ring = 0;
    for (const auto& p : pattern.points) {
      if (p.ring != ring) continue;
      ++on_ring;
      CHECK(std::hypot(p.x, p.y) == doctest::Approx(0.85 * radii[ring]).epsilon(1e-12));
      if (ring > 0) {
        const double expected = 2.0 * kPi * p.index_on_ring / counts[ring];
        CHECK(angle_difference(std::atan2(p.y, p.x), expected) < 1e-12);
      }
    }
    CHECK(on_ring == counts[ring]);
  }
  // σ_k = 1.3 r_k sin(π/n_k): 0.65, 0.99, 1.20, 1.70, 1.87 px; boxes of the same variance, odd.
  const double sigmas[] = {0.65, 0.9902, 1.2048, 1.7001, 1.8669};
  const int boxes[] = {3, 3, 5, 5, 7};
  for (std::size_t ring = 0; ring < 5; ++ring) {
    CHECK(pattern.ring_sigma[ring] == doctest::Approx(sigmas[ring]).epsilon(1e-3));
    CHECK(pattern.ring_box[ring] == boxes[ring]);
  }
  // Short pairs are shorter than δ_max = 5.85 px, long ones longer than δ_min = 8.202 px, each in
  // (i, j) lexicographic order.
  CHECK(brisk.options().max_short_distance() == doctest::Approx(5.85));
  CHECK(brisk.options().min_long_distance() == doctest::Approx(8.202));
  for (std::size_t b = 0; b < pattern.short_pairs.size(); ++b) {
    const auto& pair = pattern.short_pairs[b];
    CHECK(pair.i < pair.j);
    CHECK(pair.distance < 5.85);
    if (b > 0) {
      const auto& previous = pattern.short_pairs[b - 1];
      CHECK(std::make_pair(previous.i, previous.j) < std::make_pair(pair.i, pair.j));
    }
  }
  for (const auto& pair : pattern.long_pairs) CHECK(pair.distance > 8.202);

  // The outermost boxes: radius 9.18 lies between pixels 9 and 10, plus 3 for the 7-pixel box: 13 px;
  // border() adds one pixel. The support's diameter is 2 · (9.18 + 3.5).
  CHECK(brisk.border() == 14);
  CHECK(Brisk::kPatchSize == doctest::Approx(2.0 * (pattern.ring_radius[4] + pattern.ring_box[4] / 2.0)).epsilon(1e-3));
}

TEST_CASE("the pattern agrees with the naive pattern, pair by pair") {
  const Brisk brisk;
  const NaivePattern naive = naive_pattern();
  REQUIRE(naive.short_pairs.size() == 512);
  REQUIRE(naive.long_pairs.size() == 870);
  for (std::size_t b = 0; b < 512; ++b) {
    CHECK(brisk.pattern().short_pairs[b].i == naive.short_pairs[b].first);
    CHECK(brisk.pattern().short_pairs[b].j == naive.short_pairs[b].second);
  }
}

TEST_CASE("orientation and descriptor equal a naive implementation on graf img1") {
  const cv::Mat image = affine_orb::test::graf(1);
  const Brisk brisk;
  Brisk::LevelData data;
  brisk.prepare(image, data);
  const NaivePattern naive = naive_pattern();
  const std::vector<cv::Point> points = corners(image, brisk.border(), 150);
  REQUIRE(points.size() >= 100);

  std::mt19937 rng(7);
  std::uniform_real_distribution<float> any_angle(-10.0f, 10.0f);
  int bits_compared = 0;
  double worst_angle_error = 0.0;
  for (const cv::Point& p : points) {
    const cv::Point2f pt(static_cast<float>(p.x), static_cast<float>(p.y));
    const float theta = brisk.orientation(data, pt);
    const double reference = naive_orientation(naive, image, p.x, p.y);
    worst_angle_error = std::max(worst_angle_error, angle_difference(theta, reference));
    CHECK(theta > -kPi - 1e-6);
    CHECK(theta <= kPi + 1e-6);

    const float angles[] = {theta, any_angle(rng), any_angle(rng), 0.0f};
    for (const float angle : angles) {
      CHECK(Brisk::angle_step(angle) == naive_step(angle));
      const std::bitset<512> expected = naive_describe(naive, image, p.x, p.y, naive_step(angle));
      const std::bitset<512> got = to_bits(brisk.describe(data, pt, angle));
      CHECK(got == expected);
      bits_compared += 512;
    }
  }
  MESSAGE("worst orientation difference to the naive reference: " << worst_angle_error << " rad over " << points.size()
                                                                  << " keypoints");
  CHECK(worst_angle_error < 1e-4);
  CHECK(bits_compared >= 100 * 4 * 512);
}

TEST_CASE("a uniform patch has orientation 0 and an all-zero descriptor") {
  const cv::Mat image(40, 40, CV_8UC1, cv::Scalar(200));
  const Brisk brisk;
  Brisk::LevelData data;
  brisk.prepare(image, data);
  CHECK(brisk.orientation(data, {20.0f, 20.0f}) == 0.0f);
  const Descriptor d = brisk.describe(data, {20.0f, 20.0f}, 1.0f);
  CHECK(to_bits(d).none());
}

TEST_CASE("an exact 90 degree rotation rotates the orientation by 90 degrees and keeps the descriptor") {
  const cv::Mat photo = affine_orb::test::graf(1);
  const cv::Mat crop = photo(cv::Rect(150, 120, 420, 380)).clone();
  cv::Mat rotated;
  cv::rotate(crop, rotated, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (rows − 1 − y, x)
  const Brisk brisk;
  Brisk::LevelData data;
  Brisk::LevelData rotated_data;
  brisk.prepare(crop, data);
  brisk.prepare(rotated, rotated_data);

  const std::vector<cv::Point> points = corners(crop, brisk.border(), 300);
  REQUIRE(points.size() >= 200);
  std::vector<Descriptor> original;
  std::vector<Descriptor> turned;
  int within_5_degrees = 0;
  double error_sum = 0.0;
  for (const cv::Point& p : points) {
    const cv::Point2f pt(static_cast<float>(p.x), static_cast<float>(p.y));
    const cv::Point2f q(static_cast<float>(crop.rows - 1 - p.y), static_cast<float>(p.x));
    const float theta = brisk.orientation(data, pt);
    const float theta_rotated = brisk.orientation(rotated_data, q);
    const double error = angle_difference(theta_rotated - theta, kPi / 2);
    error_sum += error;
    if (error < 5.0 * kPi / 180.0) ++within_5_degrees;
    original.push_back(brisk.describe(data, pt, theta));
    turned.push_back(brisk.describe(rotated_data, q, theta_rotated));
  }
  const double n = static_cast<double>(points.size());
  double same = 0.0;
  double other = 0.0;
  int identical = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int d = hamming(original[i], turned[i]);
    same += d;
    if (d == 0) ++identical;
    other += hamming(original[i], turned[(i * 7 + 13) % points.size()]);
  }
  same /= n;
  other /= n;
  MESSAGE(points.size() << " corners: orientation within 5 deg of +90: " << within_5_degrees << ", mean error "
                        << error_sum / n * 180.0 / kPi << " deg; mean Hamming distance " << same
                        << " (identical: " << identical << ") vs " << other << " for unrelated pairs");
  // Measured: 298 of 300 within 5° (mean error 0.73°), mean distance 3.9 bits against 205 for
  // unrelated pairs. An exact 90° turn maps the interpolated samples of step s onto those of step
  // s + 256, so the only differences come from the orientation error.
  CHECK(within_5_degrees >= 0.95 * n);
  CHECK(same < 12.0);
  CHECK(same < 0.1 * other);
}

TEST_CASE("a keypoint exactly border() from the edges reads only pixels of the image, at every rotation") {
  const Brisk brisk;
  const int b = brisk.border();
  const NaivePattern naive = naive_pattern();
  // Smallest image with a valid keypoint: (2b + 1)^2, the keypoint in the middle; and the four
  // corners of a wider image. naive_sample throws if any box of the definition leaves the image.
  cv::Mat image(2 * b + 1, 2 * b + 1, CV_8UC1);
  cv::randu(image, 0, 256);
  cv::Mat wide(2 * b + 9, 2 * b + 15, CV_8UC1);
  cv::randu(wide, 0, 256);
  const std::vector<std::pair<cv::Mat, cv::Point>> cases = {{image, {b, b}},
                                                            {wide, {b, b}},
                                                            {wide, {wide.cols - 1 - b, b}},
                                                            {wide, {b, wide.rows - 1 - b}},
                                                            {wide, {wide.cols - 1 - b, wide.rows - 1 - b}}};
  for (const auto& [level, p] : cases) {
    Brisk::LevelData data;
    brisk.prepare(level, data);
    const cv::Point2f pt(static_cast<float>(p.x), static_cast<float>(p.y));
    CHECK(angle_difference(brisk.orientation(data, pt), naive_orientation(naive, level, p.x, p.y)) < 1e-4);
    for (int step = 0; step < Brisk::kAngleSteps; ++step) {
      const float angle = static_cast<float>(2.0 * kPi * step / Brisk::kAngleSteps);
      REQUIRE(to_bits(brisk.describe(data, pt, angle)) == naive_describe(naive, level, p.x, p.y, step));
    }
  }
  // One pixel closer than border() − 1 throws, as does the far side beyond width − border().
  Brisk::LevelData data;
  brisk.prepare(image, data);
  const auto f = static_cast<float>(b);
  CHECK_THROWS_AS(brisk.orientation(data, {f - 2.0f, f}), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(data, {f, f - 2.0f}, 0.0f), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(data, {f + 1.6f, f}, 0.0f), std::invalid_argument);
  CHECK_THROWS_AS(brisk.orientation(data, {f, f + 1.6f}), std::invalid_argument);
  CHECK_NOTHROW(brisk.describe(data, {f - 0.4f, f + 0.4f}, 0.0f));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(brisk.orientation(data, {nan, f}), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(data, {f, nan}, 0.0f), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(data, {f, f}, nan), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(data, {f, f}, std::numeric_limits<float>::infinity()), std::invalid_argument);
  const Brisk::LevelData unprepared;
  CHECK_THROWS_AS(brisk.orientation(unprepared, {f, f}), std::invalid_argument);
  CHECK_THROWS_AS(brisk.describe(unprepared, {f, f}, 0.0f), std::invalid_argument);
}

TEST_CASE("large angles and negative angles select the same rotation step as their value modulo 2 pi") {
  CHECK(Brisk::angle_step(0.0f) == 0);
  CHECK(Brisk::angle_step(static_cast<float>(kPi)) == 512);
  CHECK(Brisk::angle_step(static_cast<float>(-kPi / 2)) == 768);
  CHECK(Brisk::angle_step(static_cast<float>(2.0 * kPi - 1e-4)) == 0);
  CHECK(Brisk::angle_step(static_cast<float>(kPi / 2 + 8.0 * kPi)) == 256);
  const int huge = Brisk::angle_step(3.0e30f);
  CHECK(huge >= 0);
  CHECK(huge < Brisk::kAngleSteps);
}

TEST_CASE("a level beyond 8.4 Mpixels (wrapping integral) describes like a crop of it") {
  const cv::Mat photo = affine_orb::test::graf(1);
  cv::Mat big;
  cv::repeat(photo, 5, 4, big);  // 3200 x 3200, 10.2 Mpixels: 255 · pixels overflows 32 bits
  const Brisk brisk;
  Brisk::LevelData big_data;
  brisk.prepare(big, big_data);
  const cv::Point points[] = {{3000, 3100}, {2500, 2900}, {3150, 3150}, {100, 100}};
  for (const cv::Point& p : points) {
    const cv::Rect window(p.x - 40, p.y - 40, 81, 81);
    const cv::Mat crop = big(window).clone();
    Brisk::LevelData crop_data;
    brisk.prepare(crop, crop_data);
    const cv::Point2f in_big(static_cast<float>(p.x), static_cast<float>(p.y));
    const cv::Point2f in_crop(40.0f, 40.0f);
    const float theta = brisk.orientation(big_data, in_big);
    CHECK(theta == brisk.orientation(crop_data, in_crop));
    CHECK(brisk.describe(big_data, in_big, theta) == brisk.describe(crop_data, in_crop, theta));
  }
}

TEST_CASE("prepare() rejects images that are not CV_8UC1 and reuses its buffer") {
  const Brisk brisk;
  Brisk::LevelData data;
  CHECK_THROWS_AS(brisk.prepare(cv::Mat(), data), std::invalid_argument);
  CHECK_THROWS_AS(brisk.prepare(cv::Mat(40, 40, CV_8UC3, cv::Scalar::all(0)), data), std::invalid_argument);
  CHECK_THROWS_AS(brisk.prepare(cv::Mat(40, 40, CV_16U, cv::Scalar(0)), data), std::invalid_argument);
  CHECK_THROWS_AS(brisk.prepare(cv::Mat(40, 40, CV_32F, cv::Scalar(0)), data), std::invalid_argument);

  cv::Mat first(60, 80, CV_8UC1);
  cv::randu(first, 0, 256);
  brisk.prepare(first, data);
  const std::uint8_t* buffer = data.integral.data;
  cv::Mat second(60, 80, CV_8UC1);
  cv::randu(second, 0, 256);
  brisk.prepare(second, data);
  CHECK(data.integral.data == buffer);
  CHECK(data.integral.rows == 61);
  CHECK(data.integral.cols == 81);
  CHECK(data.integral.at<std::int32_t>(60, 80) == static_cast<std::int32_t>(cv::sum(second)[0]));
}

TEST_CASE("BriskOptions::check() rejects nonsense values and patterns without 512 short pairs") {
  const double bad[] = {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()};
  double BriskOptions::*fields[] = {&BriskOptions::pattern_scale,     &BriskOptions::sigma_factor,
                                    &BriskOptions::centre_sigma,      &BriskOptions::pair_scale,
                                    &BriskOptions::short_pair_factor, &BriskOptions::long_pair_factor};
  for (auto field : fields) {
    for (const double value : bad) {
      BriskOptions options;
      options.*field = value;
      CHECK_THROWS_AS(options.check(), std::invalid_argument);
      CHECK_THROWS_AS(Brisk{options}, std::invalid_argument);
    }
  }
  BriskOptions fewer;
  fewer.short_pair_factor = 9.0;  // δ_max = 5.4 px: fewer than 512 short pairs
  CHECK(fewer.pattern().short_pairs.size() < 512);
  CHECK_THROWS_AS(fewer.check(), std::invalid_argument);
  BriskOptions more;
  more.pair_scale = 0.7;  // δ_max = 6.8 px: more than 512
  CHECK(more.pattern().short_pairs.size() > 512);
  CHECK_THROWS_AS(Brisk{more}, std::invalid_argument);
  BriskOptions no_long;
  no_long.long_pair_factor = 40.0;  // δ_min = 24 px, longer than the pattern's diameter
  CHECK_THROWS_AS(no_long.check(), std::invalid_argument);
  BriskOptions huge;
  huge.pattern_scale = 2000.0;  // boxes far beyond 127 px
  CHECK_THROWS_AS(huge.check(), std::invalid_argument);
  BriskOptions blurred;
  blurred.sigma_factor = 100.0;  // outer σ 144 px: a 499-pixel box
  CHECK_THROWS_AS(blurred.check(), std::invalid_argument);

  // A larger pattern keeps its 512 short pairs (pair selection scales with it) and widens the border.
  BriskOptions larger;
  larger.pattern_scale = 1.7;
  CHECK_NOTHROW(larger.check());
  const Brisk wide(larger);
  CHECK(wide.pattern().short_pairs.size() == 512);
  CHECK(wide.pattern().long_pairs.size() == 870);
  CHECK(wide.border() > Brisk().border());
  // The default options' rotation table is shared by every default instance; others build their
  // own, before or after it was built.
  CHECK(Brisk().border() == 14);
  CHECK(Brisk(larger).border() == wide.border());
}
