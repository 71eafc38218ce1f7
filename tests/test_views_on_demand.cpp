// Views on demand (Extractor::extract_image() and ViewSession, extraction/view_session.hpp): stage 0
// is plain extraction, the image plus one stage of every view is extract() bit for bit, each stage
// adds the views of its tilts without repeating earlier stages, a session holds its Extractor until
// it ends, and misuse is refused.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/views/affine_views.hpp"
#include "test_data.hpp"
#include "test_views.hpp"

namespace {

using affine_orb::test::kSqrt2;
using affine_orb::test::LevelledKeypoint;
using affine_orb::test::with_levels;

/// The stages' keypoints in extract()'s order: by octave, then by view (stages are in view order),
/// each stage's own order kept within.
affine_orb::Features<256> in_extract_order(const std::vector<affine_orb::Features<256>>& stages) {
  affine_orb::Features<256> all;
  for (const auto& s : stages) {
    all.keypoints.insert(all.keypoints.end(), s.keypoints.begin(), s.keypoints.end());
    all.descriptors.insert(all.descriptors.end(), s.descriptors.begin(), s.descriptors.end());
    all.views.insert(all.views.end(), s.views.begin(), s.views.end());
  }
  std::vector<std::size_t> order(all.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return all.keypoints[a].octave < all.keypoints[b].octave; });
  affine_orb::Features<256> sorted;
  for (std::size_t i : order) {
    sorted.keypoints.push_back(all.keypoints[i]);
    sorted.descriptors.push_back(all.descriptors[i]);
    sorted.views.push_back(all.views[i]);
  }
  return sorted;
}

/// Number of keypoints that differ between a and b in any field (sizes must match).
int differing(const affine_orb::Features<256>& a, const affine_orb::Features<256>& b) {
  REQUIRE(a.size() == b.size());
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const cv::KeyPoint& p = a.keypoints[i];
    const cv::KeyPoint& q = b.keypoints[i];
    n += p.pt != q.pt || p.angle != q.angle || p.size != q.size || p.octave != q.octave || p.response != q.response ||
         a.descriptors[i] != b.descriptors[i] || a.views[i] != b.views[i];
  }
  return n;
}

}  // namespace

TEST_CASE("views on demand: stage 0 is plain extraction, and the image plus one stage of every view is extract()") {
  for (const bool wide : {false, true}) {
    const cv::Mat image = wide ? affine_orb::test::panning_frame(1, cv::Size(1226, 370)) : affine_orb::test::graf(1);
    for (const auto spreading : {affine_orb::Spreading::kQuadtree, affine_orb::Spreading::kStrongest}) {
      for (int threads : {1, 2}) {
        CAPTURE(wide);
        CAPTURE(static_cast<int>(spreading));
        CAPTURE(threads);
        affine_orb::ExtractorOptions on;
        on.features = 1000;
        on.spreading = spreading;
        on.threads = threads;
        affine_orb::ExtractorOptions off = on;
        off.views.max_tilt = 1.0;
        const auto plain = affine_orb::Extractor<affine_orb::Rbrief>(off).extract(image);
        const auto one_shot = affine_orb::Extractor<affine_orb::Rbrief>(on).extract(image);
        affine_orb::Extractor<affine_orb::Rbrief> staged(on);
        auto [image_only, session] = staged.extract_image(image);
        CHECK(session.extracted_tilt() == 1.0);
        CHECK(differing(image_only, plain) == 0);
        const double view_features = on.additive_budget()->view_features;
        const auto views =
            session.extend(on.views.max_tilt, static_cast<int>(std::lround(view_features * on.features)));
        CHECK(session.extracted_tilt() == doctest::Approx(2.0 * kSqrt2));
        CHECK(session.extracted_views() == static_cast<int>(staged.views().size()));
        CHECK(std::count(views.views.begin(), views.views.end(), 0) == 0);
        CHECK(differing(in_extract_order({image_only, views}), one_shot) == 0);
      }
    }
  }
}

