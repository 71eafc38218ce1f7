// Sub-pixel correspondences under a homography (two_view/alignment.hpp) against known geometry:
// image 2 is image 1 warped by a chosen homography, so where each point of image 1 lies in image 2
// is known exactly; and TwoViewOptions::align_correspondences on real Oxford pairs against their ground truth.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/two_view/alignment.hpp"
#include "affine_orb/two_view/two_view.hpp"
#include "test_data.hpp"

namespace {

/// A perspective map with scale, shear and foreshortening, x2 ~ H x1.
Eigen::Matrix3d known_homography() {
  Eigen::Matrix3d h;
  h << 0.9, 0.15, 20.0, -0.1, 0.8, 30.0, 1e-4, 2e-4, 1.0;
  return h;
}

cv::Mat warped(const cv::Mat& image, const Eigen::Matrix3d& h) {
  cv::Matx33d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = h(r, c);
  cv::Mat out;
  cv::warpPerspective(image, out, m, image.size(), cv::INTER_LINEAR);
  return out;
}

/// Keypoints of graf 1 whose image under h lies well inside image 2, with image 2's points moved
/// by up to `offset` px in x and y (seeded), and their true image-2 positions.
struct Perturbed {
  std::vector<cv::Point2f> points1, points2;
  std::vector<float> scales1;
  std::vector<Eigen::Vector2d> truth;
};

Perturbed perturbed_keypoints(const cv::Mat& image1, const Eigen::Matrix3d& h, double offset) {
  affine_orb::Extractor<affine_orb::Rbrief> extractor{affine_orb::ExtractorOptions{}};
  Perturbed out;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> move(-offset, offset);
  for (const cv::KeyPoint& k : extractor.extract(image1).keypoints) {
    const Eigen::Vector2d t = (h * Eigen::Vector3d(k.pt.x, k.pt.y, 1.0)).hnormalized();
    if (t.x() < 40 || t.y() < 40 || t.x() > image1.cols - 40 || t.y() > image1.rows - 40) continue;
    out.points1.push_back(k.pt);
    out.points2.emplace_back(static_cast<float>(t.x() + move(rng)), static_cast<float>(t.y() + move(rng)));
    out.scales1.push_back(std::max(1.0f, k.size / affine_orb::Rbrief::kPatchSize));
    out.truth.push_back(t);
  }
  return out;
}

double mean_error(const std::vector<cv::Point2f>& points, const std::vector<Eigen::Vector2d>& truth,
                  const std::vector<std::uint8_t>& which) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!which[i]) continue;
    sum += (Eigen::Vector2d(points[i].x, points[i].y) - truth[i]).norm();
    ++n;
  }
  return n > 0 ? sum / n : std::numeric_limits<double>::infinity();
}

/// Normalised cross-correlation, computed naively, of image 1's (2·radius + 1)² patch around x1
/// with image 2 sampled at x2 + A·u (bilinear, per sample).
double naive_correlation(const cv::Mat& image1, const cv::Mat& image2, const Eigen::Vector2d& x1,
                         const Eigen::Vector2d& x2, const Eigen::Matrix2d& a, int radius) {
  const auto bilinear = [](const cv::Mat& image, const Eigen::Vector2d& x) {
    const int ix = static_cast<int>(std::floor(x.x())), iy = static_cast<int>(std::floor(x.y()));
    const double fx = x.x() - ix, fy = x.y() - iy;
    const auto at = [&](int r, int c) { return static_cast<double>(image.at<std::uint8_t>(r, c)); };
    return (1 - fy) * ((1 - fx) * at(iy, ix) + fx * at(iy, ix + 1)) +
           fy * ((1 - fx) * at(iy + 1, ix) + fx * at(iy + 1, ix + 1));
  };
  std::vector<double> t, w;
  for (int j = -radius; j <= radius; ++j) {
    for (int i = -radius; i <= radius; ++i) {
      t.push_back(bilinear(image1, x1 + Eigen::Vector2d(i, j)));
      w.push_back(bilinear(image2, x2 + a * Eigen::Vector2d(i, j)));
    }
  }
  const auto centred = [](std::vector<double>& v) {
    double mean = 0.0;
    for (double x : v) mean += x / static_cast<double>(v.size());
    for (double& x : v) x -= mean;
  };
  centred(t);
  centred(w);
  double tw = 0.0, tt = 0.0, ww = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    tw += t[k] * w[k];
    tt += t[k] * t[k];
    ww += w[k] * w[k];
  }
  return tw / std::sqrt(tt * ww);
}

}  // namespace

