// BRISK description speed, affine_orb::Brisk vs OpenCV's cv::BRISK, on the same keypoints.
//
// graf img1 resized to 640x480; cv::FAST (threshold 20, non-maximum suppression) keypoints at least
// max(border(), 40) px from the image borders. Timed, in alternation, median of the runs:
// - ours: prepare() (integral image) + orientation() + describe() of every keypoint;
// - peer: cv::BRISK::create()->compute() on a copy of the same keypoints, which computes the integral
//   image, the orientation and the descriptor. The keypoint size is 7.2 = 0.6 · 12, the size at which
//   cv::BRISK samples its pattern at scale 1 (scale index 0: ring radii 0.85 · {0, …, 10.8}, as
//   ours); it is also timed with size 12 (its pattern × 1.7) for reference.
// OpenCV runs single-threaded (cv::setNumThreads(1)), like one extractor thread. Prints a Markdown
// table (the README's).
//
// Usage: bench_brisk [image] [runs]   (defaults: <AFFINE_ORB_DATA_DIR>/oxford/graf/img1.png, 51)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "bench_common.hpp"

namespace {

using affine_orb::bench::median;
using affine_orb::bench::milliseconds;

/// cv::FAST (threshold 20, non-maximum suppression) keypoints of `image` at least `margin` px
/// from its borders.
std::vector<cv::KeyPoint> keypoints_inside(const cv::Mat& image, int margin) {
  std::vector<cv::KeyPoint> detected;
  cv::FAST(image, detected, 20, true);
  std::vector<cv::KeyPoint> keypoints;
  for (const auto& k : detected) {
    if (k.pt.x >= margin && k.pt.y >= margin && k.pt.x < image.cols - margin && k.pt.y < image.rows - margin) {
      keypoints.push_back(k);
    }
  }
  return keypoints;
}

/// The timings of every run, and what the last run computed: our angles, cv::BRISK's keypoints.
struct Runs {
  std::vector<double> ours_ms, prepare_ms, peer_ms, peer12_ms;
  std::vector<float> angles;
  std::vector<cv::KeyPoint> peer_keypoints;
};

/// Times, in alternation, our description, its integral image alone and cv::BRISK::compute at
/// sizes 7.2 and 12, `runs` times on the same keypoints.
Runs time_runs(const affine_orb::Brisk& brisk, const cv::Mat& image, const std::vector<cv::KeyPoint>& keypoints,
               int runs) {
  Runs out;
  affine_orb::Brisk::LevelData data;
  std::vector<affine_orb::BinaryDescriptor<affine_orb::Brisk::kBits>> ours(keypoints.size());
  out.angles.resize(keypoints.size());
  const cv::Ptr<cv::BRISK> peer = cv::BRISK::create();
  std::vector<cv::KeyPoint> peer_input = keypoints;
  for (auto& k : peer_input) {
    k.size = 7.2f;
    k.angle = -1.0f;
  }
  std::vector<cv::KeyPoint> peer_input_12 = peer_input;
  for (auto& k : peer_input_12) k.size = 12.0f;
  cv::Mat peer_descriptors;
  for (int run = 0; run < runs; ++run) {
    out.prepare_ms.push_back(milliseconds([&] { brisk.prepare(image, data); }));
    out.ours_ms.push_back(milliseconds([&] {
      brisk.prepare(image, data);
      for (std::size_t i = 0; i < keypoints.size(); ++i) {
        out.angles[i] = brisk.orientation(data, keypoints[i].pt);
        ours[i] = brisk.describe(data, keypoints[i].pt, out.angles[i]);
      }
    }));
    out.peer_keypoints = peer_input;
    out.peer_ms.push_back(milliseconds([&] { peer->compute(image, out.peer_keypoints, peer_descriptors); }));
    std::vector<cv::KeyPoint> keypoints_12 = peer_input_12;
    cv::Mat descriptors_12;
    out.peer12_ms.push_back(milliseconds([&] { peer->compute(image, keypoints_12, descriptors_12); }));
  }
  return out;
}

/// Orientation agreement with cv::BRISK (same definition, different smoothing approximation):
/// cv::BRISK sums (I_i − I_j)(p_j − p_i), the opposite sign of eq. 5, hence the 180° offset.
std::string angle_note(const Runs& r) {
  if (r.peer_keypoints.size() != r.angles.size()) return "cv::BRISK dropped keypoints: no angle comparison";
  std::vector<double> difference;
  for (std::size_t i = 0; i < r.angles.size(); ++i) {
    const double ours_degrees = affine_orb::radians_to_degrees_0_360(r.angles[i]);
    const double d = std::fmod(std::abs(ours_degrees + 180.0 - r.peer_keypoints[i].angle), 360.0);
    difference.push_back(std::min(d, 360.0 - d));
  }
  char text[128];
  std::snprintf(text, sizeof(text), "median |angle(ours) + 180° − angle(cv::BRISK)|: %.2f°", median(difference));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : affine_orb::bench::data_dir() + "/oxford/graf/img1.png";
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 51;
  const cv::Mat original = affine_orb::bench::read_gray_or_exit(path);
  cv::setNumThreads(1);
  cv::Mat image;
  cv::resize(original, image, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  const affine_orb::Brisk brisk;
  const int margin = std::max(brisk.border(), 40);
  const std::vector<cv::KeyPoint> keypoints = keypoints_inside(image, margin);
  const Runs r = time_runs(brisk, image, keypoints, runs);

  const double ours_median = median(r.ours_ms), peer_median = median(r.peer_ms), peer12_median = median(r.peer12_ms);
  const std::size_t slash = path.find_last_of('/', path.find_last_of('/') - 1);
  const std::string shown = slash == std::string::npos ? path : path.substr(slash + 1);
  std::printf("%dx%d (%s resized), %zu FAST-20 keypoints at least %d px inside, medians of %d alternating runs; %s\n\n",
              image.cols, image.rows, shown.c_str(), keypoints.size(), margin, runs, angle_note(r).c_str());
  std::printf("| BRISK description, same keypoints | ms | µs per keypoint | ours / this |\n|---|---:|---:|---:|\n");
  const double n = static_cast<double>(keypoints.size());
  std::printf("| affine_orb::Brisk: integral image + orientation + descriptor | %.3f | %.2f | 1 |\n", ours_median,
              1000.0 * ours_median / n);
  std::printf("| … of which the integral image (prepare()) | %.3f | | |\n", median(r.prepare_ms));
  std::printf("| cv::BRISK::compute, size 7.2 (its pattern at scale 1, as ours) | %.3f | %.2f | %.3f |\n", peer_median,
              1000.0 * peer_median / static_cast<double>(r.peer_keypoints.size()), ours_median / peer_median);
  std::printf("| cv::BRISK::compute, size 12 (its pattern x 1.7) | %.3f | | %.3f |\n", peer12_median,
              ours_median / peer12_median);
  return 0;
}
