// init_chain.cpp -- what ORB-SLAM's monocular initialisation gets from one ORBextractor on a sequence,
// without running SLAM: compiled by init_chain.sh against a fork's src/ORBextractor.cc (ORB-SLAM's own
// extractor, or the adapter installed in it) or against an affine_orb checkout's adapter.
//
// ORB-SLAM2's Tracking::MonocularInitialization takes a frame of more than 100 keypoints as the
// reference and matches every next frame against it (ORBmatcher::SearchForInitialization): octave-0
// keypoints only, within a square window of ±100 px around where each reference keypoint was last
// matched, Hamming distance ≤ 50 (TH_LOW), best < 0.9 × second best, one match per keypoint of the
// current frame, then only the three largest bins of a histogram of orientation differences in 30°
// bins (a bin counts when it has at least a tenth of the largest; ORB-SLAM2 divides the angle by its
// 30 bins, so 13 of them are used, 30° wide). It gives the reference up at the first
// frame with fewer than 100 matches, and the frame after that becomes the next reference; until
// then the two-view reconstruction is tried on every frame. So a reference that keeps 100 matches
// for more frames gives the reconstruction more parallax to work with. ORB-SLAM3's monocular mode
// does the same with five times the budget (two in ORB-SLAM2).
//
// This file implements that matching from the description above (the frames of the sequence are
// extracted with the monocular initialisation budget: 2 × ORBextractor.nFeatures of camera.yaml, 5 ×
// for an ORB-SLAM3 tree) and prints one Markdown table row per sequence:
//   name, sequence, octave-0 keypoints per frame, matches one frame on (mean over every frame as
//   reference), frames a reference keeps 100 matches (mean), the references that keep them for 10
//   frames or more, and the same on the references ORB-SLAM's own chain takes from frame 0 (taken,
//   and of them 10 frames or more).
//
// usage: init_chain NAME SEQUENCE...   (each SEQUENCE a TUM-layout folder: rgb.txt, camera.yaml)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fork_extractor.hpp"

