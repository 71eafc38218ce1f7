#pragma once
/// \file
/// ViewCursor and StagedFeatures: views on demand as an object the caller holds
/// (Extractor::extract_image(), Extractor::extend()).

#include <cstdint>
#include <utility>

#include <opencv2/core.hpp>

#include "affine_orb/core/features.hpp"

namespace affine_orb {

template <class Descriptor>
class Extractor;

/// Where views on demand stand for one image: returned with the image's keypoints by
/// Extractor::extract_image() and advanced by each Extractor::extend(). It holds the image and the
/// mask (cv::Mat headers sharing their pixels, which must not change while the cursor is used) and
/// how many of the Extractor's views are extracted. The keypoints of earlier stages stay in the
/// Extractor's workspace, so a cursor is valid with that Extractor only, until it extracts another
/// image (or is moved); extend() throws std::invalid_argument for any other cursor.
class ViewCursor {
 public:
  ViewCursor() = default;
  /// Move-only, and a moved-from cursor is refused like a default one: one cursor per staged
  /// image, so that no stage is extracted twice.
  ViewCursor(ViewCursor&& other) { *this = std::move(other); }
  ViewCursor& operator=(ViewCursor&& other) {
    image_ = std::move(other.image_);
    mask_ = std::move(other.mask_);
    extracted_views_ = other.extracted_views_;
    extracted_tilt_ = other.extracted_tilt_;
    owner_ = std::exchange(other.owner_, nullptr);
    image_serial_ = other.image_serial_;
    return *this;
  }
  ViewCursor(const ViewCursor&) = delete;
  ViewCursor& operator=(const ViewCursor&) = delete;

  /// The largest tilt whose views are extracted: 1 after extract_image() (the image alone), 0 for
  /// a default-constructed cursor.
  double extracted_tilt() const { return extracted_tilt_; }
  /// The views extracted so far, the image included: extend() continues with view index
  /// extracted_views() (Extractor::views()).
  int extracted_views() const { return extracted_views_; }

 private:
  template <class Descriptor>
  friend class Extractor;
  cv::Mat image_;
  cv::Mat mask_;
  int extracted_views_ = 0;
  double extracted_tilt_ = 0.0;
  const void* owner_ = nullptr;     ///< the Extractor that made the cursor
  std::uint64_t image_serial_ = 0;  ///< which image of that Extractor the cursor belongs to
};

/// What Extractor::extract_image() returns: the keypoints of stage 0 and the cursor that extend()
/// advances.
template <int Bits>
struct StagedFeatures {
  Features<Bits> features;
  ViewCursor cursor;
};

}  // namespace affine_orb
