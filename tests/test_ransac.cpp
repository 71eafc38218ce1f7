// Generic RANSAC (ransac.hpp), the minimal/least-squares geometric estimators (homography.hpp,
// fundamental.hpp) and the final homography fit (homography_refinement.hpp), against independent references: a toy line
// model whose truth is known, exact correspondences generated from known cameras, and naive re-implementations of the
// scores.

#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/detail/ransac_sampler.hpp"
#include "affine_orb/geometry/fundamental.hpp"
#include "affine_orb/geometry/homography.hpp"
#include "affine_orb/geometry/homography_refinement.hpp"
#include "affine_orb/geometry/ransac.hpp"

namespace {

using affine_orb::ModelSet;
using affine_orb::PointScore;
using affine_orb::RansacOptions;

// ---------------------------------------------------------------------------------------------
// A toy estimator: 2-D lines a x + b y + c = 0 (unit normal) through two points, truncated
// quadratic score. Its truth is known exactly, so it tests the RANSAC loop on its own.

struct Line {
  double a = 0.0, b = 0.0, c = 0.0;
};

struct LineEstimator {
  using Model = Line;
  static constexpr int kSampleSize = 2;
  static constexpr int kMaxModels = 2;

  std::vector<Eigen::Vector2d> points;
  double threshold = 1.0;   // squared distance
  bool degenerate = false;  // when true, generate() never yields a model
  bool twin = false;        // when true, generate() also yields a useless second model

  std::size_t size() const { return points.size(); }

  ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const {
    ModelSet<Model, kMaxModels> set;
    if (degenerate) return set;
    const Eigen::Vector2d p = points[static_cast<std::size_t>(sample[0])];
    const Eigen::Vector2d q = points[static_cast<std::size_t>(sample[1])];
    const Eigen::Vector2d d = q - p;
    if (d.norm() == 0.0) return set;
    const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
    if (twin) set.push(Line{1.0, 0.0, 1e6});
    set.push(Line{n.x(), n.y(), -n.dot(p)});
    return set;
  }

  PointScore score(const Model& m, std::size_t i) const {
    const double d = m.a * points[i].x() + m.b * points[i].y() + m.c;
    const double d2 = d * d;
    PointScore s;
    s.inlier = d2 < threshold;
    s.value = s.inlier ? threshold - d2 : 0.0;
    return s;
  }

  double max_point_score() const { return threshold; }
};

// The same with a total-least-squares refit on the inliers.
struct RefinedLineEstimator : LineEstimator {
  std::optional<Line> refine(const Line&, const std::vector<std::uint8_t>& inliers) const {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    int count = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (inliers[i] != 0) {
        mean += points[i];
        ++count;
      }
    }
    if (count < 2) return std::nullopt;
    mean /= count;
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (inliers[i] != 0) scatter += (points[i] - mean) * (points[i] - mean).transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
    const Eigen::Vector2d n = solver.eigenvectors().col(0);  // normal: direction of least spread
    return Line{n.x(), n.y(), -n.dot(mean)};
  }
};

static_assert(!affine_orb::detail::HasRefine<LineEstimator>::value, "the toy estimator has no refine()");
static_assert(affine_orb::detail::HasRefine<RefinedLineEstimator>::value, "");
static_assert(affine_orb::detail::HasRefine<affine_orb::HomographyEstimator>::value, "");
static_assert(affine_orb::detail::HasRefine<affine_orb::FundamentalEstimator>::value, "");

// Points on y = 0.5 x + 10 (x in [0, 100]) with Gaussian noise, and uniform outliers in
// [0, 100] x [0, 100]; `truth[i]` is 1 for points on the line.
LineEstimator make_line_data(int count, double outlier_ratio, std::uint64_t seed, std::vector<int>& truth) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coordinate(0.0, 100.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.2);
  LineEstimator e;
  truth.clear();
  for (int i = 0; i < count; ++i) {
    if (unit(rng) < outlier_ratio) {
      e.points.emplace_back(coordinate(rng), coordinate(rng));
      truth.push_back(0);
    } else {
      const double x = coordinate(rng);
      e.points.emplace_back(x + noise(rng), 0.5 * x + 10.0 + noise(rng));
      truth.push_back(1);
    }
  }
  return e;
}

// Distance between the recovered line and y = 0.5 x + 10 at x = 0 and x = 100.
double line_error(const Line& l) {
  double worst = 0.0;
  for (const double x : {0.0, 100.0}) {
    const double y_true = 0.5 * x + 10.0;
    worst = std::max(worst, std::abs(l.a * x + l.b * y_true + l.c));
  }
  return worst;
}

// ---------------------------------------------------------------------------------------------
// Two calibrated cameras: x = K (R X + t), camera 1 at the origin.

