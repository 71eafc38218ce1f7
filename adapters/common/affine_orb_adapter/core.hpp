#pragma once
/// \file
/// The implementation shared by the ORB-SLAM2 and ORB-SLAM3 drop-in extractors (internal: the
/// adapters' ORBextractor.cc files include it; ORB-SLAM code never sees it).
///
/// AdapterCore runs affine_orb::Extractor (the image's keypoints, plus the tilted views' with the
/// views on, see AdapterCore) and turns its output into what ORB-SLAM's Frame, Tracking,
/// ORBmatcher, MapPoint and stereo matching rely on (SPEC §6):
/// - `octave` o means σ = s^o: a keypoint found on level l of a view of tilt t has the scale
///   s^l·√t (SPEC §1), so o = round(l + log √t / log s), clamped to [0, nlevels); `size` = 31·s^o;
/// - keypoints grouped by octave, level 0 first (within an octave: the image's keypoints, then the
///   views', each in the extractor's order), descriptor row i belonging to keypoint i, N x 32 CV_8U;
/// - every keypoint at least kBorderMargin pixels inside mvImagePyramid[o] at round(pt / s^o),
///   others dropped: the 11x11 window of stereo matching (radius kStereoWindowRadius) plus its
///   search range (kStereoSearchRadius) fit in the level;
/// - the pyramid is the original image's, level l of size round(W/s^l) x round(H/s^l), copied so
///   that it stays valid after the next frame.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <locale>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/views/affine_views.hpp"
#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb_adapter/options.hpp"

