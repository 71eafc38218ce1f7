#pragma once
// stella_vslam's own orb_extractor (../shared/slam/stock_extractors/stella_vslam_b0e60d6, compiled
// from there by cmake/stock_extractors.cmake, never copied into this tree) behind a plain
// interface, for the conformance test and the benchmark that compare StellaVslamKeypoints
// with it.

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "stock_extractor.hpp"

namespace affine_orb::stock {

/// stella_vslam's orb_extractor with its orb_params (scale factor, levels, FAST thresholds), its
/// Preprocessing.min_size and mask_rectangles ([x_min, x_max, y_min, y_max], fractions), ORB
/// descriptors.
class StockStellaExtractor {
 public:
  StockStellaExtractor(float scale_factor, int levels, int ini_fast_threshold, int min_fast_threshold,
                       unsigned min_size, const std::vector<std::vector<float>>& mask_rectangles = {});
  ~StockStellaExtractor();
  StockStellaExtractor(const StockStellaExtractor&) = delete;
  StockStellaExtractor& operator=(const StockStellaExtractor&) = delete;

  /// Its extract() on `image` with `mask` (empty: none); StockFrame::outside is the keypoint count.
  StockFrame extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat());

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace affine_orb::stock