Eigen::Matrix3d intrinsics() {
  Eigen::Matrix3d k;
  k << 520.0, 0.0, 319.5, 0.0, 520.0, 239.5, 0.0, 0.0, 1.0;
  return k;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

struct TwoViews {
  Eigen::Matrix3d k = intrinsics();
  Eigen::Matrix3d r = Eigen::AngleAxisd(0.12, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  Eigen::Vector3d t = Eigen::Vector3d(-0.6, 0.1, 0.15);
  // Plane nᵀ X = d in camera-1 coordinates.
  Eigen::Vector3d n = Eigen::Vector3d(0.1, -0.2, 1.0).normalized();
  double d = 5.0;

  Eigen::Matrix3d homography() const { return k * (r + t * n.transpose() / d) * k.inverse(); }
  Eigen::Matrix3d fundamental() const { return k.inverse().transpose() * skew(t) * r * k.inverse(); }
  Eigen::Vector2d project2(const Eigen::Vector3d& x) const { return (k * (r * x + t)).hnormalized(); }
};

// A 3-D point seen at pixel `p` of camera 1 at depth `depth`.
Eigen::Vector3d back_project(const Eigen::Matrix3d& k, const Eigen::Vector2d& p, double depth) {
  return depth * (k.inverse() * p.homogeneous());
}

Eigen::Matrix3d unit(const Eigen::Matrix3d& m) { return (m(2, 2) < 0.0 ? -1.0 : 1.0) * m / m.norm(); }

/// The largest distance between the images under h and g of a 640 x 480 image's corners, pixels.
double max_corner_distance(const Eigen::Matrix3d& h, const Eigen::Matrix3d& g) {
  double distance = 0.0;
  for (const Eigen::Vector2d& c :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(639, 0), Eigen::Vector2d(0, 479), Eigen::Vector2d(639, 479)}) {
    distance = std::max(distance, ((h * c.homogeneous()).hnormalized() - (g * c.homogeneous()).hnormalized()).norm());
  }
  return distance;
}

std::vector<cv::Point2f> to_cv(const std::vector<Eigen::Vector2d>& points) {
  std::vector<cv::Point2f> out;
  for (const Eigen::Vector2d& p : points) out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  return out;
}

// Naive symmetric transfer score of ORB-SLAM's CheckHomography (paper eq. 20), written from the
// definition with OpenCV's matrix types, as an independent check of HomographyEstimator::score.
double naive_homography_score(const cv::Matx33d& h, cv::Point2d x1, cv::Point2d x2, double sigma, bool& inlier) {
  const cv::Matx33d h_inv = h.inv();
  const cv::Vec3d f = h * cv::Vec3d(x1.x, x1.y, 1.0);
  const cv::Vec3d b = h_inv * cv::Vec3d(x2.x, x2.y, 1.0);
  const double e2 = std::pow(f[0] / f[2] - x2.x, 2) + std::pow(f[1] / f[2] - x2.y, 2);
  const double e1 = std::pow(b[0] / b[2] - x1.x, 2) + std::pow(b[1] / b[2] - x1.y, 2);
  double score = 0.0;
  inlier = true;
  for (const double e : {e2, e1}) {
    const double chi2 = e / (sigma * sigma);
    if (chi2 < 5.991) {
      score += 5.991 - chi2;
    } else {
      inlier = false;
    }
  }
  return score;
}

// Naive epipolar score of ORB-SLAM's CheckFundamental (paper eq. 21).
double naive_fundamental_score(const cv::Matx33d& f, cv::Point2d x1, cv::Point2d x2, double sigma, bool& inlier) {
  const cv::Vec3d l2 = f * cv::Vec3d(x1.x, x1.y, 1.0);
  const cv::Vec3d l1 = f.t() * cv::Vec3d(x2.x, x2.y, 1.0);
  const double d2 = std::pow(l2[0] * x2.x + l2[1] * x2.y + l2[2], 2) / (l2[0] * l2[0] + l2[1] * l2[1]);
  const double d1 = std::pow(l1[0] * x1.x + l1[1] * x1.y + l1[2], 2) / (l1[0] * l1[0] + l1[1] * l1[1]);
  double score = 0.0;
  inlier = true;
  for (const double d : {d2, d1}) {
    const double chi2 = d / (sigma * sigma);
    if (chi2 < 3.841) {
      score += 5.991 - chi2;
    } else {
      inlier = false;
    }
  }
  return score;
}

cv::Matx33d to_matx(const Eigen::Matrix3d& m) {
  cv::Matx33d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m(r, c);
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST_CASE("index sampler: distinct indices in range, seeded, roughly uniform") {
  affine_orb::detail::IndexSampler a(10, 7), b(10, 7), c(10, 8);
  std::array<int, 10> counts{};
  bool differs = false;
  for (int round = 0; round < 2000; ++round) {
    int x[8], y[8], z[8];
    a.draw(x, 8);
    b.draw(y, 8);
    c.draw(z, 8);
    std::set<int> distinct(x, x + 8);
    REQUIRE(distinct.size() == 8);
    for (int i = 0; i < 8; ++i) {
      REQUIRE(x[i] >= 0);
      REQUIRE(x[i] < 10);
      CHECK(x[i] == y[i]);
      differs = differs || x[i] != z[i];
      ++counts[static_cast<std::size_t>(x[i])];
    }
  }
  CHECK(differs);
  // 16000 draws over 10 values, 1600 expected each; the binomial standard deviation is ~13 (the
  // draws without replacement are even tighter), so +-100 can only fail for a biased sampler.
  for (const int count : counts) CHECK(std::abs(count - 1600) < 100);

  affine_orb::detail::IndexSampler all(8, 1);
  int x[8];
  all.draw(x, 8);
  CHECK(std::set<int>(x, x + 8).size() == 8);
}

TEST_CASE("progressive sampler: PROSAC's schedule, against its recursion written out") {
  // Chum & Matas 2005, Sec. 2.3: T_m = T_N C(m, m) / C(N, m), T_{n+1} = T_n (n + 1) / (n + 1 − m),
  // T'_m = 1, T'_{n+1} = T'_n + ceil(T_{n+1} − T_n); sample t comes from the first n_t, where n_t
  // grows by one whenever t reaches T'_{n_t}; it holds correspondence n_t (index n_t − 1) while
  // t <= T'_{n_t}.
  const int n = 300, m = 4, growth = 500;
  affine_orb::detail::ProgressiveSampler sampler(n, m, growth, 3);
  double t_n = growth;
  for (int i = 0; i < m; ++i) t_n *= static_cast<double>(m - i) / (n - i);
  long t_prime = 1;
  int subset = m;
  bool uniform_seen = false;
  for (long t = 1; t <= 2000; ++t) {
    if (t == t_prime && subset < n) {
      const double next = t_n * (subset + 1) / (subset + 1 - m);
      t_prime += static_cast<long>(std::ceil(next - t_n));
      t_n = next;
      ++subset;
    }
    int drawn[m];
    sampler.draw(drawn, m);
    REQUIRE(std::set<int>(drawn, drawn + m).size() == static_cast<std::size_t>(m));
    for (const int d : drawn) REQUIRE((d >= 0 && d < subset));
    if (t <= t_prime) {
      REQUIRE(drawn[0] == subset - 1);
    } else {
      uniform_seen = true;
    }
  }
  CHECK(subset == n);   // all correspondences reached by T_N samples
  CHECK(uniform_seen);  // then uniform over all of them
}

TEST_CASE("ransac: progressive sampling finds a model whose few inliers rank first, where uniform draws do not") {
  // 20 points on the line among 1000 (2 %), ranked among the first 40: PROSAC draws them together
  // within its first samples; a uniform draw holds two of them with probability 0.0004.
  std::vector<int> truth;
  LineEstimator data = make_line_data(1000, 1.0, 5, truth);  // all outliers first
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, 0.2);
  for (int i = 0; i < 40; i += 2) {
    const double x = 2.5 * i;
    data.points[static_cast<std::size_t>(i)] = {x + noise(rng), 0.5 * x + 10.0 + noise(rng)};
  }
  affine_orb::RansacOptions options;
  options.max_iterations = 100;
  const auto uniform = affine_orb::ransac(data, options);
  options.progressive_sampling = true;
  const auto progressive = affine_orb::ransac(data, options);
  REQUIRE(progressive.success);
  CHECK(progressive.inlier_count >= 20);
  CHECK(line_error(progressive.model) < 1.0);
  CHECK(line_error(uniform.model) > 5.0);  // a chance line through the outliers
}

TEST_CASE("ransac: recovers a line through 50 % outliers; result equals a naive re-scoring") {
  std::vector<int> truth;
  const RefinedLineEstimator e{make_line_data(400, 0.5, 3, truth)};
  const auto r = affine_orb::ransac(e);
  REQUIRE(r.success);
  // Without refine() (plain RANSAC): the best line through two sampled points.
  const auto unrefined = affine_orb::ransac(static_cast<const LineEstimator&>(e));
  REQUIRE(unrefined.success);
  CHECK(line_error(unrefined.model) < 2.0);  // a line through two noisy points
  CHECK(r.score >= 0.95 * unrefined.score);
  CHECK(line_error(r.model) < 0.3);
  REQUIRE(r.inliers.size() == e.size());
  double score = 0.0;
  int count = 0;
  int recovered = 0, true_inliers = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    const PointScore s = e.score(r.model, i);
    score += s.value;
    count += s.inlier ? 1 : 0;
    CHECK(static_cast<bool>(r.inliers[i]) == s.inlier);
    true_inliers += truth[i];
    recovered += truth[i] != 0 && r.inliers[i] != 0 ? 1 : 0;
  }
  CHECK(r.score == doctest::Approx(score).epsilon(1e-12));
  CHECK(r.inlier_count == count);
  CHECK(recovered >= 0.95 * true_inliers);
  CHECK(r.iterations >= RansacOptions{}.min_iterations);
  CHECK(r.iterations <= RansacOptions{}.max_iterations);
}

