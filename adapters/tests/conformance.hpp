#pragma once
// Conformance suite shared by the ORB-SLAM2 and ORB-SLAM3 adapters: every docs/algorithm.md §6 fact, checked by
// driving the adapter the way ORB-SLAM's Frame, Tracking, ORBmatcher, MapPoint and stereo matching
// do, on real frames (KITTI 06, Oxford), with the affine views off and on.
//
// The including test program defines a traits type T and instantiates the cases with
// TEST_CASE_TEMPLATE_INVOKE(adapter_conformance, T). T provides:
//   using Extractor = <ns>::ORBextractor;  using Options = <ns>::AffineOrbAdapterOptions;
//   using Fork = affine_orb::OrbSlam2Keypoints;  // or affine_orb::OrbSlam3Keypoints
//   static constexpr int kInitialisationFactor;  // 2 for ORB-SLAM2, 5 for ORB-SLAM3
//   static constexpr bool kReturnsCount;         // operator() returns a count (ORB-SLAM3)
//   static int extract(Extractor&, const cv::Mat& image, const cv::Mat& mask,
//                      std::vector<cv::KeyPoint>&, cv::Mat& descriptors);
//     calls the extractor as the SLAM system's Frame does, with no lapping split for ORB-SLAM3;
//     returns the count operator() returns (ORB-SLAM3), or the keypoint count (ORB-SLAM2).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb_adapter/options.hpp"
#include "test_data.hpp"
#include "walk.hpp"
#if AFFINE_ORB_HAVE_STOCK
#include "stock_extractor.hpp"
#endif

