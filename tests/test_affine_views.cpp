// Affine view simulation (paper eqs. 13–16), mapping back to the original image, thread
// determinism, the mask in tilted views, and matching of affine feature sets (SPEC §1, §2, §4, §7).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_matching.hpp"
#include "affine_orb/affine_views.hpp"
#include "affine_orb/brisk.hpp"
#include "affine_orb/extractor.hpp"
#include "affine_orb/rbrief.hpp"
#include "test_data.hpp"

namespace {

const double kSqrt2 = std::sqrt(2.0);

affine_orb::ExtractorOptions affine_options(int features, affine_orb::DuplicatePolicy duplicates, int threads = 1) {
  affine_orb::ExtractorOptions options;
  options.features = features;
  options.duplicates = duplicates;
  options.threads = threads;
  return options;
}

double angle_difference_degrees(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

}  // namespace

TEST_CASE("view set sizes and rotation steps follow eqs. 15-16") {
  const std::pair<double, std::size_t> expected[] = {
      {1.0, 1}, {kSqrt2, 5}, {2.0, 10}, {2.0 * kSqrt2, 18}, {4.0 * kSqrt2, 43}};
  for (const auto& row : expected) {
    const double max_tilt = row.first;
    const std::size_t count = row.second;
    CAPTURE(max_tilt);
    affine_orb::AffineViewOptions options;
    options.max_tilt = max_tilt;
    const auto params = affine_orb::view_parameters(options);
    CHECK(params.size() == count);
    CHECK(params.front() == std::pair<double, double>(1.0, 0.0));
    // Per tilt t > 1: φ = k · 72°/t for k = 0, 1, ... while φ < 180°.
    std::map<double, std::vector<double>> by_tilt;
    for (const auto& [t, phi] : params) by_tilt[t].push_back(phi);
    for (const auto& [t, phis] : by_tilt) {
      if (t == 1.0) {
        CHECK(phis == std::vector<double>{0.0});
        continue;
      }
      const double k = std::round(std::log(t) / std::log(kSqrt2));
      CHECK(t == doctest::Approx(std::pow(kSqrt2, k)));
      const double step = 72.0 / t;
      CHECK(phis.size() == static_cast<std::size_t>(std::ceil(180.0 / step - 1e-9)));
      for (std::size_t i = 0; i < phis.size(); ++i) CHECK(phis[i] == doctest::Approx(i * step));
      CHECK(phis.back() < 180.0);
    }
  }
}

TEST_CASE("view maps are mutually inverse and the view holds the whole image") {
  const cv::Size size(640, 480);
  affine_orb::AffineViewOptions options;
  options.max_tilt = 4.0 * kSqrt2;
  for (const auto& view : affine_orb::make_views(options, size)) {
    CAPTURE(view.tilt);
    CAPTURE(view.rotation_degrees);
    for (const cv::Point2d p : {cv::Point2d(0, 0), cv::Point2d(639, 0), cv::Point2d(0, 479), cv::Point2d(639, 479),
                                cv::Point2d(123.5, 77.25)}) {
      const cv::Point2d v = affine_orb::apply_affine(view.to_view, p);
      const cv::Point2d back = affine_orb::apply_affine(view.to_original, v);
      CHECK(back.x == doctest::Approx(p.x).epsilon(1e-9));
      CHECK(back.y == doctest::Approx(p.y).epsilon(1e-9));
      CHECK(v.x >= -0.5);
      CHECK(v.y >= -0.5);
      CHECK(v.x <= view.size.width - 0.5);
      CHECK(v.y <= view.size.height - 0.5);
    }
    // The linear part is diag(≈1/t, 1) R(φ): its determinant is ≈ 1/t.
    const double det = view.to_view(0, 0) * view.to_view(1, 1) - view.to_view(0, 1) * view.to_view(1, 0);
    CHECK(det == doctest::Approx(1.0 / view.tilt).epsilon(0.01));
  }
}

TEST_CASE("a rendered view samples the original image where to_view says") {
  // Smooth content so that bilinear resampling is accurate: a sum of low-frequency waves.
  cv::Mat image(300, 400, CV_8UC1);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<uchar>(y, x) = cv::saturate_cast<uchar>(128 + 60 * std::sin(x * 0.05) + 50 * std::cos(y * 0.04 + x * 0.01));
    }
  }
  const affine_orb::AffineView view = affine_orb::make_view(2.0, 36.0, image.size());
  cv::Mat canvas;
  cv::Mat rendered;
  affine_orb::render_view(image, view, 0.8, canvas, rendered);
  REQUIRE(rendered.size() == view.size);
  std::mt19937 rng(5);
  int checked = 0;
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const cv::Point2d v(rng() % static_cast<unsigned>(view.size.width), rng() % static_cast<unsigned>(view.size.height));
    const cv::Point2d p = affine_orb::apply_affine(view.to_original, v);
    if (p.x < 10 || p.y < 10 || p.x > image.cols - 11 || p.y > image.rows - 11) continue;
    cv::Mat sample;
    cv::getRectSubPix(image, cv::Size(1, 1), cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), sample);
    worst = std::max(worst, std::abs(rendered.at<uchar>(static_cast<int>(v.y), static_cast<int>(v.x)) - double(sample.at<uchar>(0, 0))));
    ++checked;
  }
  CHECK(checked > 500);
  // The anti-aliasing blur (σ = 0.8·√3 ≈ 1.4 px along x) changes these slow waves by a few levels.
  CHECK(worst <= 8.0);
}