TEST_CASE("ransac: the same seed gives the same result, another seed a correct one") {
  std::vector<int> truth;
  const RefinedLineEstimator e{make_line_data(300, 0.4, 5, truth)};
  RansacOptions options;
  options.seed = 11;
  const auto a = affine_orb::ransac(e, options);
  const auto b = affine_orb::ransac(e, options);
  options.seed = 12345;
  const auto c = affine_orb::ransac(e, options);
  REQUIRE(a.success);
  REQUIRE(c.success);
  CHECK(a.model.a == b.model.a);
  CHECK(a.model.b == b.model.b);
  CHECK(a.model.c == b.model.c);
  CHECK(a.inliers == b.inliers);
  CHECK(a.score == b.score);
  CHECK(a.iterations == b.iterations);
  CHECK(line_error(c.model) < 0.3);
}

TEST_CASE("ransac: several models per sample, adaptive termination and minimum iterations") {
  std::vector<int> truth;
  RefinedLineEstimator e{make_line_data(200, 0.0, 9, truth)};
  e.twin = true;
  RansacOptions options;
  options.min_iterations = 1;
  const auto r = affine_orb::ransac(e, options);
  REQUIRE(r.success);
  CHECK(r.model.c != 1e6);  // never the useless twin
  CHECK(line_error(r.model) < 0.3);
  // No outliers: an early sample gives a model with an inlier ratio w near 1 (w >= 0.8 needs
  // log 0.01 / log(1 − 0.8²) < 5 samples, H&Z eq. 4.18), so the search ends almost at once.
  CHECK(r.iterations <= 10);
  options.min_iterations = 37;
  CHECK(affine_orb::ransac(e, options).iterations == 37);
  CHECK(affine_orb::detail::adaptive_iterations(0.5, 4, 0.99, 1000) == 72);  // log 0.01 / log(15/16)
  CHECK(affine_orb::detail::adaptive_iterations(1.0, 8, 0.99, 1000) == 0);
  CHECK(affine_orb::detail::adaptive_iterations(0.0, 8, 0.99, 1000) == 1000);
  CHECK(affine_orb::detail::adaptive_iterations(0.1, 8, 0.99, 1000) == 1000);
}

TEST_CASE("ransac: no model, too few points and bad options") {
  std::vector<int> truth;
  LineEstimator e = make_line_data(50, 0.2, 1, truth);
  e.degenerate = true;
  RansacOptions options;
  options.max_iterations = 30;
  const auto none = affine_orb::ransac(e, options);
  CHECK_FALSE(none.success);
  CHECK(none.iterations == 30);
  CHECK(none.inlier_count == 0);
  CHECK(none.inliers == std::vector<std::uint8_t>(50, 0));

  LineEstimator one;
  one.points = {Eigen::Vector2d(1.0, 2.0)};
  const auto tiny = affine_orb::ransac(one);
  CHECK_FALSE(tiny.success);
  CHECK(tiny.iterations == 0);
  CHECK(tiny.inliers.size() == 1);
  CHECK_FALSE(affine_orb::ransac(LineEstimator{}).success);

  e.degenerate = false;
  CHECK_THROWS_AS(affine_orb::ransac(e, RansacOptions{}, 1), std::invalid_argument);
  const auto bad = [&](auto change) {
    RansacOptions o;
    change(o);
    CHECK_THROWS_AS(o.check(), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::ransac(e, o), std::invalid_argument);
  };
  bad([](RansacOptions& o) { o.max_iterations = 0; });
  bad([](RansacOptions& o) { o.max_iterations = -5; });
  bad([](RansacOptions& o) { o.min_iterations = -1; });
  bad([](RansacOptions& o) { o.min_iterations = o.max_iterations + 1; });
  bad([](RansacOptions& o) { o.confidence = 0.0; });
  bad([](RansacOptions& o) { o.confidence = 1.0; });
  bad([](RansacOptions& o) { o.confidence = 1.5; });
  bad([](RansacOptions& o) { o.confidence = std::numeric_limits<double>::quiet_NaN(); });
  bad([](RansacOptions& o) { o.refinement_passes = -1; });
  CHECK_NOTHROW(RansacOptions{}.check());
}

TEST_CASE("homography_4_point reproduces a known homography from four exact correspondences") {
  const TwoViews v;
  const Eigen::Matrix3d truth = v.homography();
  const std::array<Eigen::Vector2d, 4> x1 = {Eigen::Vector2d(50.0, 40.0), Eigen::Vector2d(600.0, 70.0),
                                             Eigen::Vector2d(580.0, 450.0), Eigen::Vector2d(90.0, 400.0)};
  std::array<Eigen::Vector2d, 4> x2;
  for (std::size_t i = 0; i < 4; ++i) x2[i] = (truth * x1[i].homogeneous()).hnormalized();
  const std::optional<Eigen::Matrix3d> h = affine_orb::homography_4_point(x1, x2);
  REQUIRE(h);
  CHECK((unit(*h) - unit(truth)).norm() < 1e-9);
  CHECK(h->norm() == doctest::Approx(1.0));
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(320.0, 240.0)}) {
    CHECK(((*h * p.homogeneous()).hnormalized() - (truth * p.homogeneous()).hnormalized()).norm() < 1e-7);
  }

  // Degenerate samples give no model.
  std::array<Eigen::Vector2d, 4> repeated = x1;
  repeated[3] = repeated[0];
  std::array<Eigen::Vector2d, 4> repeated2 = x2;
  repeated2[3] = repeated2[0];
  CHECK_FALSE(affine_orb::homography_4_point(repeated, repeated2));
  std::array<Eigen::Vector2d, 4> collinear = x1;
  collinear[2] = 0.5 * (x1[0] + x1[1]);  // three collinear points in image 1
  CHECK_FALSE(affine_orb::homography_4_point(collinear, x2));
  std::array<Eigen::Vector2d, 4> twisted = x2;
  std::swap(twisted[1], twisted[2]);  // a self-intersecting quadrilateral: no physical homography
  CHECK_FALSE(affine_orb::homography_4_point(x1, twisted));
  std::array<Eigen::Vector2d, 4> nan = x1;
  nan[1].x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(affine_orb::homography_4_point(nan, x2));
  std::array<Eigen::Vector2d, 4> same;
  same.fill(Eigen::Vector2d(3.0, 4.0));
  CHECK_FALSE(affine_orb::homography_4_point(same, same));
}

