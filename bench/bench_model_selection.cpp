// Model selection (select_model: RANSAC H and F on the same 8-point sets, eqs. 20–22) against the
// two OpenCV calls a user would otherwise make, cv::findHomography(RANSAC) and
// cv::findFundamentalMat(FM_RANSAC), side by side in one run on the same synthetic data.
//
// Data: 1000 correspondences, 30 % outliers (independent uniform points in both 640x480 images),
// isotropic Gaussian noise of 1 px per coordinate in both images. Two scenes: a tilted plane seen
// by two cameras (H is the truth) and a general 3-D scene, depths 2–10 m, with 0.6 m of
// translation (F is the truth). Every run draws new data (seed = run index); figures are medians
// over the runs.
//
// Accuracy: H: largest distance between the true and the estimated images of the four corners of
// image 1; F: mean distance of the noise-free correspondences to their epipolar lines (both
// images); recall: fraction of the true correspondences flagged as inliers.
//
// Then the decision on labelled real and synthetic pairs, for each rule (SelectionRule): the
// plane-and-parallax test (the default), the paper's eq. 22 at θ = 0.45 and ORB-SLAM2's θ = 0.40,
// Torr's GRIC and COLMAP's inlier ratio, each also with σ scaled by the keypoints' octaves.
// Correspondences come from the affine extractor (1000 + 1000 keypoints, strongest corners) and
// match_features, as affine_orb_match makes them. Labels: H for the planar pairs (every Oxford pair
// 1->2 ... 1->6 in ../shared/data, opencv-doc's graf1/graf3 and box/box_in_scene) and for pure
// camera rotations (four Oxford photos warped by K R K^-1, 6-12 degrees); F for the 3-D pairs (KITTI
// 06 frames i -> i + g for gaps g = 1, 2, 4, 8; KITTI 00 frames i -> i + 3 and i -> i + 6 where the
// camera moved at least 2 m; synthetic 3-D scenes). Pose error: for H-labelled pairs with a
// ground-truth homography, the largest distance between the true and the chosen homography's images
// of the image-1 corners (when H was chosen); for pairs with a known rotation (rotations, KITTI,
// synthetic), the angle between the true rotation and the one relative_pose() recovers from the
// chosen model. The tables are Markdown, as the README quotes them.
//
// Usage: bench_model_selection [runs (default 25)] [--labelled-only]

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/geometry/relative_pose.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "bench_common.hpp"
#include "cli.hpp"
#include "homography_io.hpp"
#include "sequence_io.hpp"

