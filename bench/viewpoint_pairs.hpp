#pragma once
// The image pairs with ground-truth homographies that the matching benches judge methods on (the
// Oxford sequences in ../shared/data/oxford and Debian opencv-doc's graf1/graf3), and the judge
// itself: correct and distinct correct matches, and whether an estimated homography solves a pair.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "affine_orb/matching/affine_matching.hpp"
#include "bench_common.hpp"

namespace affine_orb::bench {

/// Image 1 and image N of a sequence with x_N ~ h x_1 (pixels).
struct ViewpointPair {
  std::string sequence;
  int image = 0;
  std::string path1, path2;
  cv::Matx33d h;
  /// "oxford" (Oxford and opencv-doc), "hpatches", "homogr" or "evd" (../shared/data/pairs/).
  std::string subset = "oxford";
  std::string name() const { return sequence + " 1->" + std::to_string(image); }
  /// EVD pairs are judged on the overlap grid (grid_error()), the others on the corners.
  bool judged_on_grid() const { return subset == "evd"; }
};

inline cv::Mat read_gray(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error("cannot read image " + path);
  return image;
}

/// An Oxford ground-truth file: nine numbers, row-major.
inline cv::Matx33d read_oxford_homography(const std::string& path) {
  std::ifstream in(path);
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) {
    if (!(in >> h.val[i])) throw std::runtime_error("cannot read homography " + path);
  }
  return h;
}

/// Pairs 1->2 ... 1->6 of every Oxford sequence and opencv-doc's graf 1->3 ("opencv-doc graf"),
/// in that order; `only`, when not empty, is a comma-framed list (",graf,boat,") of the sequences
/// to keep ("opencv-doc" for the last pair).
inline std::vector<ViewpointPair> viewpoint_pairs(const std::string& only = "") {
  std::vector<ViewpointPair> pairs;
  const std::string oxford = data_dir() + "/oxford/";
  for (const std::string sequence : {"graf", "boat", "bark", "bikes", "trees", "leuven"}) {
    if (!only.empty() && only.find("," + sequence + ",") == std::string::npos) continue;
    for (int n = 2; n <= 6; ++n) {
      pairs.push_back({sequence, n, oxford + sequence + "/img1.png",
                       oxford + sequence + "/img" + std::to_string(n) + ".png",
                       read_oxford_homography(oxford + sequence + "/H1to" + std::to_string(n) + "p")});
    }
  }
  if (only.empty() || only.find(",opencv-doc,") != std::string::npos) {
    const std::string doc = opencv_samples_dir();
    cv::Mat h;
    cv::FileStorage fs(doc + "/H1to3p.xml", cv::FileStorage::READ);
    if (fs.isOpened()) fs.getFirstTopLevelNode() >> h;
    if (h.empty()) throw std::runtime_error("cannot read " + doc + "/H1to3p.xml");
    pairs.push_back({"opencv-doc graf", 3, doc + "/graf1.png", doc + "/graf3.png", cv::Matx33d(h)});
  }
  return pairs;
}

/// The pairs of ../shared/data/pairs/: every `<subset>/<name>/H_1_j` with its images `1.*` and
/// `j.*`, subsets in the order hpatches, homogr, evd and names sorted; `subsets`, when not empty, is
/// a comma-framed list (",hpatches,evd,") of the subsets to keep. Sequence names are
/// "<subset>/<name>".
inline std::vector<ViewpointPair> data_pairs(const std::string& subsets = "") {
  namespace fs = std::filesystem;
  const auto image_path = [](const fs::path& folder, int index) {
    for (const char* ext : {".png", ".ppm", ".jpg", ".jpeg", ".pgm"}) {
      const fs::path p = folder / (std::to_string(index) + ext);
      if (fs::exists(p)) return p.string();
    }
    throw std::runtime_error("no image " + std::to_string(index) + " in " + folder.string());
  };
  std::vector<ViewpointPair> pairs;
  for (const std::string subset : {"hpatches", "homogr", "evd"}) {
    if (!subsets.empty() && subsets.find("," + subset + ",") == std::string::npos) continue;
    const fs::path root = fs::path(data_dir()) / "pairs" / subset;
    std::vector<fs::path> folders;
    for (const auto& entry : fs::directory_iterator(root)) {
      if (entry.is_directory()) folders.push_back(entry.path());
    }
    std::sort(folders.begin(), folders.end());
    for (const fs::path& folder : folders) {
      for (int j = 2; j <= 6; ++j) {
        const fs::path h = folder / ("H_1_" + std::to_string(j));
        if (!fs::exists(h)) continue;
        pairs.push_back({subset + "/" + folder.filename().string(), j, image_path(folder, 1), image_path(folder, j),
                         read_oxford_homography(h.string()), subset});
      }
    }
  }
  return pairs;
}