TEST_CASE("fundamental_8_point on exact correspondences: epipolar constraint, rank 2, true F") {
  const TwoViews v;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> px(0.0, 639.0), py(0.0, 479.0), depth(3.0, 12.0);
  std::vector<Eigen::Vector2d> x1, x2;
  while (x1.size() < 30) {
    const Eigen::Vector2d p(px(rng), py(rng));
    const Eigen::Vector3d point = back_project(v.k, p, depth(rng));
    x1.push_back(p);
    x2.push_back(v.project2(point));
  }
  for (const std::size_t count : {std::size_t{8}, std::size_t{30}}) {
    const std::vector<Eigen::Vector2d> a(x1.begin(), x1.begin() + static_cast<std::ptrdiff_t>(count));
    const std::vector<Eigen::Vector2d> b(x2.begin(), x2.begin() + static_cast<std::ptrdiff_t>(count));
    const std::optional<Eigen::Matrix3d> f = affine_orb::fundamental_8_point(a, b);
    REQUIRE(f);
    for (std::size_t i = 0; i < x1.size(); ++i) {
      const std::array<double, 2> d = affine_orb::epipolar_squared_distances(*f, x1[i], x2[i]);
      CHECK(std::sqrt(d[0]) < 1e-5);
      CHECK(std::sqrt(d[1]) < 1e-5);
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(*f);
    CHECK(svd.singularValues()(2) < 1e-12 * svd.singularValues()(0));
    if (count == 30) CHECK((unit(*f) - unit(v.fundamental())).norm() < 1e-6);
  }

  // Degenerate configurations give no model.
  CHECK_FALSE(affine_orb::fundamental_8_point(std::vector<Eigen::Vector2d>(x1.begin(), x1.begin() + 7),
                                              std::vector<Eigen::Vector2d>(x2.begin(), x2.begin() + 7)));
  CHECK_FALSE(affine_orb::fundamental_8_point(x1, std::vector<Eigen::Vector2d>(x2.begin(), x2.end() - 1)));
  std::vector<Eigen::Vector2d> line1, line2, plane1, plane2;
  const Eigen::Matrix3d h = v.homography();
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector2d p(40.0 + 45.0 * i, 30.0 + 33.0 * i);
    line1.push_back(p);
    line2.push_back((h * p.homogeneous()).hnormalized());
    const Eigen::Vector2d q(px(rng), py(rng));
    plane1.push_back(q);
    plane2.push_back((h * q.homogeneous()).hnormalized());  // all points on one plane
  }
  CHECK_FALSE(affine_orb::fundamental_8_point(line1, line2));
  CHECK_FALSE(affine_orb::fundamental_8_point(plane1, plane2));
  std::vector<Eigen::Vector2d> same(10, Eigen::Vector2d(5.0, 5.0));
  CHECK_FALSE(affine_orb::fundamental_8_point(same, same));
  std::vector<Eigen::Vector2d> nan = x1;
  nan[4].y() = std::numeric_limits<double>::infinity();
  CHECK_FALSE(affine_orb::fundamental_8_point(nan, x2));
}

namespace {

/// 200 correspondences of a 3-D scene (depths 3–12 m) seen by `v`, Gaussian noise of 1.5 px in
/// image 2: pixels of image 1 in x1, of image 2 in x2.
void noisy_scene(const TwoViews& v, std::vector<Eigen::Vector2d>& x1, std::vector<Eigen::Vector2d>& x2) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> px(0.0, 639.0), py(0.0, 479.0), depth(3.0, 12.0);
  std::normal_distribution<double> noise(0.0, 1.5);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d p(px(rng), py(rng));
    x1.push_back(p);
    x2.push_back(v.project2(back_project(v.k, p, depth(rng))) + Eigen::Vector2d(noise(rng), noise(rng)));
  }
}

}  // namespace

TEST_CASE("geometric estimators: scores equal the naive eq. 20/21 definitions") {
  const TwoViews v;
  std::vector<Eigen::Vector2d> x1, x2;
  noisy_scene(v, x1, x2);
  const std::vector<cv::Point2f> p1 = to_cv(x1), p2 = to_cv(x2);
  const double sigma = 1.3;
  const affine_orb::HomographyEstimator he(p1, p2, {sigma, 5.991, 5.991});
  const affine_orb::FundamentalEstimator fe(p1, p2, {sigma, 3.841, 5.991});
  const affine_orb::HomographyModel hm = *affine_orb::HomographyModel::from_pixels(v.homography());
  const Eigen::Matrix3d fm = v.fundamental();
  int h_inliers = 0, f_inliers = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    const cv::Point2d a(p1[i].x, p1[i].y), b(p2[i].x, p2[i].y);
    bool inlier = false;
    const double hs = naive_homography_score(to_matx(hm.h), a, b, sigma, inlier);
    CHECK(he.score(hm, i).value == doctest::Approx(hs).epsilon(1e-9));
    CHECK(he.score(hm, i).inlier == inlier);
    h_inliers += inlier ? 1 : 0;
    const double fs = naive_fundamental_score(to_matx(fm), a, b, sigma, inlier);
    CHECK(fe.score(fm, i).value == doctest::Approx(fs).epsilon(1e-9));
    CHECK(fe.score(fm, i).inlier == inlier);
    f_inliers += inlier ? 1 : 0;
  }
  // Both branches of the truncation are exercised: the 3-D scene breaks the homography for many
  // points, and the noise pushes some beyond the epipolar threshold.
  CHECK(h_inliers > 0);
  CHECK(h_inliers < 200);
  CHECK(f_inliers > 100);
  CHECK(f_inliers < 200);
  CHECK(he.max_point_score() == 2 * 5.991);
  CHECK(fe.max_point_score() == 2 * 5.991);
}

