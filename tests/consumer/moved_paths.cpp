// Includes every header at its 0.1 path and the two headers renamed since 0.2 (each warns that
// it is deprecated and includes the header at its new path), then extracts features of a noise image
// and matches them with themselves.
#include <affine_orb/affine_matching.hpp>
#include <affine_orb/affine_views.hpp>
#include <affine_orb/brisk.hpp>
#include <affine_orb/descriptor.hpp>
#include <affine_orb/detector.hpp>
#include <affine_orb/distribution.hpp>
#include <affine_orb/extraction/view_cursor.hpp>
#include <affine_orb/extractor.hpp>
#include <affine_orb/fast.hpp>
#include <affine_orb/features.hpp>
#include <affine_orb/fundamental.hpp>
#include <affine_orb/harris.hpp>
#include <affine_orb/homography.hpp>
#include <affine_orb/matcher.hpp>
#include <affine_orb/model_selection.hpp>
#include <affine_orb/opencv_feature2d.hpp>
#include <affine_orb/orientation.hpp>
#include <affine_orb/pyramid.hpp>
#include <affine_orb/ransac.hpp>
#include <affine_orb/rbrief.hpp>
#include <affine_orb/relative_pose.hpp>
#include <affine_orb/two_view.hpp>
#include <affine_orb/two_view/refinement.hpp>

#include <cstdio>

int main() {
  cv::Mat image(240, 320, CV_8UC1);
  cv::randu(image, 0, 256);
  const auto features = affine_orb::Extractor<affine_orb::Rbrief>().extract(image);
  const auto matches = affine_orb::match(features.descriptors, features.descriptors);
  std::printf("old include paths: %zu features, %zu matches\n", features.size(), matches.size());
  return matches.empty() ? 1 : 0;
}