namespace affine_orb::adapters {

/// Half side of the SAD window ORB-SLAM2/3 stereo matching cuts around a keypoint at its octave
/// (Frame::ComputeStereoMatches: an 11x11 window, w = 5).
inline constexpr int kStereoWindowRadius = 5;
/// Search range of that window along the row, in level pixels (L = 5 in the same function).
inline constexpr int kStereoSearchRadius = 5;
/// Distance in level pixels every output keypoint keeps from the borders of mvImagePyramid[octave].
inline constexpr int kBorderMargin = kStereoWindowRadius + kStereoSearchRadius;
/// Bytes per descriptor row: ORBmatcher::DescriptorDistance reads 8 x int32, DBoW2's FORB 32 bytes.
inline constexpr int kDescriptorBytes = 32;
/// ORB's patch diameter: ORB-SLAM's keypoint size is 31·s^octave.
inline constexpr float kOrbPatchSize = 31.0f;

/// ORB-SLAM's per-level tables for scale factor s, levels i = 0 … n−1: s^i, 1/s^i, s^(2i), 1/s^(2i).
/// Computed in float by repeated multiplication, the way ORB-SLAM's callers expect them.
struct ScaleTables {
  std::vector<float> factors;
  std::vector<float> inverse_factors;
  std::vector<float> sigma2;
  std::vector<float> inverse_sigma2;
};

inline ScaleTables make_scale_tables(float scale_factor, int levels) {
  ScaleTables t;
  const auto n = static_cast<std::size_t>(std::max(levels, 0));
  t.factors.resize(n);
  t.inverse_factors.resize(n);
  t.sigma2.resize(n);
  t.inverse_sigma2.resize(n);
  float factor = 1.0f;
  for (std::size_t i = 0; i < n; ++i) {
    t.factors[i] = factor;
    t.sigma2[i] = factor * factor;
    t.inverse_factors[i] = 1.0f / t.factors[i];
    t.inverse_sigma2[i] = 1.0f / t.sigma2[i];
    factor *= scale_factor;
  }
  return t;
}

/// Parsing of environment-variable values; a failure throws std::invalid_argument naming the variable.
namespace detail_env {

inline std::string quoted(const char* text) { return std::string("\"") + text + "\""; }

/// A number as a person writes it ("1", "2.5"), for messages.
inline std::string format(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << value;
  return out.str();
}

inline double parse_number(const char* name, const char* text, double lo, double hi, bool lo_open) {
  std::istringstream in{std::string(text)};
  in.imbue(std::locale::classic());
  double value = 0.0;
  in >> value;
  const bool parsed = !in.fail() && (in >> std::ws).eof();
  const bool in_range = parsed && std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  affine_orb::detail::require(in_range, std::string(name) + " must be a number in " + (lo_open ? "(" : "[") +
                                            format(lo) + ", " + format(hi) + "], got " + quoted(text));
  return value;
}

inline int parse_integer(const char* name, const char* text, int lo, int hi) {
  std::istringstream in{std::string(text)};
  in.imbue(std::locale::classic());
  long long value = 0;
  in >> value;
  const bool parsed = !in.fail() && (in >> std::ws).eof();
  affine_orb::detail::require(parsed && value >= lo && value <= hi, std::string(name) + " must be an integer in [" +
                                                                        std::to_string(lo) + ", " + std::to_string(hi) +
                                                                        "], got " + quoted(text));
  return static_cast<int>(value);
}

}  // namespace detail_env

/// `base` with every set AFFINE_ORB_* environment variable (options.hpp) applied over its field.
/// Throws std::invalid_argument naming the variable for a malformed or out-of-range value
/// (an empty value included).
inline AdapterOptions apply_environment(AdapterOptions base) {
  if (const char* v = std::getenv(kEnvMaxTilt))
    base.max_tilt = detail_env::parse_number(kEnvMaxTilt, v, 1.0, 16.0, false);
  if (const char* v = std::getenv(kEnvDescriptor)) {
    const std::string s(v);
    affine_orb::detail::require(
        s == "rbrief" || s == "brisk",
        std::string(kEnvDescriptor) + " must be \"rbrief\" or \"brisk\", got " + detail_env::quoted(v));
    base.descriptor = s == "rbrief" ? AdapterDescriptor::kRbrief : AdapterDescriptor::kBrisk;
  }
  if (const char* v = std::getenv(kEnvThreads)) base.threads = detail_env::parse_integer(kEnvThreads, v, 1, 256);
  if (const char* v = std::getenv(kEnvDuplicates)) {
    const std::string s(v);
    affine_orb::detail::require(
        s == "merge" || s == "keep",
        std::string(kEnvDuplicates) + " must be \"merge\" or \"keep\", got " + detail_env::quoted(v));
    base.duplicates = s == "merge" ? AdapterDuplicates::kMerge : AdapterDuplicates::kKeepAll;
  }
  if (const char* v = std::getenv(kEnvMergeRadius)) {
    base.merge_radius = detail_env::parse_number(kEnvMergeRadius, v, 0.0, 64.0, true);
  }
  if (const char* v = std::getenv(kEnvViewFeatures)) {
    base.view_features = detail_env::parse_number(kEnvViewFeatures, v, 0.0, 16.0, false);
  }
  if (const char* v = std::getenv(kEnvRecoveryImageFeatures)) {
    base.recovery.image_features = detail_env::parse_number(kEnvRecoveryImageFeatures, v, 1.0, 16.0, false);
  }
  if (const char* v = std::getenv(kEnvRecoveryMaxTilt)) {
    base.recovery.max_tilt = detail_env::parse_number(kEnvRecoveryMaxTilt, v, 1.0, 16.0, false);
  }
  if (const char* v = std::getenv(kEnvRecoveryViewFeatures)) {
    base.recovery.view_features = detail_env::parse_number(kEnvRecoveryViewFeatures, v, 0.0, 16.0, false);
  }
  base.check();
  return base;
}

/// The defaults behind an adapter's static SetAffineOptions()/GetAffineOptions(), guarded by a
/// mutex: the only shared mutable state of the adapters.
class DefaultOptionsStore {
 public:
  void set(const AdapterOptions& options) {
    options.check();
    const std::lock_guard<std::mutex> lock(mutex_);
    options_ = options;
  }
  AdapterOptions get() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return options_;
  }

 private:
  mutable std::mutex mutex_;
  AdapterOptions options_;
};

