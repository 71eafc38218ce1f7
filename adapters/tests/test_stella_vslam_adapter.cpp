// Conformance of the stella_vslam adapter (adapters/stella_vslam/orb_extractor.cc, compiled against
// stella's own headers from ../shared/slam/stock_extractors) with stella's stock orb_extractor,
// compiled from there in a renamed namespace (tests/stock/stock_stella.hpp): the same keypoints,
// in order, the same descriptor rows and the same image_pyramid_ bytes, with and without
// mask_rects and an input mask; the adapter's refusals; its YAML `Feature: affine_orb:` settings
// against the AFFINE_ORB_* variables they mirror.
#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "stella_vslam/feature/orb_extractor.h"
#include "stella_vslam/feature/orb_params.h"
#include "stock_stella.hpp"
#include "test_data.hpp"

namespace {

using affine_orb::stock::StockFrame;
using affine_orb::stock::StockStellaExtractor;
using stella_vslam::feature::descriptor_type;
using stella_vslam::feature::orb_extractor;
using stella_vslam::feature::orb_params;
using Rectangles = std::vector<std::vector<float>>;

struct Case {
  unsigned min_size = 800;
  Rectangles rectangles;
  bool masked = false;  ///< extract() gets sample_mask()
};

struct Counts {
  std::size_t keypoints = 0;
  std::size_t identical = 0;
};

/// A mask of `size` hiding a disc and a slanted band.
cv::Mat sample_mask(cv::Size size) {
  cv::Mat mask(size, CV_8UC1, cv::Scalar(255));
  cv::circle(mask, cv::Point(size.width / 3, size.height / 2), size.height / 5, cv::Scalar(0), cv::FILLED);
  cv::line(mask, cv::Point(0, size.height - 1), cv::Point(size.width - 1, size.height / 3), cv::Scalar(0), 25);
  return mask;
}

bool same_keypoint(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return a.pt == b.pt && a.octave == b.octave && a.angle == b.angle && a.size == b.size && a.response == b.response;
}

bool same_pyramid(const std::vector<cv::Mat>& a, const std::vector<cv::Mat>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t l = 0; l < a.size(); ++l) {
    if (a[l].size() != b[l].size() || a[l].type() != b[l].type() || cv::norm(a[l], b[l], cv::NORM_INF) != 0.0) {
      return false;
    }
  }
  return true;
}

/// Both extractors on `images`, one pair per image as stella builds its rectangle mask for the
/// first image; each image extracted twice by the adapter (the second frame reuses its buffers).
Counts run_case(const std::vector<cv::Mat>& images, const Case& c) {
  const orb_params params("affine_orb test", 1.2f, 8, 20, 7);
  Counts counts;
  for (const cv::Mat& image : images) {
    StockStellaExtractor stock(1.2f, 8, 20, 7, c.min_size, c.rectangles);
    orb_extractor adapter(&params, c.min_size, descriptor_type::ORB, c.rectangles);
    const cv::Mat mask = c.masked ? sample_mask(image.size()) : cv::Mat();
    const StockFrame expected = stock.extract(image, mask);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    for (int frame = 0; frame < 2; ++frame) adapter.extract(image, mask, keypoints, descriptors);
    REQUIRE(keypoints.size() == expected.keypoints.size());
    CHECK(same_pyramid(adapter.image_pyramid_, expected.pyramid));
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      const int row = static_cast<int>(i);
      if (same_keypoint(keypoints[i], expected.keypoints[i]) &&
          std::memcmp(descriptors.ptr(row), expected.descriptors.ptr(row), 32) == 0) {
        ++counts.identical;
      }
    }
    counts.keypoints += keypoints.size();
  }
  MESSAGE("min_size " << c.min_size << ", " << c.rectangles.size() << " rectangles, mask " << c.masked << ": "
                      << counts.identical << " of " << counts.keypoints << " keypoints identical");
  return counts;
}

void check_cases(const std::vector<cv::Mat>& images) {
  const Rectangles rectangles = {{0.0f, 1.0f, 0.0f, 0.1f}, {0.313f, 0.547f, 0.61f, 1.0f}};
  for (const Case& c : {Case{800, {}, false}, Case{200, {}, false}, Case{800, rectangles, false}, Case{800, {}, true},
                        Case{200, rectangles, true}}) {
    const Counts counts = run_case(images, c);
    CHECK(counts.keypoints > 100 * images.size());
    CHECK(counts.identical == counts.keypoints);
  }
}