namespace conformance {

// ORB-SLAM2's KITTI 04-12 monocular settings (Examples/Monocular/KITTI04-12.yaml): 2000 features,
// 1.2, 8 levels, FAST 20/7. The suite uses 1000 features to stay fast; the facts do not depend on it.
constexpr int kFeatures = 1000;
constexpr float kScale = 1.2f;
constexpr int kLevels = 8;
constexpr int kIniFast = 20;
constexpr int kMinFast = 7;
// 2√2 written as ORB-SLAM users would (AdapterOptions::max_tilt): the 18 views of tilts up to 2√2.
constexpr double kViewsTilt = 2.83;
// Stereo matching in ORB-SLAM2/3 (Frame::ComputeStereoMatches): 11x11 window (w = 5), search ±5.
constexpr int kWindow = 5;
constexpr int kSearch = 5;

// ORB-SLAM's per-level budget for n features (ORBextractor's constructor): level l gets
// round(n (1 - 1/s) / (1 - s^-L) s^-l), the last level what the others leave of n.
inline std::vector<int> orbslam_budgets(int n) {
  std::vector<int> budget(kLevels);
  double share = n * (1.0 - 1.0 / kScale) / (1.0 - std::pow(1.0 / kScale, kLevels));
  int assigned = 0;
  for (int l = 0; l + 1 < kLevels; ++l) {
    budget[static_cast<std::size_t>(l)] = static_cast<int>(std::lround(share));
    assigned += budget[static_cast<std::size_t>(l)];
    share /= kScale;
  }
  budget.back() = n - assigned;
  return budget;
}

// Keypoints per octave.
inline std::vector<int> per_octave(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<int> count(kLevels, 0);
  for (const cv::KeyPoint& kp : keypoints) ++count[static_cast<std::size_t>(kp.octave)];
  return count;
}

struct Output {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<cv::Mat> pyramid;
  int reported = 0;
};

template <class T>
Output run(typename T::Extractor& extractor, const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
  Output out;
  out.reported = T::extract(extractor, image, mask, out.keypoints, out.descriptors);
  out.pyramid = extractor.mvImagePyramid;
  return out;
}

// Restores the adapter's static defaults when a test case ends.
template <class T>
struct DefaultsGuard {
  typename T::Options saved = T::Extractor::GetAffineOptions();
  explicit DefaultsGuard(const typename T::Options& options) { T::Extractor::SetAffineOptions(options); }
  ~DefaultsGuard() { T::Extractor::SetAffineOptions(saved); }
  DefaultsGuard(const DefaultsGuard&) = delete;
  DefaultsGuard& operator=(const DefaultsGuard&) = delete;
};

// Sets an environment variable for the lifetime of the guard.
struct EnvGuard {
  std::string name;
  EnvGuard(const char* n, const char* value) : name(n) { ::setenv(n, value, 1); }
  ~EnvGuard() { ::unsetenv(name.c_str()); }
  EnvGuard(const EnvGuard&) = delete;
  EnvGuard& operator=(const EnvGuard&) = delete;
};

template <class T>
typename T::Options views_options(affine_orb::adapters::AdapterDescriptor descriptor, double max_tilt) {
  typename T::Options o;
  o.descriptor = descriptor;
  o.max_tilt = max_tilt;
  return o;
}

// The options with affine_orb's keypoints instead of the fork's.
template <class T>
typename T::Options affine_keypoints() {
  typename T::Options o;
  o.keypoints = affine_orb::adapters::AdapterKeypoints::kAffineOrb;
  return o;
}

// ORB-SLAM's keypoint size at a level of scale `factor`: 31·s^l, truncated by the forks' own
// extractor (whose keypoints the adapter returns by default), as a float with affine_orb's.
inline float orbslam_size(float factor, bool fork) {
  const float size = 31.0f * factor;
  return fork ? static_cast<float>(static_cast<int>(size)) : size;
}

// The test images: two KITTI 06 frames and two Oxford photos.
inline std::vector<cv::Mat> frames() {
  return {affine_orb::test::kitti_frame(0), affine_orb::test::kitti_frame(30),
          affine_orb::test::oxford_image("graf", 1), affine_orb::test::oxford_image("boat", 1)};
}

// ORBmatcher::DescriptorDistance's reading of a row: 8 x int32, popcount of each xor by the
// parallel bit count (Bit Twiddling Hacks, "Counting bits set, in parallel").
inline int distance_8x32(const cv::Mat& a, const cv::Mat& b) {
  const auto* pa = a.ptr<std::int32_t>();
  const auto* pb = b.ptr<std::int32_t>();
  int dist = 0;
  for (int i = 0; i < 8; ++i) {
    unsigned v = static_cast<unsigned>(pa[i] ^ pb[i]);
    v = v - ((v >> 1) & 0x55555555u);
    v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
    dist += static_cast<int>((((v + (v >> 4)) & 0xF0F0F0Fu) * 0x1010101u) >> 24);
  }
  return dist;
}

// Bitwise reference: bit b of a row is bit b % 8 of byte b / 8.
inline int distance_bitwise(const cv::Mat& a, const cv::Mat& b) {
  int dist = 0;
  for (int bit = 0; bit < 256; ++bit) {
    const int x = (a.at<std::uint8_t>(0, bit / 8) >> (bit % 8)) & 1;
    const int y = (b.at<std::uint8_t>(0, bit / 8) >> (bit % 8)) & 1;
    dist += x != y;
  }
  return dist;
}

// Every docs/algorithm.md §6 output fact for one call on `image`; `fork`: the image's keypoints are the fork's
// (the default), whose pyramid is cv::resize's and whose sizes are truncated.
inline void check_output(const Output& out, const cv::Mat& image, const std::vector<float>& factors, bool fork = true) {
  const std::size_t n = out.keypoints.size();
  REQUIRE(n > 0);
  REQUIRE(out.reported == static_cast<int>(n));
  // Descriptors: N x 32 CV_8U, one row per keypoint.
  CHECK(out.descriptors.type() == CV_8UC1);
  CHECK(out.descriptors.cols == 32);
  CHECK(out.descriptors.rows == static_cast<int>(n));
  // Pyramid: the image at each level, round(W/s^l) x round(H/s^l), level l resized bilinearly from
  // l−1: cv::resize itself with the fork's keypoints, within a grey level of it with affine_orb's
  // (pyramid.hpp).
  REQUIRE(out.pyramid.size() == static_cast<std::size_t>(kLevels));
  CHECK(cv::norm(out.pyramid[0], image, cv::NORM_INF) == 0.0);
  for (int l = 0; l < kLevels; ++l) {
    const cv::Mat& level = out.pyramid[static_cast<std::size_t>(l)];
    CHECK(level.type() == CV_8UC1);
    const double s = std::pow(static_cast<double>(kScale), l);
    CHECK(level.cols == static_cast<int>(std::lround(image.cols / s)));
    CHECK(level.rows == static_cast<int>(std::lround(image.rows / s)));
    if (l > 0) {
      cv::Mat expected;
      cv::resize(out.pyramid[static_cast<std::size_t>(l - 1)], expected, level.size(), 0, 0, cv::INTER_LINEAR);
      CHECK(cv::norm(level, expected, cv::NORM_INF) <= (fork ? 0.0 : 1.0));
    }
  }
  int previous = 0;
  int window_failures = 0;
  for (const cv::KeyPoint& kp : out.keypoints) {
    CHECK(kp.octave >= 0);
    CHECK(kp.octave < kLevels);
    CHECK(kp.octave >= previous);  // grouped by octave, level 0 first
    previous = kp.octave;
    CHECK(kp.angle >= 0.0f);
    CHECK(kp.angle < 360.0f);
    CHECK(kp.size == doctest::Approx(31.0 * std::pow(1.2, kp.octave)).epsilon(fork ? 0.04 : 1e-5));
    CHECK(kp.size == orbslam_size(factors[static_cast<std::size_t>(kp.octave)], fork));
    CHECK(kp.pt.x >= 0.0f);
    CHECK(kp.pt.y >= 0.0f);
    CHECK(kp.pt.x <= image.cols - 1.0f);
    CHECK(kp.pt.y <= image.rows - 1.0f);
    // Stereo matching: an 11x11 window at round(pt / s^octave), and the search ±5 along the row.
    const cv::Mat& level = out.pyramid[static_cast<std::size_t>(kp.octave)];
    const float inv = 1.0f / factors[static_cast<std::size_t>(kp.octave)];
    const int u = cvRound(kp.pt.x * inv);
    const int v = cvRound(kp.pt.y * inv);
    const bool fits = u - kWindow - kSearch >= 0 && u + kWindow + kSearch < level.cols && v - kWindow >= 0 &&
                      v + kWindow < level.rows;
    window_failures += !fits;
    if (fits) {
      const cv::Mat window = level.rowRange(v - kWindow, v + kWindow + 1).colRange(u - kWindow, u + kWindow + 1);
      CHECK(window.size() == cv::Size(11, 11));
    }
  }
  CHECK(window_failures == 0);
}

// The ORB-SLAM octave of a keypoint of level `level` in a view of tilt t, by brute force: the level
// o in [0, levels) minimising |log(s^level·√t) − log(s^o)|.
inline int nearest_octave(int level, double tilt) {
  const double target = level * std::log(1.2) + 0.5 * std::log(tilt);
  int best = 0;
  for (int o = 1; o < kLevels; ++o) {
    if (std::abs(o * std::log(1.2) - target) < std::abs(best * std::log(1.2) - target)) best = o;
  }
  return best;
}

// What the adapter must return, derived from affine_orb::Extractor directly: the extractor with
// the image's keypoints `keypoints`, the additive view budget (kFeatures image keypoints, about as many from the tilted
// views, which must not change the image's: checked against max_tilt 1) and no carried shortfalls (each view and level
// at most its share, as ORB-SLAM's own extractor), each keypoint at its octave, which for a view keypoint must be the
// nearest level to its scale s^l·√t by brute force (l recovered from its size Descriptor::kPatchSize·s^l·√t); keypoints
// whose stereo window does not fit dropped; grouped by octave, the image's first; rows cut to the first 32 bytes.
// `from_views` receives the number of view keypoints in the output.
template <class Descriptor>
Output expected_output(const cv::Mat& image, const affine_orb::ImageKeypoints& keypoints, double max_tilt,
                       const std::vector<float>& factors, const std::vector<float>& inverse_factors,
                       int* from_views = nullptr) {
  affine_orb::ExtractorOptions options;
  options.image_keypoints = keypoints;
  options.features = kFeatures;
  options.pyramid.scale_factor = static_cast<double>(kScale);
  options.pyramid.levels = kLevels;
  options.detector.initial_threshold = kIniFast;
  options.detector.min_threshold = kMinFast;
  options.carry_shortfalls = false;
  options.views.max_tilt = 1.0;
  affine_orb::Extractor<Descriptor> plain(options);
  std::vector<cv::Mat> plain_pyramid;
  const auto plain_features = plain.extract(image, cv::Mat(), plain_pyramid);
  options.views.max_tilt = max_tilt;
  affine_orb::Extractor<Descriptor> extractor(options);
  const auto features = extractor.extract(image);
  const std::vector<affine_orb::AffineView> views = extractor.views();
  const auto fits = [&](const cv::KeyPoint& kp, int o) {
    const cv::Mat& level = plain_pyramid[static_cast<std::size_t>(o)];
    const int u = cvRound(kp.pt.x * inverse_factors[static_cast<std::size_t>(o)]);
    const int v = cvRound(kp.pt.y * inverse_factors[static_cast<std::size_t>(o)]);
    return u >= 10 && v >= 10 && u < level.cols - 10 && v < level.rows - 10;
  };
  std::vector<cv::KeyPoint> image_keypoints;
  int octave_errors = 0;
  int moved = 0;
  const cv::Mat rows = affine_orb::descriptors_to_mat(features.descriptors);
  Output out;
  cv::Mat descriptors;
  for (std::size_t i = 0; i < features.size(); ++i) {
    cv::KeyPoint kp = features.keypoints[i];
    const affine_orb::AffineView& view = views[static_cast<std::size_t>(features.views[i])];
    if (features.views[i] == 0) {
      image_keypoints.push_back(kp);
    } else {
      const int level = static_cast<int>(std::lround(
          std::log(kp.size / (Descriptor::kPatchSize * std::sqrt(view.tilt))) / std::log(static_cast<double>(kScale))));
      octave_errors += kp.octave != nearest_octave(level, view.tilt);
    }
    if (!fits(kp, kp.octave)) continue;
    moved += features.views[i] != 0;
    kp.size = orbslam_size(factors[static_cast<std::size_t>(kp.octave)],
                           !std::holds_alternative<affine_orb::AffineOrbKeypoints>(keypoints));
    out.keypoints.push_back(kp);
    descriptors.push_back(rows.row(static_cast<int>(i)).colRange(0, 32).clone());
  }
  CHECK(octave_errors == 0);
  // The image's keypoints are those of views off, in the same order.
  REQUIRE(image_keypoints.size() == plain_features.size());
  int image_differences = 0;
  for (std::size_t i = 0; i < image_keypoints.size(); ++i) {
    image_differences += image_keypoints[i].pt != plain_features.keypoints[i].pt ||
                         image_keypoints[i].octave != plain_features.keypoints[i].octave ||
                         image_keypoints[i].angle != plain_features.keypoints[i].angle;
  }
  CHECK(image_differences == 0);
  if (from_views != nullptr) *from_views = moved;
  out.descriptors = descriptors;
  return out;
}

inline void check_same(const Output& got, const Output& want) {
  REQUIRE(got.keypoints.size() == want.keypoints.size());
  int differences = 0;
  for (std::size_t i = 0; i < got.keypoints.size(); ++i) {
    const cv::KeyPoint& a = got.keypoints[i];
    const cv::KeyPoint& b = want.keypoints[i];
    differences +=
        a.pt != b.pt || a.angle != b.angle || a.response != b.response || a.octave != b.octave || a.size != b.size;
  }
  CHECK(differences == 0);
  REQUIRE(got.descriptors.size() == want.descriptors.size());
  CHECK(cv::norm(got.descriptors, want.descriptors, cv::NORM_HAMMING) == 0.0);
}

// ORB's rBRIEF by its definition (rbrief.hpp, Rublee et al. 2011): on the level image smoothed by a
// 7x7 Gaussian σ = 2 (reflect-101), bit i is 1 iff I(c + R a_i) < I(c + R b_i), rotated test points
// rounded. Returns the number of bits of `row` that differ.
inline int rbrief_reference_difference(const cv::Mat& smoothed, cv::Point c, float angle_degrees, const cv::Mat& row) {
  const float a = static_cast<float>(angle_degrees * CV_PI / 180.0);
  const float cs = std::cos(a);
  const float sn = std::sin(a);
  int diff = 0;
  for (std::size_t i = 0; i < affine_orb::detail::kOrbTestPairs.size(); ++i) {
    const auto& p = affine_orb::detail::kOrbTestPairs[i];
    const auto at = [&](int x, int y) {
      const int rx = cvRound(x * cs - y * sn);
      const int ry = cvRound(x * sn + y * cs);
      return smoothed.at<std::uint8_t>(c.y + ry, c.x + rx);
    };
    const int bit = at(p.xa, p.ya) < at(p.xb, p.yb);
    const int got = (row.at<std::uint8_t>(0, static_cast<int>(i / 8)) >> (i % 8)) & 1;
    diff += bit != got;
  }
  return diff;
}

// The output of an adapter constructed with `features` while `options` are the defaults, on `image`.
template <class T>
Output output_with(const typename T::Options& options, int features, const cv::Mat& image) {
  DefaultsGuard<T> guard(options);
  typename T::Extractor reference(features, kScale, kLevels, kIniFast, kMinFast);
  return run<T>(reference, image);
}

// One case of the recovery switch: an adapter with normal fields (descriptor, max_tilt) and
// recovery fields, and the extraction the recovery fields ask for written as normal fields
// (want_features, want_tilt, want_view_features).
struct RecoveryCase {
  const char* what;
  affine_orb::adapters::AdapterDescriptor descriptor;
  double max_tilt;
  double recovery_image_features;
  double recovery_max_tilt;
  double recovery_view_features;
  int want_features;
  double want_tilt;
  double want_view_features;

