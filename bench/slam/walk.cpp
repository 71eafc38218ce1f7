// walk.cpp -- the measures of adapters/tests/walk.hpp (a camera walking along a wall, known
// geometry) for one ORBextractor: compiled by walk.sh against a fork's src/ORBextractor.cc (ORB-SLAM's
// own extractor, or the adapter installed in it) or against an affine_orb checkout's adapter, so that
// stock's figures and the adapter's come from the same code. Prints one Markdown table row per wall:
// name, wall, keypoints per frame (mean), found again one frame on, 20 frames on, within 40 px of
// the border, cells occupied, and the keypoints it shares with a reference extractor, all octaves
// and octave 0.
//
// usage: walk NAME --save PREFIX WALL...     keeps every frame's keypoints in PREFIX.<wall index>
//        walk NAME --shared PREFIX WALL...   shares with the keypoints a --save run kept there
// (each WALL an image of at least 800 x 640 pixels; the --save run shows "–" as its shares)
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fork_extractor.hpp"
#include "walk.hpp"

namespace {

/// Keypoints of every frame of the walk: frame, position (pixels, level-0 coordinates), octave.
struct Located {
  int frame;
  cv::Point2f pt;
  int octave;
};

std::vector<Located> located(const std::vector<walk::Features>& frames) {
  std::vector<Located> all;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    for (const cv::KeyPoint& kp : frames[k].keypoints) all.push_back({static_cast<int>(k), kp.pt, kp.octave});
  }
  return all;
}

void save(const std::string& path, const std::vector<Located>& all) {
  std::ofstream out(path);
  for (const Located& l : all) out << l.frame << ' ' << l.pt.x << ' ' << l.pt.y << ' ' << l.octave << '\n';
}

std::vector<Located> load(const std::string& path) {
  std::ifstream in(path);
  std::vector<Located> all;
  Located l{};
  while (in >> l.frame >> l.pt.x >> l.pt.y >> l.octave) all.push_back(l);
  return all;
}

/// The share of the reference's keypoints (of octave `octave`, or of all when it is negative) that
/// `mine` has too: a keypoint of the same frame and octave within one level pixel, 1.2^octave px at
/// level 0. One level pixel absorbs where each extractor places a level pixel at level 0 (the
/// adapter at its centre's image, ORB-SLAM2 at s^l times its index: adapters/README.md).
double shared(const std::vector<Located>& reference, const std::vector<Located>& mine, int octave) {
  int total = 0;
  int found = 0;
  for (const Located& r : reference) {
    if (octave >= 0 && r.octave != octave) continue;
    ++total;
    const double radius = std::pow(1.2, r.octave);
    for (const Located& m : mine) {
      if (m.frame == r.frame && m.octave == r.octave && std::hypot(m.pt.x - r.pt.x, m.pt.y - r.pt.y) <= radius) {
        ++found;
        break;
      }
    }
  }
  return total == 0 ? 0.0 : static_cast<double>(found) / total;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 2 ? argv[2] : "";
  if (argc < 5 || (mode != "--save" && mode != "--shared")) {
    std::fprintf(stderr, "usage: %s NAME --save|--shared PREFIX WALL...\n", argv[0]);
    return 2;
  }
  const std::string prefix = argv[3];
  for (int i = 4; i < argc; ++i) {
    const cv::Mat wall = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
    if (wall.cols < 800 || wall.rows < 640) {
      std::fprintf(stderr, "%s: not an image of at least 800 x 640 pixels\n", argv[i]);
      return 2;
    }
    // ORB-SLAM2's TUM1.yaml: 1000 features, scale 1.2, 8 levels, FAST 20 / 7.
    orb_fork::ORBextractor extractor(1000, 1.2f, 8, 20, 7);
    double keypoints = 0.0;
    std::vector<walk::Features> frames;
    const walk::Measures m = walk::measure(wall, [&](const cv::Mat& frame) {
      walk::Features f = orb_fork::extract<walk::Features>(extractor, frame);
      keypoints += static_cast<double>(f.keypoints.size()) / walk::kFrames;
      frames.push_back(f);
      return f;
    });
    const std::string kept = prefix + "." + std::to_string(i - 4);
    std::string shares = "– | –";
    if (mode == "--save") {
      save(kept, located(frames));
    } else {
      const std::vector<Located> reference = load(kept);
      if (reference.empty()) {
        std::fprintf(stderr, "%s: no keypoints kept by a --save run\n", kept.c_str());
        return 2;
      }
      const std::vector<Located> mine = located(frames);
      char text[32];
      std::snprintf(text, sizeof text, "%.3f | %.3f", shared(reference, mine, -1), shared(reference, mine, 0));
      shares = text;
    }
    // The wall's name: its folder (the Oxford sequence), or the file name without a folder.
    std::string name = argv[i];
    const std::size_t slash = name.find_last_of('/');
    if (slash != std::string::npos && slash > 0) {
      const std::size_t parent = name.find_last_of('/', slash - 1);
      const std::size_t first = parent == std::string::npos ? 0 : parent + 1;
      name = name.substr(first, slash - first);
    }
    std::printf("| %s | %s | %.0f | %.3f | %.3f | %.3f | %.3f | %s |\n", argv[1], name.c_str(), keypoints, m.next,
                m.last, m.border, m.occupied, shares.c_str());
  }
  return 0;
}
