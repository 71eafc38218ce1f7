#pragma once
// fork_extractor.hpp -- how the bench programs that extractor_source.sh compiles (walk.cpp,
// init_chain.cpp) call a fork's ORBextractor: the one place that knows how ORB-SLAM2's and
// ORB-SLAM3's differ. extractor_source.sh defines WALK_ORBSLAM3 for an ORB-SLAM3 tree.

#include <vector>

#include <opencv2/core.hpp>

#include "ORBextractor.h"

namespace orb_fork {

#ifdef WALK_ORBSLAM3
using ORBextractor = ORB_SLAM3::ORBextractor;
/// Tracking's monocular initialiser extracts this many times ORBextractor.nFeatures.
constexpr int kInitialBudgetFactor = 5;
#else
using ORBextractor = ORB_SLAM2::ORBextractor;
/// Tracking's monocular initialiser extracts this many times ORBextractor.nFeatures.
constexpr int kInitialBudgetFactor = 2;
#endif

/// The keypoints and descriptors of `image` (8-bit grey, no mask) in any type with members
/// `keypoints` (std::vector<cv::KeyPoint>) and `descriptors` (cv::Mat). ORB-SLAM3's call also takes
/// the stereo overlap, none here.
template <class Features>
Features extract(ORBextractor& extractor, const cv::Mat& image) {
  Features f;
#ifdef WALK_ORBSLAM3
  std::vector<int> lapping = {0, 0};
  extractor(image, cv::Mat(), f.keypoints, f.descriptors, lapping);
#else
  extractor(image, cv::Mat(), f.keypoints, f.descriptors);
#endif
  return f;
}

}  // namespace orb_fork
