#pragma once
// A walk along a wall with known geometry, and what ORB-SLAM's tracking asks of the keypoints
// extracted on it. The wall is a photo of at least 800 x 640 pixels (the tests use Oxford graf 1, a
// wall seen head-on); the camera moves along it and slowly towards it, so frame k shows the wall
// through a known similarity and every keypoint of one frame has an exact position in every other.
// No SLAM runs: the measures are those that ORB-SLAM's tracking turns into tracked map points
// (Tracking::TrackLocalMap finds a map point again by projection, within a radius scaled by the
// octave, at a neighbouring octave, with a descriptor distance threshold).
//
// Used by conformance.hpp's "walk" case on the adapters, and usable on any extractor with the
// ORBextractor call (stock ORB-SLAM's own, to measure the figures that case states).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace walk {

/// Frame size, pixels: ORB-SLAM's TUM RGB-D and the rendered sequences' 640 x 480.
constexpr int kWidth = 640;
constexpr int kHeight = 480;
/// Frames of the walk: 21, so that the first keyframe's keypoints can be looked for 20 frames on.
constexpr int kFrames = 21;
/// ORBmatcher::TH_LOW, ORB-SLAM's strict descriptor threshold (bits of 256).
constexpr int kMaxDistance = 50;
/// Search radius at octave o: kRadius · 1.2^o pixels (level-0 coordinates), as ORB-SLAM's
/// SearchByProjection scales its window by the predicted level's scale factor.
constexpr double kRadius = 3.0;
/// A keypoint within kBand pixels of the frame's edge is the first to leave the view as the camera
/// moves (docs/slam.md, "Why the head-on wall gets fewer keyframes").
constexpr double kBand = 40.0;
/// Cells of the occupancy measure, pixels: 20 x 15 cells of a 640 x 480 frame.
constexpr int kCell = 32;

/// Where frame k looks at the wall: frame pixel p shows wall point origin + p / scale. The camera
/// moves 5.3 px right and 1.1 px down per frame (sub-pixel, so no frame repeats another's pixels)
/// and comes 0.2 % closer per frame.
struct Pose {
  double scale;
  cv::Point2d origin;
};

inline Pose pose(int k) { return {1.0 + 0.002 * k, {20.0 + 5.3 * k, 30.0 + 1.1 * k}}; }

/// Frame k of the walk: the wall resampled bilinearly (the wall must cover 800 x 640 pixels).
inline cv::Mat render(const cv::Mat& wall, int k) {
  const Pose p = pose(k);
  const cv::Matx23d to_frame(p.scale, 0.0, -p.scale * p.origin.x, 0.0, p.scale, -p.scale * p.origin.y);
  cv::Mat frame;
  cv::warpAffine(wall, frame, to_frame, cv::Size(kWidth, kHeight), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return frame;
}

/// The position in frame `to` of what frame `from` shows at p (pixels, level-0 coordinates).
inline cv::Point2d transfer(cv::Point2f p, int from, int to) {
  const Pose a = pose(from);
  const Pose b = pose(to);
  return {b.scale * (a.origin.x + p.x / a.scale - b.origin.x), b.scale * (a.origin.y + p.y / a.scale - b.origin.y)};
}

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< one 32-byte row per keypoint
};

/// The share of `from`'s keypoints, among those whose true position lies in frame `to`, that frame
/// `to` has again: a keypoint within kRadius · 1.2^octave px of that position, at an octave ±1,
/// with a descriptor within kMaxDistance bits.
inline double refound(const Features& a, int from, const Features& b, int to) {
  int visible = 0;
  int found = 0;
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    const cv::KeyPoint& kp = a.keypoints[i];
    const cv::Point2d q = transfer(kp.pt, from, to);
    if (q.x < 0.0 || q.y < 0.0 || q.x > kWidth - 1.0 || q.y > kHeight - 1.0) continue;
    ++visible;
    const double radius = kRadius * std::pow(1.2, kp.octave);
    for (std::size_t j = 0; j < b.keypoints.size(); ++j) {
      const cv::KeyPoint& other = b.keypoints[j];
      if (std::abs(other.octave - kp.octave) > 1) continue;
      if (std::hypot(other.pt.x - q.x, other.pt.y - q.y) > radius) continue;
      if (cv::norm(a.descriptors.row(static_cast<int>(i)), b.descriptors.row(static_cast<int>(j)), cv::NORM_HAMMING) <=
          kMaxDistance) {
        ++found;
        break;
      }
    }
  }
  return visible == 0 ? 0.0 : static_cast<double>(found) / visible;
}

/// The share of keypoints within kBand px of the frame's edge.
inline double border_share(const Features& f) {
  int near = 0;
  for (const cv::KeyPoint& kp : f.keypoints) {
    near += kp.pt.x < kBand || kp.pt.y < kBand || kp.pt.x >= kWidth - kBand || kp.pt.y >= kHeight - kBand;
  }
  return f.keypoints.empty() ? 0.0 : static_cast<double>(near) / static_cast<double>(f.keypoints.size());
}

/// The share of the kCell-pixel cells of the frame that hold at least one keypoint (any octave).
inline double occupancy(const Features& f) {
  constexpr int kCols = kWidth / kCell;
  constexpr int kRows = kHeight / kCell;
  std::vector<char> taken(static_cast<std::size_t>(kCols * kRows), 0);
  for (const cv::KeyPoint& kp : f.keypoints) {
    const int cx = std::min(kCols - 1, static_cast<int>(kp.pt.x) / kCell);
    const int cy = std::min(kRows - 1, static_cast<int>(kp.pt.y) / kCell);
    taken[static_cast<std::size_t>(cy * kCols + cx)] = 1;
  }
  int n = 0;
  for (const char t : taken) n += t;
  return static_cast<double>(n) / (kCols * kRows);
}

/// The walk's measures, each a mean over frames unless said.
struct Measures {
  double next = 0.0;      ///< refound() one frame on, frames 0..19 to 1..20
  double last = 0.0;      ///< refound() from frame 0 to frame 20
  double border = 0.0;    ///< border_share()
  double occupied = 0.0;  ///< occupancy()
};

/// Runs `extract` (cv::Mat -> Features) on every frame of the walk on `wall`.
template <class Extract>
Measures measure(const cv::Mat& wall, Extract extract) {
  std::vector<Features> frames;
  for (int k = 0; k < kFrames; ++k) frames.push_back(extract(render(wall, k)));
  Measures m;
  for (int k = 0; k + 1 < kFrames; ++k) {
    const auto i = static_cast<std::size_t>(k);
    m.next += refound(frames[i], k, frames[i + 1], k + 1);
  }
  m.next /= kFrames - 1;
  m.last = refound(frames.front(), 0, frames.back(), kFrames - 1);
  for (const Features& f : frames) {
    m.border += border_share(f);
    m.occupied += occupancy(f);
  }
  m.border /= kFrames;
  m.occupied /= kFrames;
  return m;
}

}  // namespace walk
