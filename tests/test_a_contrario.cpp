// The a-contrario support test (geometry/a_contrario.hpp): the number of false alarms against
// exact binomial coefficients, and the inlier probabilities against the share of a uniform grid of
// points that falls near a point or a line.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/geometry/a_contrario.hpp"

namespace {

/// Pascal's triangle up to row `n`, exact in 64 bits (C(62, 31) < 2⁶³).
std::vector<std::vector<std::uint64_t>> pascal(int n) {
  std::vector<std::vector<std::uint64_t>> c(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) {
    c[i].assign(static_cast<std::size_t>(i) + 1, 1);
    for (int j = 1; j < i; ++j) c[i][j] = c[i - 1][j - 1] + c[i - 1][j];
  }
  return c;
}

}  // namespace

TEST_CASE("log10_false_alarms is log10[(n - s) C(n, k) C(k, s) p^(k - s)] with exact binomials") {
  const int n_max = 62;
  const auto c = pascal(n_max);
  double worst = 0.0;
  for (const int s : {4, 7, 8}) {
    for (const double p : {1e-4, 0.02, 0.3, 1.0}) {
      for (int n = s + 1; n <= n_max; ++n) {
        for (int k = s; k <= n; ++k) {
          const double expected = std::log10(static_cast<double>(n - s)) + std::log10(static_cast<double>(c[n][k])) +
                                  std::log10(static_cast<double>(c[k][s])) + (k - s) * std::log10(p);
          worst = std::max(worst, std::abs(affine_orb::log10_false_alarms(n, k, s, p) - expected));
        }
      }
    }
  }
  CHECK(worst < 1e-9);
}

TEST_CASE("log10_false_alarms: no testable model is +inf; more inliers of the same matches, fewer false alarms") {
  CHECK(std::isinf(affine_orb::log10_false_alarms(100, 3, 4, 0.01)));  // fewer inliers than a sample
  CHECK(std::isinf(affine_orb::log10_false_alarms(4, 4, 4, 0.01)));    // no correspondence outside the sample
  // Beyond the mode of the binomial the evidence grows with every inlier (p small).
  double previous = affine_orb::log10_false_alarms(2000, 20, 4, 2.4e-4);
  for (int k = 21; k <= 400; ++k) {
    const double now = affine_orb::log10_false_alarms(2000, k, 4, 2.4e-4);
    REQUIRE(now < previous);
    previous = now;
  }
  // A homography on 15 of 2000 matches at 4.9 px in 640 x 480 is chance (NFA > 1); on 20, it is not,
  // although 20 is 1 % of the matches.
  const double p = affine_orb::point_inlier_probability(4.9, cv::Size(640, 480));
  CHECK(affine_orb::log10_false_alarms(2000, 15, 4, p) > 0.0);
  CHECK(affine_orb::log10_false_alarms(2000, 20, 4, p) < 0.0);
}

TEST_CASE("the inlier probabilities are the shares of uniform points near a point and near a line") {
  // The shares counted on a grid of 0.5 px over the image, the uniform distribution's quadrature.
  const cv::Size size(640, 480);
  const double length = std::hypot(size.width, size.height);
  const double nx = -size.height / length, ny = size.width / length;  // unit normal of the diagonal
  long near_point = 0, near_line = 0, all = 0;
  for (double v = 0.25; v < size.height; v += 0.5) {
    for (double u = 0.25; u < size.width; u += 0.5) {
      ++all;
      near_point += std::hypot(u - 320.0, v - 240.0) <= 10.0;
      near_line += std::abs(u * nx + v * ny) <= 3.0;  // the diagonal: the longest line in the image
    }
  }
  const double point = affine_orb::point_inlier_probability(10.0, size);
  const double line = affine_orb::line_inlier_probability(3.0, size);
  CHECK(near_point / static_cast<double>(all) == doctest::Approx(point).epsilon(0.01));
  // The band along the diagonal loses two corner triangles to the image's border: the bound is
  // reached within half a percent.
  CHECK(near_line / static_cast<double>(all) <= line);
  CHECK(near_line / static_cast<double>(all) > 0.99 * line);
  CHECK(affine_orb::point_inlier_probability(1e6, size) == 1.0);
}

TEST_CASE("the a-contrario functions refuse bad input") {
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, 11, 4, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, -1, 4, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, 5, 0, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, 5, 4, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, 5, 4, 1.5), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::log10_false_alarms(10, 5, 4, std::numeric_limits<double>::quiet_NaN()),
                  std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::point_inlier_probability(0.0, cv::Size(10, 10)), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::point_inlier_probability(1.0, cv::Size(0, 10)), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::line_inlier_probability(-1.0, cv::Size(10, 10)), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::line_inlier_probability(1.0, cv::Size(10, 0)), std::invalid_argument);
}
