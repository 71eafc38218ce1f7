// stella_vslam's feature::orb_extractor implemented by affine_orb: this file replaces stella's
// src/stella_vslam/feature/orb_extractor.cc; stella's orb_extractor.h stays but for two
// declarations, configure_affine_orb() and set_affine_orb_recovering(), that
// adapters/stella_vslam/install.sh adds with their calls in system.cc (adapters/README.md,
// "stella_vslam"). By default extract() returns stella's own keypoints, in its order, its ORB rows
// and its image_pyramid_ bytes (StellaVslamKeypoints); the YAML `Feature: affine_orb:` settings,
// then the AFFINE_ORB_* variables over them (affine_orb_adapter/options.hpp), turn on affine_orb's
// views or spreading, and with install.sh --recovery the recovery options serve the frames
// extracted while tracking is lost.
#include "stella_vslam/feature/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb_adapter/core.hpp"

namespace stella_vslam {
namespace feature {

namespace {

constexpr const char* kWho = "stella_vslam::feature::orb_extractor (affine_orb)";

/// What an extractor keeps between frames: the affine options, whether system.cc reports lost
/// tracking (install.sh --recovery) and whether it is lost now, and from the first frame on
/// affine_orb's extractor, the one for the recovery options where they differ, and the pyramid
/// they fill in place.
struct AdapterState {
  using Engine = std::variant<std::monostate, affine_orb::Extractor<affine_orb::Rbrief>,
                              affine_orb::Extractor<affine_orb::Brisk>>;
  affine_orb::adapters::AdapterOptions affine;
  unsigned min_area = 0;  ///< stella's Preprocessing.min_size
  bool recovery_hook = false;
  bool recovering = false;
  Engine engine;
  Engine recovery_engine;
  std::vector<cv::Mat> levels;
};

/// Gives an AdapterState the lifetime of a cv::Mat: orb_extractor.h, which stays stella's, has no
/// member for it, so the private rect_mask_ (stella's own rectangle mask, which affine_orb builds
/// itself) holds a 1x1 header whose reference count owns the state, deleted with the last copy.
class StateAllocator final : public cv::MatAllocator {
 public:
  cv::UMatData* allocate(int, const int*, int, void*, std::size_t*, cv::AccessFlag, cv::UMatUsageFlags) const override {
    return nullptr;
  }
  bool allocate(cv::UMatData*, cv::AccessFlag, cv::UMatUsageFlags) const override { return false; }
  void deallocate(cv::UMatData* u) const override {
    delete static_cast<AdapterState*>(u->userdata);
    delete u;
  }
};

cv::Mat own_state(AdapterState* state) {
  static StateAllocator allocator;
  auto* u = new cv::UMatData(&allocator);
  u->data = u->origdata = reinterpret_cast<uchar*>(state);
  u->size = sizeof(AdapterState);
  u->userdata = state;
  u->refcount = 1;
  cv::Mat handle(1, 1, CV_8UC1, u->data);
  handle.u = u;
  handle.allocator = &allocator;
  return handle;
}

AdapterState& state_of(const cv::Mat& handle) { return *static_cast<AdapterState*>(handle.u->userdata); }

/// stella's mask rectangles ([x_min, x_max, y_min, y_max], fractions of the image) as affine_orb's.
std::vector<affine_orb::MaskRectangle> mask_rectangles(const std::vector<std::vector<float>>& rects) {
  std::vector<affine_orb::MaskRectangle> out;
  for (const std::vector<float>& r : rects) {
    affine_orb::detail::require(r.size() == 4, std::string(kWho) + ": a mask rectangle needs 4 values, got " +
                                                   std::to_string(r.size()));
    out.push_back({r[0], r[1], r[2], r[3]});
  }
  return out;
}

/// The cells of stella's selection grid over every level for a `size` image with cells of
/// `min_area` pixels: the most keypoints its own extraction keeps, and the budget of the views and
/// of affine_orb's spreading.
int grid_cells(const orb_params& p, unsigned min_area, cv::Size size) {
  constexpr int kPatchRadius = 19;  // stella's orb_patch_radius_: no keypoint nearer the border
  const double min_area_sqrt = static_cast<unsigned>(std::sqrt(min_area));  // stella's min_area_sqrt_
  double cells = 0.0;
  for (unsigned l = 0; l < p.num_levels_; ++l) {
    const double scale = p.scale_factors_.at(l);
    const double side = min_area_sqrt / scale;
    const double w = std::max(std::round(size.width / scale) - 2 * kPatchRadius, 0.0);
    const double h = std::max(std::round(size.height / scale) - 2 * kPatchRadius, 0.0);
    cells += std::ceil(w / side) * std::ceil(h / side);
  }
  return static_cast<int>(std::clamp(cells, 1.0, 1000000.0));
}

/// affine_orb's options for stella's parameters with cells of `min_area` pixels and `plan`, whose
/// views add plan.view_features · `cells` keypoints (cells: the normal grid's count).
affine_orb::ExtractorOptions extractor_options(const orb_params& p, unsigned min_area,
                                               const std::vector<std::vector<float>>& rects,
                                               const affine_orb::adapters::AdapterOptions& affine,
                                               const affine_orb::adapters::ExtractionPlan& plan, int cells) {
  namespace ad = affine_orb::adapters;
  const ad::ForkParameters fork{cells, p.scale_factor_, static_cast<int>(p.num_levels_),
                                static_cast<int>(p.ini_fast_thr_), static_cast<int>(p.min_fast_thr_)};
  fork.check(kWho);
  affine_orb::StellaVslamKeypoints stella;
  stella.min_size = static_cast<int>(std::min(min_area, 2000000000u));  // check() refuses > 10^8
  stella.mask_rectangles = mask_rectangles(rects);
  affine_orb::ExtractorOptions options = ad::plan_options(ad::base_options(stella, fork, affine), plan, cells);
  options.check();
  return options;
}

/// The cell area of the recovery extraction: round(image_features) times the cells.
unsigned recovery_min_area(unsigned min_area, const affine_orb::adapters::AdapterOptions& affine) {
  return std::max(1u, static_cast<unsigned>(std::lround(min_area / affine.recovery.image_features)));
}

/// The options of the normal extraction of a `size` image and, with the recovery hook, of the
/// recovery one where its cells or views differ (std::invalid_argument for bad parameters).
std::pair<affine_orb::ExtractorOptions, std::optional<affine_orb::ExtractorOptions>> engine_options(
    const AdapterState& state, const orb_params& p, const std::vector<std::vector<float>>& rects, cv::Size size) {
  namespace ad = affine_orb::adapters;
  const ad::AdapterOptions& a = state.affine;
  const int cells = grid_cells(p, state.min_area, size);
  const ad::ExtractionPlan normal = ad::make_plan(cells, a.max_tilt, a.view_features);
  std::pair<affine_orb::ExtractorOptions, std::optional<affine_orb::ExtractorOptions>> out{
      extractor_options(p, state.min_area, rects, a, normal, cells), std::nullopt};
  if (!state.recovery_hook) return out;
  const unsigned area = recovery_min_area(state.min_area, a);
  const ad::ExtractionPlan recovery =
      ad::make_plan(grid_cells(p, area, size), a.recovery.max_tilt, a.recovery.view_features);
  if (area != state.min_area || recovery != normal) out.second = extractor_options(p, area, rects, a, recovery, cells);
  return out;
}

/// Builds `engine` for `options` with the descriptor `affine` names.
void build(AdapterState::Engine& engine, const affine_orb::ExtractorOptions& options,
           const affine_orb::adapters::AdapterOptions& affine) {
  if (affine.descriptor == affine_orb::adapters::AdapterDescriptor::kRbrief) {
    engine.emplace<affine_orb::Extractor<affine_orb::Rbrief>>(options);
  } else {
    engine.emplace<affine_orb::Extractor<affine_orb::Brisk>>(options);
  }
}

/// The settings of YAML `Feature: affine_orb:` (a map of scalars; absent: none) as key and value;
/// the recovery keys only with the recovery hook.
std::vector<std::pair<std::string, std::string>> yaml_settings(const YAML::Node& feature, bool recovery_hook) {
  std::vector<std::pair<std::string, std::string>> settings;
  const YAML::Node node = feature.IsMap() ? feature["affine_orb"] : YAML::Node();
  if (!node || node.IsNull()) return settings;
  affine_orb::detail::require(node.IsMap(), std::string(kWho) + ": Feature.affine_orb must be a map of settings");
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    affine_orb::detail::require(entry.second.IsScalar(),
                                std::string(kWho) + ": Feature.affine_orb." + key + " must be a single value");
    affine_orb::detail::require(recovery_hook || key.rfind("recovery_", 0) != 0,
                                std::string(kWho) + ": Feature.affine_orb." + key +
                                    " has no effect: install the adapter with --recovery, which tells the "
                                    "extractor when tracking is lost");
    settings.emplace_back(key, entry.second.Scalar());
  }
  return settings;
}

}  // namespace

orb_extractor::orb_extractor(const orb_params* orb_params, const unsigned int min_area, const descriptor_type desc_type,
                             const std::vector<std::vector<float>>& mask_rects)
    : orb_params_(orb_params), mask_rects_(mask_rects), min_area_sqrt_(0), desc_type_(desc_type) {
  affine_orb::detail::require(orb_params != nullptr, std::string(kWho) + ": orb_params is null");
  affine_orb::detail::require(desc_type == descriptor_type::ORB,
                              std::string(kWho) + ": descriptor_type " + descriptor_type_to_string(desc_type) +
                                  " is not supported, only ORB (restore stella's extractor for HashSIFT)");
  affine_orb::detail::require(min_area >= 1, std::string(kWho) + ": min_size must be at least 1");
  auto* state = new AdapterState{affine_orb::adapters::apply_environment({}), min_area, false, false, {}, {}, {}};
  rect_mask_ = own_state(state);
  engine_options(*state, *orb_params_, mask_rects_, cv::Size(640, 480));  // refuses bad parameters now
  image_pyramid_.resize(orb_params_->num_levels_);
}

/// Applies the YAML `Feature: affine_orb:` settings (keys: the AFFINE_ORB_* variables' names without
/// the prefix, in lower case, e.g. `max_tilt: 2.83`), then the set AFFINE_ORB_* variables over them;
/// std::invalid_argument for an unknown key or a bad value. `recovery_hook`: system.cc reports lost
/// tracking (set_affine_orb_recovering()), so the recovery options apply. The next frame uses them.
void orb_extractor::configure_affine_orb(const YAML::Node& feature, bool recovery_hook) {
  namespace ad = affine_orb::adapters;
  AdapterState& state = state_of(rect_mask_);
  AdapterState next{ad::apply_environment(ad::apply_settings({}, yaml_settings(feature, recovery_hook),
                                                             "Feature.affine_orb.")),
                    state.min_area, recovery_hook, false, {}, {}, {}};
  engine_options(next, *orb_params_, mask_rects_, cv::Size(640, 480));  // refuses now
  state.affine = next.affine;
  state.recovery_hook = recovery_hook;
  state.engine = std::monostate{};
  state.recovery_engine = std::monostate{};
}

/// While `recovering` (tracking lost, as system.cc reports with the recovery hook), the frames are
/// extracted with the recovery options where they differ from the normal ones.
void orb_extractor::set_affine_orb_recovering(bool recovering) { state_of(rect_mask_).recovering = recovering; }

/// Keypoints and ORB rows of `in_image` (CV_8UC1; empty: returns, outputs untouched), with
/// `in_image_mask` (non-zero = allowed) or else mask_rects_; image_pyramid_ level 0 is the image,
/// as stella's. affine_orb's extractor is built for the first image's size, as stella builds its
/// rectangle mask then.
void orb_extractor::extract(const cv::_InputArray& in_image, const cv::_InputArray& in_image_mask,
                            std::vector<cv::KeyPoint>& keypts, const cv::_OutputArray& out_descriptors) {
  if (in_image.empty()) return;
  const cv::Mat image = in_image.getMat();
  const cv::Mat mask = in_image_mask.getMat();
  AdapterState& state = state_of(rect_mask_);
  if (std::holds_alternative<std::monostate>(state.engine)) {
    const auto options = engine_options(state, *orb_params_, mask_rects_, image.size());
    build(state.engine, options.first, state.affine);
    if (options.second) build(state.recovery_engine, *options.second, state.affine);
    mask_is_initialized_ = true;
  }
  const bool recovery = state.recovering && !std::holds_alternative<std::monostate>(state.recovery_engine);
  std::visit(
      [&](auto& extractor) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(extractor)>, std::monostate>) {
          const auto features = extractor.extract(image, mask, state.levels);
          keypts.assign(features.keypoints.begin(), features.keypoints.end());
          const int n = static_cast<int>(features.size());
          if (n == 0) {
            out_descriptors.release();
          } else {
            out_descriptors.create(n, affine_orb::adapters::kDescriptorBytes, CV_8U);
            cv::Mat rows = out_descriptors.getMat();
            // BRISK's first 256 bits, as the ORB-SLAM adapters keep them.
            for (int i = 0; i < n; ++i) {
              std::memcpy(rows.ptr(i), features.descriptors[static_cast<std::size_t>(i)].data(),
                          affine_orb::adapters::kDescriptorBytes);
            }
          }
        }
      },
      recovery ? state.recovery_engine : state.engine);
  image_pyramid_.resize(state.levels.size());
  image_pyramid_[0] = image;
  for (std::size_t l = 1; l < state.levels.size(); ++l) image_pyramid_[l] = state.levels[l];
}

}  // namespace feature
}  // namespace stella_vslam