/// The process-wide switch behind an adapter's static SetRecovering()/Recovering(): an atomic
/// flag, false by default, read at every extraction; while it is true, extractors whose
/// RecoveryOptions differ from their normal options extract with the recovery ones.
class RecoverySwitch {
 public:
  void set(bool recovering) { recovering_.store(recovering, std::memory_order_relaxed); }
  bool get() const { return recovering_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> recovering_{false};
};

/// One frame's output in ORB-SLAM's layout.
struct AdapterFrame {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;           ///< keypoints.size() x 32, CV_8U (empty when there is no keypoint)
  std::vector<cv::Mat> pyramid;  ///< the original image at each level, owned (not shared)
};

/// What one of an adapter's extractors extracts: image keypoints, and the views' tilts and share.
struct ExtractionPlan {
  int image_features = 1000;   ///< keypoints from the image (ExtractorOptions::features)
  double max_tilt = 1.0;       ///< largest tilt; 1 = no views
  double view_features = 0.0;  ///< keypoints the views add, fraction of nfeatures (0 with no views)

  bool operator==(const ExtractionPlan& o) const {
    return image_features == o.image_features && max_tilt == o.max_tilt && view_features == o.view_features;
  }
  bool operator!=(const ExtractionPlan& o) const { return !(*this == o); }
};

/// The plan of `nfeatures` image keypoints and the given views; "no views" (max_tilt 1 or no view
/// budget) is written one way, so that two plans that extract the same compare equal.
inline ExtractionPlan make_plan(int image_features, double max_tilt, double view_features) {
  const bool views = max_tilt > 1.0 && view_features > 0.0;
  return {image_features, views ? max_tilt : 1.0, views ? view_features : 0.0};
}

/// ORB-SLAM's five extractor parameters plus the affine options, checked, and the extractors built
/// from them. `who` names the adapter class in error messages.
///
/// An affine_orb::Extractor with ViewBudget::kAdditive does the work: the image is extracted with
/// ORB-SLAM2's budget (nfeatures keypoints, geometric over the levels), and those keypoints are the
/// same with the views on or off, so ORB-SLAM's monocular initialisation, which matches octave-0
/// keypoints only, keeps all of its candidates. With the views on, the tilted views add about
/// view_features · nfeatures keypoints where the image has none (AdapterDuplicates::kMerge: a view's
/// candidate within merge_radius · s^l of a kept image keypoint or of a stronger view candidate of
/// the same level l is dropped first), each with the octave nearest to its scale. When the
/// recovery options plan another extraction, a second extractor serves the frames extracted while
/// recovering (RecoverySwitch): its output is that of an adapter constructed with
/// round(recovery.image_features · nfeatures) features and the recovery views.
class AdapterCore {
 public:
  AdapterCore(const char* who, int nfeatures, float scale_factor, int nlevels, int ini_th_fast, int min_th_fast,
              const AdapterOptions& affine)
      : who_(who), affine_((affine.check(), affine)) {
    const std::string w(who);
    affine_orb::detail::require(nfeatures >= 1 && nfeatures <= 1000000,
                                w + ": nfeatures must be in [1, 1000000], got " + std::to_string(nfeatures));
    affine_orb::detail::require(std::isfinite(scale_factor) && scale_factor > 1.0f && scale_factor <= 4.0f,
                                w + ": scaleFactor must be in (1, 4], got " + std::to_string(scale_factor));
    affine_orb::detail::require(nlevels >= 1 && nlevels <= 32,
                                w + ": nlevels must be in [1, 32], got " + std::to_string(nlevels));
    affine_orb::detail::require(ini_th_fast >= 1 && ini_th_fast <= 254,
                                w + ": iniThFAST must be in [1, 254], got " + std::to_string(ini_th_fast));
    affine_orb::detail::require(min_th_fast >= 1 && min_th_fast <= ini_th_fast,
                                w + ": minThFAST must be in [1, iniThFAST], got " + std::to_string(min_th_fast));
    scale_factor_ = scale_factor;
    levels_ = nlevels;
    scales_ = make_scale_tables(scale_factor, nlevels);

    ExtractorOptions options;
    options.pyramid.scale_factor = static_cast<double>(scale_factor);
    options.pyramid.levels = nlevels;
    options.detector.initial_threshold = ini_th_fast;
    options.detector.min_threshold = min_th_fast;
    options.detector.score = ScoreType::kFast;  // ORB-SLAM ranks by the FAST score
    options.subpixel = false;                    // ORB-SLAM's keypoints lie on level pixels
    // A level short of corners keeps its shortfall, as ORB-SLAM's own extractor does: carried to
    // level 0 of the monocular initialiser's frames (5 x nfeatures in ORB-SLAM3) it gave ORB-SLAM3
    // maps that drift in scale on the rendered `shake` and lose tracking at once on `fast`
    // (docs/slam.md, "Shortfalls").
    options.carry_shortfalls = false;
    options.view_budget = ViewBudget::kAdditive;
    options.duplicates =
        affine.duplicates == AdapterDuplicates::kMerge ? DuplicatePolicy::kMerge : DuplicatePolicy::kKeepAll;
    options.merge_radius = affine.merge_radius;
    options.threads = affine.threads;
    const ExtractionPlan normal = make_plan(nfeatures, affine.max_tilt, affine.view_features);
    const double recovery_features = std::round(affine.recovery.image_features * nfeatures);
    affine_orb::detail::require(recovery_features <= 1000000.0,
                                w + ": recovery.image_features x nfeatures must be at most 1000000, got " +
                                    detail_env::format(recovery_features));
    const ExtractionPlan recovery = make_plan(static_cast<int>(recovery_features), affine.recovery.max_tilt,
                                              affine.recovery.view_features);
    const auto options_for = [&](const ExtractionPlan& plan) {
      ExtractorOptions o = options;
      o.features = plan.image_features;
      o.views.max_tilt = plan.max_tilt;
      // The extractor's view_features is a fraction of its own image budget.
      o.view_features = plan.image_features == nfeatures ? plan.view_features
                                                         : plan.view_features * nfeatures / plan.image_features;
      return o;
    };
    if (affine.descriptor == AdapterDescriptor::kRbrief) {
      rbrief_.emplace(options_for(normal));
      if (recovery != normal) rbrief_recovery_.emplace(options_for(recovery));
    } else {
      brisk_.emplace(options_for(normal));
      if (recovery != normal) brisk_recovery_.emplace(options_for(recovery));
    }
  }