  // The keypoints an extraction should return, about: its image budget plus the views' share.
  double budget(bool recovering) const {
    return recovering ? want_features * (1.0 + (want_tilt > 1.0 ? want_view_features : 0.0))
                      : kFeatures * (max_tilt > 1.0 ? 2.0 : 1.0);
  }
};

inline std::vector<RecoveryCase> recovery_cases() {
  using affine_orb::adapters::AdapterDescriptor;
  constexpr int n = kFeatures;
  constexpr double t = kViewsTilt;
  return {
      {"the same plan: ignored", AdapterDescriptor::kRbrief, 1.0, 1.0, 1.0, 1.0, n, 1.0, 1.0},
      {"the same views: ignored", AdapterDescriptor::kRbrief, t, 1.0, t, 1.0, n, t, 1.0},
      {"twice the image budget", AdapterDescriptor::kRbrief, 1.0, 2.0, 1.0, 1.0, 2 * n, 1.0, 1.0},
      {"the views", AdapterDescriptor::kRbrief, 1.0, 1.0, t, 1.0, n, t, 1.0},
      {"the views, BRISK", AdapterDescriptor::kBrisk, 1.0, 1.0, t, 1.0, n, t, 1.0},
      {"both: twice the image budget and n from the views", AdapterDescriptor::kRbrief, 1.0, 2.0, t, 1.0, 2 * n, t,
       0.5},
      {"views normally, three times the image budget instead", AdapterDescriptor::kRbrief, t, 3.0, 1.0, 1.0, 3 * n, 1.0,
       1.0},
  };
}

}  // namespace conformance