TEST_CASE("geometric estimators: degenerate samples give no model, random ones finite models") {
  const TwoViews v;
  std::vector<Eigen::Vector2d> x1, x2;
  noisy_scene(v, x1, x2);
  const std::vector<cv::Point2f> p1 = to_cv(x1), p2 = to_cv(x2);
  // Minimal samples with repeated or collinear points give no model.
  std::vector<cv::Point2f> q1 = p1, q2 = p2;
  q1[1] = q1[0];
  q2[1] = q2[0];
  for (int i = 0; i < 4; ++i) {
    q1[static_cast<std::size_t>(10 + i)] = cv::Point2f(100.0f + 50.0f * i, 200.0f);
    q2[static_cast<std::size_t>(10 + i)] = cv::Point2f(90.0f + 45.0f * i, 210.0f + 3.0f * i);
  }
  const affine_orb::HomographyEstimator hq(q1, q2);
  const affine_orb::FundamentalEstimator fq(q1, q2);
  CHECK(hq.generate({0, 1, 2, 3}).count == 0);
  CHECK(hq.generate({10, 11, 12, 13}).count == 0);
  CHECK(fq.generate({0, 1, 2, 3, 4, 5, 6, 7}).count == 0);
  CHECK(fq.generate({2, 3, 4, 5, 6, 7, 8, 9}).count == 1);
  const affine_orb::HomographyEstimator he(p1, p2, {1.3, 5.991, 5.991});
  int generated = 0;
  for (int i = 0; i < 200; ++i) {
    const std::array<int, 4> s = {i % 200, (i + 37) % 200, (i + 91) % 200, (i + 150) % 200};
    const auto set = he.generate(s);
    generated += set.count;
    for (int m = 0; m < set.count; ++m) {
      CHECK(set.models[static_cast<std::size_t>(m)].h.allFinite());
      CHECK(set.models[static_cast<std::size_t>(m)].inverse.allFinite());
    }
  }
  CHECK(generated > 100);  // random 4-sets of a 3-D scene: mostly non-degenerate
  // All points identical: constructible, but no model.
  const std::vector<cv::Point2f> same(20, cv::Point2f(4.0f, 4.0f));
  CHECK(affine_orb::HomographyEstimator(same, same).generate({0, 1, 2, 3}).count == 0);
  CHECK_FALSE(affine_orb::ransac(affine_orb::FundamentalEstimator(same, same)).success);
}

TEST_CASE("geometric estimators: unequal lengths, non-finite points and bad options throw") {
  const TwoViews v;
  std::vector<Eigen::Vector2d> x1, x2;
  noisy_scene(v, x1, x2);
  const std::vector<cv::Point2f> p1 = to_cv(x1), p2 = to_cv(x2);
  std::vector<cv::Point2f> shorter = p2;
  shorter.pop_back();
  CHECK_THROWS_AS(affine_orb::HomographyEstimator(p1, shorter), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::FundamentalEstimator(p1, shorter), std::invalid_argument);
  std::vector<cv::Point2f> nan = p1;
  nan[7].x = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(affine_orb::HomographyEstimator(nan, p2), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::FundamentalEstimator(p1, nan), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::HomographyEstimator(p1, p2, {-1.0, 5.991, 5.991}), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::HomographyEstimator(p1, p2, {1.0, 0.0, 5.991}), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::FundamentalEstimator(p1, p2, {1.0, 3.841, 1.0}), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::FundamentalEstimator(p1, p2, {std::nan(""), 3.841, 5.991}), std::invalid_argument);
  CHECK_NOTHROW(affine_orb::HomographyEstimator(p1, p2, {1.0, 5.991, 5.991}));
}

TEST_CASE("geometric estimators inside ransac: plane with outliers (H) and 3-D scene (F)") {
  const TwoViews v;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> px(0.0, 639.0), py(0.0, 479.0), depth(3.0, 12.0), unit01(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::vector<Eigen::Vector2d> plane1, plane2, scene1, scene2, clean1, clean2;
  std::vector<int> plane_truth, scene_truth;
  const Eigen::Matrix3d h = v.homography();
  while (plane1.size() < 400) {
    const Eigen::Vector2d p(px(rng), py(rng));
    if (unit01(rng) < 0.3) {
      plane1.push_back(p);
      plane2.emplace_back(px(rng), py(rng));
      plane_truth.push_back(0);
      scene1.push_back(p);
      scene2.emplace_back(px(rng), py(rng));
      scene_truth.push_back(0);
      continue;
    }
    plane1.push_back(p + Eigen::Vector2d(noise(rng), noise(rng)));
    plane2.push_back((h * p.homogeneous()).hnormalized() + Eigen::Vector2d(noise(rng), noise(rng)));
    plane_truth.push_back(1);
    const Eigen::Vector2d q = v.project2(back_project(v.k, p, depth(rng)));
    clean1.push_back(p);
    clean2.push_back(q);
    scene1.push_back(p + Eigen::Vector2d(noise(rng), noise(rng)));
    scene2.push_back(q + Eigen::Vector2d(noise(rng), noise(rng)));
    scene_truth.push_back(1);
  }
  const auto hr = affine_orb::ransac(affine_orb::HomographyEstimator(to_cv(plane1), to_cv(plane2)));
  REQUIRE(hr.success);
  CHECK(max_corner_distance(hr.model.h, h) < 1.0);
  int recovered = 0, total = 0;
  for (std::size_t i = 0; i < plane1.size(); ++i) {
    total += plane_truth[i];
    recovered += plane_truth[i] != 0 && hr.inliers[i] != 0 ? 1 : 0;
    if (plane_truth[i] == 0) CHECK(hr.inliers[i] == 0);
  }
  CHECK(recovered >= 0.95 * total);

  const auto fr = affine_orb::ransac(affine_orb::FundamentalEstimator(to_cv(scene1), to_cv(scene2)));
  REQUIRE(fr.success);
  double mean_distance = 0.0;
  for (std::size_t i = 0; i < clean1.size(); ++i) {
    const std::array<double, 2> d = affine_orb::epipolar_squared_distances(fr.model, clean1[i], clean2[i]);
    mean_distance += 0.5 * (std::sqrt(d[0]) + std::sqrt(d[1]));
  }
  mean_distance /= static_cast<double>(clean1.size());
  CHECK(mean_distance < 0.75);  // 0.5 px noise per image
  int outliers_accepted = 0;
  for (std::size_t i = 0; i < scene1.size(); ++i) outliers_accepted += scene_truth[i] == 0 && fr.inliers[i] != 0;
  // A random outlier passes the epipolar test when it falls within ~2 px of its epipolar line: a
  // few percent of them.
  CHECK(outliers_accepted < 0.1 * 400 * 0.3);
}

namespace {

/// Correspondences of the plane of `v` (x2 = H x1 for the first `inliers`, random positions after
/// them) with keypoint orientations in degrees: an inlier's image-2 orientation is the direction
/// its image-1 orientation takes under H, measured by central differences of H's point map (not by
/// the estimator's Jacobian), turned by `turn(i)` degrees; an outlier's is uniform.
struct OrientedPlane {
  std::vector<cv::Point2f> points1, points2;
  std::vector<float> angles1, angles2;
};

template <class Turn>
OrientedPlane oriented_plane(const Eigen::Matrix3d& h, int count, int inliers, std::uint64_t seed, Turn turn) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> px(0.0, 639.0), py(0.0, 479.0), degrees(0.0, 360.0);
  const auto map = [&](const Eigen::Vector2d& p) { return (h * p.homogeneous()).hnormalized(); };
  OrientedPlane plane;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d p(px(rng), py(rng));
    const double a1 = degrees(rng);
    const Eigen::Vector2d u(std::cos(a1 * M_PI / 180.0), std::sin(a1 * M_PI / 180.0));
    const Eigen::Vector2d q = i < inliers ? map(p) : Eigen::Vector2d(px(rng), py(rng));
    const Eigen::Vector2d d = map(p + 1e-3 * u) - map(p - 1e-3 * u);
    const double a2 = i < inliers ? std::atan2(d.y(), d.x()) * 180.0 / M_PI + turn(i) : degrees(rng);
    plane.points1.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
    plane.points2.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    plane.angles1.push_back(static_cast<float>(a1));
    plane.angles2.push_back(static_cast<float>(a2));
  }
  return plane;
}