  const AdapterOptions& affine_options() const { return affine_; }
  const ScaleTables& scales() const { return scales_; }
  int levels() const { return levels_; }
  float scale_factor() const { return scale_factor_; }

  /// Checks the image and mask: nullopt for an empty image (ORB-SLAM's "return, outputs untouched");
  /// std::invalid_argument for a type other than CV_8UC1 or a mask that is neither empty nor CV_8UC1
  /// of the image size (non-zero = allowed, as affine_orb::Extractor::extract). With `recovering`
  /// the recovery options' extraction runs instead of the normal one (the same when they agree).
  std::optional<AdapterFrame> run(const cv::Mat& image, const cv::Mat& mask, bool recovering = false) {
    if (image.empty()) return std::nullopt;
    affine_orb::detail::require_gray8(image, who_);
    affine_orb::detail::require_mask(mask, image.size(), who_);
    if (rbrief_) return convert(recovering && rbrief_recovery_ ? *rbrief_recovery_ : *rbrief_, image, mask);
    return convert(recovering && brisk_recovery_ ? *brisk_recovery_ : *brisk_, image, mask);
  }

 private:
  /// Whether the stereo window around keypoint `pt` fits at octave `o` (kBorderMargin).
  bool fits(cv::Point2f pt, int o, const std::vector<cv::Mat>& pyramid) const {
    const cv::Mat& level = pyramid[static_cast<std::size_t>(o)];
    const float inv = scales_.inverse_factors[static_cast<std::size_t>(o)];
    const int x = cvRound(pt.x * inv);
    const int y = cvRound(pt.y * inv);
    return x >= kBorderMargin && y >= kBorderMargin && x <= level.cols - 1 - kBorderMargin &&
           y <= level.rows - 1 - kBorderMargin;
  }

