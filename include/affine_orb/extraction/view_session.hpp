#pragma once
/// \file
/// ViewSession and StagedFeatures: views on demand for one image, as an object whose lifetime
/// bounds the Extractor's use (Extractor::extract_image(), ViewSession::extend()).

#include <utility>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"

namespace affine_orb {

template <class Descriptor>
class Extractor;

namespace detail {

/// Whether an Extractor has a live ViewSession: while it does, the Extractor refuses to extract
/// another image or to be moved, since the session's earlier stages live in its workspace.
struct SessionFlag {
  bool open = false;

  SessionFlag() = default;
  SessionFlag(SessionFlag&& other) { require(!other.open, "Extractor: moved while a ViewSession of it is open"); }
  SessionFlag& operator=(SessionFlag&& other) {
    require(!open && !other.open, "Extractor: moved while a ViewSession of it is open");
    return *this;
  }
  SessionFlag(const SessionFlag&) = delete;
  SessionFlag& operator=(const SessionFlag&) = delete;
};

}  // namespace detail

/// Views on demand for one image: returned with the image's keypoints by
/// Extractor::extract_image(); each extend() adds the views of further tilts. It holds the image
/// and the mask (cv::Mat headers sharing their pixels, which must not change while it lives) and
/// borrows its Extractor, whose workspace keeps the earlier stages: while the session lives, the
/// Extractor throws std::invalid_argument on extract(), extract_image() and a move. Move-only;
/// a moved-from session refuses extend().
template <class Descriptor>
class ViewSession {
 public:
  static constexpr int kBits = Descriptor::kBits;

  ViewSession(ViewSession&& other) noexcept
      : extractor_(std::exchange(other.extractor_, nullptr)),
        image_(std::move(other.image_)),
        mask_(std::move(other.mask_)),
        extracted_views_(other.extracted_views_),
        extracted_tilt_(other.extracted_tilt_) {}
  ViewSession& operator=(ViewSession&&) = delete;
  ViewSession(const ViewSession&) = delete;
  ViewSession& operator=(const ViewSession&) = delete;
  ~ViewSession() {
    if (extractor_) extractor_->session_.open = false;
  }

  /// The next stage: the keypoints that the tilted views of ExtractorOptions::views with tilt in
  /// (extracted_tilt(), up_to_tilt] add to the image, `features` of them in all when there are
  /// enough corners (shared over the stage's views in proportion to t^view_weight_exponent, then
  /// over levels and with shortfalls carried as in Extractor::extract()). With merge_duplicates a
  /// candidate is dropped when it repeats a keypoint of an earlier stage or of an earlier view of
  /// this stage; earlier stages' keypoints do not change. Returns only the stage's keypoints
  /// (Features::views index Extractor::views()); empty, the session unchanged, when no view is
  /// left up to `up_to_tilt`. Throws std::invalid_argument on a moved-from session, for
  /// up_to_tilt not finite, or features outside [0, 1000000].
  Features<kBits> extend(double up_to_tilt, int features) {
    detail::require(extractor_ != nullptr, "ViewSession::extend: the session was moved from");
    return extractor_->extend(*this, up_to_tilt, features);
  }

  /// The largest tilt whose views are extracted: 1 after extract_image() (the image alone).
  double extracted_tilt() const { return extracted_tilt_; }
  /// The views extracted so far, the image included: extend() continues with view index
  /// extracted_views() (Extractor::views()).
  int extracted_views() const { return extracted_views_; }

 private:
  friend class Extractor<Descriptor>;
  ViewSession(Extractor<Descriptor>* extractor, cv::Mat image, cv::Mat mask)
      : extractor_(extractor), image_(std::move(image)), mask_(std::move(mask)) {
    extractor_->session_.open = true;
  }

  Extractor<Descriptor>* extractor_ = nullptr;
  cv::Mat image_;
  cv::Mat mask_;
  int extracted_views_ = 1;
  double extracted_tilt_ = 1.0;
};

/// What Extractor::extract_image() returns: the keypoints of stage 0 and the session whose
/// extend() adds the next stages.
template <class Descriptor>
struct StagedFeatures {
  Features<Descriptor::kBits> features;
  ViewSession<Descriptor> session;
};

}  // namespace affine_orb