TEST_CASE("keypoints from a tilted view map back onto the true original positions and angles") {
  // Ground truth: J = the view (t = 2, φ = 36°) of a real photo rendered independently with one
  // cv::warpAffine of the known matrix. Plain keypoints of J, mapped back through the known matrix,
  // must coincide with the keypoints the extractor found in that view of the original photo.
  const cv::Mat photo = affine_orb::test::oxford_image("graf", 1);
  affine_orb::ExtractorOptions options = affine_options(3000, affine_orb::DuplicatePolicy::kKeepAll);
  options.views.max_tilt = 2.0;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  const auto features = extractor.extract(photo);
  const auto views = extractor.views();
  const auto it = std::find_if(views.begin(), views.end(), [](const affine_orb::AffineView& v) {
    return std::abs(v.tilt - 2.0) < 1e-9 && std::abs(v.rotation_degrees - 36.0) < 1e-9;
  });
  REQUIRE(it != views.end());
  const int view_index = static_cast<int>(it - views.begin());
  const affine_orb::AffineView& view = *it;

  cv::Mat blurred;
  cv::GaussianBlur(photo, blurred, cv::Size(0, 0), 0.8, 0.8);
  cv::Mat warped;
  cv::warpAffine(blurred, warped, view.to_view, view.size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  affine_orb::ExtractorOptions plain = affine_options(4000, affine_orb::DuplicatePolicy::kKeepAll);
  plain.views.max_tilt = 1.0;
  plain.pyramid.levels = 1;
  const auto truth = affine_orb::Extractor<affine_orb::Rbrief>(plain).extract(warped);
  REQUIRE(truth.size() > 500);

  int compared = 0;
  int close = 0;
  std::vector<double> angle_errors;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (features.views[i] != view_index || features.keypoints[i].octave != 0) continue;
    ++compared;
    const cv::Point2d in_view = affine_orb::apply_affine(view.to_view, features.keypoints[i].pt);
    // The nearest ground-truth keypoint in J.
    double best = 1e9;
    std::size_t best_j = 0;
    for (std::size_t j = 0; j < truth.size(); ++j) {
      const double d = std::hypot(truth.keypoints[j].pt.x - in_view.x, truth.keypoints[j].pt.y - in_view.y);
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best > 1.0) continue;
    ++close;
    // The reported original angle, carried into J by the known matrix, against J's own angle.
    const double a = features.keypoints[i].angle * CV_PI / 180.0;
    const double dx = view.to_view(0, 0) * std::cos(a) + view.to_view(0, 1) * std::sin(a);
    const double dy = view.to_view(1, 0) * std::cos(a) + view.to_view(1, 1) * std::sin(a);
    angle_errors.push_back(angle_difference_degrees(std::atan2(dy, dx) * 180.0 / CV_PI, truth.keypoints[best_j].angle));
  }
  REQUIRE(compared > 50);
  MESSAGE("view keypoints within 1 px of the ground truth: " << close << " of " << compared);
  CHECK(close >= compared * 7 / 10);
  std::sort(angle_errors.begin(), angle_errors.end());
  const double median = angle_errors[angle_errors.size() / 2];
  MESSAGE("median angle error " << median << " degrees");
  CHECK(median < 3.0);
}