TEST_CASE_TEMPLATE_DEFINE("getters equal ORB-SLAM's scale vectors", T, getters) {
  for (const auto& [s, n] : {std::pair<float, int>{1.2f, 8}, {1.5f, 4}, {2.0f, 1}}) {
    typename T::Extractor extractor(500, s, n, 20, 7);
    CHECK(extractor.GetLevels() == n);
    CHECK(extractor.GetScaleFactor() == s);
    const std::vector<float> f = extractor.GetScaleFactors();
    const std::vector<float> fi = extractor.GetInverseScaleFactors();
    const std::vector<float> s2 = extractor.GetScaleSigmaSquares();
    const std::vector<float> s2i = extractor.GetInverseScaleSigmaSquares();
    REQUIRE(f.size() == static_cast<std::size_t>(n));
    REQUIRE(fi.size() == f.size());
    REQUIRE(s2.size() == f.size());
    REQUIRE(s2i.size() == f.size());
    CHECK(extractor.mvImagePyramid.size() == static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      CHECK(f[k] == doctest::Approx(std::pow(static_cast<double>(s), i)).epsilon(1e-6));
      CHECK(fi[k] == doctest::Approx(std::pow(static_cast<double>(s), -i)).epsilon(1e-6));
      CHECK(s2[k] == doctest::Approx(std::pow(static_cast<double>(s), 2 * i)).epsilon(1e-6));
      CHECK(s2i[k] == doctest::Approx(std::pow(static_cast<double>(s), -2 * i)).epsilon(1e-6));
    }
    CHECK(f[0] == 1.0f);
    CHECK(s2[0] == 1.0f);
  }
  CHECK(static_cast<int>(T::Extractor::HARRIS_SCORE) == 0);
  CHECK(static_cast<int>(T::Extractor::FAST_SCORE) == 1);
}

TEST_CASE_TEMPLATE_DEFINE("every output fact holds on real frames, views off and on, both descriptors", T, invariants) {
  using affine_orb::adapters::AdapterDescriptor;
  for (const AdapterDescriptor d : {AdapterDescriptor::kRbrief, AdapterDescriptor::kBrisk}) {
    for (const double tilt : {1.0, conformance::kViewsTilt}) {
      CAPTURE(static_cast<int>(d));
      CAPTURE(tilt);
      conformance::DefaultsGuard<T> guard(conformance::views_options<T>(d, tilt));
      typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                      conformance::kIniFast, conformance::kMinFast);
      CHECK(extractor.AffineOptions().max_tilt == tilt);
      const std::vector<float> factors = extractor.GetScaleFactors();
      for (const cv::Mat& image : conformance::frames()) {
        const conformance::Output out = conformance::run<T>(extractor, image);
        conformance::check_output(out, image, factors);
        // The budget: nfeatures of the image (the fork's octree may end a level a few nodes past its
        // share); the views add view_features · nfeatures (1 by default), fewer where keypoints near
        // the border are dropped.
        if (tilt == 1.0) {
          CHECK(out.keypoints.size() >= static_cast<std::size_t>(conformance::kFeatures));
          CHECK(out.keypoints.size() <= static_cast<std::size_t>(conformance::kFeatures * 102 / 100));
        } else {
          CHECK(out.keypoints.size() >= static_cast<std::size_t>(conformance::kFeatures * 14 / 10));
          CHECK(out.keypoints.size() <= static_cast<std::size_t>(conformance::kFeatures * 21 / 10));
        }
      }
    }
  }
}

TEST_CASE_TEMPLATE_DEFINE("the output is the extractor's, mapped to octaves by the nearest scale", T, mapping) {
  using affine_orb::adapters::AdapterDescriptor;
  const cv::Mat image = affine_orb::test::kitti_frame(10);
  SUBCASE("views off, rBRIEF: the keypoints and rows of Extractor<Rbrief> with the fork's keypoints") {
    typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                    conformance::kIniFast, conformance::kMinFast);
    const conformance::Output got = conformance::run<T>(extractor, image);
    int from_views = -1;
    const conformance::Output want = conformance::expected_output<affine_orb::Rbrief>(
        image, typename T::Fork{}, 1.0, extractor.GetScaleFactors(), extractor.GetInverseScaleFactors(), &from_views);
    CHECK(from_views == 0);
    CHECK(want.keypoints.size() >= static_cast<std::size_t>(conformance::kFeatures));  // nothing dropped
    conformance::check_same(got, want);
  }
  SUBCASE("affine_orb's keypoints, views off: Extractor<Rbrief> with max_tilt 1, exactly the budget") {
    conformance::DefaultsGuard<T> guard(conformance::affine_keypoints<T>());
    typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                    conformance::kIniFast, conformance::kMinFast);
    const conformance::Output got = conformance::run<T>(extractor, image);
    const conformance::Output want = conformance::expected_output<affine_orb::Rbrief>(
        image, affine_orb::AffineOrbKeypoints{}, 1.0, extractor.GetScaleFactors(), extractor.GetInverseScaleFactors());
    CHECK(want.keypoints.size() == static_cast<std::size_t>(conformance::kFeatures));  // nothing dropped
    conformance::check_same(got, want);
  }
  SUBCASE("views on, rBRIEF") {
    conformance::DefaultsGuard<T> guard(
        conformance::views_options<T>(AdapterDescriptor::kRbrief, conformance::kViewsTilt));
    typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                    conformance::kIniFast, conformance::kMinFast);
    const conformance::Output got = conformance::run<T>(extractor, image);
    int from_views = 0;
    const conformance::Output want = conformance::expected_output<affine_orb::Rbrief>(
        image, typename T::Fork{}, conformance::kViewsTilt, extractor.GetScaleFactors(),
        extractor.GetInverseScaleFactors(), &from_views);
    CHECK(from_views > 500);  // the tilted views add about kFeatures keypoints
    conformance::check_same(got, want);
  }
  SUBCASE("no tilted view or no view budget: the views-off output") {
    typename T::Extractor off(conformance::kFeatures, conformance::kScale, conformance::kLevels, conformance::kIniFast,
                              conformance::kMinFast);
    const conformance::Output want = conformance::run<T>(off, image);
    typename T::Options below_first_tilt = conformance::views_options<T>(AdapterDescriptor::kRbrief, 1.41);
    typename T::Options no_budget = conformance::views_options<T>(AdapterDescriptor::kRbrief, conformance::kViewsTilt);
    no_budget.view_features = 0.0;
    for (const typename T::Options& options : {below_first_tilt, no_budget}) {
      conformance::check_same(conformance::output_with<T>(options, conformance::kFeatures, image), want);
    }
  }
  SUBCASE("views on, BRISK: the first 256 of its 512 bits") {
    conformance::DefaultsGuard<T> guard(
        conformance::views_options<T>(AdapterDescriptor::kBrisk, conformance::kViewsTilt));
    typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                    conformance::kIniFast, conformance::kMinFast);
    const conformance::Output got = conformance::run<T>(extractor, image);
    const conformance::Output want = conformance::expected_output<affine_orb::Brisk>(
        image, typename T::Fork{}, conformance::kViewsTilt, extractor.GetScaleFactors(),
        extractor.GetInverseScaleFactors());
    conformance::check_same(got, want);
  }
}

