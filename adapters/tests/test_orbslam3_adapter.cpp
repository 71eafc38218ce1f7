// Conformance of the ORB-SLAM3 adapter (adapters/orbslam3): the shared suite of conformance.hpp,
// driving ORB_SLAM3::ORBextractor as ORB-SLAM3's Frame does, plus the lapping-area split.
#include <doctest/doctest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "ORBextractor.h"
#include "conformance.hpp"

namespace {

struct Orbslam3 {
  using Extractor = ORB_SLAM3::ORBextractor;
  using Options = ORB_SLAM3::AffineOrbAdapterOptions;
  using Fork = affine_orb::OrbSlam3Keypoints;
  /// Tracking builds mpIniORBextractor with 5·nFeatures.
  static constexpr int kInitialisationFactor = 5;
  static constexpr bool kReturnsCount = true;

  /// Frame::ExtractORB with a lapping area no keypoint falls in (x in [−2, −1]).
  static int extract(Extractor& extractor, const cv::Mat& image, const cv::Mat& mask,
                     std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
    std::vector<int> lapping{-2, -1};
    return extractor(image, mask, keypoints, descriptors, lapping);
  }
};

/// The x of the first level-0 keypoint of `all` with an integer x in (lo, hi), −1 when there is none.
int integer_x_between(const std::vector<cv::KeyPoint>& all, float lo, float hi) {
  for (const cv::KeyPoint& kp : all) {
    if (kp.octave == 0 && kp.pt.x > lo && kp.pt.x < hi && kp.pt.x == static_cast<float>(static_cast<int>(kp.pt.x))) {
      return static_cast<int>(kp.pt.x);
    }
  }
  return -1;
}

/// Reference output of a lapping-area split: the unsplit output (`all`, rows `all_rows`) with the
/// keypoints whose x is outside [area[0], area[1]] in order, then those inside from the last, as
/// ORB-SLAM3's own extractor fills the end of its outputs backwards, each with its row;
/// `n_outside` gets the number outside.
conformance::Output lapping_reference(const std::vector<cv::KeyPoint>& all, const cv::Mat& all_rows,
                                      const std::vector<int>& area, std::size_t& n_outside) {
  const auto inside = [&](const cv::KeyPoint& kp) { return kp.pt.x >= area[0] && kp.pt.x <= area[1]; };
  conformance::Output want;
  const auto add = [&](std::size_t i) {
    want.keypoints.push_back(all[i]);
    want.descriptors.push_back(all_rows.row(static_cast<int>(i)));
  };
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!inside(all[i])) add(i);
  }
  n_outside = want.keypoints.size();
  for (std::size_t i = all.size(); i-- > 0;) {
    if (inside(all[i])) add(i);
  }
  return want;
}

}  // namespace

TEST_CASE_TEMPLATE_INVOKE(getters, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(invariants, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(mapping, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(rbrief_definition, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(hamming, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(threads, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(pyramid_ownership, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(recovery_switch, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(empty, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(initialisation, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(mask, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(options, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(walk, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(bad_input, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(bad_environment, Orbslam3);
TEST_CASE_TEMPLATE_INVOKE(fork_default, Orbslam3);

TEST_CASE("lapping area: keypoints with x in [a, b] go to the end, last first, with their rows; the rest are counted") {
  const cv::Mat image = affine_orb::test::kitti_frame(3);
  ORB_SLAM3::ORBextractor extractor(1000, 1.2f, 8, 20, 7);
  std::vector<cv::KeyPoint> all;
  cv::Mat all_rows;
  std::vector<int> none{-2, -1};
  const int counted = extractor(image, cv::Mat(), all, all_rows, none);
  REQUIRE(counted == static_cast<int>(all.size()));
  REQUIRE(all.size() >= 1000);

  // A level-0 keypoint has an integer x: use it as the lower bound, to check the bound is included.
  const int lower = integer_x_between(all, 300.0f, 500.0f);
  REQUIRE(lower > 0);
  for (const std::vector<int>& area : {std::vector<int>{lower, 800}, std::vector<int>{0, 1000},
                                       std::vector<int>{0, 100000}, std::vector<int>{900, 400}}) {
    CAPTURE(area[0]);
    CAPTURE(area[1]);
    conformance::Output got;
    std::vector<int> lapping = area;
    const int outside = extractor(image, cv::Mat(), got.keypoints, got.descriptors, lapping);
    std::size_t n_outside = 0;
    const conformance::Output want = lapping_reference(all, all_rows, area, n_outside);
    CHECK(outside == static_cast<int>(n_outside));
    conformance::check_same(got, want);
    if (area[0] == lower) {
      CHECK(n_outside < all.size());
      CHECK(n_outside > 0);
    }
  }

  // The empty image returns −1 before the area is looked at; a malformed area is rejected.
  std::vector<int> bad{5};
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat rows;
  CHECK(extractor(cv::Mat(), cv::Mat(), keypoints, rows, bad) == -1);
  CHECK_THROWS_AS(extractor(image, cv::Mat(), keypoints, rows, bad), std::invalid_argument);
  std::vector<int> three{1, 2, 3};
  CHECK_THROWS_AS(extractor(image, cv::Mat(), keypoints, rows, three), std::invalid_argument);
}