  template <class Descriptor>
  AdapterFrame convert(Extractor<Descriptor>& extractor, const cv::Mat& image, const cv::Mat& mask) const {
    const Features<Descriptor::kBits> features = extractor.extract(image, mask);
    AdapterFrame frame;
    for (const cv::Mat& level : extractor.pyramid().images()) frame.pyramid.push_back(level.clone());
    // The extractor's octaves are ORB-SLAM's (the nearest scale, grouped, 0 first); the image's
    // keypoints come first within an octave.
    std::vector<std::size_t> picks;
    for (std::size_t i = 0; i < features.size(); ++i) {
      if (fits(features.keypoints[i].pt, features.keypoints[i].octave, frame.pyramid)) picks.push_back(i);
    }
    const cv::Mat rows = descriptors_to_mat(features.descriptors);
    frame.keypoints.reserve(picks.size());
    if (!picks.empty()) frame.descriptors.create(static_cast<int>(picks.size()), kDescriptorBytes, CV_8U);
    for (std::size_t i : picks) {
      cv::KeyPoint kp = features.keypoints[i];
      kp.size = kOrbPatchSize * scales_.factors[static_cast<std::size_t>(kp.octave)];
      // BRISK's 512 bits: the first 256 (bytes 0–31) are kept, see AdapterDescriptor::kBrisk.
      rows.row(static_cast<int>(i))
          .colRange(0, kDescriptorBytes)
          .copyTo(frame.descriptors.row(static_cast<int>(frame.keypoints.size())));
      frame.keypoints.push_back(kp);
    }
    return frame;
  }

  const char* who_;
  AdapterOptions affine_;
  float scale_factor_ = 1.2f;
  int levels_ = 8;
  ScaleTables scales_;
  std::optional<Extractor<Rbrief>> rbrief_;
  std::optional<Extractor<Brisk>> brisk_;
  std::optional<Extractor<Rbrief>> rbrief_recovery_;  ///< only when the recovery plan differs
  std::optional<Extractor<Brisk>> brisk_recovery_;    ///< only when the recovery plan differs
};

/// Writes descriptors to an ORB-SLAM output array: released when there is no keypoint (ORB-SLAM's
/// behaviour), else an N x 32 CV_8U copy.
inline void write_descriptors(const cv::Mat& descriptors, cv::OutputArray out) {
  if (descriptors.empty()) {
    out.release();
    return;
  }
  descriptors.copyTo(out);
}

/// Throws std::invalid_argument unless ORB-SLAM3's `vLappingArea` has exactly two elements.
inline void check_lapping_area(const std::vector<int>& area, const char* who) {
  affine_orb::detail::require(
      area.size() == 2, std::string(who) + ": vLappingArea must have 2 elements, got " + std::to_string(area.size()));
}

/// ORB-SLAM3's lapping-area split: keypoints whose x lies in [area[0], area[1]] (level-0 pixels,
/// bounds included) move to the end of `frame`, descriptor rows with them; both parts keep their
/// order, so each stays grouped by octave (ORB-SLAM3 itself fills the end part backwards; its
/// callers use the two parts as sets). Returns the number of keypoints outside the area.
/// Throws std::invalid_argument unless `area` has exactly two elements.
inline int split_lapping_area(AdapterFrame& frame, const std::vector<int>& area, const char* who) {
  check_lapping_area(area, who);
  const auto inside = [&](const cv::KeyPoint& kp) { return kp.pt.x >= area[0] && kp.pt.x <= area[1]; };
  std::vector<std::size_t> order;
  order.reserve(frame.keypoints.size());
  for (std::size_t i = 0; i < frame.keypoints.size(); ++i) {
    if (!inside(frame.keypoints[i])) order.push_back(i);
  }
  const int outside = static_cast<int>(order.size());
  for (std::size_t i = 0; i < frame.keypoints.size(); ++i) {
    if (inside(frame.keypoints[i])) order.push_back(i);
  }
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(order.size());
  cv::Mat descriptors(frame.descriptors.size(), CV_8U);
  for (std::size_t k = 0; k < order.size(); ++k) {
    keypoints.push_back(frame.keypoints[order[k]]);
    frame.descriptors.row(static_cast<int>(order[k])).copyTo(descriptors.row(static_cast<int>(k)));
  }
  frame.keypoints = std::move(keypoints);
  frame.descriptors = descriptors;
  return outside;
}

}  // namespace affine_orb::adapters
