#pragma once
/// \file
/// The Affine-ORB options of the ORB-SLAM2/3 drop-in extractors that ORB-SLAM's constructor
/// ORBextractor(nfeatures, scaleFactor, nlevels, iniThFAST, minThFAST) cannot carry (docs/algorithm.md §6).
///
/// Where an extractor's options come from, read once when it is constructed:
/// 1. the defaults: AdapterOptions{} (compiled in), or the options last given to the adapter's
///    static ORBextractor::SetAffineOptions();
/// 2. each environment variable below that is set overrides its field of those defaults.
/// stella_vslam's adapter reads no SetAffineOptions() but its YAML `Feature: affine_orb:` map, each
/// key a variable's name in lower case without AFFINE_ORB_ (`max_tilt: 2.83`), the variables over it.
/// A malformed or out-of-range value throws std::invalid_argument naming the variable.
///
/// | variable                  | field          | values                                     |
/// |---------------------------|----------------|--------------------------------------------|
/// | `AFFINE_ORB_KEYPOINTS`    | keypoints      | `fork` or `affine_orb`                     |
/// | `AFFINE_ORB_MAX_TILT`     | max_tilt       | number in [1, 16]; 1 = views off           |
/// | `AFFINE_ORB_DESCRIPTOR`   | descriptor     | `rbrief` or `brisk`                        |
/// | `AFFINE_ORB_THREADS`      | threads        | integer in [1, 256]                        |
/// | `AFFINE_ORB_DUPLICATES`   | duplicates     | `merge` or `keep`                          |
/// | `AFFINE_ORB_MERGE_RADIUS` | merge_radius   | number in (0, 64], pixels                  |
/// | `AFFINE_ORB_VIEW_FEATURES`| view_features  | number in [0, 16], fraction of nfeatures   |
/// | `AFFINE_ORB_RECOVERY_IMAGE_FEATURES` | recovery.image_features | number in [1, 16], multiple of nfeatures |
/// | `AFFINE_ORB_RECOVERY_MAX_TILT`       | recovery.max_tilt       | number in [1, 16]; 1 = no views |
/// | `AFFINE_ORB_RECOVERY_VIEW_FEATURES`  | recovery.view_features  | number in [0, 16], fraction of nfeatures |
///
/// This header is included by the adapters' ORBextractor.h, which every ORB-SLAM file including
/// Frame.h sees, and ORB-SLAM2/3 compile those as C++11: so it stays light (no extractor code) and
/// valid C++11. Only the adapters' ORBextractor.cc needs C++17.

#include <cmath>
#include <stdexcept>
#include <string>

namespace affine_orb {
namespace adapters {

/// Environment variable names (see the table above).
constexpr const char* kEnvKeypoints = "AFFINE_ORB_KEYPOINTS";
constexpr const char* kEnvMaxTilt = "AFFINE_ORB_MAX_TILT";
constexpr const char* kEnvDescriptor = "AFFINE_ORB_DESCRIPTOR";
constexpr const char* kEnvThreads = "AFFINE_ORB_THREADS";
constexpr const char* kEnvDuplicates = "AFFINE_ORB_DUPLICATES";
constexpr const char* kEnvMergeRadius = "AFFINE_ORB_MERGE_RADIUS";
constexpr const char* kEnvViewFeatures = "AFFINE_ORB_VIEW_FEATURES";
constexpr const char* kEnvRecoveryImageFeatures = "AFFINE_ORB_RECOVERY_IMAGE_FEATURES";
constexpr const char* kEnvRecoveryMaxTilt = "AFFINE_ORB_RECOVERY_MAX_TILT";
constexpr const char* kEnvRecoveryViewFeatures = "AFFINE_ORB_RECOVERY_VIEW_FEATURES";

/// Throws std::invalid_argument("affine_orb: " + what) unless `condition` holds (detail::require,
/// which is C++17).
inline void require_option(bool condition, const std::string& what) {
  if (!condition) throw std::invalid_argument("affine_orb: " + what);
}

/// Whose keypoints the image gives (affine_orb::ImageKeypoints).
enum class AdapterKeypoints {
  kFork,       ///< the fork's own ORBextractor's: the same keypoints, order and rBRIEF bits, faster
  kAffineOrb,  ///< affine_orb's selection (its pyramid, FAST grid and quadtree spreading; before 0.3 the default)
};

/// Descriptor computed in every view. ORB-SLAM reads 256 bits per row whichever is chosen.
enum class AdapterDescriptor {
  kRbrief,  ///< ORB's rBRIEF-256: bit-compatible with ORB, so ORB-SLAM's ORBvoc.txt stays valid.
  kBrisk,   ///< BRISK-512 of which the first 256 bits (bytes 0–31) are output; needs its own vocabulary.
};

/// What to do with the keypoints several views put on the same corner (affine_orb::ExtractorOptions::merge_duplicates).
enum class AdapterDuplicates {
  kMerge,    ///< One keypoint per corner and level, the strongest (docs/algorithm.md §2: the SLAM default).
  kKeepAll,  ///< Every view's keypoint.
};

/// What an extractor extracts while the fork reports that tracking is lost (the adapters' static
/// ORBextractor::SetRecovering(true), one line in the fork's Tracking, adapters/README.md "Recovery
/// mode"): these fields replace nfeatures, max_tilt and view_features for those frames. Without
/// that line, or with these fields equal to the normal ones, nothing changes.
struct RecoveryOptions {
  /// Keypoints from the image while recovering, as a multiple of ORB-SLAM's nfeatures (rounded to
  /// the nearest integer). In [1, 16]. Default 3: of the recovery modes measured inside ORB-SLAM2
  /// (2x and 3x plain, the views, 2x plain plus the views), the one that relocalised steeper than
  /// views off by more than the run-to-run range on both development seeds, at 1.07–1.15x its mean
  /// tracking time; 2000 + 1000 from the views, the same total, was better on one seed and worse
  /// on the other at 1.4–1.6x (adapters/README.md, "Recovery mode"; ../shared/slam/run.sh).
  double image_features = 3.0;
  /// Largest simulated tilt of the views while recovering (as AdapterOptions::max_tilt); 1 = no
  /// views. In [1, 16].
  double max_tilt = 1.0;
  /// Keypoints the views add while recovering, as a fraction of nfeatures (as
  /// AdapterOptions::view_features). In [0, 16].
  double view_features = 1.0;

