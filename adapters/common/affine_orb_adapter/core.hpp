#pragma once
/// \file
/// The implementation shared by the ORB-SLAM2 and ORB-SLAM3 drop-in extractors (internal: the
/// adapters' ORBextractor.cc files include it; ORB-SLAM code never sees it).
///
/// AdapterCore runs affine_orb::Extractor (the image's keypoints, plus the tilted views' with the
/// views on, see AdapterCore) and turns its output into what ORB-SLAM's Frame, Tracking,
/// ORBmatcher, MapPoint and stereo matching rely on (docs/algorithm.md §6):
/// - `octave` o means σ = s^o: a keypoint found on level l of a view of tilt t has the scale
///   s^l·√t (docs/algorithm.md §1), so o = round(l + log √t / log s), clamped to [0, nlevels); `size` = 31·s^o;
/// - keypoints grouped by octave, level 0 first (within an octave: the image's keypoints, then the
///   views', each in the extractor's order), descriptor row i belonging to keypoint i, N x 32 CV_8U;
/// - every keypoint at least kBorderMargin pixels inside mvImagePyramid[o] at round(pt / s^o),
///   others dropped: the 11x11 window of stereo matching (radius kStereoWindowRadius) plus its
///   search range (kStereoSearchRadius) fit in the level;
/// - the pyramid is the original image's, level l of size round(W/s^l) x round(H/s^l), copied so
///   that it stays valid after the next frame.

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <initializer_list>
#include <locale>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/views/affine_views.hpp"
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
  require_option(in_range, std::string(name) + " must be a number in " + (lo_open ? "(" : "[") + format(lo) + ", " +
                               format(hi) + "], got " + quoted(text));
  return value;
}

inline int parse_integer(const char* name, const char* text, int lo, int hi) {
  std::istringstream in{std::string(text)};
  in.imbue(std::locale::classic());
  long long value = 0;
  in >> value;
  const bool parsed = !in.fail() && (in >> std::ws).eof();
  require_option(parsed && value >= lo && value <= hi, std::string(name) + " must be an integer in [" +
                                                           std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                                                           quoted(text));
  return static_cast<int>(value);
}

}  // namespace detail_env

/// One of the named values of an enumerated variable.
template <class E>
struct Choice {
  const char* text;
  E value;
};

namespace detail_env {

/// The value of `choices` spelled `text`; std::invalid_argument naming `name` and the choices
/// otherwise.
template <class E>
E parse_choice(const char* name, const char* text, std::initializer_list<Choice<E>> choices) {
  std::string spelled;
  for (const Choice<E>& c : choices) {
    if (std::string(text) == c.text) return c.value;
    spelled += (spelled.empty() ? "" : " or ") + quoted(c.text);
  }
  require_option(false, std::string(name) + " must be " + spelled + ", got " + quoted(text));
  return choices.begin()->value;
}

/// An AFFINE_ORB_* variable (options.hpp) and how a value sets its field; `shown` is the name a
/// bad value's message gives (the variable's, or the setting's that carried the value).
struct Variable {
  const char* name;
  void (*apply)(AdapterOptions& options, const char* shown, const char* text);
};

/// Every variable of the table in options.hpp.
inline const std::vector<Variable>& variables() {
  static const std::vector<Variable> table = {
      {kEnvKeypoints,
       [](AdapterOptions& o, const char* n, const char* v) {
         o.keypoints = parse_choice<AdapterKeypoints>(
             n, v, {{"fork", AdapterKeypoints::kFork}, {"affine_orb", AdapterKeypoints::kAffineOrb}});
       }},
      {kEnvMaxTilt,
       [](AdapterOptions& o, const char* n, const char* v) { o.max_tilt = parse_number(n, v, 1.0, 16.0, false); }},
      {kEnvDescriptor,
       [](AdapterOptions& o, const char* n, const char* v) {
         o.descriptor = parse_choice<AdapterDescriptor>(
             n, v, {{"rbrief", AdapterDescriptor::kRbrief}, {"brisk", AdapterDescriptor::kBrisk}});
       }},
      {kEnvThreads, [](AdapterOptions& o, const char* n, const char* v) { o.threads = parse_integer(n, v, 1, 256); }},
      {kEnvDuplicates,
       [](AdapterOptions& o, const char* n, const char* v) {
         o.duplicates = parse_choice<AdapterDuplicates>(
             n, v, {{"merge", AdapterDuplicates::kMerge}, {"keep", AdapterDuplicates::kKeepAll}});
       }},
      {kEnvMergeRadius,
       [](AdapterOptions& o, const char* n, const char* v) { o.merge_radius = parse_number(n, v, 0.0, 64.0, true); }},
      {kEnvViewFeatures,
       [](AdapterOptions& o, const char* n, const char* v) { o.view_features = parse_number(n, v, 0.0, 16.0, false); }},
      {kEnvRecoveryImageFeatures,
       [](AdapterOptions& o, const char* n, const char* v) {
         o.recovery.image_features = parse_number(n, v, 1.0, 16.0, false);
       }},
      {kEnvRecoveryMaxTilt, [](AdapterOptions& o, const char* n,
                               const char* v) { o.recovery.max_tilt = parse_number(n, v, 1.0, 16.0, false); }},
      {kEnvRecoveryViewFeatures,
       [](AdapterOptions& o, const char* n, const char* v) {
         o.recovery.view_features = parse_number(n, v, 0.0, 16.0, false);
       }},
  };
  return table;
}

}  // namespace detail_env