TEST_CASE("affine extraction: exact budget, view records, identical output for every thread count") {
  const cv::Mat image = affine_orb::test::kitti_frame(20);
  const auto one = affine_orb::Extractor<affine_orb::Rbrief>(affine_options(2000, affine_orb::DuplicatePolicy::kMerge, 1))
                       .extract(image);
  REQUIRE(one.size() == 2000);
  std::set<int> views(one.views.begin(), one.views.end());
  CHECK(views.size() >= 15);  // of 18: nearly every view contributes
  int previous_octave = 0;
  for (const auto& kp : one.keypoints) {
    CHECK(kp.octave >= previous_octave);  // grouped by level
    previous_octave = kp.octave;
    CHECK(kp.pt.x >= 0);
    CHECK(kp.pt.y >= 0);
    CHECK(kp.pt.x <= image.cols - 1);
    CHECK(kp.pt.y <= image.rows - 1);
  }
  for (int threads : {2, 3, 8}) {
    CAPTURE(threads);
    const auto other =
        affine_orb::Extractor<affine_orb::Rbrief>(affine_options(2000, affine_orb::DuplicatePolicy::kMerge, threads))
            .extract(image);
    REQUIRE(other.size() == one.size());
    bool identical = true;
    for (std::size_t i = 0; i < one.size(); ++i) {
      identical = identical && other.keypoints[i].pt == one.keypoints[i].pt &&
                  other.keypoints[i].angle == one.keypoints[i].angle && other.descriptors[i] == one.descriptors[i] &&
                  other.views[i] == one.views[i];
    }
    CHECK(identical);
  }
}

TEST_CASE("merging removes cross-view duplicates; keep-all keeps them") {
  const cv::Mat image = affine_orb::test::oxford_image("graf", 1);
  auto count_duplicates = [](const affine_orb::Features<256>& f, double radius) {
    int duplicates = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      for (std::size_t j = i + 1; j < f.size(); ++j) {
        if (f.keypoints[i].octave != f.keypoints[j].octave || f.views[i] == f.views[j]) continue;
        const double r = radius * std::pow(1.2, f.keypoints[i].octave);
        duplicates += std::hypot(f.keypoints[i].pt.x - f.keypoints[j].pt.x, f.keypoints[i].pt.y - f.keypoints[j].pt.y) < r;
      }
    }
    return duplicates;
  };
  const auto merged =
      affine_orb::Extractor<affine_orb::Rbrief>(affine_options(1500, affine_orb::DuplicatePolicy::kMerge, 2)).extract(image);
  const auto all =
      affine_orb::Extractor<affine_orb::Rbrief>(affine_options(1500, affine_orb::DuplicatePolicy::kKeepAll, 2)).extract(image);
  CHECK(merged.size() == 1500);
  CHECK(all.size() == 1500);
  CHECK(count_duplicates(merged, 2.0) == 0);
  CHECK(count_duplicates(all, 2.0) > 0);
}

TEST_CASE("the mask is honoured for keypoints of tilted views too") {
  const cv::Mat image = affine_orb::test::oxford_image("boat", 1);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(image.cols / 4, image.rows / 4, image.cols / 2, image.rows / 2)).setTo(255);
  const auto f = affine_orb::Extractor<affine_orb::Rbrief>(affine_options(1000, affine_orb::DuplicatePolicy::kMerge, 2))
                     .extract(image, mask);
  CHECK(f.size() == 1000);
  int tilted = 0;
  int outside = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    tilted += f.views[i] != 0;
    outside += mask.at<uchar>(cvRound(f.keypoints[i].pt.y), cvRound(f.keypoints[i].pt.x)) == 0;
  }
  CHECK(tilted > 500);
  CHECK(outside == 0);
}

