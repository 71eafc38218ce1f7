#pragma once
// The link between stock_extractor.cpp and the two compilations of stock_fork.cpp, each of which
// sees one fork's ORBextractor.h (both headers use the same include guard).

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

#include "stock_extractor.hpp"

namespace affine_orb::stock::detail {

/// A fork's extractor behind plain functions.
struct ForkEntry {
  void* extractor = nullptr;
  StockFrame (*run)(void* extractor, const cv::Mat& image, std::vector<int>& lapping) = nullptr;
  void (*release)(void* extractor) = nullptr;
  std::size_t node_size = 0;  ///< bytes of one node of the fork's std::list<ExtractorNode>
};

ForkEntry orbslam2(int nfeatures, float scale_factor, int levels, int ini, int min);
ForkEntry orbslam3(int nfeatures, float scale_factor, int levels, int ini, int min);

}  // namespace affine_orb::stock::detail