std::vector<cv::Mat> data_frames() {
  std::vector<cv::Mat> out;
  for (int i = 0; i <= 50; i += 25) out.push_back(affine_orb::test::kitti_frame(i));
  for (const char* sequence : {"boat", "bark", "bikes", "trees", "leuven"}) {
    out.push_back(affine_orb::test::oxford_image(sequence, 1));
  }
  return out;
}

/// Keypoints and rows of `image` from an adapter configured with the YAML `feature` section, with
/// the recovery hook and tracking lost when `recovering`.
std::pair<std::vector<cv::KeyPoint>, cv::Mat> extract_configured(const cv::Mat& image, const std::string& feature,
                                                                 bool recovering = false) {
  const orb_params params("affine_orb test", 1.2f, 8, 20, 7);
  orb_extractor adapter(&params, 800);
  adapter.configure_affine_orb(YAML::Load(feature), recovering);
  adapter.set_affine_orb_recovering(recovering);
  std::pair<std::vector<cv::KeyPoint>, cv::Mat> out;
  adapter.extract(image, cv::Mat(), out.first, out.second);
  return out;
}

/// stella's own extractor's keypoints and rows at `min_size`.
std::pair<std::vector<cv::KeyPoint>, cv::Mat> extract_stock(const cv::Mat& image, unsigned min_size) {
  StockStellaExtractor stock(1.2f, 8, 20, 7, min_size, {});
  const StockFrame frame = stock.extract(image, cv::Mat());
  return {frame.keypoints, frame.descriptors};
}

bool same_output(const std::pair<std::vector<cv::KeyPoint>, cv::Mat>& a,
                 const std::pair<std::vector<cv::KeyPoint>, cv::Mat>& b) {
  if (a.first.size() != b.first.size() || a.second.size() != b.second.size()) return false;
  for (std::size_t i = 0; i < a.first.size(); ++i) {
    if (!same_keypoint(a.first[i], b.first[i])) return false;
  }
  return a.second.empty() || cv::norm(a.second, b.second, cv::NORM_HAMMING) == 0.0;
}

}  // namespace

TEST_CASE("the adapter returns stella's own keypoints, rows and pyramid on opencv-doc's photos") {
  check_cases({affine_orb::test::graf(1), affine_orb::test::graf(3), affine_orb::test::textured_photo()});
}

TEST_CASE("the same on KITTI and Oxford frames" * doctest::test_suite("data")) { check_cases(data_frames()); }

TEST_CASE("the adapter refuses what it does not support") {
  const orb_params params("affine_orb test", 1.2f, 8, 20, 7);
  CHECK_THROWS_AS(orb_extractor(&params, 800, descriptor_type::HASH_SIFT), std::invalid_argument);
  CHECK_THROWS_AS(orb_extractor(nullptr, 800), std::invalid_argument);
  CHECK_THROWS_AS(orb_extractor(&params, 0), std::invalid_argument);
  CHECK_THROWS_AS(orb_extractor(&params, 800, descriptor_type::ORB, {{0.1f, 0.2f}}), std::invalid_argument);
  orb_extractor adapter(&params, 800);
  std::vector<cv::KeyPoint> keypoints(3);
  cv::Mat descriptors;
  adapter.extract(cv::Mat(), cv::Mat(), keypoints, descriptors);  // empty: outputs untouched
  CHECK(keypoints.size() == 3);
  const cv::Mat colour(100, 100, CV_8UC3, cv::Scalar::all(0));
  CHECK_THROWS_AS(adapter.extract(colour, cv::Mat(), keypoints, descriptors), std::invalid_argument);
  const cv::Mat grey = affine_orb::test::graf(1);
  CHECK_THROWS_AS(adapter.extract(grey, cv::Mat(10, 10, CV_8UC1), keypoints, descriptors), std::invalid_argument);
}

TEST_CASE("AFFINE_ORB_MAX_TILT adds view keypoints after stella's own, which stay") {
  const orb_params params("affine_orb test", 1.2f, 8, 20, 7);
  const cv::Mat image = affine_orb::test::graf(1);
  orb_extractor plain(&params, 800);
  ::setenv("AFFINE_ORB_MAX_TILT", "2.83", 1);
  orb_extractor views(&params, 800);
  ::unsetenv("AFFINE_ORB_MAX_TILT");
  std::vector<cv::KeyPoint> a;
  std::vector<cv::KeyPoint> b;
  cv::Mat da;
  cv::Mat db;
  plain.extract(image, cv::Mat(), a, da);
  views.extract(image, cv::Mat(), b, db);
  CHECK(b.size() > a.size());
  CHECK(db.rows == static_cast<int>(b.size()));
  ::setenv("AFFINE_ORB_KEYPOINTS", "bogus", 1);
  CHECK_THROWS_AS(orb_extractor(&params, 800), std::invalid_argument);
  ::unsetenv("AFFINE_ORB_KEYPOINTS");
}

