#pragma once
// Helpers for the tests of extraction with affine views (test_affine_views, test_views_on_demand,
// test_corner_snapping): the options of an affine extractor, and each keypoint's level in its view.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor_options.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb::test {

inline const double kSqrt2 = std::sqrt(2.0);

/// The element at index n / 2 of the sorted `v` (the upper median when n is even); v not empty.
inline double upper_median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// The default options with `features` image keypoints, the merging of duplicates `merge` (nullopt:
/// keep every view's keypoint) and `threads`.
inline affine_orb::ExtractorOptions affine_options(int features, std::optional<affine_orb::MergeOptions> merge,
                                                   int threads = 1) {
  affine_orb::ExtractorOptions options;
  options.features = features;
  options.merge_duplicates = merge;
  options.threads = threads;
  return options;
}

/// A keypoint with the level it was detected at in its view, recovered from its size
/// 31·s^l·√t (Features).
struct LevelledKeypoint {
  cv::KeyPoint kp;
  int view;
  int level;
  int order;  ///< position among the keypoints of its view and level (raster order)
};

inline std::vector<LevelledKeypoint> with_levels(const affine_orb::Features<256>& f,
                                                 const std::vector<affine_orb::AffineView>& views) {
  std::vector<LevelledKeypoint> out;
  std::map<std::pair<int, int>, int> counts;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double tilt = views[static_cast<std::size_t>(f.views[i])].tilt;
    const int level = static_cast<int>(std::lround(
        std::log(f.keypoints[i].size / (affine_orb::Rbrief::kPatchSize * std::sqrt(tilt))) / std::log(1.2)));
    out.push_back({f.keypoints[i], f.views[i], level, counts[{f.views[i], level}]++});
  }
  return out;
}

}  // namespace affine_orb::test