namespace {

using affine_orb::bench::median;
using affine_orb::bench::read_gray_or_exit;
using affine_orb::examples::read_homography;

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr int kCount = 1000;
constexpr double kOutlierRatio = 0.3;
constexpr double kNoise = 1.0;
// OpenCV's default reprojection thresholds (findHomography: 3 px; findFundamentalMat: 3 px at 0.99).
constexpr double kOpenCvThreshold = 3.0;
// Least camera translation of a labelled KITTI 00 pair, metres (ground truth, poses.txt).
constexpr double kMinKittiBaseline = 2.0;

Eigen::Matrix3d intrinsics() {
  Eigen::Matrix3d k;
  k << 500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0;
  return k;
}

struct Data {
  std::vector<cv::Point2f> points1, points2;
  std::vector<Eigen::Vector2d> clean1, clean2;
  std::vector<int> truth;
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();  // the true homography (planar scene)
};

Data make_data(bool planar, std::uint64_t seed) {
  const Eigen::Matrix3d k = intrinsics();
  const Eigen::Matrix3d k_inv = k.inverse();
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(-0.6, 0.05, 0.1);
  const Eigen::Vector3d n = Eigen::Vector3d(0.15, -0.1, 1.0).normalized();
  const double d = 5.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> px(0.0, kWidth - 1), py(0.0, kHeight - 1), depth(2.0, 10.0);
  std::normal_distribution<double> noise(0.0, kNoise);
  Data data;
  data.h = k * (r + t * n.transpose() / d) * k_inv;
  std::vector<int> kinds(kCount, 1);
  std::fill(kinds.begin(), kinds.begin() + static_cast<int>(kOutlierRatio * kCount), 0);
  std::shuffle(kinds.begin(), kinds.end(), rng);
  for (const int kind : kinds) {
    if (kind == 0) {
      data.points1.emplace_back(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
      data.points2.emplace_back(static_cast<float>(px(rng)), static_cast<float>(py(rng)));
      data.truth.push_back(0);
      continue;
    }
    Eigen::Vector2d x1, x2;
    while (true) {
      x1 = Eigen::Vector2d(px(rng), py(rng));
      const Eigen::Vector3d ray = k_inv * x1.homogeneous();
      const double z = planar ? d / n.dot(ray) : depth(rng);
      const Eigen::Vector3d seen = r * (z * ray) + t;
      x2 = (k * seen).hnormalized();
      if (seen.z() > 0.0 && x2.x() >= 0.0 && x2.x() <= kWidth - 1 && x2.y() >= 0.0 && x2.y() <= kHeight - 1) break;
    }
    data.clean1.push_back(x1);
    data.clean2.push_back(x2);
    data.points1.emplace_back(static_cast<float>(x1.x() + noise(rng)), static_cast<float>(x1.y() + noise(rng)));
    data.points2.emplace_back(static_cast<float>(x2.x() + noise(rng)), static_cast<float>(x2.y() + noise(rng)));
    data.truth.push_back(1);
  }
  return data;
}

double corner_error(const Eigen::Matrix3d& h, const Eigen::Matrix3d& truth) {
  double worst = 0.0;
  for (const Eigen::Vector2d& c : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(kWidth - 1, 0.0),
                                   Eigen::Vector2d(0.0, kHeight - 1), Eigen::Vector2d(kWidth - 1, kHeight - 1)}) {
    worst = std::max(worst, ((h * c.homogeneous()).hnormalized() - (truth * c.homogeneous()).hnormalized()).norm());
  }
  return worst;
}

double epipolar_distance(const Eigen::Matrix3d& f, const Data& data) {
  double sum = 0.0;
  for (std::size_t i = 0; i < data.clean1.size(); ++i) {
    const std::array<double, 2> d = affine_orb::epipolar_squared_distances(f, data.clean1[i], data.clean2[i]);
    sum += std::sqrt(d[0]) + std::sqrt(d[1]);
  }
  return sum / (2.0 * static_cast<double>(data.clean1.size()));
}

template <class Mask>
double recall(const Mask& mask, const Data& data) {
  int found = 0, total = 0;
  for (std::size_t i = 0; i < data.truth.size(); ++i) {
    total += data.truth[i];
    found += data.truth[i] != 0 && mask[i] != 0 ? 1 : 0;
  }
  return static_cast<double>(found) / total;
}

Eigen::Matrix3d to_eigen(const cv::Mat& m) {
  Eigen::Matrix3d out = Eigen::Matrix3d::Constant(std::nan(""));
  if (m.rows != 3 || m.cols != 3) return out;  // OpenCV found nothing
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m.at<double>(r, c);
  }
  return out;
}

// "87 %": share of non-zero entries.
std::string percent(const std::vector<double>& flags) {
  double sum = 0.0;
  for (const double f : flags) sum += f;
  return std::to_string(static_cast<int>(std::lround(100.0 * sum / static_cast<double>(flags.size())))) + " %";
}

struct Figures {
  std::vector<double> time_ms, h_corner, h_recall, f_distance, f_recall, homography_chosen;
};

/// A pair with its label and what is known of its geometry.
struct LabelledPair {
  std::string name;
  std::string kind;  ///< "planar" (H), "rotation" (H) or "3-D" (F)
  std::vector<cv::Point2f> points1, points2;
  std::vector<int> octaves1, octaves2;  ///< pyramid octave of each matched keypoint (0 for synthetic points)
  cv::Size size1;
  std::optional<Eigen::Matrix3d> homography;  ///< x2 ~ H x1, when known
  std::optional<Eigen::Matrix3d> rotation;    ///< X2 = R X1 (+ t), when known with the camera
  std::optional<affine_orb::PinholeCamera> camera;
};

/// A pair named `name` of kind `kind` whose first image is `image1`; the rest filled by the caller.
LabelledPair labelled(const std::string& name, const std::string& kind, const cv::Mat& image1) {
  LabelledPair p;
  p.name = name;
  p.kind = kind;
  p.size1 = image1.size();
  return p;
}

