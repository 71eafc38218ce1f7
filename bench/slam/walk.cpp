// walk.cpp -- the measures of adapters/tests/walk.hpp (a camera walking along a wall, known
// geometry) for one ORBextractor: compiled by walk.sh against a fork's src/ORBextractor.cc (ORB-SLAM's
// own extractor, or the adapter installed in it) or against an affine_orb checkout's adapter, so that
// stock's figures and the adapter's come from the same code. Prints one Markdown table row per wall:
// name, wall, keypoints per frame (mean), found again one frame on, 20 frames on, within 40 px of
// the border, cells occupied.
//
// usage: walk NAME WALL...   (each WALL an image of at least 800 x 640 pixels)
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ORBextractor.h"
#include "walk.hpp"

#ifdef WALK_ORBSLAM3
namespace slam = ORB_SLAM3;
#else
namespace slam = ORB_SLAM2;
#endif

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s NAME WALL...\n", argv[0]);
    return 2;
  }
  for (int i = 2; i < argc; ++i) {
    const cv::Mat wall = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
    if (wall.cols < 800 || wall.rows < 640) {
      std::fprintf(stderr, "%s: not an image of at least 800 x 640 pixels\n", argv[i]);
      return 2;
    }
    // ORB-SLAM2's TUM1.yaml: 1000 features, scale 1.2, 8 levels, FAST 20 / 7.
    slam::ORBextractor extractor(1000, 1.2f, 8, 20, 7);
    double keypoints = 0.0;
    const walk::Measures m = walk::measure(wall, [&](const cv::Mat& frame) {
      walk::Features f;
#ifdef WALK_ORBSLAM3
      std::vector<int> lapping = {0, 0};
      extractor(frame, cv::Mat(), f.keypoints, f.descriptors, lapping);
#else
      extractor(frame, cv::Mat(), f.keypoints, f.descriptors);
#endif
      keypoints += static_cast<double>(f.keypoints.size()) / walk::kFrames;
      return f;
    });
    // The wall's name: its folder (the Oxford sequence), or the file name without a folder.
    std::string name = argv[i];
    const std::size_t slash = name.find_last_of('/');
    if (slash != std::string::npos && slash > 0) {
      const std::size_t parent = name.find_last_of('/', slash - 1);
      const std::size_t first = parent == std::string::npos ? 0 : parent + 1;
      name = name.substr(first, slash - first);
    }
    std::printf("| %s | %s | %.0f | %.3f | %.3f | %.3f | %.3f |\n", argv[1], name.c_str(), keypoints, m.next, m.last, m.border,
                m.occupied);
  }
  return 0;
}
