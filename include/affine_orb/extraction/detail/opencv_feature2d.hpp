#pragma once
/// \file
/// Internals (namespace detail, not part of the API): the cv::Feature2D class behind create_feature2d()
/// (extraction/opencv_feature2d.hpp).

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/detection/pyramid.hpp"
#include "affine_orb/extraction/extractor.hpp"

namespace affine_orb {
namespace detail {

/// cv::Feature2D over Extractor<Descriptor>.
template <class Descriptor>
class Feature2DExtractor : public cv::Feature2D {
 public:
  explicit Feature2DExtractor(const ExtractorOptions& options)
      : extractor_(options), pyramid_(options.pyramid), descriptor_(extractor_.descriptor()) {}

  /// With useProvidedKeypoints = false: Extractor::extract(image, mask), keypoints and descriptor
  /// rows unchanged. With true (what compute() calls): describes the given keypoints in the
  /// original image, see compute_given().
  void detectAndCompute(cv::InputArray image, cv::InputArray mask, std::vector<cv::KeyPoint>& keypoints,
                        cv::OutputArray descriptors, bool useProvidedKeypoints = false) override {
    const cv::Mat input = image.getMat();
    if (useProvidedKeypoints) {
      compute_given(input, keypoints, descriptors);
      return;
    }
    const Features<Descriptor::kBits> features = extractor_.extract(input, mask.getMat());
    keypoints = features.keypoints;
    views_ = features.views;
    if (descriptors.needed()) {
      if (features.empty()) {
        descriptors.release();
      } else {
        descriptors.assign(descriptors_to_mat(features.descriptors));
      }
    }
  }

  int descriptorSize() const override { return Descriptor::kBits / 8; }
  int descriptorType() const override { return CV_8U; }
  int defaultNorm() const override { return cv::NORM_HAMMING; }
  bool empty() const override { return false; }
  cv::String getDefaultName() const override { return "Feature2D.AffineORB"; }

  /// The view index of each keypoint of the last detectAndCompute()/detect() (0 = the image).
  const std::vector<int>& views() const { return views_; }
  const ExtractorOptions& options() const { return extractor_.options(); }

 private:
  /// compute(): each keypoint is described on level o = its octave (clamped to the pyramid) of the
  /// original image's pyramid, at its position mapped to that level and rounded to a pixel, with its
  /// angle; a keypoint with angle < 0 (OpenCV's "not computed") gets the intensity-centroid angle
  /// there, written back. An angle that is, in degrees, exactly the orientation there (as for the
  /// Extractor's own keypoints of the image) is used at full precision, so that those keypoints get
  /// exactly their Extractor descriptors. Keypoints whose support does not fit in the level are
  /// removed from `keypoints`, as OpenCV's extractors do. A non-finite angle throws
  /// std::invalid_argument.
  void compute_given(const cv::Mat& image, std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors) {
    detail::require_gray8(image, "Feature2D::compute");
    pyramid_.build(image);
    const LevelMembers members = assign_levels(image, keypoints);
    const Described described = describe_levels(keypoints, members);
    const std::vector<Row> rows = restore_caller_order(members, described, keypoints);
    views_.assign(keypoints.size(), 0);
    if (!descriptors.needed()) return;
    if (rows.empty()) {
      descriptors.release();
    } else {
      descriptors.assign(descriptors_to_mat(rows));
    }
  }

  using Row = BinaryDescriptor<Descriptor::kBits>;

  /// The keypoints of compute_given() grouped by the pyramid level they are described on.
  struct LevelMembers {
    std::vector<std::vector<std::size_t>> by_level;  ///< per level: indices into the keypoints, ascending
    std::vector<cv::Point2f> points;                 ///< per keypoint: its pixel on its level
  };

