// libFuzzer target: the input bytes choose an image size (up to 48x40, so that
// about a thousand inputs run a second), the pixels and the options, then extraction (rBRIEF or
// BRISK, affine_orb's or a fork's image keypoints, plain or affine views, with or without a mask)
// and matching of the result against itself run. Invalid options must end in std::invalid_argument, valid ones in a
// result that keeps every documented invariant; anything else (a crash, a sanitizer report, another exception, a broken
// invariant) is a finding.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::Bytes;
using affine_orb::fuzz::require;

template <class Descriptor>
void run(const cv::Mat& image, const cv::Mat& mask, const affine_orb::ExtractorOptions& options) {
  affine_orb::Extractor<Descriptor> extractor(options);
  const auto a = extractor.extract(image, mask);
  // The additive budget: features from the image plus round(view_features · features) from the
  // tilted views; the area split: features in all.
  // A fork's octree keeps one keypoint per node and may end a level above its share, as the fork's
  // own extractor does, so its image keypoints have no such bound.
  const affine_orb::AdditiveBudget* additive = options.additive_budget();
  const long views_budget = additive ? std::lround(additive->view_features * options.features) : 0;
  const long image_keypoints = std::count(a.views.begin(), a.views.end(), 0);
  if (!options.fork_keypoints()) {
    require(static_cast<long>(a.size()) <= options.features + views_budget);
    require(image_keypoints <= options.features);
  } else {
    require(static_cast<long>(a.size()) - image_keypoints <= views_budget);
  }
  require(a.descriptors.size() == a.size() && a.views.size() == a.size());
  for (const cv::KeyPoint& k : a.keypoints) {
    require(std::isfinite(k.pt.x) && std::isfinite(k.pt.y));
    require(k.pt.x >= 0 && k.pt.y >= 0 && k.pt.x <= image.cols - 1 && k.pt.y <= image.rows - 1);
    require(k.angle >= 0.0f && k.angle < 360.0f);
    require(k.octave >= 0 && k.octave < options.pyramid.levels);
    if (!mask.empty()) require(mask.at<std::uint8_t>(cvRound(k.pt.y), cvRound(k.pt.x)) != 0);
  }
  for (const affine_orb::Match& m : affine_orb::match_features(a, a)) {
    require(m.query >= 0 && static_cast<std::size_t>(m.query) < a.size());
    require(m.train >= 0 && static_cast<std::size_t>(m.train) < a.size());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes bytes(data, size);
  const int width = 1 + bytes.next() % 48;
  const int height = 1 + bytes.next() % 40;
  const std::uint8_t flags = bytes.next();
  affine_orb::ExtractorOptions options;
  options.features = static_cast<int>(bytes.next()) * 4 - 8;  // may be <= 0: invalid
  // 0.5 is invalid; 1, √2, 2, 2√2 and 4 give 1, 5, 10, 18 and 28 views (the cost of an input
  // grows with them, so the larger sets come up less often).
  constexpr double kTilts[] = {0.5, 1.0, 1.0, 1.42, 2.01, 2.01, 2.83, 4.01};
  options.views.max_tilt = kTilts[bytes.next() % 8];
  options.pyramid.levels = bytes.next() % 10;                      // 0 is invalid
  options.pyramid.scale_factor = 0.9 + (bytes.next() % 8) * 0.15;  // <= 1 is invalid
  options.detector.initial_threshold = bytes.next() % 64;          // 0 is invalid
  options.detector.min_threshold = bytes.next() % 64;              // may exceed the initial one
  options.detector.cell_size = bytes.next() % 80;                  // < 4 is invalid
  options.detector.score = (flags & 2) ? affine_orb::ScoreType::kHarris : affine_orb::ScoreType::kFast;
  if (flags & 4) options.merge_duplicates.reset();
  if (flags & 32) options.view_budget = affine_orb::AreaSplitBudget{};  // invalid with a fork's keypoints
  if (flags & 64) options.snap_to_corners = affine_orb::CornerSnapOptions{};
  if (options.merge_duplicates) options.merge_duplicates->repeat_levels = (flags >> 7) & 1;
  const std::uint8_t shortlist = bytes.next();
  options.shortlist = 0.5 + (shortlist % 8) * 0.5;  // 0.5 is invalid
  // The image's keypoints: affine_orb's, ORB-SLAM2's or ORB-SLAM3's, the last two less often.
  switch ((shortlist >> 3) & 3) {
    case 2:
      options.image_keypoints = affine_orb::OrbSlam2Keypoints{};
      break;
    case 3:
      options.image_keypoints = affine_orb::OrbSlam3Keypoints{};
      break;
    default:
      break;
  }
  // Two worker threads in one input of 32: glibc frees a finished thread's TLS lazily, so an input
  // that starts threads ends with more mallocs than frees, and libFuzzer then runs its leak check
  // (a scan of the whole heap, several ms). The thread pool is tested in ctest, also under TSan.
  options.threads = (flags & 8) != 0 && (shortlist & 0xF0) == 0 ? 2 : 1;

  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at<std::uint8_t>(y, x) = bytes.next();
  }
  cv::Mat mask;
  if (flags & 16) {
    mask = cv::Mat(height, width, CV_8UC1, cv::Scalar(0));
    mask(cv::Rect(0, 0, (width + 1) / 2, height)).setTo(255);
  }
  try {
    if (flags & 1) {
      run<affine_orb::Brisk>(image, mask, options);
    } else {
      run<affine_orb::Rbrief>(image, mask, options);
    }
  } catch (const std::invalid_argument&) {
    // Rejected options: the documented outcome.
  }
  return 0;
}
