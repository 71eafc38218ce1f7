#pragma once
// The forks' own ORB extractors (../shared/slam/stock_extractors, compiled from there by
// cmake/stock_extractors.cmake, never copied into this tree) behind one interface, for the
// conformance tests and the benchmarks that compare affine_orb's fork extraction with them.

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

namespace affine_orb::stock {

/// Which fork's ORBextractor.
enum class Fork { kOrbSlam2, kOrbSlam3 };

/// One frame as the fork's extractor returns it.
struct StockFrame {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<cv::Mat> pyramid;  ///< mvImagePyramid after the call (shallow)
  int outside = 0;               ///< ORB-SLAM3's return value (keypoints outside the lapping area); ORB-SLAM2: size
};

/// How the fork's octree meets nodes of equal size (ORB-SLAM2 orders them by heap address).
enum class Heap {
  kSystem,   ///< the process's allocator, as inside the fork
  kGrowing,  ///< every allocation of the call above the last (a bump arena): creation order
};

/// A fork's ORBextractor with the constructor arguments of ORB-SLAM's.
class StockExtractor {
 public:
  StockExtractor(Fork fork, int nfeatures, float scale_factor, int levels, int ini_th_fast, int min_th_fast);
  ~StockExtractor();
  StockExtractor(const StockExtractor&) = delete;
  StockExtractor& operator=(const StockExtractor&) = delete;

  /// The fork's operator() on `image` (no mask); ORB-SLAM3 with the lapping area `lapping`.
  StockFrame extract(const cv::Mat& image, Heap heap = Heap::kSystem, std::vector<int> lapping = {0, 0});

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Whether the stock extractors were found at configure time (AFFINE_ORB_STOCK_EXTRACTORS_DIR).
bool available();

}  // namespace affine_orb::stock
