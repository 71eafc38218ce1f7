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
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/brisk.hpp"

namespace {

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

template <class F>
double milliseconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : std::string(AFFINE_ORB_DATA_DIR) + "/oxford/graf/img1.png";
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 51;
  const cv::Mat original = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (original.empty()) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    return 1;
  }
  cv::setNumThreads(1);
  cv::Mat image;
  cv::resize(original, image, cv::Size(640, 480), 0, 0, cv::INTER_AREA);

  const affine_orb::Brisk brisk;
  const int margin = std::max(brisk.border(), 40);
  std::vector<cv::KeyPoint> detected;
  cv::FAST(image, detected, 20, true);
  std::vector<cv::KeyPoint> keypoints;
  for (const auto& k : detected) {
    if (k.pt.x >= margin && k.pt.y >= margin && k.pt.x < image.cols - margin && k.pt.y < image.rows - margin) {
      keypoints.push_back(k);
    }
  }
  affine_orb::Brisk::LevelData data;
  std::vector<affine_orb::BinaryDescriptor<affine_orb::Brisk::kBits>> ours(keypoints.size());
  std::vector<float> angles(keypoints.size());
  const cv::Ptr<cv::BRISK> peer = cv::BRISK::create();
  std::vector<cv::KeyPoint> peer_input = keypoints;
  for (auto& k : peer_input) {
    k.size = 7.2f;
    k.angle = -1.0f;
  }
  std::vector<cv::KeyPoint> peer_input_12 = peer_input;
  for (auto& k : peer_input_12) k.size = 12.0f;

  std::vector<double> ours_ms;
  std::vector<double> peer_ms;
  std::vector<double> peer12_ms;
  std::vector<cv::KeyPoint> peer_keypoints;
  cv::Mat peer_descriptors;
  std::vector<double> prepare_ms;
  for (int run = 0; run < runs; ++run) {
    prepare_ms.push_back(milliseconds([&] { brisk.prepare(image, data); }));
    ours_ms.push_back(milliseconds([&] {
      brisk.prepare(image, data);
      for (std::size_t i = 0; i < keypoints.size(); ++i) {
        angles[i] = brisk.orientation(data, keypoints[i].pt);
        ours[i] = brisk.describe(data, keypoints[i].pt, angles[i]);
      }
    }));
    peer_keypoints = peer_input;
    peer_ms.push_back(milliseconds([&] { peer->compute(image, peer_keypoints, peer_descriptors); }));
    std::vector<cv::KeyPoint> keypoints_12 = peer_input_12;
    cv::Mat descriptors_12;
    peer12_ms.push_back(milliseconds([&] { peer->compute(image, keypoints_12, descriptors_12); }));
  }

  const double ours_median = median(ours_ms);
  const double peer_median = median(peer_ms);
  const double peer12_median = median(peer12_ms);
  // Orientation agreement with cv::BRISK (same definition, different smoothing approximation):
  // cv::BRISK sums (I_i − I_j)(p_j − p_i), the opposite sign of eq. 5, hence the 180° offset.
  std::string angles_note = "cv::BRISK dropped keypoints: no angle comparison";
  if (peer_keypoints.size() == keypoints.size()) {
    std::vector<double> difference;
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      const double ours_degrees = affine_orb::radians_to_degrees_0_360(angles[i]);
      const double d = std::fmod(std::abs(ours_degrees + 180.0 - peer_keypoints[i].angle), 360.0);
      difference.push_back(std::min(d, 360.0 - d));
    }
    char text[128];
    std::snprintf(text, sizeof(text), "median |angle(ours) + 180° − angle(cv::BRISK)|: %.2f°", median(difference));
    angles_note = text;
  }
  const std::size_t slash = path.find_last_of('/', path.find_last_of('/') - 1);
  const std::string shown = slash == std::string::npos ? path : path.substr(slash + 1);
  std::printf("%dx%d (%s resized), %zu FAST-20 keypoints at least %d px inside, medians of %d alternating runs; %s\n\n",
              image.cols, image.rows, shown.c_str(), keypoints.size(), margin, runs, angles_note.c_str());
  std::printf("| BRISK description, same keypoints | ms | µs per keypoint | ours / this |\n|---|---:|---:|---:|\n");
  const double n = static_cast<double>(keypoints.size());
  std::printf("| affine_orb::Brisk: integral image + orientation + descriptor | %.3f | %.2f | 1 |\n", ours_median,
              1000.0 * ours_median / n);
  std::printf("| … of which the integral image (prepare()) | %.3f | | |\n", median(prepare_ms));
  std::printf("| cv::BRISK::compute, size 7.2 (its pattern at scale 1, as ours) | %.3f | %.2f | %.3f |\n", peer_median,
              1000.0 * peer_median / static_cast<double>(peer_keypoints.size()), ours_median / peer_median);
  std::printf("| cv::BRISK::compute, size 12 (its pattern x 1.7) | %.3f | | %.3f |\n", peer12_median,
              ours_median / peer12_median);
  return 0;
}
