#pragma once
// Access to the real evaluation images for the tests: ../shared/data (Oxford sequences with
// ground-truth homographies, KITTI 06 frames) and Debian opencv-doc's sample photos. A missing file
// fails the test that asked for it: the data is part of the test environment, not optional.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace affine_orb::test {

inline std::string data_dir() { return AFFINE_ORB_DATA_DIR; }
inline std::string opencv_samples_dir() { return AFFINE_ORB_OPENCV_SAMPLES_DIR; }

/// Reads an image as CV_8UC1; throws std::runtime_error when the file cannot be read.
inline cv::Mat load_gray(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error("test data missing: " + path);
  return image;
}

/// imgN.png of an Oxford sequence ("graf", "boat", "bark", ...), grey.
inline cv::Mat oxford_image(const std::string& sequence, int n) {
  return load_gray(data_dir() + "/oxford/" + sequence + "/img" + std::to_string(n) + ".png");
}

/// Ground-truth homography H1toNp of an Oxford sequence, CV_64F 3x3, x_N ~ H x_1 (pixels).
inline cv::Matx33d oxford_homography(const std::string& sequence, int n) {
  const std::string path = data_dir() + "/oxford/" + sequence + "/H1to" + std::to_string(n) + "p";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("test data missing: " + path);
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) {
    if (!(in >> h.val[i])) throw std::runtime_error("malformed homography: " + path);
  }
  return h;
}

/// KITTI 06 frame `index` (0..50), grey 1226x370.
inline cv::Mat kitti_frame(int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "/kitti06/image_0/%06d.png", index);
  return load_gray(data_dir() + name);
}

/// Maps a point through a homography (x2 ~ H x1).
inline cv::Point2d apply_homography(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

/// Mean distance, pixels of image 2, between the four corners of an image of `size` mapped by the
/// estimate and by the ground truth (the "solved" judge of bench/eval_two_view: <= 5 px).
inline double corner_error(const Eigen::Matrix3d& estimate, const cv::Matx33d& truth, cv::Size size) {
  double sum = 0.0;
  for (const cv::Point2d c : {cv::Point2d(0, 0), cv::Point2d(size.width - 1, 0), cv::Point2d(0, size.height - 1),
                              cv::Point2d(size.width - 1, size.height - 1)}) {
    const Eigen::Vector3d e = estimate * Eigen::Vector3d(c.x, c.y, 1.0);
    const cv::Point2d t = apply_homography(truth, c);
    sum += std::hypot(e.x() / e.z() - t.x, e.y() / e.z() - t.y);
  }
  return sum / 4.0;
}

}  // namespace affine_orb::test