TEST_CASE_TEMPLATE_DEFINE("views off: rows are ORB's rBRIEF by its definition", T, rbrief_definition) {
  const cv::Mat image = affine_orb::test::oxford_image("boat", 1);
  typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                  conformance::kIniFast, conformance::kMinFast);
  const conformance::Output out = conformance::run<T>(extractor, image);
  const std::vector<float> factors = extractor.GetScaleFactors();
  std::vector<cv::Mat> smoothed(conformance::kLevels);
  for (int l = 0; l < conformance::kLevels; ++l) {
    cv::GaussianBlur(out.pyramid[static_cast<std::size_t>(l)], smoothed[static_cast<std::size_t>(l)], cv::Size(7, 7),
                     2.0, 2.0, cv::BORDER_REFLECT_101);
  }
  int exact = 0;
  int bits = 0;
  for (std::size_t i = 0; i < out.keypoints.size(); ++i) {
    const cv::KeyPoint& kp = out.keypoints[i];
    const cv::Mat& level = out.pyramid[static_cast<std::size_t>(kp.octave)];
    // Level pixel of the keypoint: the fork places level pixel p at p·s^octave.
    const float inverse = 1.0f / factors[static_cast<std::size_t>(kp.octave)];
    const cv::Point c(cvRound(kp.pt.x * inverse), cvRound(kp.pt.y * inverse));
    REQUIRE(c.x < level.cols);
    const int d = conformance::rbrief_reference_difference(smoothed[static_cast<std::size_t>(kp.octave)], c, kp.angle,
                                                           out.descriptors.row(static_cast<int>(i)));
    exact += d == 0;
    bits += d;
  }
  // The angle passes through degrees, so a rotated test point on a .5 boundary could round the other
  // way in a rare row; every other row is exact.
  CHECK(exact >= static_cast<int>(out.keypoints.size()) * 99 / 100);
  CHECK(bits <= static_cast<int>(out.keypoints.size()) / 50);
}

TEST_CASE_TEMPLATE_DEFINE("Hamming distance read as 8 x int32 equals the bitwise distance", T, hamming) {
  using affine_orb::adapters::AdapterDescriptor;
  for (const AdapterDescriptor d : {AdapterDescriptor::kRbrief, AdapterDescriptor::kBrisk}) {
    conformance::DefaultsGuard<T> guard(conformance::views_options<T>(d, 1.0));
    typename T::Extractor extractor(300, conformance::kScale, conformance::kLevels, conformance::kIniFast,
                                    conformance::kMinFast);
    const conformance::Output a = conformance::run<T>(extractor, affine_orb::test::kitti_frame(0));
    const conformance::Output b = conformance::run<T>(extractor, affine_orb::test::kitti_frame(1));
    REQUIRE(a.descriptors.isContinuous());
    int mismatches = 0;
    int small = 0;
    for (int i = 0; i < a.descriptors.rows; ++i) {
      int best = 256;
      for (int j = 0; j < b.descriptors.rows; ++j) {
        const int fast = conformance::distance_8x32(a.descriptors.row(i), b.descriptors.row(j));
        if (j % 17 == 0)
          mismatches += fast != conformance::distance_bitwise(a.descriptors.row(i), b.descriptors.row(j));
        best = std::min(best, fast);
      }
      small += best <= 50;  // ORBmatcher::TH_LOW
    }
    CHECK(mismatches == 0);
    // Consecutive frames of a real sequence: many keypoints find a match under ORB-SLAM's threshold.
    CHECK(small >= a.descriptors.rows / 3);
  }
}

TEST_CASE_TEMPLATE_DEFINE("two instances on two threads give the sequential results", T, threads) {
  using affine_orb::adapters::AdapterDescriptor;
  for (const double tilt : {1.0, conformance::kViewsTilt}) {
    typename T::Options options = conformance::views_options<T>(AdapterDescriptor::kRbrief, tilt);
    options.threads = 2;
    conformance::DefaultsGuard<T> guard(options);
    const cv::Mat left = affine_orb::test::kitti_frame(20);
    const cv::Mat right = affine_orb::test::kitti_frame(21);
    typename T::Extractor a(conformance::kFeatures, 1.2f, 8, 20, 7);
    typename T::Extractor b(conformance::kFeatures, 1.2f, 8, 20, 7);
    const conformance::Output seq_a = conformance::run<T>(a, left);
    const conformance::Output seq_b = conformance::run<T>(b, right);
    conformance::Output par_a;
    conformance::Output par_b;
    std::thread ta([&] { par_a = conformance::run<T>(a, left); });
    std::thread tb([&] { par_b = conformance::run<T>(b, right); });
    ta.join();
    tb.join();
    conformance::check_same(par_a, seq_a);
    conformance::check_same(par_b, seq_b);
    for (int l = 0; l < 8; ++l) {
      CHECK(cv::norm(par_a.pyramid[static_cast<std::size_t>(l)], seq_a.pyramid[static_cast<std::size_t>(l)],
                     cv::NORM_INF) == 0.0);
    }
  }
}

TEST_CASE_TEMPLATE_DEFINE("the pyramid of a frame stays valid after the next frame", T, pyramid_ownership) {
  typename T::Extractor extractor(500, 1.2f, 8, 20, 7);
  const cv::Mat first = affine_orb::test::kitti_frame(0);
  conformance::run<T>(extractor, first);
  const std::vector<cv::Mat> kept = extractor.mvImagePyramid;
  const std::vector<cv::Mat> copy = [&] {
    std::vector<cv::Mat> c;
    for (const cv::Mat& m : kept) c.push_back(m.clone());
    return c;
  }();
  conformance::run<T>(extractor, affine_orb::test::kitti_frame(40));
  for (std::size_t l = 0; l < kept.size(); ++l) CHECK(cv::norm(kept[l], copy[l], cv::NORM_INF) == 0.0);
  CHECK(cv::norm(extractor.mvImagePyramid[0], first, cv::NORM_INF) > 0.0);
}

