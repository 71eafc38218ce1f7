// Sequences: the readers of support/sequence_io.hpp (KITTI, TUM with time-stamp association,
// folders in name order) on fixtures written to a temporary directory; KeyframeTracker
// (keyframe_tracker.hpp) on synthetic sequences with known breaks (a real photo seen by a rotating
// camera, x_i ~ K R_i K⁻¹ x_0, with a noise frame or a scene cut) and on the first 20 frames of
// KITTI 06 against its ground-truth poses.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/relative_pose.hpp"
#include "homography_io.hpp"
#include "keyframe_tracker.hpp"
#include "sequence_io.hpp"
#include "test_data.hpp"

namespace {

namespace ex = affine_orb::examples;
using affine_orb::rotation_angle_degrees;
using Tracker = affine_orb::KeyframeTracker<affine_orb::Rbrief::kBits>;
using Features = affine_orb::Features<affine_orb::Rbrief::kBits>;

constexpr double kPi = 3.14159265358979323846;

// Under AddressSanitizer (about 5x slower in RelWithDebInfo, 40x in a Debug build, mostly in the
// 18-view extraction) the affine runs use fewer frames; plain runs keep all of them.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

bool is_affine(double max_tilt) { return max_tilt > 1.0; }

// A fresh directory under the system temporary directory, removed with its contents at the end.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "affine_orb_test_sequence_XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  REQUIRE(out.good());
}

// A small image whose single pixel value encodes `tag`, to check which file a frame is.
void write_tagged_image(const std::filesystem::path& path, int tag) {
  std::filesystem::create_directories(path.parent_path());
  REQUIRE(cv::imwrite(path.string(), cv::Mat(8, 8, CV_8UC1, cv::Scalar(tag))));
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int tag_of(const ex::SequenceFrame& frame) { return ex::load_frame(frame).at<std::uint8_t>(0, 0); }

Eigen::Matrix3d rotation(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(degrees * kPi / 180.0, axis.normalized()).toRotationMatrix();
}

// --- synthetic sequences -------------------------------------------------------------------

// A camera with intrinsics `camera` rotating about its centre while looking at a photo: frame i
// is the photo warped by H_i = K R_i K⁻¹ (x_i ~ H_i x_photo), R_i = rotation(i · step) about a
// fixed axis. A point X in the frame-0 camera is R_i X in frame i's.
struct RotatingCamera {
  affine_orb::PinholeCamera camera;
  std::vector<cv::Mat> frames;
  std::vector<Eigen::Matrix3d> rotations;

  Eigen::Matrix3d homography(std::size_t i) const { return camera.matrix() * rotations[i] * camera.inverse(); }
};

RotatingCamera rotating_camera(const cv::Mat& photo, int count, double degrees_per_frame, int first_index = 0) {
  RotatingCamera s;
  s.camera = {600.0, 600.0, (photo.cols - 1) / 2.0, (photo.rows - 1) / 2.0};
  for (int i = first_index; i < first_index + count; ++i) {
    const Eigen::Matrix3d r = rotation(degrees_per_frame * i, {0.3, 1.0, 0.1});
    s.rotations.push_back(r);
    const Eigen::Matrix3d h = s.camera.matrix() * r * s.camera.inverse();
    cv::Mat hm(3, 3, CV_64F);
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) hm.at<double>(a, b) = h(a, b);
    }
    cv::Mat frame;
    cv::warpPerspective(photo, frame, hm, photo.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    s.frames.push_back(frame);
  }
  return s;
}

