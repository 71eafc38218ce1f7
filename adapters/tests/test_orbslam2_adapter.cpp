// Conformance of the ORB-SLAM2 adapter (adapters/orbslam2): the shared suite of conformance.hpp,
// driving ORB_SLAM2::ORBextractor as ORB-SLAM2's Frame does.
#include <doctest/doctest.h>

#include <vector>

#include <opencv2/core.hpp>

#include "ORBextractor.h"
#include "conformance.hpp"

namespace {

struct Orbslam2 {
  using Extractor = ORB_SLAM2::ORBextractor;
  using Options = ORB_SLAM2::AffineOrbAdapterOptions;
  using Fork = affine_orb::OrbSlam2Keypoints;
  /// Tracking::Tracking builds mpIniORBextractor with 2·nFeatures.
  static constexpr int kInitialisationFactor = 2;
  static constexpr bool kReturnsCount = false;

  /// Frame::ExtractORB: (*mpORBextractorLeft)(im, cv::Mat(), mvKeys, mDescriptors).
  static int extract(Extractor& extractor, const cv::Mat& image, const cv::Mat& mask,
                     std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
    extractor(image, mask, keypoints, descriptors);
    return static_cast<int>(keypoints.size());
  }
};

}  // namespace

TEST_CASE_TEMPLATE_INVOKE(getters, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(invariants, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(mapping, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(rbrief_definition, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(hamming, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(threads, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(pyramid_ownership, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(recovery_switch, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(empty, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(initialisation, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(mask, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(options, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(walk, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(bad_input, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(bad_environment, Orbslam2);
TEST_CASE_TEMPLATE_INVOKE(fork_default, Orbslam2);