/// `base` with every set AFFINE_ORB_* environment variable (options.hpp) applied over its field.
/// Throws std::invalid_argument naming the variable for a malformed or out-of-range value
/// (an empty value included).
inline AdapterOptions apply_environment(AdapterOptions base) {
  for (const detail_env::Variable& variable : detail_env::variables()) {
    if (const char* value = std::getenv(variable.name)) variable.apply(base, variable.name, value);
  }
  base.check();
  return base;
}

/// The key that names an AFFINE_ORB_* variable among settings: its name without the prefix, in
/// lower case ("max_tilt" for AFFINE_ORB_MAX_TILT).
inline std::string setting_key(const char* variable) {
  std::string key(variable + std::char_traits<char>::length("AFFINE_ORB_"));
  for (char& c : key) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return key;
}

/// `base` with each (key, value) of `settings` applied over the field of the variable whose
/// setting_key() is `key`, as its environment value would be: how a fork's own configuration file
/// carries the options (stella_vslam's YAML `Feature: affine_orb:` map). `where` prefixes a key in
/// messages ("Feature.affine_orb."). An unknown key or a bad value throws std::invalid_argument
/// naming it; the environment is not read.
inline AdapterOptions apply_settings(AdapterOptions base,
                                     const std::vector<std::pair<std::string, std::string>>& settings,
                                     const std::string& where) {
  const std::vector<detail_env::Variable>& table = detail_env::variables();
  for (const auto& [key, value] : settings) {
    const auto variable = std::find_if(table.begin(), table.end(),
                                       [&](const detail_env::Variable& v) { return setting_key(v.name) == key; });
    if (variable == table.end()) {
      std::string known;
      for (const detail_env::Variable& v : table) known += (known.empty() ? "" : ", ") + setting_key(v.name);
      require_option(false, "unknown setting " + where + key + " (known: " + known + ")");
    }
    variable->apply(base, (where + key).c_str(), value.c_str());
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

/// ORB-SLAM's five extractor parameters, checked (std::invalid_argument naming `who`).
struct ForkParameters {
  int nfeatures = 1000;
  float scale_factor = 1.2f;
  int levels = 8;
  int ini_th_fast = 20;
  int min_th_fast = 7;

  void check(const std::string& who) const {
    affine_orb::detail::require_range(nfeatures, {1, 1000000}, (who + ": nfeatures").c_str());
    affine_orb::detail::require_range(scale_factor, {1, 4, true}, (who + ": scaleFactor").c_str());
    affine_orb::detail::require_range(levels, {1, 32}, (who + ": nlevels").c_str());
    affine_orb::detail::require_range(ini_th_fast, {1, 254}, (who + ": iniThFAST").c_str());
    require_option(min_th_fast >= 1 && min_th_fast <= ini_th_fast,
                   who + ": minThFAST must be in [1, iniThFAST], got " + std::to_string(min_th_fast));
  }
};

/// The ExtractorOptions of an adapter's extractions but for their budget and views: the fork's
/// parameters, its keypoints (`fork`) unless AdapterKeypoints::kAffineOrb, ranked by the FAST
/// score on level pixels, each level at most its share (a level short of corners keeps its
/// shortfall, as ORB-SLAM's own extractor does: carried to level 0 of the monocular initialiser's
/// frames it gave ORB-SLAM3 maps that drift in scale, docs/slam.md "Shortfalls"), the views adding
/// to the image's keypoints.
inline ExtractorOptions base_options(const ImageKeypoints& fork, const ForkParameters& p,
                                     const AdapterOptions& affine) {
  ExtractorOptions options;
  options.image_keypoints = affine.keypoints == AdapterKeypoints::kFork ? fork : ImageKeypoints{AffineOrbKeypoints{}};
  options.pyramid.scale_factor = static_cast<double>(p.scale_factor);
  options.pyramid.levels = p.levels;
  options.detector.initial_threshold = p.ini_th_fast;
  options.detector.min_threshold = p.min_th_fast;
  options.detector.score = ScoreType::kFast;
  options.subpixel = false;
  options.carry_shortfalls = false;
  options.view_budget = AdditiveBudget{};
  options.merge_duplicates.reset();
  if (affine.duplicates == AdapterDuplicates::kMerge) options.merge_duplicates = MergeOptions{affine.merge_radius, 0};
  options.threads = affine.threads;
  return options;
}

/// `base` set to extract `plan`, whose views add plan.view_features · nfeatures keypoints.
inline ExtractorOptions plan_options(ExtractorOptions base, const ExtractionPlan& plan, int nfeatures) {
  base.features = plan.image_features;
  base.views.max_tilt = plan.max_tilt;
  // The extractor's view_features is a fraction of its own image budget.
  std::get<AdditiveBudget>(base.view_budget).view_features =
      plan.image_features == nfeatures ? plan.view_features : plan.view_features * nfeatures / plan.image_features;
  return base;
}

/// An adapter's extractor, and the one for the frames extracted while recovering when its plan
/// differs.
template <class Descriptor>
struct ExtractorPair {
  Extractor<Descriptor> normal;
  std::optional<Extractor<Descriptor>> recovery;

  ExtractorPair(const ExtractorOptions& base, const ExtractionPlan& normal_plan, const ExtractionPlan& recovery_plan,
                int nfeatures)
      : normal(plan_options(base, normal_plan, nfeatures)) {
    if (recovery_plan != normal_plan) recovery.emplace(plan_options(base, recovery_plan, nfeatures));
  }
  Extractor<Descriptor>& pick(bool recovering) { return recovering && recovery ? *recovery : normal; }
};

/// ORB-SLAM's five extractor parameters plus the affine options, checked, and the extractors built
/// from them. `who` names the adapter class in error messages; `fork` is the fork's keypoints
/// (OrbSlam2Keypoints or OrbSlam3Keypoints), which AdapterKeypoints::kFork returns.
///
/// An affine_orb::Extractor with AdditiveBudget does the work: the image is extracted with
/// ORB-SLAM's budget (nfeatures keypoints, geometric over the levels), and those keypoints are the
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
  AdapterCore(const char* who, const ImageKeypoints& fork, const ForkParameters& parameters,
              const AdapterOptions& affine)
      : who_(who),
        affine_((affine.check(), affine)),
        parameters_((parameters.check(who), parameters)),
        scales_(make_scale_tables(parameters.scale_factor, parameters.levels)),
        extractors_(make_extractors(who, fork, parameters, affine)) {}

  const AdapterOptions& affine_options() const { return affine_; }
  const ScaleTables& scales() const { return scales_; }
  int levels() const { return parameters_.levels; }
  float scale_factor() const { return parameters_.scale_factor; }

  /// Checks the image and mask: nullopt for an empty image (ORB-SLAM's "return, outputs untouched");
  /// std::invalid_argument for a type other than CV_8UC1 or a mask that is neither empty nor CV_8UC1
  /// of the image size (non-zero = allowed, as affine_orb::Extractor::extract). With `recovering`
  /// the recovery options' extraction runs instead of the normal one (the same when they agree).
  std::optional<AdapterFrame> run(const cv::Mat& image, const cv::Mat& mask, bool recovering = false) {
    if (image.empty()) return std::nullopt;
    affine_orb::detail::require_gray8(image, who_);
    affine_orb::detail::require_mask(mask, image.size(), who_);
    return std::visit([&](auto& pair) { return convert(pair.pick(recovering), image, mask); }, extractors_);
  }

 private:
  using Extractors = std::variant<ExtractorPair<Rbrief>, ExtractorPair<Brisk>>;

  static Extractors make_extractors(const std::string& who, const ImageKeypoints& fork, const ForkParameters& p,
                                    const AdapterOptions& affine) {
    const ExtractionPlan normal = make_plan(p.nfeatures, affine.max_tilt, affine.view_features);
    const double recovery_features = std::round(affine.recovery.image_features * p.nfeatures);
    require_option(recovery_features <= 1000000.0, who +
                                                       ": recovery.image_features x nfeatures must be at most "
                                                       "1000000, got " +
                                                       detail_env::format(recovery_features));
    const ExtractionPlan recovery =
        make_plan(static_cast<int>(recovery_features), affine.recovery.max_tilt, affine.recovery.view_features);
    const ExtractorOptions base = base_options(fork, p, affine);
    if (affine.descriptor == AdapterDescriptor::kRbrief) {
      return Extractors(std::in_place_type<ExtractorPair<Rbrief>>, base, normal, recovery, p.nfeatures);
    }
    return Extractors(std::in_place_type<ExtractorPair<Brisk>>, base, normal, recovery, p.nfeatures);
  }

  /// Whether the stereo window around keypoint `pt` fits at octave `o` (kBorderMargin).
  bool fits(cv::Point2f pt, int o, const std::vector<cv::Mat>& pyramid) const {
    const cv::Mat& level = pyramid[static_cast<std::size_t>(o)];
    const float inv = scales_.inverse_factors[static_cast<std::size_t>(o)];
    const int x = cvRound(pt.x * inv);
    const int y = cvRound(pt.y * inv);
    return x >= kBorderMargin && y >= kBorderMargin && x <= level.cols - 1 - kBorderMargin &&
           y <= level.rows - 1 - kBorderMargin;
  }

  /// ORB-SLAM's keypoint size at octave o: 31·s^o, truncated as the forks store it when the image's
  /// keypoints are the fork's.
  float keypoint_size(int o) const {
    const float size = kOrbPatchSize * scales_.factors[static_cast<std::size_t>(o)];
    return affine_.keypoints == AdapterKeypoints::kFork ? static_cast<float>(static_cast<int>(size)) : size;
  }

  template <class Descriptor>
  AdapterFrame convert(Extractor<Descriptor>& extractor, const cv::Mat& image, const cv::Mat& mask) const {
    AdapterFrame frame;
    const Features<Descriptor::kBits> features = extractor.extract(image, mask, frame.pyramid);
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
      kp.size = keypoint_size(kp.octave);
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
  ForkParameters parameters_;
  ScaleTables scales_;
  Extractors extractors_;
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

/// ORB-SLAM3's lapping-area split, as its own extractor orders it: keypoints whose x lies in
/// [area[0], area[1]] (level-0 pixels, bounds included) move to the end of `frame`, descriptor rows
/// with them, the others keep their order at the front and the moved ones fill the end backwards
/// (the last of them first). Returns the number of keypoints outside the area. Throws
/// std::invalid_argument unless `area` has exactly two elements.
inline int split_lapping_area(AdapterFrame& frame, const std::vector<int>& area, const char* who) {
  check_lapping_area(area, who);
  const auto inside = [&](const cv::KeyPoint& kp) { return kp.pt.x >= area[0] && kp.pt.x <= area[1]; };
  const std::size_t n = frame.keypoints.size();
  std::vector<std::size_t> order(n);
  std::size_t front = 0;
  std::size_t back = n;
  for (std::size_t i = 0; i < n; ++i) order[inside(frame.keypoints[i]) ? --back : front++] = i;
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(n);
  cv::Mat descriptors(frame.descriptors.size(), CV_8U);
  for (std::size_t k = 0; k < n; ++k) {
    keypoints.push_back(frame.keypoints[order[k]]);
    frame.descriptors.row(static_cast<int>(order[k])).copyTo(descriptors.row(static_cast<int>(k)));
  }
  frame.keypoints = std::move(keypoints);
  frame.descriptors = descriptors;
  return static_cast<int>(front);
}

}  // namespace affine_orb::adapters
