// libFuzzer target: FAST scoring and non-maximum suppression on small images. The bytes
// give a size (up to 24 x 24), a threshold, a region of interest and the pixels; the score map
// (SIMD where the target has it) must equal fast_score() evaluated pixel by pixel, and the corners
// must be exactly the pixels that the suppression rule, evaluated naively, keeps.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/detection/fast.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::require;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 7) return 0;
  const int width = 1 + data[0] % 24;
  const int height = 1 + data[1] % 24;
  const int threshold = data[2];  // 0 is invalid: std::invalid_argument
  const cv::Rect roi(data[3] % 32 - 4, data[4] % 32 - 4, data[5] % 32, data[6] % 32);
  cv::Mat image(height, width, CV_8UC1, cv::Scalar(0));
  std::size_t next = 7;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at<std::uint8_t>(y, x) = next < size ? data[next++] : 0;
  }
  cv::Mat scores;
  try {
    affine_orb::fast_score_map(image, roi, threshold, scores);
  } catch (const std::invalid_argument&) {
    require(threshold < 1);
    return 0;
  }
  require(threshold >= 1);
  // The scored rectangle: roi clipped to the pixels whose circle lies inside the image.
  const cv::Rect inner = roi & cv::Rect(affine_orb::kFastRadius, affine_orb::kFastRadius,
                                        width - 2 * affine_orb::kFastRadius, height - 2 * affine_orb::kFastRadius);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      int want = 0;
      if (inner.contains(cv::Point(x, y))) {
        const int score =
            affine_orb::fast_score(image.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(image.step[0]));
        want = score >= threshold ? score : 0;
      }
      require(scores.at<std::uint8_t>(y, x) == want);
    }
  }
  // Suppression: a corner scores >= threshold, strictly more than its neighbours before it in
  // raster order (the row above and its left neighbour) and at least as much as those after it.
  const std::vector<affine_orb::Corner> corners = affine_orb::non_max_suppression(scores, roi, threshold);
  const cv::Rect candidates = roi & cv::Rect(1, 1, width - 2, height - 2);
  std::vector<affine_orb::Corner> want;
  for (int y = candidates.y; y < candidates.y + candidates.height; ++y) {
    for (int x = candidates.x; x < candidates.x + candidates.width; ++x) {
      const int s = scores.at<std::uint8_t>(y, x);
      if (s < threshold) continue;
      bool keep = true;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int n = scores.at<std::uint8_t>(y + dy, x + dx);
          const bool before = dy < 0 || (dy == 0 && dx < 0);
          keep = keep && (before ? s > n : s >= n);
        }
      }
      if (keep) want.push_back({x, y, s});
    }
  }
  require(corners.size() == want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    require(corners[i].x == want[i].x && corners[i].y == want[i].y && corners[i].score == want[i].score);
  }
  return 0;
}
