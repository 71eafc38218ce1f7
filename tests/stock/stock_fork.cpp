// One fork's own ORBextractor behind stock_extractor.hpp's interface, compiled once per fork by
// cmake/stock_extractors.cmake with AFFINE_ORB_STOCK_ORBSLAM set to 2 or 3 and that fork's header
// on the include path.
#include <list>
#include <vector>

#include <opencv2/core.hpp>

#include "ORBextractor.h"
#include "stock_detail.hpp"

#if AFFINE_ORB_STOCK_ORBSLAM == 2
#define AFFINE_ORB_STOCK_NAMESPACE ORB_SLAM2
#define AFFINE_ORB_STOCK_ENTRY orbslam2
#else
#define AFFINE_ORB_STOCK_NAMESPACE ORB_SLAM3
#define AFFINE_ORB_STOCK_ENTRY orbslam3
#endif

namespace affine_orb::stock::detail {

namespace {
using Fork = AFFINE_ORB_STOCK_NAMESPACE::ORBextractor;

StockFrame run(void* extractor, const cv::Mat& image, std::vector<int>& lapping) {
  Fork& e = *static_cast<Fork*>(extractor);
  StockFrame frame;
#if AFFINE_ORB_STOCK_ORBSLAM == 2
  (void)lapping;
  e(image, cv::Mat(), frame.keypoints, frame.descriptors);
  frame.outside = static_cast<int>(frame.keypoints.size());
#else
  frame.outside = e(image, cv::Mat(), frame.keypoints, frame.descriptors, lapping);
#endif
  frame.pyramid = e.mvImagePyramid;
  return frame;
}

void release(void* extractor) { delete static_cast<Fork*>(extractor); }
}  // namespace

ForkEntry AFFINE_ORB_STOCK_ENTRY(int nfeatures, float scale_factor, int levels, int ini, int min) {
  // libstdc++'s list node: the two links, then the element.
  return {new Fork(nfeatures, scale_factor, levels, ini, min), &run, &release,
          sizeof(std::_List_node<AFFINE_ORB_STOCK_NAMESPACE::ExtractorNode>)};
}

}  // namespace affine_orb::stock::detail
