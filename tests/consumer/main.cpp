// Extracts features from a synthetic image through the installed umbrella header and prints the
// version of the headers it was compiled with.
#include <affine_orb/affine_orb.hpp>

#include <cstdio>

int main() {
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(128));
  for (int y = 20; y < 220; y += 25) {
    for (int x = 20; x < 300; x += 25)
      cv::rectangle(image, {x, y, 10, 10}, cv::Scalar((x * 7 + y * 3) % 256), cv::FILLED);
  }
  affine_orb::ExtractorOptions options;
  options.features = 100;
  const auto features = affine_orb::Extractor<affine_orb::Rbrief>(options).extract(image);
  std::printf("affine_orb %s: %zu features\n", affine_orb::version(), features.size());
  return features.empty() ? 1 : 0;
}