TEST_CASE("aligned points land within a twentieth of a pixel of the truth on a known warp") {
  const cv::Mat image1 = affine_orb::test::graf(1);
  const Eigen::Matrix3d h = known_homography();
  const cv::Mat image2 = warped(image1, h);
  const Perturbed p = perturbed_keypoints(image1, h, 1.5);
  REQUIRE(p.points1.size() > 500);
  const affine_orb::AlignedCorrespondences r =
      affine_orb::align_correspondences(image1, image2, p.points1, p.points2, p.scales1, h);
  REQUIRE(r.points2.size() == p.points1.size());
  CHECK(r.aligned_count == std::count(r.aligned.begin(), r.aligned.end(), 1));
  CHECK(r.aligned_count > 0.9 * static_cast<double>(p.points1.size()));
  const std::vector<std::uint8_t> all(p.points1.size(), 1);
  const double before = mean_error(p.points2, p.truth, r.aligned);
  const double after = mean_error(r.points2, p.truth, r.aligned);
  MESSAGE("mean error of the aligned points: " << before << " px before, " << after << " px after");
  CHECK(before > 0.9);
  CHECK(after < 0.08);
  // Points it did not align keep exactly the position handed in.
  for (std::size_t i = 0; i < r.points2.size(); ++i) {
    if (!r.aligned[i]) CHECK(r.points2[i] == p.points2[i]);
  }
}

TEST_CASE("align_patch reports the correlation of the patches at the point it returns") {
  // The alignment stops after an update below 0.01 px without sampling image 2 again, so the
  // correlation it reports is the one before that update: it must still be the returned point's.
  const cv::Mat image1 = affine_orb::test::graf(1);
  const Eigen::Matrix3d h = known_homography();
  const cv::Mat image2 = warped(image1, h);
  const Perturbed p = perturbed_keypoints(image1, h, 1.5);
  affine_orb::detail::PatchAlignmentWork work;
  int checked = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < p.points1.size(); i += 7) {
    const Eigen::Vector2d x1(p.points1[i].x, p.points1[i].y);
    const std::optional<Eigen::Matrix2d> a = affine_orb::detail::homography_jacobian(h, x1);
    REQUIRE(a);
    const Eigen::Vector2d start(p.points2[i].x, p.points2[i].y);
    const std::optional<affine_orb::detail::PatchAlignment> found =
        affine_orb::detail::align_patch(image1, image2, x1, start, *a, 5, 5, 4.0, 2.0, work);
    if (!found) continue;
    CHECK((found->point2 - start).norm() <= 2.0);
    worst = std::max(worst, std::abs(found->correlation - naive_correlation(image1, image2, x1, found->point2, *a, 5)));
    ++checked;
  }
  MESSAGE(checked << " patches, largest difference from the correlation at the returned point " << worst);
  CHECK(checked > 50);
  CHECK(worst < 2e-3);
}

TEST_CASE("a change of light between the images does not move the aligned points") {
  const cv::Mat image1 = affine_orb::test::graf(1);
  const Eigen::Matrix3d h = known_homography();
  cv::Mat image2;
  warped(image1, h).convertTo(image2, CV_8U, 0.6, 40.0);  // less contrast, brighter
  const Perturbed p = perturbed_keypoints(image1, h, 1.5);
  const affine_orb::AlignedCorrespondences r =
      affine_orb::align_correspondences(image1, image2, p.points1, p.points2, p.scales1, h);
  CHECK(r.aligned_count > 0.8 * static_cast<double>(p.points1.size()));
  CHECK(mean_error(r.points2, p.truth, r.aligned) < 0.12);
}

TEST_CASE("flat patches, patches leaving an image and far moves keep their points") {
  const cv::Mat image1 = affine_orb::test::graf(1);
  const Eigen::Matrix3d h = known_homography();
  const cv::Mat image2 = warped(image1, h);
  SUBCASE("a flat image pair has nothing to align") {
    const cv::Mat flat(200, 200, CV_8UC1, cv::Scalar(90));
    const std::vector<cv::Point2f> points = {{100.0f, 100.0f}, {50.0f, 60.0f}};
    const affine_orb::AlignedCorrespondences r =
        affine_orb::align_correspondences(flat, flat, points, points, {1.0f, 1.0f}, Eigen::Matrix3d::Identity());
    CHECK(r.aligned_count == 0);
    CHECK(r.points2 == points);
  }
  SUBCASE("points at or beyond the border") {
    const std::vector<cv::Point2f> points1 = {{1.0f, 1.0f}, {-30.0f, 20.0f}, {1e6f, 5.0f}};
    const std::vector<cv::Point2f> points2 = {{2.0f, 2.0f}, {10.0f, 10.0f}, {5.0f, 5.0f}};
    const affine_orb::AlignedCorrespondences r =
        affine_orb::align_correspondences(image1, image2, points1, points2, {1.0f, 1.0f, 1.0f}, h);
    CHECK(r.aligned_count == 0);
    CHECK(r.points2 == points2);
  }
  SUBCASE("a start farther than max_shift from the truth is not pulled there") {
    Perturbed p = perturbed_keypoints(image1, h, 0.0);
    for (cv::Point2f& q : p.points2) q.x += 6.0f;  // 6 px off: beyond max_shift
    affine_orb::CorrespondenceAlignmentOptions options;
    options.max_shift = 2.0;
    const affine_orb::AlignedCorrespondences r =
        affine_orb::align_correspondences(image1, image2, p.points1, p.points2, p.scales1, h, options);
    for (std::size_t i = 0; i < r.points2.size(); ++i) {
      const double moved = std::hypot(r.points2[i].x - p.points2[i].x, r.points2[i].y - p.points2[i].y);
      CHECK(moved <= options.max_shift + 1e-4);
    }
  }
}