  void check() const {
    require_option(std::isfinite(image_features) && image_features >= 1.0 && image_features <= 16.0,
                   "RecoveryOptions::image_features must be in [1, 16], got " + std::to_string(image_features));
    require_option(std::isfinite(max_tilt) && max_tilt >= 1.0 && max_tilt <= 16.0,
                   "RecoveryOptions::max_tilt must be in [1, 16], got " + std::to_string(max_tilt));
    require_option(std::isfinite(view_features) && view_features >= 0.0 && view_features <= 16.0,
                   "RecoveryOptions::view_features must be in [0, 16], got " + std::to_string(view_features));
  }
};

/// Options of the drop-in extractors beyond ORB-SLAM's five constructor arguments.
struct AdapterOptions {
  /// Whose keypoints the image gives. Default kFork: ORB-SLAM's thresholds (keyframe insertion,
  /// initialisation, map reset) were tuned on its own extractor's keypoints, and any other selection
  /// moves them (docs/slam.md); kAffineOrb is affine_orb's spreading.
  AdapterKeypoints keypoints = AdapterKeypoints::kFork;
  /// Largest simulated tilt t (views t = √2^k <= max_tilt, docs/algorithm.md §1); 1 = plain ORB extraction.
  /// A value between two tilts keeps the tilts below it: write 1.42 for √2, 2.83 for 2√2.
  /// In [1, 16]. Default 1 (views off): inside ORB-SLAM2 the views cost more tracking time than
  /// they bring (docs/slam.md, "What the options do inside ORB-SLAM").
  double max_tilt = 1.0;
  AdapterDescriptor descriptor = AdapterDescriptor::kRbrief;
  /// Worker threads for the views of one frame (ExtractorOptions::threads), in [1, 256]; results
  /// do not depend on it. 1 because ORB-SLAM already runs tracking, local mapping and loop closing
  /// in parallel.
  int threads = 1;
  AdapterDuplicates duplicates = AdapterDuplicates::kMerge;
  /// Merge radius in original pixels times the level scale (affine_orb::MergeOptions::radius), in
  /// (0, 64]: 2 px is the docs/algorithm.md §7 duplicate cell.
  double merge_radius = 2.0;
  /// Keypoints the tilted views add to ORB-SLAM's nfeatures keypoints of the image, as a fraction
  /// of nfeatures (affine_orb::ExtractorOptions::view_features: view_features · nfeatures when the
  /// views have enough corners, fewer where keypoints near the border are dropped); 0 adds none.
  /// The image's own keypoints never change, so that monocular initialisation keeps them. In
  /// [0, 16]; 1, as many from the views as from the image, is the library's default.
  double view_features = 1.0;
  /// What the extractor extracts while tracking is lost (RecoveryOptions).
  RecoveryOptions recovery;

  void check() const {
    recovery.check();
    require_option(keypoints == AdapterKeypoints::kFork || keypoints == AdapterKeypoints::kAffineOrb,
                   "AdapterOptions::keypoints is invalid");
    require_option(std::isfinite(max_tilt) && max_tilt >= 1.0 && max_tilt <= 16.0,
                   "AdapterOptions::max_tilt must be in [1, 16], got " + std::to_string(max_tilt));
    require_option(descriptor == AdapterDescriptor::kRbrief || descriptor == AdapterDescriptor::kBrisk,
                   "AdapterOptions::descriptor is invalid");
    require_option(threads >= 1 && threads <= 256,
                   "AdapterOptions::threads must be in [1, 256], got " + std::to_string(threads));
    require_option(duplicates == AdapterDuplicates::kMerge || duplicates == AdapterDuplicates::kKeepAll,
                   "AdapterOptions::duplicates is invalid");
    require_option(std::isfinite(merge_radius) && merge_radius > 0.0 && merge_radius <= 64.0,
                   "AdapterOptions::merge_radius must be in (0, 64], got " + std::to_string(merge_radius));
    require_option(std::isfinite(view_features) && view_features >= 0.0 && view_features <= 16.0,
                   "AdapterOptions::view_features must be in [0, 16], got " + std::to_string(view_features));
  }
};

}  // namespace adapters
}  // namespace affine_orb