cv::Mat noise_image(cv::Size size, std::uint64_t seed) {
  cv::Mat noise(size, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  return noise;
}

affine_orb::ExtractorOptions extractor_options(double max_tilt) {
  affine_orb::ExtractorOptions o;
  o.features = 1000;
  o.threads = 2;
  o.views.max_tilt = max_tilt;
  return o;
}

// Share of a frame's inlier matches that the true homography between the keyframe and the frame
// confirms: within SPEC §7's 3 px, counted in pixels of the coarser keypoint's scale
// (KeyPoint::size / Rbrief::kPatchSize = s^level · √tilt), since a keypoint of pyramid level l is
// located to about a level pixel (up to 3.6 original pixels at level 7).
double correct_inlier_share(const affine_orb::TrackedFrame& t, const Features& keyframe, const Features& frame,
                            const Eigen::Matrix3d& keyframe_to_frame) {
  int inliers = 0, correct = 0;
  for (std::size_t k = 0; k < t.matches.size(); ++k) {
    if (t.inlier_mask[k] == 0) continue;
    ++inliers;
    const cv::Point2f& a = keyframe.keypoints[static_cast<std::size_t>(t.matches[k].query)].pt;
    const cv::Point2f& b = frame.keypoints[static_cast<std::size_t>(t.matches[k].train)].pt;
    const Eigen::Vector2d mapped = (keyframe_to_frame * Eigen::Vector3d(a.x, a.y, 1.0)).hnormalized();
    const double scale = std::max(keyframe.keypoints[static_cast<std::size_t>(t.matches[k].query)].size,
                                  frame.keypoints[static_cast<std::size_t>(t.matches[k].train)].size) /
                         affine_orb::Rbrief::kPatchSize;
    correct += (mapped - Eigen::Vector2d(b.x, b.y)).norm() < 3.0 * scale ? 1 : 0;
  }
  return inliers == 0 ? 0.0 : static_cast<double>(correct) / inliers;
}

// The keyframe rules of keyframe_tracker.hpp, checked frame by frame against the results.
void check_keyframe_rules(const std::vector<affine_orb::TrackedFrame>& results,
                          const affine_orb::KeyframeTrackerOptions& options) {
  int keyframe = -1;
  int streak = 0;
  for (const affine_orb::TrackedFrame& t : results) {
    CHECK(t.reference_keyframe == keyframe);
    if (keyframe >= 0) {
      CHECK(t.lost == (t.model == affine_orb::GeometricModel::kNone || t.inliers < options.min_inliers));
    }
    if (!t.lost && keyframe >= 0) {
      CHECK(t.keyframe == (t.inlier_ratio < options.keyframe_inlier_ratio));
      CHECK_FALSE(t.initialised);
      streak = 0;
    }
    if (t.lost) {
      ++streak;
      CHECK(t.keyframe == (keyframe >= 0 && streak >= options.max_lost_frames && t.features >= options.min_inliers));
    }
    if (t.keyframe) {
      keyframe = t.index;
      streak = 0;
    }
  }
}

}  // namespace

// --- readers ---------------------------------------------------------------------------------

namespace {

/// Writes a KITTI-layout sequence of three frames into `dir`: tagged images, times, poses (frame
/// 1 rotated 90° about y, at (1, 2, 3)) and a calib.txt of key=value intrinsics.
void write_kitti_sequence(const std::filesystem::path& dir) {
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "image_0/%06d.png", i);
    write_tagged_image(dir / name, 10 + i);
  }
  write_text(dir / "times.txt", "0.0\n1.036e-01\n2.07e-01\n");
  write_text(dir / "poses.txt",
             "1 0 0 0 0 1 0 0 0 0 1 0\n"
             "0 0 1 1 0 1 0 2 -1 0 0 3\n"
             "1 0 0 0 0 1 0 0 0 0 1 5\n");
  write_text(dir / "calib.txt", "# comment\nfx=707.0912 fy=707.0912 cx=601.8873 cy=183.1104\nwidth=1226\n");
}

}  // namespace

