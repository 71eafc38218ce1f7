// libFuzzer target: descriptor computation at arbitrary keypoints, through the
// cv::Feature2D compute() of opencv_feature2d.hpp (the entry point that takes keypoints from the
// caller). The bytes give a small image, the descriptor (rBRIEF or BRISK) and up to 24 keypoints
// whose position, octave and angle are arbitrary (raw float bits included: NaN, infinities, huge
// values). compute() must either throw std::invalid_argument or return keypoints that are a subset
// of the given ones, each with one descriptor row, the same row for the same keypoint given twice.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/extraction/opencv_feature2d.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::Bytes;
using affine_orb::fuzz::require;

/// One Feature2D per descriptor, built once and reused across inputs, as a caller holds one.
cv::Ptr<cv::Feature2D>& feature2d(bool brisk) {
  static cv::Ptr<cv::Feature2D> rbrief =
      affine_orb::create_feature2d(affine_orb::ExtractorOptions{}, affine_orb::DescriptorKind::kRbrief);
  static cv::Ptr<cv::Feature2D> brisk_feature =
      affine_orb::create_feature2d(affine_orb::ExtractorOptions{}, affine_orb::DescriptorKind::kBrisk);
  return brisk ? brisk_feature : rbrief;
}

bool same_keypoint(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return std::memcmp(&a.pt, &b.pt, sizeof(a.pt)) == 0 && a.octave == b.octave &&
         std::memcmp(&a.angle, &b.angle, sizeof(a.angle)) == 0;
}

/// Up to 24 keypoints read from the input, raw or near the image, then the first one again.
std::vector<cv::KeyPoint> given_keypoints(Bytes& bytes, int width, int height) {
  std::vector<cv::KeyPoint> given;
  const int count = bytes.next() % 25;
  for (int i = 0; i < count; ++i) {
    const std::uint8_t kind = bytes.next();
    cv::KeyPoint kp;
    if (kind & 1) {
      kp.pt = {bytes.raw_float(), bytes.raw_float()};
    } else {  // near the image, in quarter pixels: borders and rounding ties are likely
      kp.pt = {(static_cast<int>(bytes.next()) - 16) * 0.25f * (width / 48.0f),
               (static_cast<int>(bytes.next()) - 16) * 0.25f * (height / 48.0f)};
    }
    kp.octave = static_cast<std::int8_t>(bytes.next());
    kp.angle = (kind & 2) ? bytes.raw_float() : (kind & 4) ? -1.0f : bytes.next() * 1.5f;
    kp.size = 31.0f;
    given.push_back(kp);
  }
  if (!given.empty()) given.push_back(given.front());  // the same keypoint twice
  return given;
}

/// The kept keypoints are given ones in the caller's order (each angle filled in when it was < 0,
/// then in [0, 360)), with finite positions and angles.
void require_kept_in_order(const std::vector<cv::KeyPoint>& given, const std::vector<cv::KeyPoint>& keypoints) {
  std::size_t g = 0;
  for (const cv::KeyPoint& kp : keypoints) {
    bool computed = false;  // its angle was filled in (given < 0)
    while (g < given.size()) {
      cv::KeyPoint candidate = given[g++];
      computed = candidate.angle < 0.0f;
      if (computed) candidate.angle = kp.angle;
      if (same_keypoint(candidate, kp)) break;
      require(g < given.size());
    }
    require(std::isfinite(kp.angle));
    if (computed) require(kp.angle >= 0.0f && kp.angle < 360.0f);
    require(std::isfinite(kp.pt.x) && std::isfinite(kp.pt.y));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  Bytes bytes(data, size);
  const int width = 16 + bytes.next() % 81;
  const int height = 16 + bytes.next() % 81;
  const std::uint8_t flags = bytes.next();
  const bool brisk = flags & 1;
  cv::Mat image(height, width, CV_8UC1);
  // A few blocks of the input's grey levels, so that corners and gradients exist.
  const int block = 1 + (flags >> 1) % 8;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at<std::uint8_t>(y, x) = data[((y / block) * 7 + (x / block) * 13) % size];
  }
  const std::vector<cv::KeyPoint> given = given_keypoints(bytes, width, height);
  std::vector<cv::KeyPoint> keypoints = given;
  cv::Mat descriptors;
  bool finite_angles = true;
  for (const cv::KeyPoint& kp : given) finite_angles = finite_angles && std::isfinite(kp.angle);
  try {
    feature2d(brisk)->compute(image, keypoints, descriptors);
  } catch (const std::invalid_argument&) {
    require(!finite_angles);  // the only documented rejection for a valid image
    return 0;
  }
  require(keypoints.size() <= given.size());
  require(descriptors.rows == static_cast<int>(keypoints.size()));
  if (!keypoints.empty()) require(descriptors.cols == (brisk ? 64 : 32) && descriptors.type() == CV_8U);
  require_kept_in_order(given, keypoints);
  // The first keypoint and its copy at the end: both kept or both removed, with equal rows.
  if (keypoints.size() >= 2 && same_keypoint(keypoints.front(), given.front()) &&
      same_keypoint(keypoints.back(), given.back())) {
    require(cv::countNonZero(descriptors.row(0) != descriptors.row(descriptors.rows - 1)) == 0);
  }
  return 0;
}
