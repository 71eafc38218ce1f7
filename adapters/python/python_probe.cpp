// The C++ side of the Python module's tests and overhead bench: extracts features from an image
// with the same options the Python Extractor takes and prints them, or times the extraction; or
// matches two images with views on demand as affine_orb.match_images does with its defaults.
//   affine_orb_python_probe IMAGE FEATURES MAX_TILT rbrief|brisk THREADS [--time N]
//   affine_orb_python_probe --match IMAGE1 IMAGE2 FEATURES MIN_INLIERS
// Without --time: one line per keypoint, "x y size angle response octave view hex-descriptor",
// floats with 9 significant digits (exact for float). With --time N: the median of N extractions
// after a warm-up, in milliseconds. --match: "stage S verified V", the keypoint lines of image 1,
// "--", those of image 2, "--", then one line per match "query train distance inlier".
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/two_view/two_view.hpp"

namespace {

template <int Bits>
void print_features(const affine_orb::Features<Bits>& f) {
  for (std::size_t i = 0; i < f.size(); ++i) {
    const cv::KeyPoint& k = f.keypoints[i];
    std::printf("%.9g %.9g %.9g %.9g %.9g %d %d ", k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave, f.views[i]);
    const auto* bytes = reinterpret_cast<const unsigned char*>(f.descriptors[i].data());
    for (int b = 0; b < Bits / 8; ++b) std::printf("%02x", bytes[b]);
    std::printf("\n");
  }
}

int match(const cv::Mat& image1, const cv::Mat& image2, int features, int min_inliers) {
  affine_orb::TwoViewOptions options;
  options.extractor.features = features;
  options.min_inliers = min_inliers;
  const auto r = affine_orb::TwoViewMatcher<affine_orb::Rbrief>(options).match(image1, image2);
  std::printf("stage %d verified %d\n", r.stage, r.verified ? 1 : 0);
  print_features(r.features1);
  std::printf("--\n");
  print_features(r.features2);
  std::printf("--\n");
  for (std::size_t i = 0; i < r.matches.size(); ++i)
    std::printf("%d %d %d %d\n", r.matches[i].query, r.matches[i].train, r.matches[i].distance, r.inliers[i]);
  return 0;
}

template <class Descriptor>
int run(const cv::Mat& image, const affine_orb::ExtractorOptions& options, int timed) {
  affine_orb::Extractor<Descriptor> extractor(options);
  if (timed > 0) {
    extractor.extract(image);
    std::vector<double> ms;
    for (int i = 0; i < timed; ++i) {
      const auto start = std::chrono::steady_clock::now();
      extractor.extract(image);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(ms.size() / 2), ms.end());
    std::printf("%.4f\n", ms[ms.size() / 2]);
    return 0;
  }
  print_features(extractor.extract(image));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 6 && std::string(argv[1]) == "--match") {
    const cv::Mat image1 = cv::imread(argv[2], cv::IMREAD_GRAYSCALE);
    const cv::Mat image2 = cv::imread(argv[3], cv::IMREAD_GRAYSCALE);
    if (image1.empty() || image2.empty()) {
      std::fprintf(stderr, "affine_orb_python_probe: cannot read %s or %s\n", argv[2], argv[3]);
      return 2;
    }
    return match(image1, image2, std::atoi(argv[4]), std::atoi(argv[5]));
  }
  if (argc != 6 && argc != 8) {
    std::fprintf(stderr, "usage: affine_orb_python_probe IMAGE FEATURES MAX_TILT rbrief|brisk THREADS [--time N]\n");
    return 2;
  }
  const cv::Mat image = cv::imread(argv[1], cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "affine_orb_python_probe: cannot read %s\n", argv[1]);
    return 2;
  }
  affine_orb::ExtractorOptions options;
  options.features = std::atoi(argv[2]);
  options.views.max_tilt = std::atof(argv[3]);
  options.threads = std::atoi(argv[5]);
  const int timed = argc == 8 ? std::atoi(argv[7]) : 0;
  const std::string descriptor = argv[4];
  return descriptor == "brisk" ? run<affine_orb::Brisk>(image, options, timed)
                               : run<affine_orb::Rbrief>(image, options, timed);
}
