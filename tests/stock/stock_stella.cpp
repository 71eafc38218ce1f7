// StockStellaExtractor (stock_stella.hpp): stella_vslam's orb_extractor and the orb_params it
// reads, compiled by cmake/stock_extractors.cmake with stella's folder on the include path.
#include "stock_stella.hpp"

#include <string>

#include "stella_vslam/feature/orb_extractor.h"
#include "stella_vslam/feature/orb_params.h"

namespace affine_orb::stock {

struct StockStellaExtractor::Impl {
  stella_vslam::feature::orb_params params;
  stella_vslam::feature::orb_extractor extractor;

  Impl(float scale_factor, int levels, int ini, int min, unsigned min_size,
       const std::vector<std::vector<float>>& rectangles)
      : params("affine_orb stock", scale_factor, static_cast<unsigned>(levels), static_cast<unsigned>(ini),
               static_cast<unsigned>(min)),
        extractor(&params, min_size, stella_vslam::feature::descriptor_type::ORB, rectangles) {}
};

StockStellaExtractor::StockStellaExtractor(float scale_factor, int levels, int ini, int min, unsigned min_size,
                                           const std::vector<std::vector<float>>& mask_rectangles)
    : impl_(new Impl(scale_factor, levels, ini, min, min_size, mask_rectangles)) {}

StockStellaExtractor::~StockStellaExtractor() = default;

StockFrame StockStellaExtractor::extract(const cv::Mat& image, const cv::Mat& mask) {
  StockFrame frame;
  impl_->extractor.extract(image, mask, frame.keypoints, frame.descriptors);
  frame.pyramid = impl_->extractor.image_pyramid_;
  frame.outside = static_cast<int>(frame.keypoints.size());
  return frame;
}

}  // namespace affine_orb::stock