TEST_CASE("YAML Feature: affine_orb: settings act as the AFFINE_ORB_* variables, which override them") {
  const cv::Mat image = affine_orb::test::graf(1);
  const auto plain = extract_configured(image, "{name: test, scale_factor: 1.2}");
  CHECK(same_output(extract_configured(image, "{affine_orb: {}}"), plain));
  CHECK(same_output(extract_configured(image, "{affine_orb: {max_tilt: 1}}"), plain));
  ::setenv("AFFINE_ORB_MAX_TILT", "2.83", 1);
  const auto from_environment = extract_configured(image, "{}");
  ::setenv("AFFINE_ORB_MAX_TILT", "1", 1);
  const auto overridden = extract_configured(image, "{affine_orb: {max_tilt: 2.83}}");
  ::unsetenv("AFFINE_ORB_MAX_TILT");
  const auto from_yaml = extract_configured(image, "{affine_orb: {max_tilt: 2.83}}");
  CHECK(from_environment.first.size() > plain.first.size());
  CHECK(same_output(from_yaml, from_environment));
  CHECK(same_output(overridden, plain));
  ::setenv("AFFINE_ORB_KEYPOINTS", "affine_orb", 1);
  const auto spread_from_environment = extract_configured(image, "{}");
  ::unsetenv("AFFINE_ORB_KEYPOINTS");
  CHECK_FALSE(same_output(spread_from_environment, plain));
  CHECK(same_output(extract_configured(image, "{affine_orb: {keypoints: affine_orb}}"), spread_from_environment));
}

TEST_CASE("bad YAML Feature: affine_orb: settings are refused by name") {
  const cv::Mat image = affine_orb::test::graf(1);
  const auto refused = [&](const std::string& feature, const char* named) {
    CHECK_THROWS_WITH_AS(extract_configured(image, feature), doctest::Contains(named), std::invalid_argument);
  };
  refused("{affine_orb: {max_tilt: 40}}", "Feature.affine_orb.max_tilt");
  refused("{affine_orb: {max_tilt: steep}}", "Feature.affine_orb.max_tilt");
  refused("{affine_orb: {keypoints: octree}}", "Feature.affine_orb.keypoints");
  refused("{affine_orb: {max_tlit: 2}}", "unknown setting Feature.affine_orb.max_tlit");
  refused("{affine_orb: {max_tilt: [2, 3]}}", "Feature.affine_orb.max_tilt must be a single value");
  refused("{affine_orb: {recovery_max_tilt: 2.83}}", "Feature.affine_orb.recovery_max_tilt has no effect");
  CHECK_NOTHROW(extract_configured(image, "{affine_orb: {recovery_max_tilt: 2.83}}", true));
  refused("{affine_orb: 2.83}", "Feature.affine_orb must be a map");
}

TEST_CASE("with the recovery hook, lost frames are stella's own extraction at a third of min_size") {
  // RecoveryOptions::image_features (default 3) times the keypoints: cells of round(800 / 3) pixels,
  // as stella's own extractor makes them at that min_size; the normal frames stay stella's own at 800.
  for (const cv::Mat& image : {affine_orb::test::graf(1), affine_orb::test::textured_photo()}) {
    const auto own = extract_stock(image, 800);
    const auto lost = extract_configured(image, "{}", true);
    CHECK(same_output(lost, extract_stock(image, 267)));
    CHECK(lost.first.size() * 2 > own.first.size() * 3);
    CHECK(same_output(extract_configured(image, "{affine_orb: {recovery_image_features: 1}}", true), own));
    CHECK(same_output(extract_configured(image, "{affine_orb: {recovery_image_features: 2}}", true),
                      extract_stock(image, 400)));
    CHECK(same_output(extract_configured(image, "{}", false), own));
  }
  // The switch: the same extractor follows it frame by frame.
  const orb_params params("affine_orb test", 1.2f, 8, 20, 7);
  orb_extractor adapter(&params, 800);
  adapter.configure_affine_orb(YAML::Load("{}"), true);
  const cv::Mat image = affine_orb::test::graf(1);
  std::pair<std::vector<cv::KeyPoint>, cv::Mat> out;
  for (const bool recovering : {false, true, false}) {
    adapter.set_affine_orb_recovering(recovering);
    adapter.extract(image, cv::Mat(), out.first, out.second);
    CHECK(same_output(out, extract_stock(image, recovering ? 267 : 800)));
  }
}