/// The estimator of `plane`'s correspondences and orientations under the 45° test.
affine_orb::OrientedHomographyEstimator oriented_estimator(const OrientedPlane& plane) {
  return affine_orb::OrientedHomographyEstimator(plane.points1, plane.points2, plane.angles1, plane.angles2, 45.0);
}

/// Calls f(sample) for `count` samples of four distinct indices in [0, n), drawn with seed `seed`.
template <class F>
void for_each_sample(std::size_t n, std::uint64_t seed, int count, F f) {
  affine_orb::detail::IndexSampler sampler(n, seed);
  for (int t = 0; t < count; ++t) {
    std::array<int, 4> sample{};
    sampler.draw(sample.data(), 4);
    f(sample);
  }
}

}  // namespace

TEST_CASE("oriented homography estimator: a sample's model is kept exactly when its orientations agree") {
  // Every correspondence is on the plane; correspondence i's image-2 orientation is turned by
  // 0–80° (away from the 45° bound by more than the float angles' rounding). A sample's model is
  // the plain estimator's, kept exactly when all four turns are within 45°.
  const TwoViews v;
  std::vector<double> turns;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> small(0.0, 40.0), large(50.0, 80.0), sign(-1.0, 1.0);
  for (int i = 0; i < 300; ++i) turns.push_back((i % 3 == 0 ? large(rng) : small(rng)) * (sign(rng) < 0 ? -1 : 1));
  const OrientedPlane plane = oriented_plane(v.homography(), 300, 300, 22, [&](int i) { return turns[i]; });
  const affine_orb::HomographyEstimator plain(plane.points1, plane.points2);
  const affine_orb::OrientedHomographyEstimator oriented = oriented_estimator(plane);
  int kept = 0, refused = 0;
  for_each_sample(300, 23, 2000, [&](const std::array<int, 4>& sample) {
    const auto expected = plain.generate(sample);
    const auto got = oriented.generate(sample);
    bool agree = true;
    for (const int i : sample) agree = agree && std::abs(turns[static_cast<std::size_t>(i)]) <= 45.0;
    if (expected.count == 0) {
      CHECK(got.count == 0);
      return;
    }
    REQUIRE(got.count == (agree ? 1 : 0));
    kept += agree ? 1 : 0;
    refused += agree ? 0 : 1;
    if (agree) CHECK((got.models[0].h - expected.models[0].h).norm() == 0.0);
  });
  CHECK(kept > 300);  // (2/3)⁴ of the samples
  CHECK(refused > 1000);
  // Score and refinement are the plain estimator's.
  const std::optional<affine_orb::HomographyModel> truth = affine_orb::HomographyModel::from_pixels(v.homography());
  REQUIRE(truth);
  CHECK(oriented.score(*truth, 7).value == plain.score(*truth, 7).value);
  CHECK(oriented.max_point_score() == plain.max_point_score());
}

TEST_CASE("oriented homography estimator: wrong matches pass with the chance their orientations agree") {
  // Samples of four outliers, whose image-2 orientations are uniform and independent of the
  // model: each passes the 45° test with probability 90/360, a sample with (1/4)⁴ = 0.39 %.
  const TwoViews v;
  const OrientedPlane plane = oriented_plane(v.homography(), 400, 0, 31, [](int) { return 0.0; });
  const affine_orb::HomographyEstimator plain(plane.points1, plane.points2);
  const affine_orb::OrientedHomographyEstimator oriented = oriented_estimator(plane);
  int models = 0, kept = 0;
  for_each_sample(400, 32, 150000, [&](const std::array<int, 4>& sample) {
    models += plain.generate(sample).count;
    kept += oriented.generate(sample).count;
  });
  // Binomial(models, 1/256): mean and standard deviation; the bounds are 4 deviations wide.
  const double mean = models / 256.0, deviation = std::sqrt(mean * (1.0 - 1.0 / 256.0));
  CHECK(models > 20000);
  CHECK(kept > mean - 4.0 * deviation);
  CHECK(kept < mean + 4.0 * deviation);
}