double corner_error(const Eigen::Matrix3d& h, const Eigen::Matrix3d& truth, cv::Size size) {
  double worst = 0.0;
  for (const Eigen::Vector2d& c :
       {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(size.width - 1, 0.0), Eigen::Vector2d(0.0, size.height - 1),
        Eigen::Vector2d(size.width - 1, size.height - 1)}) {
    worst = std::max(worst, ((h * c.homogeneous()).hnormalized() - (truth * c.homogeneous()).hnormalized()).norm());
  }
  return worst;
}

/// Fills `p` with the matched keypoint positions and octaves of two images, as affine_orb_match
/// makes them.
void match_into(LabelledPair& p, affine_orb::Extractor<affine_orb::Rbrief>& extractor, const cv::Mat& a,
                const cv::Mat& b) {
  const auto fa = extractor.extract(a);
  const auto fb = extractor.extract(b);
  for (const affine_orb::Match& m : affine_orb::match_features(fa, fb)) {
    const cv::KeyPoint& ka = fa.keypoints[static_cast<std::size_t>(m.query)];
    const cv::KeyPoint& kb = fb.keypoints[static_cast<std::size_t>(m.train)];
    p.points1.push_back(ka.pt);
    p.points2.push_back(kb.pt);
    p.octaves1.push_back(ka.octave);
    p.octaves2.push_back(kb.octave);
  }
}

using PairExtractor = affine_orb::Extractor<affine_orb::Rbrief>;

/// Every Oxford pair 1->2 ... 1->6 with its ground-truth homography, then opencv-doc's graf1->graf3
/// (with its homography) and box->box_in_scene; all planar.
void add_planar_pairs(PairExtractor& extractor, std::vector<LabelledPair>& pairs) {
  const std::string data = affine_orb::bench::data_dir();
  const std::string doc = affine_orb::bench::opencv_samples_dir();
  for (const std::string sequence : {"graf", "boat", "bark", "bikes", "trees", "leuven"}) {
    const cv::Mat a = read_gray_or_exit(data + "/oxford/" + sequence + "/img1.png");
    for (int n = 2; n <= 6; ++n) {
      LabelledPair p = labelled(sequence + " 1->" + std::to_string(n), "planar", a);
      match_into(p, extractor, a,
                 read_gray_or_exit(data + "/oxford/" + sequence + "/img" + std::to_string(n) + ".png"));
      p.homography =
          to_eigen(cv::Mat(read_homography(data + "/oxford/" + sequence + "/H1to" + std::to_string(n) + "p")));
      pairs.push_back(p);
    }
  }
  const cv::Mat a = read_gray_or_exit(doc + "/graf1.png");
  LabelledPair p = labelled("opencv-doc graf1->graf3", "planar", a);
  match_into(p, extractor, a, read_gray_or_exit(doc + "/graf3.png"));
  p.homography = to_eigen(cv::Mat(read_homography(doc + "/H1to3p.xml")));
  pairs.push_back(p);
  const cv::Mat box = read_gray_or_exit(doc + "/box.png");
  LabelledPair q = labelled("opencv-doc box->box_in_scene", "planar", box);
  match_into(q, extractor, box, read_gray_or_exit(doc + "/box_in_scene.png"));
  pairs.push_back(q);
}

