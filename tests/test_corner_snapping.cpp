// Snapping view keypoints to corners of the original image (ExtractorOptions::snap_to_corners,
// CornerSnapOptions) on a synthetic scene whose corners are known to 1/8 px: snapped keypoints lie on
// FAST corners of their level near the mapped position, as precisely as the image's own keypoints.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/fast.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/views/affine_views.hpp"
#include "test_views.hpp"

namespace {

using affine_orb::test::affine_options;
using affine_orb::test::upper_median;

/// An oblique view of a synthetic scene and the true positions of the scene's corners in it.
struct ObliqueScene {
  cv::Mat image;
  std::vector<cv::Point2d> vertices;

  /// Distance from `p` to the nearest true vertex, pixels.
  double error(cv::Point2f p) const {
    double best = 1e9;
    for (const cv::Point2d& t : vertices) best = std::min(best, std::hypot(t.x - p.x, t.y - p.y));
    return best;
  }
};

/// Random grey quadrilaterals drawn at 8x resolution and averaged down (area interpolation), so
/// that every vertex is known to 1/8 px; `vertices` gets them.
cv::Mat quadrilaterals(int size, std::vector<cv::Point2d>& vertices) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(0.0, 1.0);
  std::uniform_int_distribution<int> grey(20, 235);
  cv::Mat fine(size * 8, size * 8, CV_8UC1, cv::Scalar(128));
  for (int q = 0; q < 70; ++q) {
    const cv::Point2d centre(40 + coordinate(rng) * (size - 80), 40 + coordinate(rng) * (size - 80));
    std::vector<cv::Point> polygon;
    for (int k = 0; k < 4; ++k) {
      const double angle = (k + 0.4 * coordinate(rng)) * CV_PI / 2.0;
      const double radius = 12.0 + 18.0 * coordinate(rng);
      const cv::Point2d v(centre.x + radius * std::cos(angle), centre.y + radius * std::sin(angle));
      vertices.push_back(v);
      // Pixel centres at integers: fine pixel (8x + 3.5) is the centre of coarse pixel x.
      polygon.emplace_back(cvRound(8.0 * v.x + 3.5), cvRound(8.0 * v.y + 3.5));
    }
    cv::fillConvexPoly(fine, polygon, cv::Scalar(grey(rng)), cv::LINE_8);
  }
  cv::Mat scene;
  cv::resize(fine, scene, cv::Size(size, size), 0, 0, cv::INTER_AREA);
  return scene;
}

/// The scene of quadrilaterals() seen by a known affine map A (tilt 2.5 at 30°, cv::warpAffine),
/// whose vertices are A·v.
ObliqueScene oblique_scene() {
  const int size = 480;
  std::vector<cv::Point2d> vertices;
  const cv::Mat scene = quadrilaterals(size, vertices);
  const double phi = 30.0 * CV_PI / 180.0;
  const cv::Matx22d rotate(std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi));
  const cv::Matx22d squeeze = cv::Matx22d(rotate.t()) * cv::Matx22d(1.0 / 2.5, 0.0, 0.0, 1.0) * rotate;
  const cv::Point2d centre(size / 2.0, size / 2.0);
  const cv::Vec2d offset = cv::Vec2d(centre.x, centre.y) - squeeze * cv::Vec2d(centre.x, centre.y);
  const cv::Matx23d a(squeeze(0, 0), squeeze(0, 1), offset[0], squeeze(1, 0), squeeze(1, 1), offset[1]);
  ObliqueScene out;
  cv::warpAffine(scene, out.image, a, scene.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  for (const cv::Point2d& v : vertices) out.vertices.push_back(affine_orb::apply_affine(a, v));
  return out;
}