TEST_CASE("KITTI reader: images in name order, times, poses, key=value calibration") {
  TempDir dir;
  write_kitti_sequence(dir.path());
  const ex::Sequence s = ex::read_sequence(dir.path());
  CHECK(s.format == "kitti");
  REQUIRE(s.frames.size() == 3);
  for (int i = 0; i < 3; ++i) CHECK(tag_of(s.frames[static_cast<std::size_t>(i)]) == 10 + i);
  CHECK(s.frames[1].timestamp == doctest::Approx(0.1036));
  REQUIRE(s.frames[1].pose);
  Eigen::Matrix3d r1;
  r1 << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  CHECK((s.frames[1].pose->rotation - r1).norm() == 0.0);
  CHECK((s.frames[1].pose->position - Eigen::Vector3d(1, 2, 3)).norm() == 0.0);
  // X_1 = R X_0 + t with R = R_1ᵀ R_0: a 90° turn.
  CHECK(rotation_angle_degrees(Eigen::Matrix3d::Identity(),
                               ex::relative_rotation(*s.frames[0].pose, *s.frames[1].pose)) == doctest::Approx(90.0));
  REQUIRE(s.camera);
  CHECK(s.camera->fx == 707.0912);
  CHECK(s.camera->cy == 183.1104);

  SUBCASE("poses elsewhere (the official poses/NN.txt)") {
    write_text(dir.path() / "other.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n1 0 0 0 0 1 0 0 0 0 1 2\n");
    const ex::Sequence o = ex::read_kitti(dir.path(), dir.path() / "other.txt");
    CHECK(o.frames[2].pose->position.z() == 2.0);
  }
  SUBCASE("without poses and times") {
    std::filesystem::remove(dir.path() / "poses.txt");
    std::filesystem::remove(dir.path() / "times.txt");
    const ex::Sequence o = ex::read_kitti(dir.path());
    CHECK_FALSE(o.frames[0].pose);
    CHECK(o.frames[2].timestamp == 2.0);
  }
}

TEST_CASE("KITTI calibration: the official P0 line and four plain numbers") {
  TempDir dir;
  write_text(dir.path() / "calib.txt",
             "P0: 7.188560e+02 0.000000e+00 6.071928e+02 0.000000e+00 0.000000e+00 7.188560e+02 1.852157e+02 "
             "0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\nP1: 1 2 3\n");
  const affine_orb::PinholeCamera p0 = ex::read_calibration(dir.path() / "calib.txt");
  CHECK(p0.fx == 718.856);
  CHECK(p0.fy == 718.856);
  CHECK(p0.cx == 607.1928);
  CHECK(p0.cy == 185.2157);
  write_text(dir.path() / "calib.txt", "500 510 320 240\n");
  const affine_orb::PinholeCamera plain = ex::read_calibration(dir.path() / "calib.txt");
  CHECK(plain.fy == 510.0);
  CHECK(plain.cx == 320.0);
}