  /// Assigns each keypoint to level o = its octave (clamped to the pyramid) of the built pyramid,
  /// at its position mapped to that level and rounded to a pixel. A keypoint with a non-finite
  /// position or whose support does not fit in the level is in no level.
  LevelMembers assign_levels(const cv::Mat& image, const std::vector<cv::KeyPoint>& keypoints) const {
    const int levels = pyramid_.levels();
    const int border = descriptor_.border();
    LevelMembers members;
    members.by_level.resize(static_cast<std::size_t>(levels));
    members.points.resize(keypoints.size());
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      const cv::KeyPoint& kp = keypoints[i];
      if (!std::isfinite(kp.pt.x) || !std::isfinite(kp.pt.y)) continue;
      const int l = std::clamp(kp.octave, 0, levels - 1);
      const cv::Mat& level = pyramid_.level(l);
      const double rx = static_cast<double>(image.cols) / level.cols;
      const double ry = static_cast<double>(image.rows) / level.rows;
      const double x = std::round((kp.pt.x + 0.5) / rx - 0.5);
      const double y = std::round((kp.pt.y + 0.5) / ry - 0.5);
      if (x < border || y < border || x >= level.cols - border || y >= level.rows - border) continue;
      members.points[i] = cv::Point2f(static_cast<float>(x), static_cast<float>(y));
      members.by_level[static_cast<std::size_t>(l)].push_back(i);
    }
    return members;
  }

  /// Described keypoints and their descriptor rows, in the same order.
  struct Described {
    std::vector<cv::KeyPoint> keypoints;
    std::vector<Row> rows;
  };

  /// Describes the keypoints of `members` level by level (level 0 first, each level's in index
  /// order) with the angle rule of compute_given(); a keypoint without an angle gets the centroid's.
  Described describe_levels(const std::vector<cv::KeyPoint>& keypoints, const LevelMembers& members) {
    Described described;
    std::vector<cv::Point2f> points;
    for (std::size_t l = 0; l < members.by_level.size(); ++l) {
      const std::vector<std::size_t>& level_members = members.by_level[l];
      if (level_members.empty()) continue;
      points.clear();
      for (std::size_t i : level_members) points.push_back(members.points[i]);
      descriptor_.prepare(pyramid_.level(static_cast<int>(l)), points, data_);
      for (std::size_t i : level_members) {
        cv::KeyPoint kp = keypoints[i];
        const float centroid = descriptor_.orientation(data_, members.points[i]);
        float angle = centroid;
        if (kp.angle < 0.0f) {
          kp.angle = radians_to_degrees_0_360(centroid);
        } else if (radians_to_degrees_0_360(centroid) != kp.angle) {
          angle = kp.angle * static_cast<float>(CV_PI / 180.0);
        }
        described.rows.push_back(descriptor_.describe(data_, members.points[i], angle));
        described.keypoints.push_back(kp);
      }
    }
    return described;
  }

  /// Puts the described keypoints (in level order) into `keypoints` in the caller's order, the
  /// order of their indices in `members`, and returns their rows in that order.
  static std::vector<Row> restore_caller_order(const LevelMembers& members, const Described& described,
                                               std::vector<cv::KeyPoint>& keypoints) {
    std::vector<std::size_t> order;
    for (const auto& level_members : members.by_level) {
      order.insert(order.end(), level_members.begin(), level_members.end());
    }
    std::vector<std::size_t> rank(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) rank[k] = k;
    std::sort(rank.begin(), rank.end(), [&](std::size_t a, std::size_t b) { return order[a] < order[b]; });
    keypoints.clear();
    std::vector<Row> rows;
    for (std::size_t k : rank) {
      keypoints.push_back(described.keypoints[k]);
      rows.push_back(described.rows[k]);
    }
    return rows;
  }

  Extractor<Descriptor> extractor_;
  Pyramid pyramid_;
  Descriptor descriptor_;
  typename Descriptor::LevelData data_;
  std::vector<int> views_;
};

}  // namespace detail
}  // namespace affine_orb