TEST_CASE_TEMPLATE_DEFINE("SetRecovering(true) extracts with the recovery options, false with the normal ones", T,
                          recovery_switch) {
  struct Restore {
    ~Restore() { T::Extractor::SetRecovering(false); }
  } restore;
  CHECK(!T::Extractor::Recovering());
  // The subject: an adapter with a case's normal and recovery fields. The references, built with
  // the switch off: an adapter with the normal fields, and one with the recovery's extraction
  // written as its normal fields.
  const cv::Mat image = affine_orb::test::kitti_frame(10);
  for (const conformance::RecoveryCase& row : conformance::recovery_cases()) {
    const std::string what = row.what;
    CAPTURE(what);
    const typename T::Options normal = conformance::views_options<T>(row.descriptor, row.max_tilt);
    const conformance::Output want_normal = conformance::output_with<T>(normal, conformance::kFeatures, image);
    typename T::Options asked = conformance::views_options<T>(row.descriptor, row.want_tilt);
    asked.view_features = row.want_view_features;
    const conformance::Output want_recovering = conformance::output_with<T>(asked, row.want_features, image);
    typename T::Options options = normal;
    options.recovery.image_features = row.recovery_image_features;
    options.recovery.max_tilt = row.recovery_max_tilt;
    options.recovery.view_features = row.recovery_view_features;
    conformance::DefaultsGuard<T> guard(options);
    typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                    conformance::kIniFast, conformance::kMinFast);
    // Normal, recovering, normal, recovering on the same frame: the switch is read at every call.
    for (const bool recovering : {false, true, false, true}) {
      CAPTURE(recovering);
      T::Extractor::SetRecovering(recovering);
      CHECK(T::Extractor::Recovering() == recovering);
      const conformance::Output out = conformance::run<T>(extractor, image);
      const conformance::Output& want = recovering ? want_recovering : want_normal;
      conformance::check_same(out, want);
      REQUIRE(out.pyramid.size() == want.pyramid.size());
      for (std::size_t l = 0; l < out.pyramid.size(); ++l) {
        CHECK(cv::norm(out.pyramid[l], want.pyramid[l], cv::NORM_INF) == 0.0);
      }
      // The frame has the corners: each extraction returns about its budget (the views' share
      // loses the keypoints whose stereo window would not fit).
      // The fork's octree may end a little past it.
      const double budget = row.budget(recovering);
      CHECK(static_cast<double>(out.keypoints.size()) >= 0.8 * budget);
      CHECK(static_cast<double>(out.keypoints.size()) <= 1.02 * budget);
    }
    T::Extractor::SetRecovering(false);
  }
}

TEST_CASE_TEMPLATE_DEFINE("an empty image leaves every output untouched", T, empty) {
  typename T::Extractor extractor(500, 1.2f, 8, 20, 7);
  conformance::run<T>(extractor, affine_orb::test::kitti_frame(0));
  const std::vector<cv::Mat> pyramid = extractor.mvImagePyramid;
  std::vector<cv::KeyPoint> keypoints{cv::KeyPoint(1.0f, 2.0f, 3.0f)};
  cv::Mat descriptors(3, 5, CV_32F, cv::Scalar(7.0f));
  const int reported = T::extract(extractor, cv::Mat(), cv::Mat(), keypoints, descriptors);
  if constexpr (T::kReturnsCount) CHECK(reported == -1);
  REQUIRE(keypoints.size() == 1);
  CHECK(keypoints[0].pt == cv::Point2f(1.0f, 2.0f));
  CHECK(descriptors.size() == cv::Size(5, 3));
  CHECK(descriptors.type() == CV_32F);
  CHECK(descriptors.at<float>(2, 4) == 7.0f);
  REQUIRE(extractor.mvImagePyramid.size() == pyramid.size());
  for (std::size_t l = 0; l < pyramid.size(); ++l) CHECK(extractor.mvImagePyramid[l].data == pyramid[l].data);
}

TEST_CASE_TEMPLATE_DEFINE("monocular initialisation: the larger extractor, ORB-SLAM's budget on every level", T,
                          initialisation) {
  // Tracking builds a second extractor with kInitialisationFactor x nFeatures for initialisation;
  // the monocular initialiser matches octave-0 keypoints only. Every level keeps at most ORB-SLAM's
  // share of the larger budget, as ORB-SLAM's own extractor: a level short of corners does not
  // pass its shortfall on (to level 0, where it would add extra corners to the initialiser's).
  // With the fork's keypoints the output is the fork's own at that budget ("by default, the fork's
  // own keypoints and bits"); this pins affine_orb's keypoints.
  conformance::DefaultsGuard<T> guard(conformance::affine_keypoints<T>());
  const int n = T::kInitialisationFactor * 1000;
  const std::vector<int> budget = conformance::orbslam_budgets(n);
  typename T::Extractor normal(1000, 1.2f, 8, 20, 7);
  typename T::Extractor initial(n, 1.2f, 8, 20, 7);
  SUBCASE("a KITTI frame has the corners: about that many more") {
    const cv::Mat image = affine_orb::test::kitti_frame(0);
    const conformance::Output a = conformance::run<T>(normal, image);
    const conformance::Output b = conformance::run<T>(initial, image);
    CHECK(a.keypoints.size() == 1000);
    const double ratio = static_cast<double>(b.keypoints.size()) / static_cast<double>(a.keypoints.size());
    CHECK(ratio >= 0.9 * T::kInitialisationFactor);
    CHECK(ratio <= T::kInitialisationFactor);
    const std::vector<int> count = conformance::per_octave(b.keypoints);
    for (int l = 0; l < conformance::kLevels; ++l) {
      CHECK(count[static_cast<std::size_t>(l)] <= budget[static_cast<std::size_t>(l)]);
    }
    CHECK(count[0] == budget[0]);
    conformance::check_output(b, image, initial.GetScaleFactors(), false);
  }
  SUBCASE("a frame whose coarse levels run short: level 0 keeps its own share") {
    cv::Mat image;
    cv::resize(affine_orb::test::kitti_frame(0), image, cv::Size(620, 188), 0, 0, cv::INTER_AREA);
    const conformance::Output b = conformance::run<T>(initial, image);
    const std::vector<int> count = conformance::per_octave(b.keypoints);
    int short_levels = 0;
    for (int l = 0; l < conformance::kLevels; ++l) {
      CAPTURE(l);
      CHECK(count[static_cast<std::size_t>(l)] <= budget[static_cast<std::size_t>(l)]);
      short_levels += count[static_cast<std::size_t>(l)] < budget[static_cast<std::size_t>(l)];
    }
    REQUIRE(short_levels > 0);
    CHECK(count[0] == budget[0]);
    CHECK(static_cast<int>(b.keypoints.size()) < n);
    conformance::check_output(b, image, initial.GetScaleFactors(), false);
  }
}

TEST_CASE_TEMPLATE_DEFINE("the mask is honoured and a ROI image is fine", T, mask) {
  const cv::Mat image = affine_orb::test::kitti_frame(5);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(0, 0, image.cols / 2, image.rows)).setTo(0);
  typename T::Extractor extractor(1000, 1.2f, 8, 20, 7);
  const conformance::Output out = conformance::run<T>(extractor, image, mask);
  REQUIRE(!out.keypoints.empty());
  int masked = 0;
  for (const cv::KeyPoint& kp : out.keypoints) masked += mask.at<std::uint8_t>(cvRound(kp.pt.y), cvRound(kp.pt.x)) == 0;
  CHECK(masked == 0);

  // A ROI (non-continuous rows) gives the result of its copy.
  const cv::Mat big = affine_orb::test::oxford_image("graf", 1);
  const cv::Mat roi = big(cv::Rect(37, 21, 600, 500));
  typename T::Extractor e1(800, 1.2f, 8, 20, 7);
  typename T::Extractor e2(800, 1.2f, 8, 20, 7);
  conformance::check_same(conformance::run<T>(e1, roi), conformance::run<T>(e2, roi.clone()));
}