/// Pure rotations: a photo and its image by a camera turned by R about its centre, x2 ~ K R K^-1 x1.
void add_rotation_pairs(PairExtractor& extractor, std::vector<LabelledPair>& pairs) {
  const std::string data = affine_orb::bench::data_dir();
  const std::array<std::pair<std::string, double>, 4> rotated = {
      std::make_pair("graf", 6.0), std::make_pair("boat", 8.0), std::make_pair("bikes", 10.0),
      std::make_pair("leuven", 12.0)};
  for (const auto& [sequence, degrees] : rotated) {
    const cv::Mat a = read_gray_or_exit(data + "/oxford/" + sequence + "/img1.png");
    affine_orb::PinholeCamera camera{0.9 * a.cols, 0.9 * a.cols, (a.cols - 1) / 2.0, (a.rows - 1) / 2.0};
    Eigen::Matrix3d k;
    k << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(degrees * CV_PI / 180.0, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
    const Eigen::Matrix3d h = k * r * k.inverse();
    cv::Mat warp(3, 3, CV_64F);
    for (int i = 0; i < 9; ++i) warp.at<double>(i / 3, i % 3) = h(i / 3, i % 3);
    cv::Mat b;
    cv::warpPerspective(a, b, warp, a.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    LabelledPair p =
        labelled(sequence + " turned " + std::to_string(static_cast<int>(degrees)) + " deg", "rotation", a);
    p.homography = h;
    p.rotation = r;
    p.camera = camera;
    match_into(p, extractor, a, b);
    pairs.push_back(p);
  }
}

/// The 3-D pair of `sequence`'s frames i -> i + gap, named "`label` i->i+gap", with its true
/// relative rotation and the sequence's camera.
LabelledPair kitti_pair(PairExtractor& extractor, const affine_orb::examples::Sequence& sequence,
                        const std::string& label, int i, int gap) {
  const auto& f1 = sequence.frames[static_cast<std::size_t>(i)];
  const auto& f2 = sequence.frames[static_cast<std::size_t>(i + gap)];
  const cv::Mat a = affine_orb::examples::load_frame(f1);
  LabelledPair p = labelled(label + " " + std::to_string(i) + "->" + std::to_string(i + gap), "3-D", a);
  p.rotation = affine_orb::examples::relative_rotation(*f1.pose, *f2.pose);
  p.camera = sequence.camera;
  match_into(p, extractor, a, affine_orb::examples::load_frame(f2));
  return p;
}

/// KITTI 06: real 3-D street scenes, frame gaps 1, 2, 4, 8. KITTI 00: real forward driving (the
/// car drives off and takes its first turn), frames i -> i + 3 and i -> i + 6 for i = 0, 10, ...,
/// 150, kept when poses.txt gives the camera a translation of at least 2 m between them: under
/// forward motion parallax grows with the baseline, and 2 m makes the scene clearly 3-D for the
/// near half of the image (road, parked cars, walls).
void add_kitti_pairs(PairExtractor& extractor, std::vector<LabelledPair>& pairs) {
  const std::string data = affine_orb::bench::data_dir();
  const affine_orb::examples::Sequence kitti = affine_orb::examples::read_kitti(data + "/kitti06");
  for (const int gap : {1, 2, 4, 8}) {
    for (int i = 0; i + gap < static_cast<int>(kitti.frames.size()); i += 10) {
      pairs.push_back(kitti_pair(extractor, kitti, "KITTI 06", i, gap));
    }
  }
  const affine_orb::examples::Sequence kitti00 = affine_orb::examples::read_kitti(data + "/kitti00");
  for (int i = 0; i + 3 < static_cast<int>(kitti00.frames.size()); i += 10) {
    for (const int gap : {3, 6}) {
      if (i + gap >= static_cast<int>(kitti00.frames.size())) continue;
      const auto& f1 = kitti00.frames[static_cast<std::size_t>(i)];
      const auto& f2 = kitti00.frames[static_cast<std::size_t>(i + gap)];
      if ((f2.pose->position - f1.pose->position).norm() < kMinKittiBaseline) continue;
      pairs.push_back(kitti_pair(extractor, kitti00, "KITTI 00", i, gap));
    }
  }
}

/// Synthetic 3-D scenes (make_data(): depths 2-10 m, 0.6 m of translation, 30 % outliers).
void add_synthetic_pairs(std::vector<LabelledPair>& pairs) {
  const Eigen::Matrix3d k = intrinsics();
  for (std::uint64_t seed = 1000; seed < 1010; ++seed) {
    const Data d = make_data(false, seed);
    LabelledPair p = labelled("synthetic 3-D #" + std::to_string(seed - 999), "3-D", cv::Mat(kHeight, kWidth, CV_8UC1));
    p.points1 = d.points1;
    p.points2 = d.points2;
    p.octaves1.assign(d.points1.size(), 0);
    p.octaves2.assign(d.points2.size(), 0);
    p.rotation = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
    p.camera = affine_orb::PinholeCamera{k(0, 0), k(1, 1), k(0, 2), k(1, 2)};
    pairs.push_back(p);
  }
}

/// Every labelled pair: planar, rotations, KITTI, synthetic, in that order.
std::vector<LabelledPair> labelled_pairs() {
  affine_orb::ExtractorOptions options;
  options.spreading = affine_orb::Spreading::kStrongest;
  options.threads = 2;
  PairExtractor extractor(options);
  std::vector<LabelledPair> pairs;
  add_planar_pairs(extractor, pairs);
  add_rotation_pairs(extractor, pairs);
  add_kitti_pairs(extractor, pairs);
  add_synthetic_pairs(pairs);
  return pairs;
}

/// A selection rule of the decision table.
struct Rule {
  std::string name;
  affine_orb::ModelSelectionOptions options;
  bool octaves = false;  ///< σ scaled by each keypoint's octave (select_model() with octaves)
};

/// The rules of the decision table, the default first.
std::vector<Rule> selection_rules() {
  using affine_orb::SelectionRule;
  const auto make_rule = [](const std::string& name, SelectionRule r, bool octaves) {
    Rule out{name, {}, octaves};
    out.options.rule = r;
    return out;
  };
  std::vector<Rule> rules = {
      make_rule("plane-and-parallax test (DEGENSAC-style), z <= 3.8 (default)", SelectionRule::kPlaneParallax, false),
      make_rule("plane-and-parallax test, octave sigma", SelectionRule::kPlaneParallax, true),
      make_rule("eq. 22, R_H > 0.45 (paper)", SelectionRule::kScoreRatio, false),
      make_rule("eq. 22, R_H > 0.45, octave sigma", SelectionRule::kScoreRatio, true),
      make_rule("eq. 22, R_H > 0.40 (ORB-SLAM2)", SelectionRule::kScoreRatio, false),
      make_rule("GRIC (Torr 1998), sigma 1 px", SelectionRule::kGric, false),
      make_rule("GRIC, sigma 1 px, octave sigma", SelectionRule::kGric, true),
      make_rule("GRIC, sigma 2 px", SelectionRule::kGric, false),
      make_rule("COLMAP inlier ratio H/F > 0.8", SelectionRule::kInlierRatio, false),
      make_rule("COLMAP inlier ratio H/F > 0.8, octave sigma", SelectionRule::kInlierRatio, true),
  };
  rules[4].options.score_ratio.threshold = 0.40;
  rules[7].options.gric.sigma = 2.0;
  return rules;
}

/// Prints the decision table's line of `rule` over `pairs`: right decisions per class, median
/// corner and rotation errors, the pairs it gets wrong.
void print_rule_line(const Rule& rule, const std::vector<LabelledPair>& pairs) {
  std::map<std::string, std::pair<int, int>> right;  // kind -> (right, total)
  std::vector<double> corner, rotation_error_rot, rotation_error_3d;
  std::string wrong;
  for (const LabelledPair& p : pairs) {
    affine_orb::ModelSelectionResult r;
    if (p.points1.size() >= 8) {
      r = rule.octaves ? affine_orb::select_model(p.points1, p.points2, p.octaves1, p.octaves2, rule.options)
                       : affine_orb::select_model(p.points1, p.points2, rule.options);
    }
    const bool want_h = p.kind != "3-D";
    const bool is_right = r.success && (r.model == affine_orb::GeometricModel::kHomography) == want_h;
    right[p.kind].first += is_right;
    right[p.kind].second += 1;
    if (!is_right) wrong += (wrong.empty() ? "" : ", ") + p.name;
    if (p.homography && r.model == affine_orb::GeometricModel::kHomography)
      corner.push_back(corner_error(r.homography, *p.homography, p.size1));
    if (p.rotation && p.camera && r.success) {
      const affine_orb::RelativePose pose = affine_orb::relative_pose(r, *p.camera, p.points1, p.points2);
      if (pose.success)
        (p.kind == "rotation" ? rotation_error_rot : rotation_error_3d)
            .push_back(affine_orb::rotation_angle_degrees(pose.rotation, *p.rotation));
    }
  }
  auto share = [&](const std::string& kind) {
    const auto [ok, total] = right[kind];
    char text[32];
    std::snprintf(text, sizeof(text), "%d / %d", ok, total);
    return std::string(text);
  };
  auto med = [](const std::vector<double>& v) { return v.empty() ? std::nan("") : median(v); };
  std::printf("| %s | %s | %s | %s | %.2f | %.3f / %.3f | %s |\n", rule.name.c_str(), share("planar").c_str(),
              share("rotation").c_str(), share("3-D").c_str(), med(corner), med(rotation_error_rot),
              med(rotation_error_3d), wrong.empty() ? "none" : wrong.c_str());
}

/// The decision table: per rule, the right decisions per class and the pose errors; then the
/// statistics of the default rule and of eq. 22 per pair, to show the margins.
void labelled_table() {
  const std::vector<LabelledPair> pairs = labelled_pairs();
  std::printf(
      "\n## H or F on labelled pairs\n\n%zu pairs; right = H chosen on planar and rotation pairs, F on 3-D "
      "pairs; corner error = median px of the chosen H on the pairs with a ground-truth H where H was "
      "chosen; rotation error = median degrees of relative_pose() from the chosen model.\n\n",
      pairs.size());
  std::printf(
      "| rule | planar right | rotations right | 3-D right | planar corner error px | rotation error deg, "
      "rotations / 3-D | wrong pairs |\n|---|---:|---:|---:|---:|---:|---|\n");
  for (const Rule& rule : selection_rules()) print_rule_line(rule, pairs);
  std::printf("\nPer pair: parallax z-score of the default rule (H when <= %.1f), R_H of eq. 22 (H when > %.2f):\n\n",
              affine_orb::ModelSelectionOptions{}.plane_parallax.significance,
              affine_orb::ModelSelectionOptions{}.score_ratio.threshold);
  std::printf(
      "| pair | label | matches | parallax inliers | expected by chance | z | R_H "
      "|\n|---|---|---:|---:|---:|---:|---:|\n");
  for (const LabelledPair& p : pairs) {
    if (p.points1.size() < 8) continue;
    const affine_orb::ModelSelectionResult r = affine_orb::select_model(p.points1, p.points2);
    std::printf("| %s | %s | %zu | %d | %.1f | %.1f | %.3f |\n", p.name.c_str(), p.kind == "3-D" ? "F" : "H",
                p.points1.size(), r.parallax_inlier_count, r.parallax_expected_count, r.parallax_significance,
                r.homography_ratio);
  }
}

/// The figures of the synthetic runs: per scene, ours with σ 2 (the default) and σ 1 in [0], [1],
/// both OpenCV calls in [2], and OpenCV's two calls' times separately.
struct SyntheticFigures {
  std::array<Figures, 3> planar, general;
  std::vector<double> cv_h_planar, cv_f_planar, cv_h_general, cv_f_general;
};

/// Our two σ, the default first.
std::array<affine_orb::ModelSelectionOptions, 2> our_options() {
  affine_orb::ModelSelectionOptions sigma2;
  // The score's σ for this per-image noise (the default), see ModelSelectionOptions::sigma.
  sigma2.sigma = 2.0 * kNoise;
  affine_orb::ModelSelectionOptions sigma1;
  sigma1.sigma = kNoise;  // ORB-SLAM2's value
  return {sigma2, sigma1};
}

/// Runs both OpenCV calls on `data` and records their times and accuracy in `out`.
void run_opencv(const Data& data, bool is_planar, SyntheticFigures& out) {
  cv::Mat h_mask, f_mask;
  const auto start_h = std::chrono::steady_clock::now();
  const cv::Mat h = cv::findHomography(data.points1, data.points2, cv::RANSAC, kOpenCvThreshold, h_mask);
  const double h_ms = affine_orb::examples::ms_since(start_h);
  const auto start_f = std::chrono::steady_clock::now();
  const cv::Mat f = cv::findFundamentalMat(data.points1, data.points2, cv::FM_RANSAC, kOpenCvThreshold, 0.99, f_mask);
  const double f_ms = affine_orb::examples::ms_since(start_f);
  (is_planar ? out.cv_h_planar : out.cv_h_general).push_back(h_ms);
  (is_planar ? out.cv_f_planar : out.cv_f_general).push_back(f_ms);
  Figures& peer = (is_planar ? out.planar : out.general)[2];
  peer.time_ms.push_back(h_ms + f_ms);
  if (is_planar) {
    peer.h_corner.push_back(corner_error(to_eigen(h), data.h));
    peer.h_recall.push_back(h_mask.empty() ? 0.0 : recall(h_mask.ptr<std::uint8_t>(), data));
  } else {
    peer.f_distance.push_back(epipolar_distance(to_eigen(f), data));
    peer.f_recall.push_back(f_mask.empty() ? 0.0 : recall(f_mask.ptr<std::uint8_t>(), data));
  }
}

/// `runs` runs of both scenes, new data each (seed = 2 run + scene), ours and OpenCV's.
SyntheticFigures run_synthetic(int runs) {
  const std::array<affine_orb::ModelSelectionOptions, 2> ours = our_options();
  SyntheticFigures out;
  for (int run = 0; run < runs; ++run) {
    for (const bool is_planar : {true, false}) {
      const Data data = make_data(is_planar, static_cast<std::uint64_t>(run) * 2 + (is_planar ? 0 : 1));
      std::array<Figures, 3>& figures = is_planar ? out.planar : out.general;
      for (std::size_t which = 0; which < ours.size(); ++which) {
        const auto start = std::chrono::steady_clock::now();
        const affine_orb::ModelSelectionResult r = affine_orb::select_model(data.points1, data.points2, ours[which]);
        Figures& f = figures[which];
        f.time_ms.push_back(affine_orb::examples::ms_since(start));
        f.homography_chosen.push_back(r.model == affine_orb::GeometricModel::kHomography ? 1.0 : 0.0);
        if (is_planar) {
          f.h_corner.push_back(r.homography_found ? corner_error(r.homography, data.h) : std::nan(""));
          f.h_recall.push_back(recall(r.homography_inliers, data));
        } else {
          f.f_distance.push_back(r.fundamental_found ? epipolar_distance(r.fundamental, data) : std::nan(""));
          f.f_recall.push_back(recall(r.fundamental_inliers, data));
        }
      }
      run_opencv(data, is_planar, out);
    }
  }
  return out;
}

/// Prints the time table of the synthetic runs: per scene, ours and OpenCV's, and their ratios.
void print_time_table(const SyntheticFigures& s, int runs) {
  std::printf(
      "Model selection, %d correspondences, %.0f %% outliers, %.1f px Gaussian noise per coordinate in "
      "each image; medians over %d runs (new data each run), one thread.\n\n",
      kCount, 100.0 * kOutlierRatio, kNoise, runs);
  std::printf("Time, ms:\n\n");
  std::printf(
      "| scene | ours sigma 2 | ours sigma 1 | cv::findHomography | cv::findFundamentalMat | both cv calls | "
      "ratio ours sigma 2 / both | ratio ours sigma 1 / both |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const bool is_planar : {true, false}) {
    const std::array<Figures, 3>& f = is_planar ? s.planar : s.general;
    const double both = median(f[2].time_ms);
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f |\n", is_planar ? "planar" : "3-D",
                median(f[0].time_ms), median(f[1].time_ms), median(is_planar ? s.cv_h_planar : s.cv_h_general),
                median(is_planar ? s.cv_f_planar : s.cv_f_general), both, median(f[0].time_ms) / both,
                median(f[1].time_ms) / both);
  }
}

/// Prints the accuracy table of the synthetic runs: H on the planar scene, F on the 3-D one.
void print_accuracy_table(const SyntheticFigures& s) {
  const std::array<const char*, 2> our_names = {"affine_orb select_model, sigma 2 px (default)",
                                                "affine_orb select_model, sigma 1 px (ORB-SLAM2)"};
  const std::array<Figures, 3>& planar = s.planar;
  const std::array<Figures, 3>& general = s.general;
  std::printf("\nAccuracy (H on the planar scene, F on the 3-D scene):\n\n");
  std::printf(
      "| method | H corner error px | H inlier recall | F epipolar distance px | F inlier recall | H chosen, "
      "planar | H chosen, 3-D |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (std::size_t which = 0; which < 3; ++which) {
    const bool peer = which == 2;
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %s | %s |\n",
                peer ? "cv::findHomography + cv::findFundamentalMat" : our_names[which], median(planar[which].h_corner),
                median(planar[which].h_recall), median(general[which].f_distance), median(general[which].f_recall),
                peer ? "n/a" : percent(planar[which].homography_chosen).c_str(),
                peer ? "n/a" : percent(general[which].homography_chosen).c_str());
  }
  for (std::size_t which = 0; which < 2; ++which) {
    std::printf("| ratio ours/cv, %s | %.2f | %.2f | %.2f | %.2f | | |\n", which == 0 ? "sigma 2" : "sigma 1",
                median(planar[which].h_corner) / median(planar[2].h_corner),
                median(planar[which].h_recall) / median(planar[2].h_recall),
                median(general[which].f_distance) / median(general[2].f_distance),
                median(general[which].f_recall) / median(general[2].f_recall));
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool labelled_only = argc > 1 && std::string(argv[argc - 1]) == "--labelled-only";
  if (!labelled_only) {
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 25;
    cv::setNumThreads(1);  // both sides on one thread
    const SyntheticFigures figures = run_synthetic(runs);
    print_time_table(figures, runs);
    print_accuracy_table(figures);
  }
  labelled_table();
  return 0;
}
