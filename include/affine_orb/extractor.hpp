#pragma once
/// \file
/// Extractor<Descriptor>: oriented FAST keypoints on a scale pyramid, spread over the image under an
/// exact feature budget, described by a descriptor policy (Rbrief, Brisk).

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptor.hpp"
#include "affine_orb/detail/check.hpp"
#include "affine_orb/detector.hpp"
#include "affine_orb/distribution.hpp"
#include "affine_orb/features.hpp"
#include "affine_orb/pyramid.hpp"

namespace affine_orb {

/// Extraction parameters (SPEC §2).
struct ExtractorOptions {
  /// Number of features returned when the image has enough corners (exactly this many); ORB-SLAM2's
  /// default configuration files use 1000 to 2000. Must be in [1, 1000000].
  int features = 1000;
  PyramidOptions pyramid;
  DetectorOptions detector;

  void check() const {
    detail::require(features >= 1 && features <= 1000000,
                    "ExtractorOptions::features must be in [1, 1000000], got " + std::to_string(features));
    pyramid.check();
    detector.check();
  }
};

/// Extracts keypoints and descriptors from grey images.
///
/// Pipeline for an image of size W x H: a pyramid of PyramidOptions::levels levels; on each level,
/// FAST candidates inside the band where the descriptor's support fits (Descriptor::border() level
/// pixels from every edge), graded by DetectorOptions; candidates outside the mask are dropped;
/// each level gets a geometric share of the budget (level_budgets(), shortfalls carried to the other
/// levels by allocate_with_carry()) and keeps that many candidates by quadtree spreading
/// (distribute_quadtree()); the kept ones are oriented and described on their level.
///
/// Output order: grouped by level, level 0 first; raster order within a level.
///
/// An Extractor holds a workspace (pyramid, score maps, descriptor level data) reused across calls,
/// so extract() allocates nothing for the pyramid once images keep their size. One instance must
/// not be used by two threads at once; separate instances are independent (no shared state).
template <class Descriptor>
class Extractor {
 public:
  static constexpr int kBits = Descriptor::kBits;
  using DescriptorOptions = typename Descriptor::Options;

  explicit Extractor(ExtractorOptions options = {}, DescriptorOptions descriptor_options = {})
      : options_((options.check(), options)), descriptor_(descriptor_options), pyramid_(options_.pyramid) {}

  const ExtractorOptions& options() const { return options_; }
  const Descriptor& descriptor() const { return descriptor_; }

  /// The pyramid of the last image passed to extract() (empty before the first call).
  const Pyramid& pyramid() const { return pyramid_; }

  /// Keypoints and descriptors of a CV_8UC1 image (any ROI of a larger matrix is fine).
  ///
  /// `mask`: empty (everything allowed) or CV_8UC1 of the image size; a keypoint is kept only where
  /// the mask pixel nearest to its level-0 position is non-zero.
  ///
  /// Throws std::invalid_argument for an empty image, a type other than CV_8UC1, or a mask of the
  /// wrong size or type. A valid image with no corners (flat, or smaller than the descriptor
  /// support 2·border()+1 on every level) gives an empty result.
  Features<kBits> extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat()) {
    detail::require_gray8(image, "Extractor::extract");
    detail::require_mask(mask, image.size(), "Extractor::extract");
    pyramid_.build(image);
    const int levels = pyramid_.levels();
    level_work_.resize(static_cast<std::size_t>(levels));

    std::vector<int> available(static_cast<std::size_t>(levels), 0);
    for (int l = 0; l < levels; ++l) {
      LevelWork& work = level_work_[static_cast<std::size_t>(l)];
      collect_candidates(l, mask, work);
      available[static_cast<std::size_t>(l)] = static_cast<int>(work.level_points.size());
    }
    const std::vector<int> take = allocate_with_carry(
        level_budgets(options_.features, options_.pyramid.scale_factor, levels), available);

    Features<kBits> features;
    features.keypoints.reserve(static_cast<std::size_t>(options_.features));
    features.descriptors.reserve(static_cast<std::size_t>(options_.features));
    features.views.reserve(static_cast<std::size_t>(options_.features));
    for (int l = 0; l < levels; ++l) {
      LevelWork& work = level_work_[static_cast<std::size_t>(l)];
      if (take[static_cast<std::size_t>(l)] == 0) continue;
      const std::vector<int> kept =
          distribute_quadtree(work.level_points, work.responses, work.region, take[static_cast<std::size_t>(l)]);
      descriptor_.prepare(pyramid_.level(l), work.descriptor_data);
      const float scale = static_cast<float>(options_.pyramid.scale(l));
      for (int index : kept) {
        const cv::Point2f p = work.level_points[static_cast<std::size_t>(index)];
        const float angle = descriptor_.orientation(work.descriptor_data, p);
        features.descriptors.push_back(descriptor_.describe(work.descriptor_data, p, angle));
        features.keypoints.emplace_back(pyramid_.to_level0(p, l), Descriptor::kPatchSize * scale,
                                        radians_to_degrees_0_360(angle), work.responses[static_cast<std::size_t>(index)],
                                        l);
        features.views.push_back(0);
      }
    }
    return features;
  }

 private:
  struct LevelWork {
    cv::Mat scores;
    cv::Rect2f region;
    std::vector<cv::Point2f> level_points;
    std::vector<float> responses;
    typename Descriptor::LevelData descriptor_data;
  };

  /// Candidates of level l inside the descriptor band, filtered by the mask, in `work`.
  void collect_candidates(int l, const cv::Mat& mask, LevelWork& work) {
    work.level_points.clear();
    work.responses.clear();
    const cv::Mat& image = pyramid_.level(l);
    const int border = std::max(descriptor_.border(), options_.detector.support_radius());
    const cv::Rect roi(border, border, image.cols - 2 * border, image.rows - 2 * border);
    work.region = cv::Rect2f(static_cast<float>(roi.x), static_cast<float>(roi.y), static_cast<float>(roi.width),
                             static_cast<float>(roi.height));
    if (roi.width <= 0 || roi.height <= 0) return;
    const Candidates candidates = detect_candidates(image, roi, options_.detector, work.scores);
    for (std::size_t i = 0; i < candidates.corners.size(); ++i) {
      const Corner& c = candidates.corners[i];
      const cv::Point2f p(static_cast<float>(c.x), static_cast<float>(c.y));
      if (!mask.empty()) {
        const cv::Point2f p0 = pyramid_.to_level0(p, l);
        const int mx = std::clamp(cvRound(p0.x), 0, mask.cols - 1);
        const int my = std::clamp(cvRound(p0.y), 0, mask.rows - 1);
        if (mask.at<std::uint8_t>(my, mx) == 0) continue;
      }
      work.level_points.push_back(p);
      work.responses.push_back(candidates.responses[i]);
    }
  }

  ExtractorOptions options_;
  Descriptor descriptor_;
  Pyramid pyramid_;
  std::vector<LevelWork> level_work_;
};

}  // namespace affine_orb
