#pragma once
// Images for the tests. Most tests need nothing outside the repository: Debian opencv-doc's sample
// photos (a test dependency; graf1.png and graf3.png are Oxford's graf img1 and img3 pixel for
// pixel, H1to3p.xml their ground-truth homography), the fixtures in tests/data (tests/data/README.md)
// and synthetic scenes. The evaluation data (AFFINE_ORB_DATA_DIR: Oxford sequences with
// ground-truth homographies, KITTI 06 frames; docs/data.md) is read only by the test cases of
// doctest's test suite "data", which ctest runs as the tests labelled "data" (tests/test_main.cpp).
// A missing file fails the test that asked for it.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

namespace affine_orb::test {

inline std::string data_dir() { return AFFINE_ORB_DATA_DIR; }
inline std::string opencv_samples_dir() { return AFFINE_ORB_OPENCV_SAMPLES_DIR; }
inline std::string fixtures_dir() { return AFFINE_ORB_TEST_FIXTURES_DIR; }

/// Exit code of a program run with --needs-data when the evaluation data is missing; ctest reports
/// it as a skip (GNU's convention for a skipped test).
constexpr int kSkipReturnCode = 77;

/// The folders of the evaluation data that the "data" test cases read and that are missing, joined
/// by ", "; empty when all are there.
inline std::string missing_data() {
  std::string missing;
  for (const char* folder : {"/oxford", "/kitti06"}) {
    const std::string path = data_dir() + folder;
    if (std::filesystem::is_directory(path)) continue;
    missing += (missing.empty() ? "" : ", ") + path;
  }
  return missing;
}

/// Reads an image as CV_8UC1; throws std::runtime_error when the file cannot be read.
inline cv::Mat load_gray(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error("test data missing: " + path);
  return image;
}

/// An image of Debian opencv-doc's samples (`name` as "aloeL.jpg"), grey.
inline cv::Mat sample_image(const std::string& name) { return load_gray(opencv_samples_dir() + "/" + name); }

/// Oxford's graf img1 or img3 (`n` 1 or 3), grey 800x640, from opencv-doc's graf1.png and graf3.png.
inline cv::Mat graf(int n) {
  if (n != 1 && n != 3) throw std::invalid_argument("opencv-doc has graf 1 and 3 only");
  return sample_image("graf" + std::to_string(n) + ".png");
}

/// Oxford's ground-truth homography from graf img1 to img3 (x_3 ~ H x_1, pixels), from opencv-doc's
/// H1to3p.xml.
inline cv::Matx33d graf_homography_1to3() {
  const std::string path = opencv_samples_dir() + "/H1to3p.xml";
  cv::FileStorage storage(path, cv::FileStorage::READ);
  if (!storage.isOpened()) throw std::runtime_error("test data missing: " + path);
  cv::Mat h;
  storage["H13"] >> h;
  if (h.rows != 3 || h.cols != 3 || h.type() != CV_64F) throw std::runtime_error("malformed homography: " + path);
  return cv::Matx33d(h);
}

/// A real photo with texture everywhere, larger than any crop the tests take: opencv-doc's
/// aloeL.jpg (Middlebury's "Aloe" stereo pair, left view), grey 1282x1110.
inline cv::Mat textured_photo() { return sample_image("aloeL.jpg"); }

/// A crop of textured_photo() of `size` whose top-left corner moves by (7, 5) pixels per index:
/// frames of a camera panning over a plane, for tests that need several different real frames.
inline cv::Mat panning_frame(int index, cv::Size size) {
  const cv::Mat photo = textured_photo();
  const cv::Rect crop(7 * index, 5 * index, size.width, size.height);
  if ((crop & cv::Rect(0, 0, photo.cols, photo.rows)) != crop)
    throw std::invalid_argument("panning_frame: outside the photo");
  return photo(crop).clone();
}

/// imgN.png of an Oxford sequence ("graf", "boat", "bark", ...), grey.
inline cv::Mat oxford_image(const std::string& sequence, int n) {
  return load_gray(data_dir() + "/oxford/" + sequence + "/img" + std::to_string(n) + ".png");
}

/// A homography in Oxford's text format: nine numbers, row-major.
inline cv::Matx33d read_homography_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("test data missing: " + path);
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) {
    if (!(in >> h.val[i])) throw std::runtime_error("malformed homography: " + path);
  }
  return h;
}

/// Ground-truth homography H1toNp of an Oxford sequence, CV_64F 3x3, x_N ~ H x_1 (pixels).
inline cv::Matx33d oxford_homography(const std::string& sequence, int n) {
  return read_homography_text(data_dir() + "/oxford/" + sequence + "/H1to" + std::to_string(n) + "p");
}

/// KITTI 06 frame `index` (0..50), grey 1226x370.
inline cv::Mat kitti_frame(int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "/kitti06/image_0/%06d.png", index);
  return load_gray(data_dir() + name);
}

/// KITTI 00 frame `index` (0..159), grey 1241x376.
inline cv::Mat kitti00_frame(int index) {
  char name[40];
  std::snprintf(name, sizeof(name), "/kitti00/image_0/%06d.png", index);
  return load_gray(data_dir() + name);
}

/// The frames the conformance tests compare a SLAM system's extraction on in every clone:
/// opencv-doc's graf img1 and img3 and Middlebury's aloeL.
inline std::vector<cv::Mat> conformance_sample_frames() { return {graf(1), graf(3), textured_photo()}; }

/// The evaluation data's frames the conformance tests compare on: KITTI 00 and 06, and the Oxford
/// sequences' first images.
inline std::vector<cv::Mat> conformance_data_frames() {
  std::vector<cv::Mat> out;
  for (int i = 0; i < 160; i += 20) out.push_back(kitti00_frame(i));
  for (int i = 0; i <= 50; i += 25) out.push_back(kitti_frame(i));
  for (const char* sequence : {"boat", "bark", "bikes", "trees", "leuven"}) out.push_back(oxford_image(sequence, 1));
  return out;
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