inline cv::Point2d map_point(const cv::Matx33d& h, cv::Point2f p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

/// A match is correct when the ground truth maps its image-1 point within this many pixels of its
/// image-2 point (SPEC §7).
inline constexpr double kCorrectMatchError = 3.0;

/// |h·x1 − x2|, pixels of image 2: a match's distance from the ground truth h.
inline double match_residual(const cv::Matx33d& h, cv::Point2f x1, cv::Point2f x2) {
  const cv::Point2d y = map_point(h, x1);
  return std::hypot(y.x - x2.x, y.y - x2.y);
}

/// Matches the ground truth maps within kCorrectMatchError of their partner, and how many distinct
/// image-1 points (2-px cells) they have.
struct CorrectMatches {
  std::size_t correct = 0;
  std::size_t distinct = 0;
};

inline CorrectMatches correct_matches(const std::vector<std::pair<cv::Point2f, cv::Point2f>>& matches,
                                      const cv::Matx33d& h) {
  CorrectMatches c;
  std::set<std::pair<int, int>> cells;
  for (const auto& [x1, x2] : matches) {
    if (match_residual(h, x1, x2) >= kCorrectMatchError) continue;
    ++c.correct;
    cells.insert({static_cast<int>(std::floor(x1.x / 2)), static_cast<int>(std::floor(x1.y / 2))});
  }
  c.distinct = cells.size();
  return c;
}

/// Mean distance, pixels of image 2, between image 1's four corners mapped by `estimate` and by
/// the ground truth; a pair is solved when it is at most 5 px.
inline double corner_error(const cv::Matx33d& estimate, const cv::Matx33d& truth, cv::Size size1) {
  double sum = 0.0;
  for (const cv::Point2f c : {cv::Point2f(0, 0), cv::Point2f(static_cast<float>(size1.width - 1), 0),
                              cv::Point2f(0, static_cast<float>(size1.height - 1)),
                              cv::Point2f(static_cast<float>(size1.width - 1), static_cast<float>(size1.height - 1))}) {
    const cv::Point2d e = map_point(estimate, c);
    const cv::Point2d t = map_point(truth, c);
    sum += std::hypot(e.x - t.x, e.y - t.y);
  }
  return std::isfinite(sum) ? sum / 4.0 : 1e9;
}

inline constexpr double kSolvedCornerError = 5.0;

/// Mean distance, pixels of image 2, between `estimate` and the ground truth on a 20 x 20 grid of
/// image-1 points (cell centres) that the ground truth maps inside image 2: the judge of the EVD
/// pairs, whose corners fall far outside the other image (../shared/data/README.md). Solved, as
/// for the corners, at most 5 px; 1e9 when no grid point lands inside image 2.
inline double grid_error(const cv::Matx33d& estimate, const cv::Matx33d& truth, cv::Size size1, cv::Size size2) {
  constexpr int kGrid = 20;
  double sum = 0.0;
  int count = 0;
  for (int gy = 0; gy < kGrid; ++gy) {
    for (int gx = 0; gx < kGrid; ++gx) {
      const cv::Point2f p(static_cast<float>((gx + 0.5) * size1.width / kGrid),
                          static_cast<float>((gy + 0.5) * size1.height / kGrid));
      const cv::Vec3d tq = truth * cv::Vec3d(p.x, p.y, 1.0);
      if (tq[2] == 0.0) continue;
      const cv::Point2d t(tq[0] / tq[2], tq[1] / tq[2]);
      if (t.x < 0 || t.y < 0 || t.x > size2.width - 1 || t.y > size2.height - 1) continue;
      const cv::Point2d e = map_point(estimate, p);
      sum += std::hypot(e.x - t.x, e.y - t.y);
      ++count;
    }
  }
  return count > 0 && std::isfinite(sum) ? sum / count : 1e9;
}

/// Float descriptors (SIFT, ASIFT; CV_32F rows) matched by the rules of
/// affine_orb::match_features with its default AffineMatchOptions, on L2 distances: ratio 0.8
/// against the nearest train descriptor farther than 4 px from the best one's keypoint (none among
/// the 32 nearest: accepted), then duplicate correspondences (both points within 2 px) removed,
/// the smaller distance kept.
inline std::vector<affine_orb::Match> match_float(const std::vector<cv::KeyPoint>& keypoints1,
                                                  const cv::Mat& descriptors1,
                                                  const std::vector<cv::KeyPoint>& keypoints2,
                                                  const cv::Mat& descriptors2) {
  if (descriptors1.empty() || descriptors2.empty()) return {};
  const affine_orb::AffineMatchOptions rules;
  const int k = std::min(32, descriptors2.rows);
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_L2).knnMatch(descriptors1, descriptors2, knn, k);
  std::vector<affine_orb::Match> matches;
  for (const auto& neighbours : knn) {
    if (neighbours.empty()) continue;
    const cv::DMatch& best = neighbours.front();
    const cv::Point2f at = keypoints2[static_cast<std::size_t>(best.trainIdx)].pt;
    bool accepted = true;
    for (std::size_t j = 1; j < neighbours.size(); ++j) {
      const cv::Point2f other = keypoints2[static_cast<std::size_t>(neighbours[j].trainIdx)].pt;
      if (std::hypot(other.x - at.x, other.y - at.y) <= rules.ratio_exclusion_radius) continue;
      accepted = best.distance < rules.matcher.ratio * neighbours[j].distance;
      break;
    }
    // Distances scaled to integers for affine_orb::Match; only their order matters.
    if (accepted)
      matches.push_back({best.queryIdx, best.trainIdx, static_cast<int>(std::lround(best.distance * 1000.0f))});
  }
  std::vector<cv::Point2f> p1, p2;
  for (const auto& kp : keypoints1) p1.push_back(kp.pt);
  for (const auto& kp : keypoints2) p2.push_back(kp.pt);
  return affine_orb::remove_duplicate_matches(matches, p1, p2, rules.duplicate_radius);
}

}  // namespace affine_orb::bench