namespace {

/// MonocularInitialization's thresholds: keypoints a reference needs (more than), matches a frame
/// needs to keep the reference (at least), the window half-width (pixels, level-0 coordinates).
constexpr std::size_t kMinKeypoints = 100;
constexpr int kMinMatches = 100;
constexpr float kWindow = 100.f;
/// SearchForInitialization: TH_LOW (bits of 256), nearest-neighbour ratio, histogram bins and their
/// width (degrees).
constexpr int kMaxDistance = 50;
constexpr double kRatio = 0.9;
constexpr int kBins = 30;
constexpr float kBinDegrees = 30.f;
/// A reference that keeps its matches this many frames counts as a real attempt at parallax.
constexpr int kLongChain = 10;
/// Frames followed from each reference at most (longer chains are counted as this long).
constexpr int kMaxAge = 60;

struct Frame {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // CV_8U, 32 bytes a row
};

/// Matches `current` against `reference` as described above; `last` holds, per reference keypoint,
/// where it was last matched (pixels, level-0 coordinates) and is moved to this frame's matches.
int match(const Frame& reference, const Frame& current, std::vector<cv::Point2f>& last) {
  const int n1 = static_cast<int>(reference.keypoints.size());
  const int n2 = static_cast<int>(current.keypoints.size());
  std::vector<int> to2(n1, -1);
  std::vector<int> to1(n2, -1);
  std::vector<int> distance2(n2, 1 << 30);
  for (int i = 0; i < n1; ++i) {
    if (reference.keypoints[i].octave != 0) continue;
    int best = 256, second = 256, best_j = -1;
    for (int j = 0; j < n2; ++j) {
      const cv::KeyPoint& k = current.keypoints[j];
      if (k.octave != 0 || std::abs(k.pt.x - last[i].x) >= kWindow || std::abs(k.pt.y - last[i].y) >= kWindow) continue;
      const int d = cv::hal::normHamming(reference.descriptors.ptr<std::uint8_t>(i),
                                         current.descriptors.ptr<std::uint8_t>(j), current.descriptors.cols);
      if (distance2[j] <= d) continue;  // already matched as well or better
      if (d < best) {
        second = best;
        best = d;
        best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best > kMaxDistance || best >= kRatio * second) continue;
    if (to1[best_j] >= 0) to2[to1[best_j]] = -1;
    to2[i] = best_j;
    to1[best_j] = i;
    distance2[best_j] = best;
  }
  std::array<std::vector<int>, kBins> bins;
  for (int i = 0; i < n1; ++i) {
    if (to2[i] < 0) continue;
    float rotation = reference.keypoints[i].angle - current.keypoints[to2[i]].angle;
    if (rotation < 0.f) rotation += 360.f;
    int bin = static_cast<int>(std::lround(rotation / kBinDegrees));
    if (bin == kBins) bin = 0;
    bins[bin].push_back(i);
  }
  std::array<int, kBins> order{};
  for (int b = 0; b < kBins; ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return bins[a].size() > bins[b].size(); });
  const double largest = static_cast<double>(bins[order[0]].size());
  int matches = 0;
  for (int rank = 0; rank < 3 && static_cast<double>(bins[order[rank]].size()) >= 0.1 * largest; ++rank) {
    for (int i : bins[order[rank]]) {
      last[i] = current.keypoints[to2[i]].pt;
      ++matches;
    }
  }
  return matches;
}

/// What frame r gives as the reference: the frames after it that keep kMinMatches matches, and the
/// matches of the frame after it (both 0 when r is not a reference).
struct Chain {
  int age = 0;
  int first_matches = 0;
};

Chain chain(const std::vector<Frame>& frames, std::size_t r) {
  Chain result;
  if (frames[r].keypoints.size() <= kMinKeypoints) return result;
  std::vector<cv::Point2f> last;
  for (const cv::KeyPoint& k : frames[r].keypoints) last.push_back(k.pt);
  for (std::size_t c = r + 1; c < frames.size() && result.age < kMaxAge; ++c) {
    const int matches = frames[c].keypoints.size() <= kMinKeypoints ? 0 : match(frames[r], frames[c], last);
    if (c == r + 1) result.first_matches = matches;
    if (matches < kMinMatches) break;
    ++result.age;
  }
  return result;
}

/// The frames of the TUM-layout `folder`, each extracted with the monocular initialisation budget of
/// its camera.yaml; `octave0` gets the mean octave-0 keypoints per frame. Nothing when a file is
/// missing or an image cannot be read (the reason printed).
std::optional<std::vector<Frame>> extract_frames(const std::string& folder, double& octave0) {
  cv::FileStorage settings(folder + "/camera.yaml", cv::FileStorage::READ);
  std::ifstream list(folder + "/rgb.txt");
  if (!settings.isOpened() || !list) {
    std::fprintf(stderr, "%s: no camera.yaml or rgb.txt\n", folder.c_str());
    return std::nullopt;
  }
  const int features = static_cast<int>(settings["ORBextractor.nFeatures"]);
  const float scale = static_cast<float>(settings["ORBextractor.scaleFactor"]);
  const int levels = static_cast<int>(settings["ORBextractor.nLevels"]);
  const int fast_initial = static_cast<int>(settings["ORBextractor.iniThFAST"]);
  const int fast_minimum = static_cast<int>(settings["ORBextractor.minThFAST"]);
  const bool rgb_order = static_cast<int>(settings["Camera.RGB"]) != 0;
  orb_fork::ORBextractor extractor(orb_fork::kInitialBudgetFactor * features, scale, levels, fast_initial,
                                   fast_minimum);
  std::vector<Frame> frames;
  std::string line;
  double octave0_sum = 0.0;
  while (std::getline(list, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double time = 0.0;
    std::string file;
    fields >> time >> file;
    const cv::Mat colour = cv::imread(folder + "/" + file, cv::IMREAD_COLOR);
    if (colour.empty()) {
      std::fprintf(stderr, "%s/%s: not an image\n", folder.c_str(), file.c_str());
      return std::nullopt;
    }
    cv::Mat grey;
    cv::cvtColor(colour, grey, rgb_order ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
    Frame f = orb_fork::extract<Frame>(extractor, grey);
    octave0_sum += static_cast<double>(
        std::count_if(f.keypoints.begin(), f.keypoints.end(), [](const cv::KeyPoint& k) { return k.octave == 0; }));
    frames.push_back(std::move(f));
  }
  octave0 = frames.empty() ? 0.0 : octave0_sum / static_cast<double>(frames.size());
  return frames;
}

/// The table row's figures of one sequence (see the top of this file).
struct Summary {
  double first_matches = 0.0, age = 0.0;  ///< means over every frame as the reference
  int long_chains = 0, taken = 0, taken_long = 0;
};

/// Every frame as the reference, then ORB-SLAM's own chain from frame 0: a reference is given up
/// on the frame after its last kept one, and the frame after that is the next reference (frames of
/// too few keypoints are skipped).
Summary summarise(const std::vector<Frame>& frames) {
  Summary s;
  std::vector<int> ages(frames.size());
  for (std::size_t r = 0; r + 1 < frames.size(); ++r) {
    const Chain c = chain(frames, r);
    ages[r] = c.age;
    s.first_matches += c.first_matches;
    s.age += c.age;
    s.long_chains += ages[r] >= kLongChain;
  }
  const double references = static_cast<double>(frames.size() - 1);
  s.first_matches /= references;
  s.age /= references;
  for (std::size_t r = 0; r + 1 < frames.size();) {
    if (frames[r].keypoints.size() <= kMinKeypoints) {
      ++r;
      continue;
    }
    ++s.taken;
    s.taken_long += ages[r] >= kLongChain;
    r += static_cast<std::size_t>(ages[r]) + 2;
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s NAME SEQUENCE...\n", argv[0]);
    return 2;
  }
  for (int arg = 2; arg < argc; ++arg) {
    const std::string folder = argv[arg];
    double octave0 = 0.0;
    const std::optional<std::vector<Frame>> frames = extract_frames(folder, octave0);
    if (!frames) return 2;
    if (frames->size() < 2) {
      std::fprintf(stderr, "%s: fewer than two frames\n", folder.c_str());
      return 2;
    }
    const Summary s = summarise(*frames);
    std::string name = folder;
    while (name.size() > 1 && name.back() == '/') name.pop_back();
    name = name.substr(name.find_last_of('/') + 1);
    std::printf("| %s | %s | %.0f | %.1f | %.2f | %d | %d | %d |\n", argv[1], name.c_str(), octave0, s.first_matches,
                s.age, s.long_chains, s.taken, s.taken_long);
  }
  return 0;
}