TEST_CASE("duplicate correspondences are removed exactly as defined") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> coord(0.0f, 40.0f);
  std::vector<cv::Point2f> p1(60);
  std::vector<cv::Point2f> p2(60);
  for (auto& p : p1) p = {coord(rng), coord(rng)};
  for (auto& p : p2) p = {coord(rng), coord(rng)};
  std::vector<affine_orb::Match> matches;
  for (int k = 0; k < 300; ++k) {
    matches.push_back({static_cast<int>(rng() % 60), static_cast<int>(rng() % 60), static_cast<int>(rng() % 20)});
  }
  const auto kept = affine_orb::remove_duplicate_matches(matches, p1, p2, 3.0);
  // Naive reference: greedy by (distance, query, train), O(n²).
  auto order = matches;
  std::sort(order.begin(), order.end(), [](const affine_orb::Match& a, const affine_orb::Match& b) {
    return std::tie(a.distance, a.query, a.train) < std::tie(b.distance, b.query, b.train);
  });
  std::vector<affine_orb::Match> expected;
  for (const auto& m : order) {
    bool duplicate = false;
    for (const auto& k : expected) {
      const auto& a = p1[static_cast<std::size_t>(m.query)];
      const auto& b = p1[static_cast<std::size_t>(k.query)];
      const auto& c = p2[static_cast<std::size_t>(m.train)];
      const auto& d = p2[static_cast<std::size_t>(k.train)];
      duplicate = duplicate || (std::hypot(a.x - b.x, a.y - b.y) < 3.0 && std::hypot(c.x - d.x, c.y - d.y) < 3.0);
    }
    if (!duplicate) expected.push_back(m);
  }
  std::sort(expected.begin(), expected.end(), [](const affine_orb::Match& a, const affine_orb::Match& b) {
    return std::tie(a.query, a.train) < std::tie(b.query, b.train);
  });
  REQUIRE(kept.size() == expected.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    CHECK(kept[i].query == expected[i].query);
    CHECK(kept[i].train == expected[i].train);
    CHECK(kept[i].distance == expected[i].distance);
  }
  CHECK_THROWS_AS(affine_orb::remove_duplicate_matches(matches, p1, p2, -1.0), std::invalid_argument);
}