/// True when the snapped keypoint `r` lies on a pixel of its level within one pixel of where the
/// mapped keypoint `m` falls on that level; counts in `on_corner` when it is a FAST corner there.
bool on_level_pixel_near(const cv::KeyPoint& r, const cv::KeyPoint& m, const cv::Mat& level, cv::Size original,
                         int min_threshold, int& on_corner) {
  const double rx = static_cast<double>(original.width) / level.cols;
  const double ry = static_cast<double>(original.height) / level.rows;
  const double x = (r.pt.x + 0.5) / rx - 0.5;
  const double y = (r.pt.y + 0.5) / ry - 0.5;
  on_corner += affine_orb::fast_score(level.ptr<std::uint8_t>(cvRound(y)) + cvRound(x),
                                      static_cast<std::ptrdiff_t>(level.step[0])) >= min_threshold;
  return std::abs(x - std::round(x)) < 1e-3 && std::abs(y - std::round(y)) < 1e-3 &&
         std::abs(std::round(x) - std::round((m.pt.x + 0.5) / rx - 0.5)) <= 1.0 &&
         std::abs(std::round(y) - std::round((m.pt.y + 0.5) / ry - 0.5)) <= 1.0;
}

}  // namespace

TEST_CASE("snapping puts view keypoints on corners of the original image, as precisely as image keypoints") {
  const ObliqueScene scene = oblique_scene();
  affine_orb::ExtractorOptions options = affine_options(600, std::nullopt);
  std::get<affine_orb::AdditiveBudget>(options.view_budget).view_features = 2.0;
  affine_orb::Extractor<affine_orb::Rbrief> mapped(options);
  options.snap_to_corners = affine_orb::CornerSnapOptions{};
  affine_orb::Extractor<affine_orb::Rbrief> snapped(options);
  const auto f_mapped = mapped.extract(scene.image);
  std::vector<cv::Mat> pyramid;
  const auto f_snapped = snapped.extract(scene.image, cv::Mat(), pyramid);
  REQUIRE(f_mapped.size() == f_snapped.size());
  std::vector<double> image_errors, mapped_errors, snapped_errors;
  int moved = 0;
  int on_corner = 0;
  for (std::size_t i = 0; i < f_snapped.size(); ++i) {
    const cv::KeyPoint& r = f_snapped.keypoints[i];
    const cv::KeyPoint& m = f_mapped.keypoints[i];
    REQUIRE(f_snapped.views[i] == f_mapped.views[i]);
    REQUIRE(r.octave == m.octave);
    CHECK(r.angle == m.angle);
    CHECK(f_snapped.descriptors[i] == f_mapped.descriptors[i]);
    // Distances in pixels of the keypoint's octave, where both kinds are located to a pixel.
    const double unit = std::pow(1.2, r.octave);
    if (f_snapped.views[i] == 0) {
      CHECK(r.pt == m.pt);
      if (scene.error(r.pt) < 3.0 * unit) image_errors.push_back(scene.error(r.pt) / unit);
      continue;
    }
    if (r.pt != m.pt) {
      ++moved;
      CHECK(on_level_pixel_near(r, m, pyramid[static_cast<std::size_t>(r.octave)], scene.image.size(),
                                options.detector.min_threshold, on_corner));
    }
    if (scene.error(r.pt) < 3.0 * unit && scene.error(m.pt) < 3.0 * unit) {
      snapped_errors.push_back(scene.error(r.pt) / unit);
      mapped_errors.push_back(scene.error(m.pt) / unit);
    }
  }
  REQUIRE(image_errors.size() > 30);
  REQUIRE(snapped_errors.size() > 30);
  CHECK(moved > 0);
  CHECK(on_corner == moved);
  MESSAGE("median distance to the true vertex in pixels of the keypoint's octave: image keypoints "
          << upper_median(image_errors) << " px (" << image_errors.size() << "), view keypoints mapped "
          << upper_median(mapped_errors) << " px, snapped " << upper_median(snapped_errors) << " px ("
          << snapped_errors.size() << ", " << moved << " moved)");
  // Both are located as precisely as the image's own keypoints (the mapped position already is).
  CHECK(upper_median(mapped_errors) <= upper_median(image_errors) + 0.25);
  CHECK(upper_median(snapped_errors) <= upper_median(image_errors) + 0.25);
}