TEST_CASE_TEMPLATE_DEFINE("options: environment over the setter's defaults, read once at construction", T, options) {
  using affine_orb::adapters::AdapterDescriptor;
  using affine_orb::adapters::AdapterDuplicates;
  const typename T::Options compiled;
  CHECK(T::Extractor::GetAffineOptions().max_tilt == compiled.max_tilt);
  CHECK(compiled.keypoints == affine_orb::adapters::AdapterKeypoints::kFork);
  {
    typename T::Options set;
    set.max_tilt = 2.0;
    set.threads = 3;
    conformance::DefaultsGuard<T> guard(set);
    CHECK(T::Extractor::GetAffineOptions().max_tilt == 2.0);
    typename T::Extractor from_setter(100, 1.2f, 8, 20, 7);
    CHECK(from_setter.AffineOptions().max_tilt == 2.0);
    CHECK(from_setter.AffineOptions().threads == 3);
    {
      conformance::EnvGuard e1(affine_orb::adapters::kEnvMaxTilt, "1.42");
      conformance::EnvGuard e2(affine_orb::adapters::kEnvDescriptor, "brisk");
      conformance::EnvGuard e3(affine_orb::adapters::kEnvDuplicates, "keep");
      conformance::EnvGuard e4(affine_orb::adapters::kEnvMergeRadius, "3.5");
      conformance::EnvGuard e5(affine_orb::adapters::kEnvViewFeatures, "0.5");
      conformance::EnvGuard e6(affine_orb::adapters::kEnvRecoveryImageFeatures, "3");
      conformance::EnvGuard e7(affine_orb::adapters::kEnvRecoveryMaxTilt, "2.01");
      conformance::EnvGuard e8(affine_orb::adapters::kEnvRecoveryViewFeatures, "0.25");
      conformance::EnvGuard e9(affine_orb::adapters::kEnvKeypoints, "affine_orb");
      typename T::Extractor from_env(100, 1.2f, 8, 20, 7);
      const typename T::Options o = from_env.AffineOptions();
      CHECK(o.keypoints == affine_orb::adapters::AdapterKeypoints::kAffineOrb);
      CHECK(o.recovery.image_features == 3.0);
      CHECK(o.recovery.max_tilt == 2.01);
      CHECK(o.recovery.view_features == 0.25);
      CHECK(o.max_tilt == 1.42);
      CHECK(o.descriptor == AdapterDescriptor::kBrisk);
      CHECK(o.duplicates == AdapterDuplicates::kKeepAll);
      CHECK(o.merge_radius == 3.5);
      CHECK(o.view_features == 0.5);
      CHECK(o.threads == 3);  // not set in the environment: the setter's value
    }
    {
      conformance::EnvGuard e(affine_orb::adapters::kEnvThreads, "2");
      typename T::Extractor from_env(100, 1.2f, 8, 20, 7);
      CHECK(from_env.AffineOptions().threads == 2);
    }
    // Read once: the instance built before keeps its options.
    CHECK(from_setter.AffineOptions().max_tilt == 2.0);
  }
  CHECK(T::Extractor::GetAffineOptions().max_tilt == compiled.max_tilt);
  CHECK(T::Extractor::GetAffineOptions().threads == compiled.threads);
}

TEST_CASE_TEMPLATE_DEFINE("a walk along a wall: per-level budgets, keypoints found again, spread, off the border", T,
                          walk) {
  // What ORB-SLAM's tracking asks of the keypoints of a camera moving along a textured wall
  // (walk.hpp: known geometry, no SLAM), with affine_orb's keypoints (the fork's are the fork's
  // extractor's, checked keypoint by keypoint where it is available). The bounds sit a little beyond
  // stock ORB-SLAM2's own extractor on the same walk (bench/slam/walk.sh, docs/slam.md "The walk"):
  // found again one frame on 0.671, 20 frames on 0.504, within 40 px of the border 0.082, cells
  // occupied 0.727 (±0.002 between builds: its quadtree breaks ties by heap address). The adapter
  // before its candidate-rectangle spreading crowded the border (0.121) and lost more of the first
  // frame's keypoints by the last (0.472); both bounds catch that.
  const cv::Mat wall = affine_orb::test::oxford_image("graf", 1);
  REQUIRE(wall.cols >= 800);
  REQUIRE(wall.rows >= 640);
  conformance::DefaultsGuard<T> guard(conformance::affine_keypoints<T>());
  typename T::Extractor extractor(conformance::kFeatures, conformance::kScale, conformance::kLevels,
                                  conformance::kIniFast, conformance::kMinFast);
  const std::vector<int> budget = conformance::orbslam_budgets(conformance::kFeatures);
  int frames_off_budget = 0;
  const walk::Measures m = walk::measure(wall, [&](const cv::Mat& frame) {
    walk::Features f;
    T::extract(extractor, frame, cv::Mat(), f.keypoints, f.descriptors);
    frames_off_budget += conformance::per_octave(f.keypoints) != budget;
    return f;
  });
  CHECK(frames_off_budget == 0);
  CAPTURE(m.next);
  CAPTURE(m.last);
  CAPTURE(m.border);
  CAPTURE(m.occupied);
  CHECK(m.next >= 0.66);
  CHECK(m.last >= 0.49);
  CHECK(m.border <= 0.09);
  CHECK(m.occupied >= 0.70);
}