TEST_CASE("the location-aware ratio test equals a naive reference") {
  // Descriptors with planted near-duplicates at nearly the same image-2 location.
  std::mt19937_64 rng(23);
  affine_orb::Features<256> a;
  affine_orb::Features<256> b;
  for (int i = 0; i < 80; ++i) {
    affine_orb::BinaryDescriptor<256> d{rng(), rng(), rng(), rng()};
    a.descriptors.push_back(d);
    a.keypoints.emplace_back(cv::Point2f(static_cast<float>(rng() % 300), static_cast<float>(rng() % 300)), 31.0f);
    a.views.push_back(0);
    const cv::Point2f at(static_cast<float>(rng() % 300), static_cast<float>(rng() % 300));
    for (int copy = 0; copy < 1 + i % 3; ++copy) {
      affine_orb::BinaryDescriptor<256> e = d;
      for (int flip = 0; flip < 20 + 15 * copy; ++flip) {
        const unsigned bit = static_cast<unsigned>(rng() % 256);
        e[bit / 64] ^= 1ull << (bit % 64);
      }
      b.descriptors.push_back(e);
      b.keypoints.emplace_back(at + cv::Point2f(static_cast<float>(copy), 0.5f * copy), 31.0f);
      b.views.push_back(copy);
    }
  }
  for (double radius : {0.0, 4.0}) {
    for (bool cross : {false, true}) {
      CAPTURE(radius);
      CAPTURE(cross);
      affine_orb::AffineMatchOptions options;
      options.ratio_exclusion_radius = radius;
      options.matcher.cross_check = cross;
      options.duplicate_radius = 0.0;
      const auto got = affine_orb::match_features(a, b, options);
      std::vector<affine_orb::Match> expected;
      for (std::size_t i = 0; i < a.size(); ++i) {
        int best = 1 << 30;
        std::size_t j1 = 0;
        for (std::size_t j = 0; j < b.size(); ++j) {
          const int d = affine_orb::hamming_distance(a.descriptors[i], b.descriptors[j]);
          if (d < best) {
            best = d;
            j1 = j;
          }
        }
        int second = 1 << 30;
        for (std::size_t j = 0; j < b.size(); ++j) {
          if (j == j1) continue;
          const auto& p = b.keypoints[j].pt;
          const auto& q = b.keypoints[j1].pt;
          if (std::hypot(p.x - q.x, p.y - q.y) <= radius) continue;
          second = std::min(second, affine_orb::hamming_distance(a.descriptors[i], b.descriptors[j]));
        }
        if (!(best < 0.8 * second)) continue;
        if (cross) {
          int back = 1 << 30;
          std::size_t i1 = 0;
          for (std::size_t k = 0; k < a.size(); ++k) {
            const int d = affine_orb::hamming_distance(a.descriptors[k], b.descriptors[j1]);
            if (d < back) {
              back = d;
              i1 = k;
            }
          }
          if (i1 != i) continue;
        }
        expected.push_back({static_cast<int>(i), static_cast<int>(j1), best});
      }
      REQUIRE(got.size() == expected.size());
      for (std::size_t k = 0; k < got.size(); ++k) {
        CHECK(got[k].query == expected[k].query);
        CHECK(got[k].train == expected[k].train);
      }
      if (radius > 0.0) CHECK(got.size() > 60);  // the planted copies no longer veto their originals
    }
  }
  affine_orb::AffineMatchOptions bad;
  bad.ratio_exclusion_radius = -1.0;
  CHECK_THROWS_AS(affine_orb::match_features(a, b, bad), std::invalid_argument);
  bad = {};
  bad.matcher.ratio = 0.0f;
  CHECK_THROWS_AS(affine_orb::match_features(a, b, bad), std::invalid_argument);
  CHECK(affine_orb::match_features(affine_orb::Features<256>{}, b).empty());
}

TEST_CASE("graf 1->3: affine features give more distinct correct matches than plain ones") {
  const cv::Mat a = affine_orb::test::oxford_image("graf", 1);
  const cv::Mat b = affine_orb::test::oxford_image("graf", 3);
  const cv::Matx33d h = affine_orb::test::oxford_homography("graf", 3);
  auto distinct_correct = [&](double max_tilt) {
    affine_orb::ExtractorOptions options = affine_options(2000, affine_orb::DuplicatePolicy::kMerge, 2);
    options.views.max_tilt = max_tilt;
    affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
    const auto fa = extractor.extract(a);
    const auto fb = extractor.extract(b);
    std::set<std::pair<int, int>> cells;
    for (const auto& m : affine_orb::match_features(fa, fb)) {
      const cv::Point2f p = fa.keypoints[static_cast<std::size_t>(m.query)].pt;
      const cv::Point2d q = affine_orb::test::apply_homography(h, p);
      const cv::Point2f r = fb.keypoints[static_cast<std::size_t>(m.train)].pt;
      if (std::hypot(q.x - r.x, q.y - r.y) < 3.0) cells.insert({static_cast<int>(p.x / 2), static_cast<int>(p.y / 2)});
    }
    return static_cast<int>(cells.size());
  };
  const int plain = distinct_correct(1.0);
  const int affine = distinct_correct(2.0 * kSqrt2);
  MESSAGE("graf 1->3 distinct correct matches: plain " << plain << ", affine " << affine);
  // Regression floors at about 70 % of what was measured when they were set (plain 127, affine 171).
  CHECK(plain >= 90);
  CHECK(affine >= 120);
  CHECK(affine > plain);
}