TEST_CASE("views on demand: each stage adds the views of its tilts and keeps what earlier stages found") {
  const cv::Mat image = affine_orb::test::textured_photo();
  affine_orb::ExtractorOptions options;
  options.features = 800;
  affine_orb::Extractor<affine_orb::Rbrief> staged(options);
  auto [s0, session] = staged.extract_image(image);
  const auto s1 = session.extend(kSqrt2, 300);
  const auto s2 = session.extend(2.0, 400);
  const auto s3 = session.extend(2.0 * kSqrt2, 500);
  const std::vector<affine_orb::AffineView> views = staged.views();
  CHECK(s0.size() == 800);
  CHECK(s1.size() == 300);
  CHECK(s2.size() == 400);
  CHECK(s3.size() == 500);
  const auto tilt_of = [&](int v) { return views[static_cast<std::size_t>(v)].tilt; };
  for (int v : s1.views) CHECK(tilt_of(v) == doctest::Approx(kSqrt2));
  for (int v : s2.views) CHECK(tilt_of(v) == doctest::Approx(2.0));
  for (int v : s3.views) CHECK(tilt_of(v) == doctest::Approx(2.0 * kSqrt2));
  CHECK(session.extracted_tilt() == doctest::Approx(2.0 * kSqrt2));
  CHECK(session.extend(4.0, 100).empty());  // no view is left up to 4 (max_tilt 2√2)
  CHECK(session.extracted_tilt() == doctest::Approx(2.0 * kSqrt2));

  SUBCASE("the first stage is the one-shot extraction of the same views") {
    affine_orb::ExtractorOptions first = options;
    first.views.max_tilt = kSqrt2;
    std::get<affine_orb::AdditiveBudget>(first.view_budget).view_features = 300.0 / 800.0;
    CHECK(differing(in_extract_order({s0, s1}), affine_orb::Extractor<affine_orb::Rbrief>(first).extract(image)) == 0);
  }
  SUBCASE("no keypoint of a stage repeats one of an earlier stage (same level, within the merge radius)") {
    const std::vector<affine_orb::Features<256>> stages = {s0, s1, s2, s3};
    std::vector<std::vector<LevelledKeypoint>> levelled;
    for (const auto& s : stages) levelled.push_back(with_levels(s, views));
    int repeats = 0;
    for (std::size_t k = 1; k < levelled.size(); ++k) {
      for (const LevelledKeypoint& a : levelled[k]) {
        for (std::size_t j = 0; j < k; ++j) {
          for (const LevelledKeypoint& b : levelled[j]) {
            if (a.level != b.level) continue;
            const double r = options.merge_duplicates->radius * std::pow(options.pyramid.scale_factor, a.level);
            repeats += cv::norm(a.kp.pt - b.kp.pt) < r;
          }
        }
      }
    }
    CHECK(repeats == 0);
  }
  SUBCASE("another image waits for the session's end") {
    CHECK_THROWS_AS(staged.extract_image(affine_orb::test::graf(3)), std::invalid_argument);
    CHECK_THROWS_AS(staged.extract(affine_orb::test::graf(3)), std::invalid_argument);
  }
}

TEST_CASE("views on demand: a session holds its Extractor, and misuse is refused with std::invalid_argument") {
  const cv::Mat image = affine_orb::test::graf(1);
  affine_orb::Extractor<affine_orb::Rbrief> extractor;
  {
    auto stage = extractor.extract_image(image);
    CHECK(stage.session.extracted_tilt() == 1.0);
    CHECK(stage.session.extracted_views() == 1);
    CHECK_THROWS_AS(stage.session.extend(std::nan(""), 100), std::invalid_argument);
    CHECK_THROWS_AS(stage.session.extend(2.0, -1), std::invalid_argument);
    CHECK_THROWS_AS(extractor.extract(image), std::invalid_argument);  // the session holds the Extractor
    CHECK_THROWS_AS(extractor.extract_image(image), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::Extractor<affine_orb::Rbrief>(std::move(extractor)), std::invalid_argument);
    affine_orb::ViewSession<affine_orb::Rbrief> moved = std::move(stage.session);
    CHECK_THROWS_AS(stage.session.extend(2.0, 100), std::invalid_argument);  // moved from
    CHECK(moved.extend(2.0, 100).size() == 100);
  }
  // The session has ended: the refused move left the Extractor whole, and it starts a new image
  // from stage 0.
  const cv::Mat other = affine_orb::test::graf(3);
  {
    auto again = extractor.extract_image(other);
    CHECK(again.session.extracted_tilt() == 1.0);
    const auto first = again.session.extend(kSqrt2, 300);
    CHECK(first.size() == 300);
    const std::vector<affine_orb::AffineView> views = extractor.views();
    for (int v : first.views) CHECK(views[static_cast<std::size_t>(v)].tilt == doctest::Approx(kSqrt2));
  }
  CHECK(differing(extractor.extract(other), affine_orb::Extractor<affine_orb::Rbrief>().extract(other)) == 0);
  affine_orb::ExtractorOptions split;
  split.view_budget = affine_orb::AreaSplitBudget{};
  affine_orb::Extractor<affine_orb::Rbrief> area(split);
  CHECK_THROWS_AS(area.extract_image(image), std::invalid_argument);
  CHECK_THROWS_AS(extractor.extract_image(cv::Mat()), std::invalid_argument);
}