TEST_CASE("align_correspondences refuses bad input") {
  const cv::Mat image(64, 64, CV_8UC1, cv::Scalar(0));
  const std::vector<cv::Point2f> one = {{10.0f, 10.0f}};
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  CHECK_THROWS_AS(affine_orb::align_correspondences(cv::Mat(), image, one, one, {1.0f}, identity),
                  std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::align_correspondences(cv::Mat(64, 64, CV_8UC3), image, one, one, {1.0f}, identity),
                  std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::align_correspondences(image, image, one, {}, {1.0f}, identity), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::align_correspondences(image, image, one, one, {}, identity), std::invalid_argument);
  CHECK_THROWS_AS(affine_orb::align_correspondences(image, image, one, one, {0.5f}, identity), std::invalid_argument);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(affine_orb::align_correspondences(image, image, {{nan, 1.0f}}, one, {1.0f}, identity),
                  std::invalid_argument);
  Eigen::Matrix3d broken = identity;
  broken(0, 2) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(affine_orb::align_correspondences(image, image, one, one, {1.0f}, broken), std::invalid_argument);
  affine_orb::CorrespondenceAlignmentOptions options;
  options.patch_radius = 1;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  options = {};
  options.max_shift = 0.0;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  options = {};
  options.min_correlation = 1.5;
  CHECK_THROWS_AS(options.check(), std::invalid_argument);
  affine_orb::TwoViewOptions two_view;
  two_view.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
  two_view.align_correspondences->iterations = 0;
  CHECK_THROWS_AS(two_view.check(), std::invalid_argument);
}

TEST_CASE("TwoViewOptions::align_correspondences brings the matcher's homography closer to the ground truth" *
          doctest::test_suite("data")) {
  // Oxford pairs with their published homographies; the judge of bench/eval_two_view's corners.
  double sum_off = 0.0, sum_on = 0.0;
  for (const auto& pair : {std::pair<std::string, int>{"graf", 2}, {"boat", 3}, {"bikes", 3}}) {
    const std::string& sequence = pair.first;
    const int n = pair.second;
    const cv::Mat image1 = affine_orb::test::oxford_image(sequence, 1);
    const cv::Mat image2 = affine_orb::test::oxford_image(sequence, n);
    const cv::Matx33d truth = affine_orb::test::oxford_homography(sequence, n);
    affine_orb::TwoViewOptions options;
    const auto off = affine_orb::TwoViewMatcher<affine_orb::Rbrief>(options).match(image1, image2);
    options.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
    const auto on = affine_orb::TwoViewMatcher<affine_orb::Rbrief>(options).match(image1, image2);
    REQUIRE(off.verified);
    REQUIRE(on.verified);
    // Without alignment, points2 are the train keypoints' positions.
    REQUIRE(off.points2.size() == off.matches.size());
    CHECK(off.aligned_count == 0);
    for (std::size_t i = 0; i < off.matches.size(); ++i) {
      CHECK(off.points2[i] == off.features2.keypoints[static_cast<std::size_t>(off.matches[i].train)].pt);
    }
    REQUIRE(on.points2.size() == on.matches.size());
    CHECK(on.aligned_count > on.inlier_count / 2);
    CHECK(on.stages.back().aligned == on.aligned_count);
    const double e_off = affine_orb::test::corner_error(off.model.homography, truth, image1.size());
    const double e_on = affine_orb::test::corner_error(on.model.homography, truth, image1.size());
    MESSAGE(sequence << " 1->" << n << ": corner error " << e_off << " px without, " << e_on << " px with");
    CHECK(e_on < 3.0);
    sum_off += e_off;
    sum_on += e_on;
  }
  CHECK(sum_on < sum_off);
}