TEST_CASE("KITTI reader: errors name the file") {
  TempDir dir;
  write_kitti_sequence(dir.path());
  write_text(dir.path() / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("poses.txt has 2 lines"), std::runtime_error);
  write_text(dir.path() / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("poses.txt:2: expected 12 numbers"),
                       std::runtime_error);
  write_text(dir.path() / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 x\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_AS(ex::read_kitti(dir.path()), std::runtime_error);
  std::filesystem::remove(dir.path() / "poses.txt");
  write_text(dir.path() / "times.txt", "0\n1\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("times.txt has 2 lines"), std::runtime_error);
  std::filesystem::remove(dir.path() / "times.txt");
  write_text(dir.path() / "calib.txt", "fx=1 fy=2\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("no intrinsics"), std::runtime_error);
  write_text(dir.path() / "calib.txt", "fx=-1 fy=2 cx=3 cy=4\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("positive"), std::runtime_error);
  write_text(dir.path() / "calib.txt", "fx=abc fy=2 cx=3 cy=4\n");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path()), doctest::Contains("bad value"), std::runtime_error);
  std::filesystem::remove(dir.path() / "calib.txt");
  CHECK_THROWS_WITH_AS(ex::read_kitti(dir.path(), dir.path() / "missing.txt"), doctest::Contains("cannot read"),
                       std::runtime_error);
  std::filesystem::remove_all(dir.path() / "image_0");
  CHECK_THROWS_AS(ex::read_kitti(dir.path()), std::runtime_error);
}

TEST_CASE("homography reader: Oxford numbers and OpenCV XML equal the files; bad files throw") {
  namespace ex = affine_orb::examples;
  // A file in Oxford's text format (tests/data/graf_H1to3p) against the test's own reader of it.
  const std::string text = affine_orb::test::fixtures_dir() + "/graf_H1to3p";
  const cv::Matx33d oxford = ex::read_homography(text);
  const cv::Matx33d reference = affine_orb::test::read_homography_text(text);
  for (int i = 0; i < 9; ++i) CHECK(oxford.val[i] == reference.val[i]);
  // opencv-doc's graf H1to3p.xml is the same matrix in OpenCV's XML storage (to 1e-6 relative).
  const cv::Matx33d stored = ex::read_homography(affine_orb::test::opencv_samples_dir() + "/H1to3p.xml");
  for (int i = 0; i < 9; ++i) CHECK(stored.val[i] == doctest::Approx(reference.val[i]).epsilon(1e-5));
  CHECK(ex::parse_homography("%YAML:1.0\n---\nH: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                             "   data: [ 2., 0., 1., 0., 2., 3., 0., 0., 1. ]\n",
                             "h.yml")(1, 2) == 3.0);
  CHECK_THROWS_WITH_AS(ex::parse_homography("1 2 3 4 5", "h"), doctest::Contains("expected 9 numbers"),
                       std::runtime_error);
  CHECK_THROWS_WITH_AS(ex::parse_homography("1 2 3 2 4 6 0 0 1", "h"), doctest::Contains("singular"),
                       std::runtime_error);
  CHECK_THROWS_WITH_AS(ex::parse_homography("<?xml version=\"1.0\"?><opencv_storage><a>1</a></opencv_storage>", "h"),
                       doctest::Contains("no 3x3 matrix"), std::runtime_error);
  // Truncated storage (OpenCV 4.6's own in-memory XML parser crashes on this one) and a 2x3 matrix.
  CHECK_THROWS_AS(ex::parse_homography("<?xml version=\"1.0\"?><opencv_storage><H type_id=", "h"), std::runtime_error);
  CHECK_THROWS_WITH_AS(ex::parse_homography("%YAML:1.0\nH: !!opencv-matrix\n rows: 2\n cols: 3\n dt: d\n"
                                            " data: [ 1, 0, 0, 0, 1, 0 ]\n",
                                            "h"),
                       doctest::Contains("no 3x3 matrix"), std::runtime_error);
  CHECK_THROWS_WITH_AS(ex::parse_homography("<?xml version=\"1.0\"?><opencv_storage><H type_id=\"opencv-matrix\">"
                                            "<rows>3</rows><cols>3</cols><dt>d</dt><data>1 0 0 0 1",
                                            "h"),
                       doctest::Contains("expected 9 numbers"), std::runtime_error);
  CHECK_THROWS_WITH_AS(ex::read_homography("/nonexistent/H"), doctest::Contains("cannot read"), std::runtime_error);
}

TEST_CASE("TUM reader: ground truth associated by the nearest time stamp within 0.02 s") {
  TempDir dir;
  write_tagged_image(dir.path() / "rgb/1.000000.png", 1);
  write_tagged_image(dir.path() / "rgb/1.033000.png", 2);
  write_tagged_image(dir.path() / "rgb/1.066000.png", 3);
  write_tagged_image(dir.path() / "rgb/2.000000.png", 4);
  write_text(dir.path() / "rgb.txt",
             "# color images\n# file: 'rgbd_dataset'\n# timestamp filename\n"
             "1.000000 rgb/1.000000.png\n1.033000 rgb/1.033000.png\n1.066000 rgb/1.066000.png\n"
             "2.000000 rgb/2.000000.png\n");
  // Ground truth at 100 Hz around the images, out of order; x = time stamp marks each row.
  // qw = cos(45°) about z for the row at 1.03: a 90° turn.
  write_text(dir.path() / "groundtruth.txt",
             "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
             "1.0400 1.0400 0 0 0 0 0 1\n"
             "0.9950 0.9950 0 0 0 0 0 1\n"
             "1.0030 1.0030 0 0 0 0 0 1\n"
             "1.0300 1.0300 0 0 0 0 0.7071067811865476 0.7071067811865476\n"
             "1.0700 1.0700 0 0 0 0 0 1\n"
             "1.9700 1.9700 0 0 0 0 0 1\n");
  const ex::Sequence s = ex::read_sequence(dir.path());
  CHECK(s.format == "tum");
  REQUIRE(s.frames.size() == 4);
  for (int i = 0; i < 4; ++i) CHECK(tag_of(s.frames[static_cast<std::size_t>(i)]) == i + 1);
  CHECK(s.frames[1].timestamp == doctest::Approx(1.033));
  // 1.000 -> 1.003 (0.003 after) rather than 0.995 (0.005 before).
  REQUIRE(s.frames[0].pose);
  CHECK(s.frames[0].pose->position.x() == doctest::Approx(1.003));
  // 1.033 -> 1.030 (0.003) rather than 1.040 (0.007), with its rotation.
  REQUIRE(s.frames[1].pose);
  CHECK(s.frames[1].pose->position.x() == doctest::Approx(1.030));
  CHECK(rotation_angle_degrees(Eigen::Matrix3d::Identity(), s.frames[1].pose->rotation) == doctest::Approx(90.0));
  CHECK(s.frames[1].pose->rotation(1, 0) == doctest::Approx(1.0));  // x axis to y: about +z
  // 1.066 -> 1.070 (0.004).
  REQUIRE(s.frames[2].pose);
  CHECK(s.frames[2].pose->position.x() == doctest::Approx(1.070));
  // 2.000: the nearest row is 0.03 s away, beyond 0.02 s: no pose.
  CHECK_FALSE(s.frames[3].pose);
  // A looser association bound reaches it.
  CHECK(ex::read_tum(dir.path(), 0.05).frames[3].pose);
  CHECK_FALSE(s.camera);

  SUBCASE("errors") {
    write_text(dir.path() / "groundtruth.txt", "1.0 0 0 0 0 0 0 2\n");
    CHECK_THROWS_WITH_AS(ex::read_tum(dir.path()), doctest::Contains("not unit length"), std::runtime_error);
    write_text(dir.path() / "groundtruth.txt", "1.0 0 0 0 0 0 1\n");
    CHECK_THROWS_WITH_AS(ex::read_tum(dir.path()), doctest::Contains("groundtruth.txt:1: expected 8 numbers"),
                         std::runtime_error);
    write_text(dir.path() / "rgb.txt", "1.0 rgb/1.000000.png extra\n");
    CHECK_THROWS_WITH_AS(ex::read_tum(dir.path()), doctest::Contains("rgb.txt:1"), std::runtime_error);
    write_text(dir.path() / "rgb.txt", "2.0 rgb/2.000000.png\n1.0 rgb/1.000000.png\n");
    CHECK_THROWS_WITH_AS(ex::read_tum(dir.path()), doctest::Contains("increasing"), std::runtime_error);
    write_text(dir.path() / "rgb.txt", "# nothing\n");
    CHECK_THROWS_WITH_AS(ex::read_tum(dir.path()), doctest::Contains("no images"), std::runtime_error);
  }
}

TEST_CASE("folder reader: image files only, natural name order; subsample keeps every K-th frame") {
  TempDir dir;
  const std::vector<std::string> names = {"frame10.png", "frame2.png", "frame1.jpg", "frame02b.PNG", "a.pgm"};
  for (std::size_t i = 0; i < names.size(); ++i) write_tagged_image(dir.path() / names[i], static_cast<int>(i) + 1);
  write_text(dir.path() / "notes.txt", "not an image\n");
  std::filesystem::create_directories(dir.path() / "sub.png");  // a directory, not a file
  const ex::Sequence s = ex::read_sequence(dir.path());
  CHECK(s.format == "folder");
  REQUIRE(s.frames.size() == 5);
  // a, frame1, frame2, frame02b, frame10
  const std::vector<int> expected = {5, 3, 2, 4, 1};
  for (std::size_t i = 0; i < 5; ++i) {
    CHECK(tag_of(s.frames[i]) == expected[i]);
    CHECK(s.frames[i].timestamp == static_cast<double>(i));
    CHECK_FALSE(s.frames[i].pose);
  }
  CHECK(ex::detail::natural_less("img9", "img10"));
  CHECK_FALSE(ex::detail::natural_less("img10", "img9"));
  CHECK(ex::detail::natural_less("img", "img0"));
  CHECK(ex::detail::natural_less("img01", "img1"));  // same value: plain order decides
  CHECK_FALSE(ex::detail::natural_less("same", "same"));

  const ex::Sequence every2 = ex::subsample(s, 2);
  REQUIRE(every2.frames.size() == 3);
  CHECK(tag_of(every2.frames[1]) == 2);
  CHECK(ex::subsample(s, 7).frames.size() == 1);
  CHECK_THROWS_AS(ex::subsample(s, 0), std::runtime_error);

  CHECK_THROWS_AS(ex::read_sequence(dir.path(), "vicon"), std::runtime_error);
  CHECK_THROWS_AS(ex::read_sequence(dir.path() / "missing"), std::runtime_error);
  TempDir empty;
  CHECK_THROWS_WITH_AS(ex::read_folder(empty.path()), doctest::Contains("no images"), std::runtime_error);
  write_text(empty.path() / "broken.png", "not a png");
  CHECK_THROWS_WITH_AS(ex::load_frame(ex::read_folder(empty.path()).frames[0]), doctest::Contains("cannot read"),
                       std::runtime_error);
}

// --- tracker ---------------------------------------------------------------------------------

TEST_CASE("tracker: a noise frame is lost, tracking recovers after it, inliers and rotations are right") {
  const cv::Mat photo = affine_orb::test::graf(1);
  const RotatingCamera scene = rotating_camera(photo, 12, 0.6);
  constexpr std::size_t kNoiseFrame = 5;
  for (const double max_tilt : {1.0, 2.0 * std::sqrt(2.0)}) {
    CAPTURE(max_tilt);
    affine_orb::Extractor<affine_orb::Rbrief> extractor(extractor_options(max_tilt));
    // Measured: the inlier ratio to frame 0 falls from 0.35 (frame 1) to 0.23–0.26 (frame 11);
    // a keyframe threshold of 0.3 instead of the default 0.1 makes this short drift take some.
    affine_orb::KeyframeTrackerOptions options;
    options.keyframe_inlier_ratio = 0.3;
    Tracker tracker(options, scene.camera);
    std::vector<affine_orb::TrackedFrame> results;
    std::vector<Features> features;
    // 12 frames; 8 (still two after the noise frame) for affine features under a sanitizer.
    const std::size_t frames = kSanitized && is_affine(max_tilt) ? 8 : scene.frames.size();
    for (std::size_t i = 0; i < frames; ++i) {
      const cv::Mat image = i == kNoiseFrame ? noise_image(photo.size(), 7) : scene.frames[i];
      features.push_back(extractor.extract(image));
      results.push_back(tracker.track(features.back()));
    }
    check_keyframe_rules(results, options);
    CHECK(results[0].keyframe);
    CHECK(results[0].initialised);
    CHECK_FALSE(results[0].lost);
    for (std::size_t i = 1; i < results.size(); ++i) {
      const affine_orb::TrackedFrame& t = results[i];
      CAPTURE(i);
      if (i == kNoiseFrame) {
        CHECK(t.lost);
        CHECK_FALSE(t.keyframe);
        CHECK(t.inliers < options.min_inliers);
        continue;
      }
      // Every real frame is tracked, the one after the noise frame against a keyframe before it.
      CHECK_FALSE(t.lost);
      if (i == kNoiseFrame + 1) CHECK(t.reference_keyframe < static_cast<int>(kNoiseFrame));
      // A camera rotating about its centre: the homography is chosen, and the inliers agree with
      // the true keyframe-to-frame homography H_i H_k⁻¹.
      CHECK(t.model == affine_orb::GeometricModel::kHomography);
      const std::size_t k = static_cast<std::size_t>(t.reference_keyframe);
      const Eigen::Matrix3d truth = scene.homography(i) * scene.homography(k).inverse();
      CHECK(correct_inlier_share(t, features[k], features[i], truth) > 0.95);
      // The relative rotation to the previous frame, when both are real frames.
      if (i != kNoiseFrame + 1) {
        REQUIRE(t.relative_pose.success);
        const Eigen::Matrix3d relative = scene.rotations[i] * scene.rotations[i - 1].transpose();
        CHECK(rotation_angle_degrees(t.relative_pose.rotation, relative) < 0.5);
      }
    }
    CHECK(tracker.frames() == static_cast<int>(frames));
    CHECK(tracker.lost_frames() == 1);
    CHECK(tracker.frame_loss_rate() == doctest::Approx(1.0 / static_cast<double>(frames)));
    int keyframes = 0;
    for (const affine_orb::TrackedFrame& t : results) keyframes += t.keyframe ? 1 : 0;
    CHECK(tracker.keyframes() == keyframes);
    CHECK(keyframes >= 2);  // the first frame and at least one taken as the view drifts
  }
}

TEST_CASE("tracker: a scene cut makes the keyframe stale; the last of max_lost_frames lost frames restarts") {
  const RotatingCamera first = rotating_camera(affine_orb::test::graf(1), 4, 0.5);
  const cv::Mat other = affine_orb::test::textured_photo()(cv::Rect(0, 0, 800, 640)).clone();
  const RotatingCamera second = rotating_camera(other, 6, 0.5);
  affine_orb::Extractor<affine_orb::Rbrief> extractor(extractor_options(1.0));
  affine_orb::KeyframeTrackerOptions options;
  options.max_lost_frames = 3;
  Tracker tracker(options);
  std::vector<affine_orb::TrackedFrame> results;
  for (const cv::Mat& image : first.frames) results.push_back(tracker.track(extractor.extract(image)));
  for (const cv::Mat& image : second.frames) results.push_back(tracker.track(extractor.extract(image)));
  check_keyframe_rules(results, options);
  for (int i = 0; i < 4; ++i) CHECK_FALSE(results[static_cast<std::size_t>(i)].lost);
  // Frames 4, 5, 6 lost; frame 6 becomes the keyframe; 7, 8, 9 tracked against it.
  for (int i = 4; i < 7; ++i) CHECK(results[static_cast<std::size_t>(i)].lost);
  CHECK_FALSE(results[4].keyframe);
  CHECK_FALSE(results[5].keyframe);
  CHECK(results[6].keyframe);
  CHECK(results[6].initialised);
  for (int i = 7; i < 10; ++i) {
    CHECK_FALSE(results[static_cast<std::size_t>(i)].lost);
    CHECK(results[static_cast<std::size_t>(i)].reference_keyframe >= 6);
  }
  CHECK(tracker.lost_frames() == 3);
  // No camera: no frame-to-previous matching.
  for (const affine_orb::TrackedFrame& t : results) {
    CHECK(t.previous_matches == 0);
    CHECK_FALSE(t.relative_pose.success);
  }

  tracker.reset();
  CHECK(tracker.frames() == 0);
  CHECK(tracker.keyframe_index() == -1);
  const affine_orb::TrackedFrame again = tracker.track(extractor.extract(first.frames[0]));
  CHECK(again.index == 0);
  CHECK(again.initialised);
}

TEST_CASE("tracker: frames without features are lost and cannot become keyframes") {
  const RotatingCamera scene = rotating_camera(affine_orb::test::graf(1), 3, 0.5);
  affine_orb::Extractor<affine_orb::Rbrief> extractor(extractor_options(1.0));
  affine_orb::KeyframeTrackerOptions options;
  options.max_lost_frames = 1;
  Tracker tracker(options, scene.camera);
  const cv::Mat flat(scene.frames[0].size(), CV_8UC1, cv::Scalar(128));
  const affine_orb::TrackedFrame a = tracker.track(extractor.extract(flat));
  CHECK(a.features == 0);
  CHECK(a.lost);
  CHECK_FALSE(a.keyframe);
  const affine_orb::TrackedFrame b = tracker.track(extractor.extract(scene.frames[0]));
  CHECK_FALSE(b.lost);
  CHECK(b.keyframe);
  CHECK(b.initialised);
  CHECK_FALSE(b.relative_pose.success);  // its previous frame had no features
  // A featureless frame after a keyframe: lost, and with max_lost_frames = 1 still no keyframe.
  const affine_orb::TrackedFrame c = tracker.track(Features{});
  CHECK(c.lost);
  CHECK_FALSE(c.keyframe);
  CHECK(c.matches.empty());
  const affine_orb::TrackedFrame d = tracker.track(extractor.extract(scene.frames[1]));
  CHECK_FALSE(d.lost);
  CHECK(d.reference_keyframe == 1);
  CHECK(tracker.lost_frames() == 2);
}

TEST_CASE("tracker: bad options and inconsistent features throw") {
  const auto rejects = [](const affine_orb::KeyframeTrackerOptions& o) {
    CHECK_THROWS_AS(o.check(), std::invalid_argument);
    CHECK_THROWS_AS(Tracker{o}, std::invalid_argument);
  };
  affine_orb::KeyframeTrackerOptions o;
  o.min_inliers = 7;
  rejects(o);
  o = {};
  o.keyframe_inlier_ratio = 0.0;
  rejects(o);
  o.keyframe_inlier_ratio = 1.5;
  rejects(o);
  o.keyframe_inlier_ratio = std::numeric_limits<double>::quiet_NaN();
  rejects(o);
  o = {};
  o.max_lost_frames = 0;
  rejects(o);
  o = {};
  o.model_selection.sigma = 0.0;
  rejects(o);
  o = {};
  o.matching.matcher.ratio = -1.0f;
  rejects(o);
  o = {};
  o.pose.min_good_points = 0;
  rejects(o);
  CHECK_THROWS_AS(Tracker({}, affine_orb::PinholeCamera{0.0, 1.0, 0.0, 0.0}), std::invalid_argument);

  Tracker tracker;
  Features broken;
  broken.keypoints.resize(3);
  broken.descriptors.resize(2);
  CHECK_THROWS_AS(tracker.track(broken), std::invalid_argument);
  broken.descriptors.resize(3);
  broken.views.resize(1);
  CHECK_THROWS_AS(tracker.track(broken), std::invalid_argument);
  CHECK(tracker.frames() == 0);
}

TEST_CASE("KITTI 06, first 20 frames: every frame tracked, rotations against the ground truth" *
          doctest::test_suite("data")) {
  // Measured (1000 features, 2 threads, default options): plain features track all 20 frames with
  // 71–194 inliers to the keyframe (the loss threshold is 30) and take 7 keyframes; affine features
  // (max tilt 2√2, 18 views) also track all 20 and take 8. Frame-to-frame rotations are recovered
  // for 18 (plain) and 19 (affine) of the 19 pairs with median errors of 0.13° and 0.35°; the car
  // turns by a median 0.06° per frame. Under a sanitizer the affine run covers frames 0-5 only:
  // 5 rotations, median error 0.45°. Floors: at most one lost frame, at least two keyframes,
  // rotations for all but two pairs, median error below 0.5° for plain features (the accuracy the
  // synthetic tests demand) and 0.75° for affine ones, whose keypoints are located less precisely
  // (mapped back from views subsampled by up to 2√2 along one axis).
  ex::Sequence sequence = ex::read_kitti(affine_orb::test::data_dir() + "/kitti06");
  REQUIRE(sequence.frames.size() == 51);
  REQUIRE(sequence.camera);
  sequence.frames.resize(20);
  const double max_tilts[] = {1.0, 2.0 * std::sqrt(2.0)};
  for (const double max_tilt : max_tilts) {
    CAPTURE(max_tilt);
    affine_orb::Extractor<affine_orb::Rbrief> extractor(extractor_options(max_tilt));
    const affine_orb::KeyframeTrackerOptions options;
    Tracker tracker(options, sequence.camera);
    std::vector<affine_orb::TrackedFrame> results;
    std::vector<double> errors;
    // 20 frames; the first 6 for affine features under a sanitizer.
    const std::size_t frames = kSanitized && is_affine(max_tilt) ? 6 : sequence.frames.size();
    for (std::size_t i = 0; i < frames; ++i) {
      results.push_back(tracker.track(extractor.extract(ex::load_frame(sequence.frames[i]))));
      const affine_orb::TrackedFrame& t = results.back();
      if (i > 0 && t.relative_pose.success) {
        const Eigen::Matrix3d truth = ex::relative_rotation(*sequence.frames[i - 1].pose, *sequence.frames[i].pose);
        errors.push_back(rotation_angle_degrees(t.relative_pose.rotation, truth));
      }
    }
    check_keyframe_rules(results, options);
    CHECK(tracker.lost_frames() <= 1);
    CHECK(tracker.keyframes() >= 2);
    CHECK(errors.size() + 2 >= frames - 1);
    CHECK(median(errors) < (is_affine(max_tilt) ? 0.75 : 0.5));
    MESSAGE("KITTI 06 frames 0-19, max tilt " << max_tilt << ": lost " << tracker.lost_frames() << ", keyframes "
                                              << tracker.keyframes() << ", rotations " << errors.size()
                                              << ", median rotation error " << median(errors) << " deg");
  }
}