TEST_CASE_TEMPLATE_DEFINE("bad input is rejected with std::invalid_argument", T, bad_input) {
  const cv::Mat image = affine_orb::test::kitti_frame(0);
  typename T::Extractor extractor(500, 1.2f, 8, 20, 7);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::Mat colour;
  cv::cvtColor(image, colour, cv::COLOR_GRAY2BGR);
  CHECK_THROWS_AS(T::extract(extractor, colour, cv::Mat(), keypoints, descriptors), std::invalid_argument);
  cv::Mat floats;
  image.convertTo(floats, CV_32F);
  CHECK_THROWS_AS(T::extract(extractor, floats, cv::Mat(), keypoints, descriptors), std::invalid_argument);
  const cv::Mat small_mask(image.rows / 2, image.cols, CV_8UC1, cv::Scalar(255));
  CHECK_THROWS_AS(T::extract(extractor, image, small_mask, keypoints, descriptors), std::invalid_argument);
  const cv::Mat float_mask(image.size(), CV_32F, cv::Scalar(1));
  CHECK_THROWS_AS(T::extract(extractor, image, float_mask, keypoints, descriptors), std::invalid_argument);
  CHECK(keypoints.empty());
  CHECK(descriptors.empty());

  // ORB-SLAM's constructor parameters.
  CHECK_THROWS_AS(typename T::Extractor(0, 1.2f, 8, 20, 7), std::invalid_argument);
  CHECK_THROWS_AS(typename T::Extractor(500, 1.0f, 8, 20, 7), std::invalid_argument);
  CHECK_THROWS_AS(typename T::Extractor(500, 1.2f, 0, 20, 7), std::invalid_argument);
  CHECK_THROWS_AS(typename T::Extractor(500, 1.2f, 8, 7, 20), std::invalid_argument);
  CHECK_THROWS_AS(typename T::Extractor(500, std::nanf(""), 8, 20, 7), std::invalid_argument);

  // The setter.
  typename T::Options bad;
  bad.max_tilt = 0.5;
  CHECK_THROWS_AS(T::Extractor::SetAffineOptions(bad), std::invalid_argument);
  bad = typename T::Options{};
  bad.threads = 0;
  CHECK_THROWS_AS(T::Extractor::SetAffineOptions(bad), std::invalid_argument);
  for (const double image_features : {0.5, 17.0, std::nan("")}) {
    bad = typename T::Options{};
    bad.recovery.image_features = image_features;
    CHECK_THROWS_AS(T::Extractor::SetAffineOptions(bad), std::invalid_argument);
  }
  bad = typename T::Options{};
  bad.recovery.max_tilt = 0.9;
  CHECK_THROWS_AS(T::Extractor::SetAffineOptions(bad), std::invalid_argument);
  bad = typename T::Options{};
  bad.recovery.view_features = -1.0;
  CHECK_THROWS_AS(T::Extractor::SetAffineOptions(bad), std::invalid_argument);
  {
    // The recovery budget is bounded like nfeatures.
    typename T::Options large;
    large.recovery.image_features = 16.0;
    conformance::DefaultsGuard<T> guard(large);
    CHECK_NOTHROW(typename T::Extractor(62500, 1.2f, 8, 20, 7));
    CHECK_THROWS_AS(typename T::Extractor(62501, 1.2f, 8, 20, 7), std::invalid_argument);
  }
}

TEST_CASE_TEMPLATE_DEFINE("a bad environment value is rejected with std::invalid_argument naming its variable", T,
                          bad_environment) {
  const std::vector<std::pair<const char*, const char*>> rows = {
      {affine_orb::adapters::kEnvMaxTilt, "abc"},
      {affine_orb::adapters::kEnvMaxTilt, "0.5"},
      {affine_orb::adapters::kEnvMaxTilt, "2.8x"},
      {affine_orb::adapters::kEnvMaxTilt, ""},
      {affine_orb::adapters::kEnvMaxTilt, "nan"},
      {affine_orb::adapters::kEnvDescriptor, "orb"},
      {affine_orb::adapters::kEnvDescriptor, "BRISK"},
      {affine_orb::adapters::kEnvThreads, "0"},
      {affine_orb::adapters::kEnvThreads, "1.5"},
      {affine_orb::adapters::kEnvThreads, "99999999999"},
      {affine_orb::adapters::kEnvDuplicates, "drop"},
      {affine_orb::adapters::kEnvMergeRadius, "0"},
      {affine_orb::adapters::kEnvMergeRadius, "-1"},
      {affine_orb::adapters::kEnvViewFeatures, "-0.5"},
      {affine_orb::adapters::kEnvViewFeatures, "x"},
      {affine_orb::adapters::kEnvRecoveryImageFeatures, "0.5"},
      {affine_orb::adapters::kEnvRecoveryImageFeatures, "two"},
      {affine_orb::adapters::kEnvRecoveryMaxTilt, "17"},
      {affine_orb::adapters::kEnvRecoveryViewFeatures, "-1"},
      {affine_orb::adapters::kEnvKeypoints, "orb"},
      {affine_orb::adapters::kEnvKeypoints, ""},
  };
  for (const auto& [name, value] : rows) {
    CAPTURE(name);
    CAPTURE(value);
    conformance::EnvGuard env(name, value);
    std::string message;
    try {
      typename T::Extractor e(500, 1.2f, 8, 20, 7);
    } catch (const std::invalid_argument& error) {
      message = error.what();
    }
    CHECK(message.find(name) != std::string::npos);
  }
}

// The fork's own ORBextractor (tests/stock, compiled from ../shared/slam/stock_extractors) beside
// the adapter's default on real frames, at ORB-SLAM's budgets and its monocular initialiser's:
// every keypoint (position, octave, angle, size, response) and row equal, in the same order, and
// the same pyramid bytes. ORB-SLAM2's octree orders nodes of equal size by heap address; the fork
// runs on a heap that grows (creation order), the order the adapter takes.
TEST_CASE_TEMPLATE_DEFINE("by default, the fork's own keypoints and bits" * doctest::skip(!AFFINE_ORB_HAVE_STOCK), T,
                          fork_default) {
#if AFFINE_ORB_HAVE_STOCK
  using affine_orb::stock::Fork;
  const Fork fork = std::is_same_v<typename T::Fork, affine_orb::OrbSlam2Keypoints> ? Fork::kOrbSlam2 : Fork::kOrbSlam3;
  std::vector<cv::Mat> images = conformance::frames();
  for (int i = 0; i < 160; i += 53) {
    char name[40];
    std::snprintf(name, sizeof(name), "/kitti00/image_0/%06d.png", i);
    images.push_back(affine_orb::test::load_gray(affine_orb::test::data_dir() + name));
  }
  for (const int n : {1000, 2000, T::kInitialisationFactor * 1000}) {
    CAPTURE(n);
    typename T::Extractor adapter(n, conformance::kScale, conformance::kLevels, conformance::kIniFast,
                                  conformance::kMinFast);
    affine_orb::stock::StockExtractor stock(fork, n, conformance::kScale, conformance::kLevels, conformance::kIniFast,
                                            conformance::kMinFast);
    for (const cv::Mat& image : images) {
      const conformance::Output got = conformance::run<T>(adapter, image);
      const affine_orb::stock::StockFrame want = stock.extract(image, affine_orb::stock::Heap::kGrowing, {-2, -1});
      conformance::Output expected;
      expected.keypoints = want.keypoints;
      expected.descriptors = want.descriptors;
      conformance::check_same(got, expected);
      CHECK(got.reported == want.outside);
      REQUIRE(got.pyramid.size() == want.pyramid.size());
      for (std::size_t l = 0; l < got.pyramid.size(); ++l) {
        CHECK(cv::norm(got.pyramid[l], want.pyramid[l], cv::NORM_INF) == 0.0);
      }
    }
  }
#endif
}