TEST_CASE("oriented homography estimator inside ransac: a plane among 90 % wrong matches") {
  // 40 correct correspondences of 400, 0.5 px noise, orientations within 20° of the truth. Four
  // correct ones are drawn with probability 10⁻⁴; 30 000 samples of which the orientation test
  // scores a fraction find the plane.
  const TwoViews v;
  const Eigen::Matrix3d h = v.homography();
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> turn(-20.0, 20.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  OrientedPlane plane = oriented_plane(h, 400, 40, 42, [&](int) { return turn(rng); });
  for (std::size_t i = 0; i < 40; ++i) {
    plane.points2[i] += cv::Point2f(static_cast<float>(noise(rng)), static_cast<float>(noise(rng)));
  }
  const affine_orb::OrientedHomographyEstimator oriented = oriented_estimator(plane);
  RansacOptions options;
  options.max_iterations = 30000;
  options.confidence = 0.999;
  const auto found = affine_orb::ransac(oriented, options);
  REQUIRE(found.success);
  CHECK(max_corner_distance(found.model.h, h) < 2.0);
  int correct = 0;
  for (std::size_t i = 0; i < 40; ++i) correct += found.inliers[i] != 0 ? 1 : 0;
  CHECK(correct >= 36);

  // Bad input.
  const auto make = [&](std::vector<float> a1, std::vector<float> a2, double bound) {
    return affine_orb::OrientedHomographyEstimator(plane.points1, plane.points2, a1, a2, bound);
  };
  CHECK_THROWS_AS(make(plane.angles1, {}, 45.0), std::invalid_argument);
  CHECK_THROWS_AS(make(plane.angles1, plane.angles2, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(make(plane.angles1, plane.angles2, 181.0), std::invalid_argument);
  CHECK_THROWS_AS(make(plane.angles1, plane.angles2, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  std::vector<float> nan = plane.angles1;
  nan[3] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(make(nan, plane.angles2, 45.0), std::invalid_argument);
  CHECK_NOTHROW(make(plane.angles1, plane.angles2, 180.0));
}

TEST_CASE("geometric estimators at their minimal sizes: 3, 4 and 5 correspondences for H, 7 and 8 for F") {
  const TwoViews v;
  const Eigen::Matrix3d h = v.homography();
  std::vector<Eigen::Vector2d> x1 = {{40.0, 30.0},   {600.0, 50.0},  {620.0, 450.0}, {30.0, 420.0},
                                     {320.0, 240.0}, {150.0, 300.0}, {480.0, 120.0}, {250.0, 60.0}};
  std::vector<Eigen::Vector2d> on_plane, in_depth;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    on_plane.push_back((h * x1[i].homogeneous()).hnormalized());
    in_depth.push_back(v.project2(back_project(v.k, x1[i], 3.0 + static_cast<double>(i))));
  }
  for (const std::size_t count : {std::size_t{3}, std::size_t{4}, std::size_t{5}}) {
    CAPTURE(count);
    const std::vector<Eigen::Vector2d> a(x1.begin(), x1.begin() + static_cast<std::ptrdiff_t>(count));
    const std::vector<Eigen::Vector2d> b(on_plane.begin(), on_plane.begin() + static_cast<std::ptrdiff_t>(count));
    const auto r = affine_orb::ransac(affine_orb::HomographyEstimator(to_cv(a), to_cv(b)));
    CHECK(r.success == (count >= 4));
    CHECK(r.inliers.size() == count);
    if (r.success) {
      CHECK(r.inlier_count == static_cast<int>(count));
      CHECK((unit(r.model.h) - unit(h)).norm() < 1e-4);  // float input coordinates
    }
  }
  for (const std::size_t count : {std::size_t{7}, std::size_t{8}}) {
    CAPTURE(count);
    const std::vector<Eigen::Vector2d> a(x1.begin(), x1.begin() + static_cast<std::ptrdiff_t>(count));
    const std::vector<Eigen::Vector2d> b(in_depth.begin(), in_depth.begin() + static_cast<std::ptrdiff_t>(count));
    const auto r = affine_orb::ransac(affine_orb::FundamentalEstimator(to_cv(a), to_cv(b)));
    CHECK(r.success == (count == 8));
    if (r.success) CHECK(r.inlier_count == 8);
  }
}

// ---------------------------------------------------------------------------------------------
// refine_homography() against the maximum-likelihood estimate on synthetic planes with known
// Gaussian noise: the Levenberg–Marquardt minimum of the symmetric transfer error over the true
// inliers, computed here independently (8 parameters, H(2, 2) = 1, numeric Jacobian).

namespace {

/// The residuals of the symmetric transfer error of `h` on the correspondences a[i] ↔ b[i].
Eigen::VectorXd symmetric_residuals(const Eigen::Matrix3d& h, const std::vector<Eigen::Vector2d>& a,
                                    const std::vector<Eigen::Vector2d>& b) {
  const Eigen::Matrix3d inverse = h.inverse();
  Eigen::VectorXd r(4 * static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Eigen::Index k = 4 * static_cast<Eigen::Index>(i);
    r.segment<2>(k) = (h * a[i].homogeneous()).hnormalized() - b[i];
    r.segment<2>(k + 2) = (inverse * b[i].homogeneous()).hnormalized() - a[i];
  }
  return r;
}

/// Levenberg–Marquardt on the symmetric transfer error from `start`.
Eigen::Matrix3d symmetric_transfer_minimum(Eigen::Matrix3d start, const std::vector<Eigen::Vector2d>& a,
                                           const std::vector<Eigen::Vector2d>& b) {
  const auto matrix = [](const Eigen::Matrix<double, 8, 1>& p) {
    Eigen::Matrix3d h;
    h << p(0), p(1), p(2), p(3), p(4), p(5), p(6), p(7), 1.0;
    return h;
  };
  start /= start(2, 2);
  Eigen::Matrix<double, 8, 1> p;
  p << start(0, 0), start(0, 1), start(0, 2), start(1, 0), start(1, 1), start(1, 2), start(2, 0), start(2, 1);
  double lambda = 1e-3;
  Eigen::VectorXd r = symmetric_residuals(matrix(p), a, b);
  for (int iteration = 0; iteration < 100; ++iteration) {
    Eigen::MatrixXd j(r.size(), 8);
    for (int c = 0; c < 8; ++c) {
      const double step = 1e-6 * std::max(1.0, std::abs(p(c)));
      Eigen::Matrix<double, 8, 1> plus = p, minus = p;
      plus(c) += step;
      minus(c) -= step;
      j.col(c) = (symmetric_residuals(matrix(plus), a, b) - symmetric_residuals(matrix(minus), a, b)) / (2 * step);
    }
    const Eigen::Matrix<double, 8, 8> jtj = j.transpose() * j;
    const Eigen::Matrix<double, 8, 1> g = j.transpose() * r;
    Eigen::Matrix<double, 8, 8> damped = jtj;
    damped.diagonal() *= 1.0 + lambda;
    const Eigen::Matrix<double, 8, 1> delta = damped.ldlt().solve(-g);
    const Eigen::VectorXd next = symmetric_residuals(matrix(p + delta), a, b);
    if (next.squaredNorm() < r.squaredNorm()) {
      p += delta;
      r = next;
      lambda *= 0.3;
      if (delta.norm() < 1e-12 * (1.0 + p.norm())) break;
    } else {
      lambda *= 10.0;
    }
  }
  return matrix(p);
}

/// Mean distance over the corners of a 640 x 480 image 1 between their images under h and g.
double corner_distance(const Eigen::Matrix3d& h, const Eigen::Matrix3d& g) {
  double sum = 0.0;
  for (const Eigen::Vector2d& c :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(639, 0), Eigen::Vector2d(0, 479), Eigen::Vector2d(639, 479)}) {
    sum += ((h * c.homogeneous()).hnormalized() - (g * c.homogeneous()).hnormalized()).norm();
  }
  return sum / 4.0;
}

}  // namespace

TEST_CASE("refine_homography: as precise as the maximum-likelihood estimate, more than local optimisation") {
  // A plane seen under perspective, its points in the left two fifths of image 1 so that the far
  // corners extrapolate; Gaussian noise of 0.7 px in both images (a median transfer error of about
  // 1.2 px, as correct keypoint matches have on the Oxford pairs), 30 % outliers.
  Eigen::Matrix3d truth;
  truth << 0.9, 0.12, 35.0, -0.06, 1.05, 12.0, 2e-4, 1e-4, 1.0;
  double refined_to_ml = 0.0, optimised_to_ml = 0.0, refined_error = 0.0, optimised_error = 0.0, ml_error = 0.0;
  const int trials = 20;
  for (int trial = 0; trial < trials; ++trial) {
    std::mt19937_64 rng(100 + static_cast<std::uint64_t>(trial));
    std::uniform_real_distribution<double> px(0.0, 255.0), py(0.0, 479.0), ox(0.0, 639.0), unit01(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.7);
    std::vector<Eigen::Vector2d> x1, x2, inlier1, inlier2;
    while (x1.size() < 300) {
      const Eigen::Vector2d p(px(rng), py(rng));
      if (unit01(rng) < 0.3) {
        x1.push_back(p);
        x2.emplace_back(ox(rng), py(rng));
        continue;
      }
      x1.push_back(p + Eigen::Vector2d(noise(rng), noise(rng)));
      x2.push_back((truth * p.homogeneous()).hnormalized() + Eigen::Vector2d(noise(rng), noise(rng)));
      inlier1.push_back(x1.back());
      inlier2.push_back(x2.back());
    }
    // The matcher's model before the final fit: LO-RANSAC at σ = 1 px.
    const auto optimised = affine_orb::ransac(affine_orb::HomographyEstimator(to_cv(x1), to_cv(x2)));
    REQUIRE(optimised.success);
    const affine_orb::RefinedHomography refined =
        affine_orb::refine_homography(to_cv(x1), to_cv(x2), optimised.model.h);
    REQUIRE(refined.success);
    const Eigen::Matrix3d ml = symmetric_transfer_minimum(truth, inlier1, inlier2);
    refined_to_ml += corner_distance(refined.homography, ml) / trials;
    optimised_to_ml += corner_distance(optimised.model.h, ml) / trials;
    refined_error += corner_distance(refined.homography, truth) / trials;
    optimised_error += corner_distance(optimised.model.h, truth) / trials;
    ml_error += corner_distance(ml, truth) / trials;
  }
  MESSAGE("corner distance to the ML estimate: refined "
          << refined_to_ml << " px, LO-RANSAC " << optimised_to_ml << " px; to the truth: refined " << refined_error
          << " px, LO-RANSAC " << optimised_error << " px, ML " << ml_error << " px");
  // LO-RANSAC's hard inlier set at 2.4 px leaves out a fifth of the inliers; the refinement takes
  // them back, weighted.
  CHECK(refined_to_ml < 0.7 * optimised_to_ml);
  CHECK(refined_error < 1.1 * ml_error);
  CHECK(optimised_error > 1.1 * ml_error);  // the test tells the two apart
}

namespace {

/// The normal matrix of one reweighting step written out (sampson_normal_matrix()'s reference):
/// each correspondence's two equations as rows, the Jacobian of their residual by central
/// differences in pixels (exact: the residual is affine in each coordinate), the Sampson distance,
/// the Cauchy weight and the product Aᵀ (w M) A, for the correspondences within max_error both
/// ways of the homography `h_pixels` (a HomographyModel's h: M scales with the homography's
/// norm); `used` counts them.
Eigen::Matrix<double, 9, 9> naive_normal_matrix(const std::vector<cv::Point2f>& x1, const std::vector<cv::Point2f>& x2,
                                                const affine_orb::detail::NormalizedCorrespondences& data,
                                                const Eigen::Matrix3d& h_pixels,
                                                const affine_orb::HomographyRefinementOptions& options,
                                                std::size_t& used) {
  const Eigen::Matrix3d hn = data.t2 * h_pixels * data.t1_inverse;
  Eigen::Matrix<double, 9, 1> h;
  h << hn(0, 0), hn(0, 1), hn(0, 2), hn(1, 0), hn(1, 1), hn(1, 2), hn(2, 0), hn(2, 1), hn(2, 2);
  // The two equations of pixel points a ↔ b, in the normalised coordinates.
  const auto equations = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d n1 = (data.t1 * a.homogeneous()).hnormalized(),
                          n2 = (data.t2 * b.homogeneous()).hnormalized();
    const double x = n1.x(), y = n1.y(), u = n2.x(), v = n2.y();
    Eigen::Matrix<double, 2, 9> rows;
    rows << 0, 0, 0, -x, -y, -1, v * x, v * y, v, x, y, 1, 0, 0, 0, -u * x, -u * y, -u;
    return rows;
  };
  Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
  used = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    const Eigen::Vector2d a(x1[i].x, x1[i].y), b(x2[i].x, x2[i].y);
    const double forward = ((h_pixels * a.homogeneous()).hnormalized() - b).norm();
    const double backward = ((h_pixels.inverse() * b.homogeneous()).hnormalized() - a).norm();
    if (!(forward <= options.max_error && backward <= options.max_error)) continue;
    const Eigen::Matrix<double, 2, 9> rows = equations(a, b);
    const Eigen::Vector2d residual = rows * h;
    Eigen::Matrix<double, 2, 4> jacobian;
    for (int c = 0; c < 4; ++c) {
      Eigen::Vector4d plus(a.x(), a.y(), b.x(), b.y()), minus = plus;
      plus(c) += 0.5;
      minus(c) -= 0.5;
      jacobian.col(c) = equations(plus.head<2>(), plus.tail<2>()) * h - equations(minus.head<2>(), minus.tail<2>()) * h;
    }
    const Eigen::Matrix2d m = (jacobian * jacobian.transpose()).inverse();
    const double sampson_squared = residual.dot(m * residual);
    const double weight = 1.0 / (1.0 + sampson_squared / (options.cauchy_scale * options.cauchy_scale));
    normal += rows.transpose() * (weight * m) * rows;
    ++used;
  }
  return normal;
}

}  // namespace

TEST_CASE("refine_homography's normal matrix is Σ w Aᵀ M A of the DLT equations written out") {
  // Noise, outliers and a perturbed model, so that the weights vary and some correspondences are
  // left out.
  Eigen::Matrix3d truth;
  truth << 0.9, 0.12, 35.0, -0.06, 1.05, 12.0, 2e-4, 1e-4, 1.0;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> px(0.0, 639.0), py(0.0, 479.0), unit01(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.5);
  std::vector<cv::Point2f> x1, x2;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d p(px(rng), py(rng));
    const Eigen::Vector2d q = unit01(rng) < 0.2 ? Eigen::Vector2d(px(rng), py(rng))
                                                : Eigen::Vector2d((truth * p.homogeneous()).hnormalized());
    x1.emplace_back(static_cast<float>(p.x() + noise(rng)), static_cast<float>(p.y() + noise(rng)));
    x2.emplace_back(static_cast<float>(q.x() + noise(rng)), static_cast<float>(q.y() + noise(rng)));
  }
  Eigen::Matrix3d start = truth;
  start(0, 2) += 1.5;
  start(2, 0) += 2e-5;
  const affine_orb::detail::NormalizedCorrespondences data =
      affine_orb::detail::normalize_correspondences(x1, x2, "test");
  REQUIRE(data.normalizable);
  const std::optional<affine_orb::HomographyModel> model = affine_orb::HomographyModel::from_pixels(start);
  REQUIRE(model);
  const affine_orb::HomographyRefinementOptions options;
  std::size_t expected_used = 0, used = 0;
  const Eigen::Matrix<double, 9, 9> expected = naive_normal_matrix(x1, x2, data, model->h, options, expected_used);
  const Eigen::Matrix<double, 9, 9> got = affine_orb::detail::sampson_normal_matrix(data, *model, options, used);
  CHECK(used == expected_used);
  CHECK(expected_used > 60);
  CHECK(expected_used < x1.size());  // the outliers are left out
  CHECK((got - expected).norm() <= 1e-9 * expected.norm());
  CHECK((got - got.transpose()).norm() == 0.0);  // mirrored, not summed twice
}
