// Relative pose recovery (relative_pose.hpp) on synthetic two-view scenes with known R and t:
// the decompositions of exact E and H contain the true motion, and the full chain
// select_model() -> relative pose recovers the rotation within 0.5° from noisy matches with
// outliers, for general scenes (F), planes (H) and pure rotations (H).
//
// Noise: 0.5 px per coordinate in both images; select_model() and the pose test use σ = 1 px,
// about twice the per-image noise (see the σ note of ModelSelectionOptions).

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/geometry/relative_pose.hpp"

namespace {

using affine_orb::direction_angle_degrees;
using affine_orb::GeometricModel;
using affine_orb::PinholeCamera;
using affine_orb::PoseHypothesis;
using affine_orb::RelativePose;
using affine_orb::rotation_angle_degrees;

constexpr double kNoise = 0.5;  // px per coordinate, each image
constexpr double kPi = 3.14159265358979323846;

// KITTI 06's left camera (calib.txt): a wide, short image.
PinholeCamera kitti_camera() { return {707.0912, 707.0912, 601.8873, 183.1104}; }
constexpr double kWidth = 1226;
constexpr double kHeight = 370;

Eigen::Matrix3d rotation(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(degrees * kPi / 180.0, axis.normalized()).toRotationMatrix();
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

bool inside(const Eigen::Vector2d& p) {
  return p.x() >= 0 && p.x() <= kWidth - 1 && p.y() >= 0 && p.y() <= kHeight - 1;
}

struct Scene {
  std::vector<cv::Point2f> points1, points2;
};

// `count` correspondences of camera 1 = [I | 0] and camera 2 = [R | t]: a random pixel of image 1,
// a depth from depth_of(ray, rng), kept when it is in front of camera 2 and inside image 2; then
// `outliers` uniform random pairs. Noise kNoise on every coordinate (scene points).
template <class DepthOf>
Scene make_scene(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, DepthOf depth_of, int count, int outliers,
                 std::uint64_t seed) {
  const PinholeCamera camera = kitti_camera();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> px(0.0, kWidth - 1), py(0.0, kHeight - 1);
  std::normal_distribution<double> noise(0.0, kNoise);
  Scene scene;
  while (static_cast<int>(scene.points1.size()) < count) {
    const Eigen::Vector2d x1(px(rng), py(rng));
    const Eigen::Vector3d ray = camera.ray(cv::Point2f(static_cast<float>(x1.x()), static_cast<float>(x1.y())));
    const double depth = depth_of(ray, rng);
    if (!(depth > 0.0)) continue;
    const Eigen::Vector3d seen = r * (depth * ray) + t;
    if (!(seen.z() > 0.1)) continue;
    const Eigen::Vector2d x2 = camera.project(seen);
    if (!inside(x2)) continue;
    scene.points1.emplace_back(static_cast<float>(x1.x() + noise(rng)), static_cast<float>(x1.y() + noise(rng)));
    scene.points2.emplace_back(static_cast<float>(x2.x() + noise(rng)), static_cast<float>(x2.y() + noise(rng)));
  }
  for (int i = 0; i < outliers; ++i) {
    scene.points1.emplace_back(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
    scene.points2.emplace_back(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
  }
  return scene;
}

// Depth uniform in [near, far] along the ray's z.
auto uniform_depth(double near, double far) {
  return [near, far](const Eigen::Vector3d&, std::mt19937_64& rng) {
    return std::uniform_real_distribution<double>(near, far)(rng);
  };
}

// The plane nᵀ X = d (camera 1).
auto plane_depth(const Eigen::Vector3d& n, double d) {
  return [n, d](const Eigen::Vector3d& ray, std::mt19937_64&) { return d / n.dot(ray); };
}

affine_orb::ModelSelectionOptions selection_options() {
  affine_orb::ModelSelectionOptions o;
  o.sigma = 1.0;
  return o;
}

// A general motion of a forward-driving camera, per case.
struct Motion {
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
};

std::vector<Motion> general_motions() {
  return {
      {rotation(2.0, {0.0, 1.0, 0.0}), {0.0, 0.0, 1.0}},     // KITTI-like: forward, turning
      {rotation(5.0, {0.1, 1.0, 0.05}), {0.2, -0.05, 1.0}},  // faster turn
      {rotation(1.0, {1.0, 0.2, 0.0}), {1.0, 0.0, 0.2}},     // sideways
      {rotation(8.0, {0.3, -1.0, 0.4}), {-0.5, 0.3, -0.6}},  // backwards, general axis
      {rotation(0.5, {0.0, 0.0, 1.0}), {0.05, 0.02, 0.5}},   // little rotation, roll
  };
}

}  // namespace

TEST_CASE("rotation_angle_degrees and direction_angle_degrees against AngleAxis") {
  for (const double degrees : {0.0, 1e-6, 0.01, 1.0, 45.0, 120.0, 179.0}) {
    const Eigen::Matrix3d a = rotation(30.0, {1.0, 2.0, 3.0});
    const Eigen::Matrix3d b = a * rotation(degrees, {-0.3, 1.0, 0.2});
    CHECK(rotation_angle_degrees(a, b) == doctest::Approx(degrees).epsilon(1e-9).scale(1.0));
    CHECK(rotation_angle_degrees(b, a) == doctest::Approx(degrees).epsilon(1e-9).scale(1.0));
  }
  CHECK(direction_angle_degrees({1, 0, 0}, {0, 2, 0}) == doctest::Approx(90.0));
  CHECK(direction_angle_degrees({1, 0, 0}, {-3, 0, 0}) == doctest::Approx(180.0));
  CHECK(direction_angle_degrees({0, 0, 0}, {1, 0, 0}) == 0.0);
}

TEST_CASE("the four essential hypotheses contain the true motion") {
  for (const Motion& m : general_motions()) {
    const Eigen::Vector3d t = m.t.normalized();
    const std::vector<PoseHypothesis> hs = affine_orb::essential_hypotheses(skew(t) * m.r * 3.7);
    REQUIRE(hs.size() == 4);
    int found = 0;
    for (const PoseHypothesis& h : hs) {
      CHECK(std::abs(h.rotation.determinant() - 1.0) < 1e-12);
      CHECK((h.rotation * h.rotation.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
      CHECK(h.translation.norm() == doctest::Approx(1.0));
      if (rotation_angle_degrees(h.rotation, m.r) < 1e-8 && (h.translation - t).norm() < 1e-10) ++found;
    }
    CHECK(found == 1);
  }
  CHECK(affine_orb::essential_hypotheses(Eigen::Matrix3d::Zero()).empty());
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK(affine_orb::essential_hypotheses(nan).empty());
}

TEST_CASE("the four homography hypotheses contain the true motion and plane, each reproduces G") {
  const std::vector<Eigen::Vector3d> normals = {{0.0, -1.0, 0.0}, {0.2, -0.1, 1.0}, {-0.6, 0.3, -0.7}};
  for (const Motion& m : general_motions()) {
    for (const Eigen::Vector3d& normal : normals) {
      const Eigen::Vector3d n = normal.normalized();
      const double d = 4.0;
      const Eigen::Matrix3d g = m.r + m.t * n.transpose() / d;
      // Scaled by any positive factor: the decomposition normalises by σ₂.
      const std::vector<PoseHypothesis> hs = affine_orb::homography_hypotheses(2.5 * g);
      REQUIRE(hs.size() == 4);
      int found = 0;
      for (const PoseHypothesis& h : hs) {
        CHECK(std::abs(h.rotation.determinant() - 1.0) < 1e-9);
        CHECK(h.normal.norm() == doctest::Approx(1.0));
        CHECK((h.rotation + h.translation * h.normal.transpose() - g).norm() < 1e-9);
        if (rotation_angle_degrees(h.rotation, m.r) < 1e-6 && (h.translation - m.t / d).norm() < 1e-9 &&
            (h.normal - n).norm() < 1e-9) {
          ++found;
        }
      }
      CHECK(found == 1);
    }
  }
  // A pure rotation: one hypothesis, the rotation itself.
  const Eigen::Matrix3d r = rotation(3.0, {0.2, 1.0, -0.1});
  const std::vector<PoseHypothesis> pure = affine_orb::homography_hypotheses(0.3 * r);
  REQUIRE(pure.size() == 1);
  CHECK(rotation_angle_degrees(pure[0].rotation, r) < 1e-9);
  CHECK(pure[0].translation.norm() == 0.0);
  CHECK(affine_orb::homography_hypotheses(Eigen::Matrix3d::Zero()).empty());
}

TEST_CASE("exact F and noise-free points give the exact motion") {
  const PinholeCamera camera = kitti_camera();
  const Eigen::Matrix3d k = camera.matrix();
  std::uint64_t seed = 11;
  for (const Motion& m : general_motions()) {
    const Scene scene = make_scene(m.r, m.t, uniform_depth(3.0, 40.0), 200, 0, seed++);
    // Exact F of the motion; the points carry noise, so compare loosely.
    const Eigen::Matrix3d f = k.inverse().transpose() * skew(m.t) * m.r * k.inverse();
    const RelativePose pose = affine_orb::relative_pose_from_fundamental(f, camera, scene.points1, scene.points2);
    REQUIRE(pose.success);
    CHECK(rotation_angle_degrees(pose.rotation, m.r) < 1e-9);
    CHECK(direction_angle_degrees(pose.translation, m.t) < 1e-7);
    CHECK(pose.translation_unique);
    CHECK(pose.good_points > 190);
    CHECK(pose.runner_up_points < pose.good_points / 2);
  }
}

TEST_CASE("general scenes: select_model chooses F and the rotation is recovered within 0.5 degrees") {
  const PinholeCamera camera = kitti_camera();
  std::uint64_t seed = 100;
  double worst_rotation = 0.0, worst_translation = 0.0;
  for (const Motion& m : general_motions()) {
    for (int repeat = 0; repeat < 3; ++repeat) {
      const Scene scene = make_scene(m.r, m.t, uniform_depth(3.0, 40.0), 300, 60, seed++);
      const affine_orb::ModelSelectionResult sel =
          affine_orb::select_model(scene.points1, scene.points2, selection_options());
      REQUIRE(sel.success);
      CHECK(sel.model == GeometricModel::kFundamental);
      const RelativePose pose = affine_orb::relative_pose(sel, camera, scene.points1, scene.points2);
      REQUIRE(pose.success);
      const double rotation_error = rotation_angle_degrees(pose.rotation, m.r);
      const double translation_error = direction_angle_degrees(pose.translation, m.t);
      CHECK(rotation_error < 0.5);
      CHECK(translation_error < 10.0);
      worst_rotation = std::max(worst_rotation, rotation_error);
      worst_translation = std::max(worst_translation, translation_error);
    }
  }
  MESSAGE("F scenes: worst rotation error " << worst_rotation << " deg, worst translation direction error "
                                            << worst_translation << " deg");
}

// The road seen by a forward camera 1.65 m above it (KITTI's camera height), and a wall ahead.
struct Plane {
  Eigen::Vector3d n;
  double d;
};
const std::vector<Plane> kPlanes = {{{0.0, 1.0, 0.0}, 1.65}, {Eigen::Vector3d(0.3, 0.1, 1.0).normalized(), 8.0}};

TEST_CASE("points on one plane only: H is chosen and the result is right or reported ambiguous") {
  // Two decompositions of a plane's homography usually put every point in front of both cameras
  // and reproject them exactly (the twofold ambiguity); the function must then say so
  // (success = false), never return the wrong one.
  const PinholeCamera camera = kitti_camera();
  std::uint64_t seed = 200;
  int resolved = 0;
  for (const Plane& plane : kPlanes) {
    for (const Motion& m : general_motions()) {
      const Scene scene = make_scene(m.r, m.t, plane_depth(plane.n, plane.d), 300, 60, seed++);
      const affine_orb::ModelSelectionResult sel =
          affine_orb::select_model(scene.points1, scene.points2, selection_options());
      REQUIRE(sel.success);
      CHECK(sel.model == GeometricModel::kHomography);
      const RelativePose pose = affine_orb::relative_pose(sel, camera, scene.points1, scene.points2);
      if (pose.success) {
        ++resolved;
        CHECK(rotation_angle_degrees(pose.rotation, m.r) < 0.5);
      } else {
        CHECK(pose.runner_up_points >= 0.95 * pose.good_points);
      }
    }
  }
  MESSAGE("plane only: " << resolved << " of 10 resolved");
}

TEST_CASE("a dominant plane with a tenth of the scene off it: the rotation within 0.5 degrees") {
  // The default rule (plane and parallax) sees the parallax of the points off the plane and
  // chooses F, estimated as the plane-and-parallax completion of H (SelectionRule::kPlaneParallax);
  // under eq. 22 (R_H near 0.45 here) either model may be chosen, and from H the points off the
  // plane break the planar ambiguity (relative_pose() scores H's hypotheses on all
  // correspondences). A wrong rotation is never returned.
  const PinholeCamera camera = kitti_camera();
  std::uint64_t seed = 250;
  double worst = 0.0;
  int recovered = 0, from_h = 0;
  for (const Plane& plane : kPlanes) {
    for (const Motion& m : general_motions()) {
      // 270 points on the plane, 30 anywhere between 3 and 40 m, then 60 outliers.
      Scene scene = make_scene(m.r, m.t, plane_depth(plane.n, plane.d), 270, 0, seed++);
      const Scene off = make_scene(m.r, m.t, uniform_depth(3.0, 40.0), 30, 60, seed++);
      scene.points1.insert(scene.points1.end(), off.points1.begin(), off.points1.end());
      scene.points2.insert(scene.points2.end(), off.points2.begin(), off.points2.end());
      const affine_orb::ModelSelectionResult sel =
          affine_orb::select_model(scene.points1, scene.points2, selection_options());
      REQUIRE(sel.success);
      const RelativePose pose = affine_orb::relative_pose(sel, camera, scene.points1, scene.points2);
      if (!pose.success) continue;
      ++recovered;
      from_h += sel.model == GeometricModel::kHomography ? 1 : 0;
      const double error = rotation_angle_degrees(pose.rotation, m.r);
      CHECK(error < 0.5);
      worst = std::max(worst, error);
    }
  }
  MESSAGE("dominant plane: " << recovered << " of 10 recovered (" << from_h << " from H), worst rotation error "
                             << worst << " deg");
  CHECK(recovered >= 8);
  CHECK(from_h == 0);  // the scene is 3-D
}

TEST_CASE("pure rotation: H is chosen and gives the rotation") {
  const PinholeCamera camera = kitti_camera();
  std::uint64_t seed = 300;
  for (const Eigen::Matrix3d& r :
       {rotation(2.0, {0.0, 1.0, 0.0}), rotation(4.0, {0.3, 1.0, 0.1}), rotation(1.0, {1.0, 0.0, 0.2})}) {
    const Scene scene = make_scene(r, Eigen::Vector3d::Zero(), uniform_depth(3.0, 40.0), 300, 60, seed++);
    const affine_orb::ModelSelectionResult sel =
        affine_orb::select_model(scene.points1, scene.points2, selection_options());
    REQUIRE(sel.success);
    CHECK(sel.model == GeometricModel::kHomography);
    const RelativePose pose = affine_orb::relative_pose(sel, camera, scene.points1, scene.points2);
    REQUIRE(pose.success);
    CHECK(rotation_angle_degrees(pose.rotation, r) < 0.5);
  }
  // The exact rotation homography K R K⁻¹ takes the pure-rotation branch: t = 0, unique.
  const Eigen::Matrix3d r = rotation(3.0, {0.2, 1.0, 0.0});
  const Scene scene = make_scene(r, Eigen::Vector3d::Zero(), uniform_depth(3.0, 40.0), 100, 0, 7);
  const Eigen::Matrix3d h = camera.matrix() * r * camera.inverse();
  const RelativePose pose = affine_orb::relative_pose_from_homography(-2.0 * h, camera, scene.points1, scene.points2);
  REQUIRE(pose.success);
  CHECK(rotation_angle_degrees(pose.rotation, r) < 1e-9);
  CHECK(pose.translation.norm() == 0.0);
  CHECK(pose.translation_unique);
  CHECK(pose.good_points > 90);
}

TEST_CASE("a plane whose two decompositions both explain every point is reported as ambiguous") {
  // Fronto-parallel plane far ahead, camera moving sideways and rotating about y: the second
  // decomposition (normal along the motion, translation along the true normal) puts every point in
  // front as long as all of them lie on one side of the image. Keep the points on the right half.
  const PinholeCamera camera = kitti_camera();
  const Eigen::Matrix3d r = rotation(3.0, {0.0, 1.0, 0.0});
  const Eigen::Vector3d t(1.0, 0.0, 0.0);
  const Eigen::Vector3d n(0.0, 0.0, 1.0);
  const double d = 10.0;
  const Eigen::Matrix3d g = r + t * n.transpose() / d;
  std::vector<cv::Point2f> p1, p2;
  for (double y = 20; y < kHeight - 20; y += 20) {
    for (double x = 700; x < kWidth - 20; x += 25) {
      const Eigen::Vector3d ray = camera.ray(cv::Point2f(static_cast<float>(x), static_cast<float>(y)));
      const Eigen::Vector3d seen = g * ray;
      const Eigen::Vector2d q = camera.project(seen);
      p1.emplace_back(static_cast<float>(x), static_cast<float>(y));
      p2.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    }
  }
  const Eigen::Matrix3d h = camera.matrix() * g * camera.inverse();
  const std::vector<PoseHypothesis> hs = affine_orb::homography_hypotheses(g);
  int rotations_far_apart = 0;
  for (const PoseHypothesis& a : hs) {
    rotations_far_apart += rotation_angle_degrees(a.rotation, r) > 1.0 ? 1 : 0;
  }
  REQUIRE(rotations_far_apart == 2);  // the twofold ambiguity exists for this motion
  const RelativePose pose = affine_orb::relative_pose_from_homography(h, camera, p1, p2);
  CHECK_FALSE(pose.success);
  CHECK(pose.runner_up_points >= pose.good_points * 3 / 4);
  // The same plane seen across the whole image: the wrong decomposition puts the left half behind.
  std::vector<cv::Point2f> q1, q2;
  for (double y = 20; y < kHeight - 20; y += 20) {
    for (double x = 20; x < kWidth - 20; x += 25) {
      const Eigen::Vector2d q =
          camera.project(g * camera.ray(cv::Point2f(static_cast<float>(x), static_cast<float>(y))));
      if (!inside(q)) continue;
      q1.emplace_back(static_cast<float>(x), static_cast<float>(y));
      q2.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    }
  }
  const RelativePose full = affine_orb::relative_pose_from_homography(h, camera, q1, q2);
  REQUIRE(full.success);
  CHECK(rotation_angle_degrees(full.rotation, r) < 1e-6);
  CHECK(direction_angle_degrees(full.translation, t) < 1e-6);
  CHECK(direction_angle_degrees(full.normal, n) < 1e-6);
}

TEST_CASE("the inlier mask selects the correspondences") {
  const PinholeCamera camera = kitti_camera();
  const Motion m = general_motions()[0];
  const Scene scene = make_scene(m.r, m.t, uniform_depth(3.0, 40.0), 100, 0, 5);
  const Eigen::Matrix3d k = camera.matrix();
  const Eigen::Matrix3d f = k.inverse().transpose() * skew(m.t) * m.r * k.inverse();
  std::vector<std::uint8_t> mask(scene.points1.size(), 0);
  for (std::size_t i = 0; i < mask.size(); i += 2) mask[i] = 1;
  const RelativePose half = affine_orb::relative_pose_from_fundamental(f, camera, scene.points1, scene.points2, mask);
  REQUIRE(half.success);
  CHECK(half.good_points <= 50);
  CHECK(half.good_points >= 45);
  // Too few selected correspondences: no result.
  std::vector<std::uint8_t> few(scene.points1.size(), 0);
  for (std::size_t i = 0; i < 5; ++i) few[i] = 1;
  CHECK_FALSE(affine_orb::relative_pose_from_fundamental(f, camera, scene.points1, scene.points2, few).success);
}

TEST_CASE("RelativePoseOptions::check() refuses every out-of-range field") {
  using Options = affine_orb::RelativePoseOptions;
  using Change = void (*)(Options&);
  for (const Change change : std::initializer_list<Change>{
           [](Options& o) { o.sigma = 0.0; }, [](Options& o) { o.reprojection_chi2 = std::nan(""); },
           [](Options& o) { o.min_good_points = 0; }, [](Options& o) { o.ambiguity_ratio = 1.5; },
           [](Options& o) { o.ambiguity_ratio = 0.0; }, [](Options& o) { o.tolerance_degrees = 0.0; },
           [](Options& o) { o.tolerance_degrees = 181.0; }}) {
    Options o;
    CHECK_NOTHROW(o.check());
    change(o);
    CHECK_THROWS_AS(o.check(), std::invalid_argument);
  }
}

TEST_CASE("bad input: clear errors or documented failures") {
  const PinholeCamera camera = kitti_camera();
  const Motion m = general_motions()[0];
  const Scene scene = make_scene(m.r, m.t, uniform_depth(3.0, 40.0), 50, 0, 3);
  const Eigen::Matrix3d f = camera.inverse().transpose() * skew(m.t) * m.r * camera.inverse();
  const auto& p1 = scene.points1;
  const auto& p2 = scene.points2;

  SUBCASE("camera") {
    for (const PinholeCamera& bad : {PinholeCamera{0.0, 700.0, 600.0, 180.0}, PinholeCamera{700.0, -1.0, 600.0, 180.0},
                                     PinholeCamera{700.0, 700.0, std::nan(""), 180.0},
                                     PinholeCamera{std::numeric_limits<double>::infinity(), 700.0, 600.0, 180.0}}) {
      CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(f, bad, p1, p2), std::invalid_argument);
      CHECK_THROWS_AS(affine_orb::relative_pose_from_homography(f, bad, p1, p2), std::invalid_argument);
    }
  }
  SUBCASE("options") {
    affine_orb::RelativePoseOptions o;
    o.sigma = -1.0;
    CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(f, camera, p1, p2, {}, o), std::invalid_argument);
  }
  SUBCASE("inputs") {
    std::vector<cv::Point2f> shorter(p2.begin(), p2.end() - 1);
    CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(f, camera, p1, shorter), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::relative_pose_from_homography(f, camera, p1, shorter), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(f, camera, p1, p2, std::vector<std::uint8_t>(3, 1)),
                    std::invalid_argument);
    std::vector<cv::Point2f> nan_points = p1;
    nan_points[4].y = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(f, camera, nan_points, p2), std::invalid_argument);
    Eigen::Matrix3d bad = f;
    bad(0, 2) = std::numeric_limits<double>::infinity();
    CHECK_THROWS_AS(affine_orb::relative_pose_from_fundamental(bad, camera, p1, p2), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::relative_pose_from_homography(bad, camera, p1, p2), std::invalid_argument);
  }
  SUBCASE("documented failures") {
    CHECK_FALSE(affine_orb::relative_pose_from_fundamental(Eigen::Matrix3d::Zero(), camera, p1, p2).success);
    CHECK_FALSE(affine_orb::relative_pose_from_homography(Eigen::Matrix3d::Zero(), camera, p1, p2).success);
    CHECK_FALSE(affine_orb::relative_pose_from_fundamental(f, camera, {}, {}).success);
    CHECK_FALSE(affine_orb::relative_pose_from_homography(Eigen::Matrix3d::Identity(), camera, {}, {}).success);
    const affine_orb::ModelSelectionResult none;
    CHECK_FALSE(affine_orb::relative_pose(none, camera, p1, p2).success);
  }
}
