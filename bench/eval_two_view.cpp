// eval_two_view [--out DIR] [--subsets oxford,hpatches,homogr,evd] [--sequences a,b,...]
//               [--methods SUBSTRING,...] [--asift-sequences a,b,...|all] [--peer-cache FILE] [--sweep]
//               [--placement] [--origins] [--repeats N] [--judge-spread N] [--seeds N]
//
// Two-view matching judged where users feel it: on every Oxford pair 1->2 ... 1->6, opencv-doc's
// graf 1->3 (subset "oxford") and every pair of ../shared/data/pairs/ (hpatches, homogr, evd), per
// pair and method, whether the pair is solved (the homography that the RANSAC judge,
// cv::findHomography with RANSAC at 3 px, 10 000 iterations, confidence 0.999, estimates from the
// method's matches puts image 1's corners within 5 px of the ground truth's, mean of the four; on
// EVD a 20 x 20 grid of image-1 points that the ground truth maps inside image 2), the same error
// for the MAGSAC++ judge (cv::USAC_MAGSAC, 3 px) and for the method's own homography, its distinct
// correct matches (within 3 px, image-1 points in
// distinct 2-px cells) and the total time: both extractions, matching and verification by the
// method's own select_model(), single thread, peers in the same run, pair after pair. The matcher's correspondences are
// its query keypoints and TwoViewResult::points2 (the train keypoints' positions unless aligned).
//
// Methods: ours plain 2000 (rBRIEF, strongest corners), the affine default (1000 image + 1000 view
// keypoints, one-shot views), both also with ExtractorOptions::subpixel, the two-view matcher with views on demand
// (TwoViewMatcher's defaults; with sub-pixel keypoints; with aligned correspondences
// (TwoViewOptions::align_correspondences), with and without sub-pixel keypoints; with stages to tilt 4√2; with the
// precision test max_half_disagreement at 5 px and off; without guided matching, with and without the precision test;
// without the final fit of the homography (TwoViewOptions::final_fit), with and without guided matching; with
// min_inliers 15 and without the last stage's search, the matcher before those defaults), cv::ORB 2000, cv::AKAZE,
// cv::SIFT, cv::AffineFeature(cv::ORB) with 18 views (43 on EVD: tilts to 4√2, maxTilt 5) and ASIFT
// (cv::AffineFeature(cv::SIFT), the same views; graf and opencv-doc only unless --asift-sequences says otherwise: its
// float matching takes minutes a pair). Every method but the matcher is verified by select_model() with the matcher's
// ModelSelectionOptions, so the own homographies come from the same estimator. --peer-cache FILE reads the OpenCV
// peers' rows from FILE when there and appends the ones it computes, so that reruns of our methods are cheap.
// --sweep adds matcher variants (stages, min_inliers, the support tests, the final fit's Cauchy
// scale and max_error, the RANSAC searches, the last stage's search, the alignment's options, the
// rule choosing between H and F), the measurement behind TwoViewOptions' defaults. --placement
// adds where the keypoints land: for plain 2000 and views on demand, with and without sub-pixel
// positions, per octave of the keypoint in image 1 and in image 2, the residuals |H·x1 − x2|
// (ground truth H, pixels of image 2, level-0 coordinates) of the matches correct within 3 px over
// all pairs run: count, median and 90th percentile. --repeats N
// runs every method it computes N times on each pair in a row and reports the median time (the
// methods are deterministic: the outcome is the last run's); one run by default. Rows read from
// --peer-cache keep the time of the run that wrote them. --origins adds, per matcher and subset, the
// correct matches by the stage that extracted them (which stage finds them). --judge-spread N runs,
// for the matchers, the MAGSAC++ judge on N seeded reorderings of the same returned matches and
// tables where the own model lies against the range of those estimates (the judge's own run-to-run
// range: differences inside it are not the estimator's). --seeds N runs our methods N times, the k-th
// with the seeds of their RANSAC searches offset by k (ModelSelectionOptions::ransac, the last
// stage's search; k = 0: the options as they are, the run every other table reports), and tables
// the own model's AUC@5 per group over the seeds, median and range, and each method's difference
// from "ours views on demand" seed by seed: the matcher's own run-to-run range, which a change of
// default must clear. The CSV holds every seed's rows (column seed), the per-pair Markdown seed 0's.
//
// --methods keeps the methods whose name contains one of the comma-separated substrings, or, for an
// entry that starts with '=', whose name is the rest of it.
//
// Writes DIR/eval_two_view.md (per subset and method, pairs solved and seconds, and the union of
// all methods; AUC@3 / @5 / @10 of the corner error for the own model and both judges, per subset,
// over all pairs and over the pairs of odd and even index in the run's list, the halves on which
// a default change must win as well (docs/two_view.md); the matchers' false accepts and false
// refusals, and the unverified pairs by the test that refused them (TwoViewStageReport::failure);
// the summary over all pairs; then every pair) and
// DIR/eval_two_view.csv, and prints the Markdown.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"
#include "viewpoint_pairs.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using PointPairs = std::vector<std::pair<cv::Point2f, cv::Point2f>>;

/// What a method made of a pair.
struct Outcome {
  PointPairs matches;
  bool homography_found = false;
  cv::Matx33d homography;
  double ms = 0.0;
  int keypoints1 = 0, keypoints2 = 0;
  int stage = -1;         ///< matcher only: the stage it stopped at
  bool verified = false;  ///< matcher only
  std::string stages;     ///< matcher only: per stage run, matches / inliers and the model chosen
  /// matcher only: the test the last stage failed, nullopt when verified
  std::optional<affine_orb::VerificationFailure> failure;
  std::vector<std::pair<int, int>> octaves;  ///< ours only: per match, the octaves of its two keypoints
  std::vector<int> origins;                  ///< matcher only: per match, the stage that extracted its later keypoint
};

struct Method {
  std::string name;
  std::function<Outcome(const cv::Mat&, const cv::Mat&, const affine_orb::bench::ViewpointPair&)> run;
  bool matcher = false;
  bool peer = false;  ///< an OpenCV peer: its rows may come from the --peer-cache file
  int stages = 0;     ///< matcher only: its number of stages after stage 0
};

double since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

cv::Matx33d to_matx(const Eigen::Matrix3d& h) {
  cv::Matx33d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = h(r, c);
  return m;
}

/// Verification shared by every method but the matcher: select_model() on the matched points.
void verify(Outcome& o, const affine_orb::ModelSelectionOptions& model) {
  if (o.matches.size() < 8) return;
  std::vector<cv::Point2f> p1, p2;
  for (const auto& [a, b] : o.matches) {
    p1.push_back(a);
    p2.push_back(b);
  }
  const affine_orb::ModelSelectionResult r = affine_orb::select_model(p1, p2, model);
  o.homography_found = r.homography_found;
  if (r.homography_found) o.homography = to_matx(r.homography);
}

/// Ours, one-shot extraction of both images with `options`, matched by match_features().
Method ours(const std::string& name, const affine_orb::ExtractorOptions& options,
            const affine_orb::ModelSelectionOptions& model) {
  auto extractor = std::make_shared<affine_orb::Extractor<affine_orb::Rbrief>>(options);
  return {name, [extractor, model](const cv::Mat& a, const cv::Mat& b, const affine_orb::bench::ViewpointPair&) {
            Outcome o;
            const auto start = Clock::now();
            const auto f1 = extractor->extract(a);
            const auto f2 = extractor->extract(b);
            for (const affine_orb::Match& m : affine_orb::match_features(f1, f2)) {
              const cv::KeyPoint& k1 = f1.keypoints[static_cast<std::size_t>(m.query)];
              const cv::KeyPoint& k2 = f2.keypoints[static_cast<std::size_t>(m.train)];
              o.matches.emplace_back(k1.pt, k2.pt);
              o.octaves.emplace_back(k1.octave, k2.octave);
            }
            verify(o, model);
            o.ms = since(start);
            o.keypoints1 = static_cast<int>(f1.size());
            o.keypoints2 = static_cast<int>(f2.size());
            return o;
          }};
}

/// The two-view matcher with views on demand.
Method two_view(const std::string& name, const affine_orb::TwoViewOptions& options) {
  auto matcher = std::make_shared<affine_orb::TwoViewMatcher<affine_orb::Rbrief>>(options);
  // Per view index (Features::views), the stage that extracts it: 0 for the image, else the first
  // stage whose max_tilt covers the view's tilt.
  std::vector<int> view_stage;
  for (const auto& [tilt, rotation] : affine_orb::view_parameters(options.extractor.views)) {
    int stage = 0;
    while (tilt > 1.0 && stage < static_cast<int>(options.stages.size()) &&
           tilt > options.stages[static_cast<std::size_t>(stage)].max_tilt * (1.0 + 1e-3)) {
      ++stage;
    }
    view_stage.push_back(tilt > 1.0 ? stage + 1 : 0);
  }
  return {name,
          [matcher, view_stage](const cv::Mat& a, const cv::Mat& b, const affine_orb::bench::ViewpointPair&) {
            Outcome o;
            const auto start = Clock::now();
            const auto r = matcher->match(a, b);
            o.ms = since(start);
            for (std::size_t i = 0; i < r.matches.size(); ++i) {
              const cv::KeyPoint& k1 = r.features1.keypoints[static_cast<std::size_t>(r.matches[i].query)];
              const cv::KeyPoint& k2 = r.features2.keypoints[static_cast<std::size_t>(r.matches[i].train)];
              o.matches.emplace_back(k1.pt, r.points2[i]);
              o.octaves.emplace_back(k1.octave, k2.octave);
              const auto origin = [&](const auto& features, int index) {
                return view_stage[static_cast<std::size_t>(features.views[static_cast<std::size_t>(index)])];
              };
              o.origins.push_back(
                  std::max(origin(r.features1, r.matches[i].query), origin(r.features2, r.matches[i].train)));
            }
            o.homography_found = r.model.homography_found;
            if (r.model.homography_found) o.homography = to_matx(r.model.homography);
            o.keypoints1 = static_cast<int>(r.features1.size());
            o.keypoints2 = static_cast<int>(r.features2.size());
            o.stage = r.stage;
            o.verified = r.verified;
            o.failure = r.stages.back().failure;
            for (const affine_orb::TwoViewStageReport& s : r.stages) {
              o.stages += " " + std::to_string(s.matches) + "/" + std::to_string(s.homography_inlier_count) + "/" +
                          std::to_string(s.fundamental_inlier_count) +
                          (s.model == affine_orb::GeometricModel::kHomography    ? "H"
                           : s.model == affine_orb::GeometricModel::kFundamental ? "F"
                                                                                 : "-");
              if (s.guided_rounds > 0) o.stages += "/g" + std::to_string(s.guided_rounds);
              if (s.half_disagreement) o.stages += "/" + std::to_string(*s.half_disagreement).substr(0, 5) + "px";
              if (s.log10_false_alarms) o.stages += "/nfa" + std::to_string(*s.log10_false_alarms).substr(0, 5);
            }
            return o;
          },
          true, false, static_cast<int>(options.stages.size())};
}

/// An OpenCV Feature2D peer: binary descriptors matched by match_features(), float ones by the
/// same rules on L2 (match_float()). `extreme`, when given, replaces `detector` on the EVD pairs
/// (the affine peers with tilts to 5.66 there).
Method peer(const std::string& name, cv::Ptr<cv::Feature2D> default_detector,
            const affine_orb::ModelSelectionOptions& model, cv::Ptr<cv::Feature2D> extreme = nullptr) {
  return {name,
          [default_detector, extreme, model](const cv::Mat& a, const cv::Mat& b,
                                             const affine_orb::bench::ViewpointPair& pair) {
            Outcome o;
            const cv::Ptr<cv::Feature2D> detector = extreme && pair.judged_on_grid() ? extreme : default_detector;
            const auto start = Clock::now();
            std::vector<cv::KeyPoint> k1, k2;
            cv::Mat d1, d2;
            detector->detectAndCompute(a, cv::noArray(), k1, d1);
            detector->detectAndCompute(b, cv::noArray(), k2, d2);
            std::vector<affine_orb::Match> matches;
            if (d1.type() == CV_32F) {
              matches = affine_orb::bench::match_float(k1, d1, k2, d2);
            } else if (!d1.empty() && !d2.empty()) {
              // AKAZE's 61-byte rows padded with zero bytes to 64: the Hamming distances stay.
              const int padding = (8 - d1.cols % 8) % 8;
              if (padding > 0) {
                cv::copyMakeBorder(d1, d1, 0, 0, 0, padding, cv::BORDER_CONSTANT, 0);
                cv::copyMakeBorder(d2, d2, 0, 0, 0, padding, cv::BORDER_CONSTANT, 0);
              }
              matches = affine_orb::match(d1, d2, affine_orb::MatcherOptions{});
            }
            for (const affine_orb::Match& m : matches) {
              o.matches.emplace_back(k1[static_cast<std::size_t>(m.query)].pt,
                                     k2[static_cast<std::size_t>(m.train)].pt);
            }
            verify(o, model);
            o.ms = since(start);
            o.keypoints1 = static_cast<int>(k1.size());
            o.keypoints2 = static_cast<int>(k2.size());
            return o;
          },
          false, true};
}

/// The corner error of homography `h` against the ground truth (1e9 when `h` is empty): the mean
/// over image 1's four corners, on EVD over the overlap grid (grid_error()).
double pair_error(const cv::Mat& h, const affine_orb::bench::ViewpointPair& pair, cv::Size size1, cv::Size size2) {
  if (h.empty()) return 1e9;
  return pair.judged_on_grid() ? affine_orb::bench::grid_error(cv::Matx33d(h), pair.h, size1, size2)
                               : affine_orb::bench::corner_error(cv::Matx33d(h), pair.h, size1);
}

/// The two judges, the same for every method, re-estimating from the method's matches:
/// cv::findHomography with RANSAC (3 px, 10 000 iterations, confidence 0.999) and with MAGSAC++
/// (cv::USAC_MAGSAC, 3 px, the same iterations and confidence); their errors (pair_error()).
struct JudgeErrors {
  double ransac = 1e9;
  double magsac = 1e9;
};

JudgeErrors judge_errors(const PointPairs& matches, const affine_orb::bench::ViewpointPair& pair, cv::Size size1,
                         cv::Size size2) {
  JudgeErrors e;
  if (matches.size() < 4) return e;
  std::vector<cv::Point2f> p1, p2;
  for (const auto& [a, b] : matches) {
    p1.push_back(a);
    p2.push_back(b);
  }
  e.ransac = pair_error(cv::findHomography(p1, p2, cv::RANSAC, 3.0, cv::noArray(), 10000, 0.999), pair, size1, size2);
  e.magsac =
      pair_error(cv::findHomography(p1, p2, cv::USAC_MAGSAC, 3.0, cv::noArray(), 10000, 0.999), pair, size1, size2);
  return e;
}

/// The MAGSAC++ judge's corner errors over reorderings of the same matches (--judge-spread).
struct JudgeSpread {
  double min = 0.0, median = 0.0, max = 0.0;
};

/// The MAGSAC++ judge of judge_errors() on `orderings` random orderings of `matches` (std::mt19937
/// seeded with `seed`): cv::findHomography's sampling depends on the order of its points, so this
/// is how far the judge moves on one set of matches, the range within which the own model and the
/// judge cannot be told apart.
JudgeSpread judge_spread(PointPairs matches, const affine_orb::bench::ViewpointPair& pair, cv::Size size1,
                         cv::Size size2, int orderings, unsigned seed) {
  std::mt19937 random(seed);
  std::vector<double> errors;
  for (int k = 0; k < orderings && matches.size() >= 4; ++k) {
    std::shuffle(matches.begin(), matches.end(), random);
    std::vector<cv::Point2f> p1, p2;
    for (const auto& [a, b] : matches) {
      p1.push_back(a);
      p2.push_back(b);
    }
    errors.push_back(
        pair_error(cv::findHomography(p1, p2, cv::USAC_MAGSAC, 3.0, cv::noArray(), 10000, 0.999), pair, size1, size2));
  }
  if (errors.empty()) return {1e9, 1e9, 1e9};
  std::sort(errors.begin(), errors.end());
  return {errors.front(), errors[errors.size() / 2], errors.back()};
}

struct Row {
  std::string pair;
  std::string subset;
  std::string method;
  std::size_t index = 0;          ///< the pair's place in the run's ordered list (the odd and even halves)
  int seed = 0;                   ///< --seeds: the offset of the RANSAC seeds the row ran with
  bool solved = false;            ///< by the RANSAC judge
  double corner_error = 0.0;      ///< the RANSAC judge's homography
  double magsac_error = 0.0;      ///< the MAGSAC++ judge's homography
  double own_corner_error = 0.0;  ///< the method's own (select_model()'s) homography
  affine_orb::bench::CorrectMatches correct;
  std::size_t matches = 0;
  Outcome outcome;
  std::optional<JudgeSpread> spread;  ///< --judge-spread, matcher methods only
};

/// One cached peer row, tab-separated: pair, method, keypoints1, keypoints2, matches, correct,
/// distinct correct, RANSAC judge's error, own error, solved, ms, MAGSAC++ judge's error.
std::string cache_line(const Row& r) {
  std::ostringstream line;
  line << r.pair << '\t' << r.method << '\t' << r.outcome.keypoints1 << '\t' << r.outcome.keypoints2 << '\t'
       << r.matches << '\t' << r.correct.correct << '\t' << r.correct.distinct << '\t' << r.corner_error << '\t'
       << r.own_corner_error << '\t' << r.solved << '\t' << r.outcome.ms << '\t' << r.magsac_error << '\n';
  return line.str();
}

/// The rows of a --peer-cache file, by "pair\tmethod"; lines without the MAGSAC++ judge's error
/// (written before it was measured) are skipped, so that their peers run again.
std::map<std::string, Row> read_cache(const std::string& path) {
  std::map<std::string, Row> rows;
  std::ifstream in(path);
  std::string text;
  while (std::getline(in, text)) {
    std::istringstream line(text);
    Row r;
    std::string field;
    std::getline(line, r.pair, '\t');
    std::getline(line, r.method, '\t');
    if (line >> r.outcome.keypoints1 >> r.outcome.keypoints2 >> r.matches >> r.correct.correct >> r.correct.distinct >>
        r.corner_error >> r.own_corner_error >> r.solved >> r.outcome.ms >> r.magsac_error) {
      rows[r.pair + '\t' + r.method] = r;
    }
  }
  return rows;
}

/// The pair of the run named `name` (ViewpointPair::name(); every row's pair is one of them).
const affine_orb::bench::ViewpointPair& pair_named(const std::vector<affine_orb::bench::ViewpointPair>& pairs,
                                                   const std::string& name) {
  return *std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.name() == name; });
}

/// --placement: per octave of the image-1 keypoint and of the image-2 keypoint, the residuals
/// |H·x1 − x2| (pixels of image 2) of the matches of `method` within 3 px of the ground truth.
void placement_table(const std::string& method, const std::vector<Row>& rows,
                     const std::vector<affine_orb::bench::ViewpointPair>& pairs, std::ostringstream& md) {
  if (std::none_of(rows.begin(), rows.end(), [&](const Row& r) { return r.method == method; })) return;
  std::map<int, std::vector<double>> by1, by2;
  for (const Row& r : rows) {
    if (r.method != method) continue;
    const cv::Matx33d& h = pair_named(pairs, r.pair).h;
    for (std::size_t i = 0; i < r.outcome.matches.size(); ++i) {
      const auto& [x1, x2] = r.outcome.matches[i];
      const double residual = affine_orb::bench::match_residual(h, x1, x2);
      if (residual >= affine_orb::bench::kCorrectMatchError) continue;
      by1[r.outcome.octaves[i].first].push_back(residual);
      by2[r.outcome.octaves[i].second].push_back(residual);
    }
  }
  const auto stats = [](std::vector<double> v) {
    if (v.empty()) return std::string(" 0 | | |");
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) { return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)]; };
    char cell[96];
    std::snprintf(cell, sizeof(cell), " %zu | %.2f | %.2f |", v.size(), at(0.5), at(0.9));
    return std::string(cell);
  };
  std::vector<double> all;
  for (const auto& [octave, v] : by1) all.insert(all.end(), v.begin(), v.end());
  int last = 0;
  for (const auto& [octave, v] : by1) last = std::max(last, octave);
  for (const auto& [octave, v] : by2) last = std::max(last, octave);
  for (int octave = 0; octave <= last; ++octave) {
    md << "| " << method << " | " << octave << " |" << stats(by1[octave]) << stats(by2[octave]) << "\n";
  }
  md << "| " << method << " | all |" << stats(all) << stats(all) << "\n";
}

/// AUC@k of errors `e` (pixels): the area under the share-of-pairs-below-error curve from 0 to k
/// px, normalised by k, the HPatches homography metric of SuperGlue and LoFTR; the mean of
/// max(0, 1 − e/k) over the pairs, which is that area exactly.
double auc(const std::vector<double>& e, double k) {
  double sum = 0.0;
  for (const double x : e) sum += std::max(0.0, 1.0 - x / k);
  return e.empty() ? 0.0 : sum / static_cast<double>(e.size());
}

/// A titled subset of the rows: a subset of pairs, all of them, or a half of the run's list.
using Group = std::pair<std::string, std::function<bool(const Row&)>>;

/// The groups of the AUC tables: each subset, all pairs, the pairs of odd and of even index.
std::vector<Group> auc_groups(const std::vector<std::pair<std::string, std::string>>& subset_names) {
  std::vector<Group> groups;
  for (const auto& [key, title] : subset_names) {
    groups.emplace_back(title, [key = key](const Row& r) { return r.subset == key; });
  }
  groups.emplace_back("all", [](const Row&) { return true; });
  groups.emplace_back("odd half", [](const Row& r) { return r.index % 2 == 1; });
  groups.emplace_back("even half", [](const Row& r) { return r.index % 2 == 0; });
  return groups;
}

/// The AUC tables: for the own model, the RANSAC judge and the MAGSAC++ judge, per method and per
/// subset, over all pairs and over the pairs of odd and even index in the run's list, AUC@3 / @5 /
/// @10 and, in brackets, the pairs within 5 px (solved).
void auc_tables(const std::vector<Method>& methods, const std::vector<Row>& rows,
                const std::vector<std::pair<std::string, std::string>>& subset_names, std::ostringstream& md) {
  const std::vector<Group> groups = auc_groups(subset_names);
  const std::vector<std::pair<std::string, std::function<double(const Row&)>>> estimates = {
      {"own model", [](const Row& r) { return r.own_corner_error; }},
      {"RANSAC judge", [](const Row& r) { return r.corner_error; }},
      {"MAGSAC++ judge", [](const Row& r) { return r.magsac_error; }}};
  for (const auto& [estimate, error] : estimates) {
    md << "| " << estimate << ": AUC@3 / @5 / @10 (solved) |";
    for (const auto& group : groups) md << " " << group.first << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < groups.size(); ++i) md << "---|";
    md << "\n";
    for (const Method& m : methods) {
      md << "| " << m.name << " |";
      for (const auto& [title, select] : groups) {
        std::vector<double> e;
        for (const Row& r : rows) {
          if (r.method == m.name && select(r)) e.push_back(error(r));
        }
        const auto solved =
            std::count_if(e.begin(), e.end(), [](double x) { return x <= affine_orb::bench::kSolvedCornerError; });
        char cell[96];
        std::snprintf(cell, sizeof(cell), e.empty() ? " |" : " %.2f / %.2f / %.2f (%td) |", auc(e, 3.0), auc(e, 5.0),
                      auc(e, 10.0), solved);
        md << cell;
      }
      md << "\n";
    }
    md << "\n";
  }
}

/// AUC@5 of the own model of `method` over the rows `select` keeps, one value per seed 0 … seeds − 1;
/// empty when it keeps none.
std::vector<double> own_auc_by_seed(const std::vector<Row>& rows, const std::string& method,
                                    const std::function<bool(const Row&)>& select, int seeds) {
  std::vector<std::vector<double>> errors(static_cast<std::size_t>(seeds));
  bool any = false;
  for (const Row& r : rows) {
    if (r.method != method || !select(r)) continue;
    errors[static_cast<std::size_t>(r.seed)].push_back(r.own_corner_error);
    any = true;
  }
  std::vector<double> out;
  if (!any) return out;
  for (const std::vector<double>& e : errors) out.push_back(auc(e, 5.0));
  return out;
}

/// " median (min – max) |" of `values`, with `sign` for differences; " |" when there are none.
std::string median_and_range(const std::vector<double>& values, bool sign) {
  if (values.empty()) return " |";
  const auto [low, high] = std::minmax_element(values.begin(), values.end());
  char cell[96];
  std::snprintf(cell, sizeof(cell), sign ? " %+.3f (%+.3f – %+.3f) |" : " %.3f (%.3f – %.3f) |",
                affine_orb::bench::median(values), *low, *high);
  return cell;
}

/// --seeds N: per method run with every seed, AUC@5 of the own model per group, the median over the
/// N seeds and their range; then, for every other such method, its difference from "ours views on
/// demand" seed by seed (both ran with the same seeds): the median and range of the differences.
void seed_tables(const std::vector<Method>& methods, const std::vector<Row>& rows, int seeds,
                 const std::vector<Group>& groups, std::ostringstream& md) {
  const std::string reference = "ours views on demand";
  const bool has_reference =
      std::any_of(methods.begin(), methods.end(), [&](const Method& m) { return m.name == reference; });
  for (const bool paired : {false, true}) {
    if (paired && !has_reference) break;
    md << "| own model, AUC@5" << (paired ? " minus the default's, same seed" : "") << ": median (range) over " << seeds
       << " seeds |";
    for (const Group& group : groups) md << " " << group.first << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < groups.size(); ++i) md << "---|";
    md << "\n";
    std::vector<std::vector<double>> base(groups.size());
    if (paired) {
      for (std::size_t g = 0; g < groups.size(); ++g)
        base[g] = own_auc_by_seed(rows, reference, groups[g].second, seeds);
    }
    for (const Method& m : methods) {
      if (m.peer || (paired && m.name == reference)) continue;
      md << "| " << m.name << " |";
      for (std::size_t g = 0; g < groups.size(); ++g) {
        std::vector<double> values = own_auc_by_seed(rows, m.name, groups[g].second, seeds);
        for (std::size_t i = 0; i < values.size() && i < base[g].size(); ++i) values[i] -= base[g][i];
        md << median_and_range(values, paired);
      }
      md << "\n";
    }
    md << "\n";
  }
}

/// The matcher's verification against the ground truth, per matcher method: pairs verified; false
/// accepts, verified with the own homography more than 5 px off; false refusals, not verified
/// with the own homography within 5 px; and the pairs not verified whose returned matches hold a
/// homography within 5 px that the matcher did not find (the MAGSAC++ judge's).
void verification_table(const std::vector<Method>& methods, const std::vector<Row>& rows, std::ostringstream& md) {
  md << "| method | pairs | verified | false accepts: verified, own > 5 px | false refusals: not verified, own "
        "≤ 5 px | not verified, own > 5 px, MAGSAC++ judge ≤ 5 px |\n|---|---:|---:|---:|---:|---:|\n";
  const double line = affine_orb::bench::kSolvedCornerError;
  for (const Method& m : methods) {
    if (!m.matcher) continue;
    int pairs = 0, verified = 0, accepts = 0, refusals = 0, missed = 0;
    for (const Row& r : rows) {
      if (r.method != m.name) continue;
      ++pairs;
      verified += r.outcome.verified;
      accepts += r.outcome.verified && r.own_corner_error > line;
      refusals += !r.outcome.verified && r.own_corner_error <= line;
      missed += !r.outcome.verified && r.own_corner_error > line && r.magsac_error <= line;
    }
    md << "| " << m.name << " | " << pairs << " | " << verified << " | " << accepts << " | " << refusals << " | "
       << missed << " |\n";
  }
  md << "\n";
}

/// Per matcher method, the pairs not verified by the test that refused them
/// (TwoViewStageReport::failure of the last stage), and in brackets the false refusals among them,
/// whose own homography lies within 5 px.
void refusal_table(const std::vector<Method>& methods, const std::vector<Row>& rows, std::ostringstream& md) {
  using Failure = affine_orb::VerificationFailure;
  const std::vector<Failure> tests = {Failure::kNoModel, Failure::kFewInliers, Failure::kFalseAlarms,
                                      Failure::kInlierRatio, Failure::kImprecise};
  md << "| not verified, by the test that refused them (false refusals: own ≤ 5 px) | pairs not verified";
  for (const Failure f : tests) md << " | " << affine_orb::verification_failure_name(f);
  md << " |\n|---|---:";
  for (std::size_t i = 0; i < tests.size(); ++i) md << "|---:";
  md << "|\n";
  for (const Method& m : methods) {
    if (!m.matcher) continue;
    int refused = 0;
    std::vector<std::pair<int, int>> by(tests.size());  // (refused, of which false refusals)
    for (const Row& r : rows) {
      if (r.method != m.name || !r.outcome.failure) continue;
      ++refused;
      const std::size_t i =
          static_cast<std::size_t>(std::find(tests.begin(), tests.end(), *r.outcome.failure) - tests.begin());
      ++by[i].first;
      by[i].second += r.own_corner_error <= affine_orb::bench::kSolvedCornerError;
    }
    md << "| " << m.name << " | " << refused;
    for (const auto& [count, wrong] : by) md << " | " << count << " (" << wrong << ")";
    md << " |\n";
  }
  md << "\n";
}

/// --judge-spread: per matcher method, over the pairs where the own model or the judge's median
/// is within 10 px (the range of AUC@10), how the own model's corner error lies against the MAGSAC++ judge's over
/// reorderings of the returned matches (judge_spread()), and the median width of that range; then
/// each such pair whose own error is more than 0.5 px above the judge's median.
void spread_tables(const std::vector<Method>& methods, const std::vector<Row>& rows, int orderings,
                   std::ostringstream& md) {
  const auto counted = [](const Row& r) { return r.spread && std::min(r.own_corner_error, r.spread->median) <= 10.0; };
  md << "| method | pairs, own or judge ≤ 10 px | own > judge's median + 0.5 px | own above the judge's range | "
        "own below it | judge's range, median width px |\n|---|---:|---:|---:|---:|---:|\n";
  for (const Method& m : methods) {
    if (!m.matcher) continue;
    int pairs = 0, behind = 0, above = 0, below = 0;
    std::vector<double> widths;
    for (const Row& r : rows) {
      if (r.method != m.name || !counted(r)) continue;
      ++pairs;
      behind += r.own_corner_error > r.spread->median + 0.5;
      above += r.own_corner_error > r.spread->max;
      below += r.own_corner_error < r.spread->min;
      widths.push_back(r.spread->max - r.spread->min);
    }
    if (pairs == 0) continue;
    std::nth_element(widths.begin(), widths.begin() + static_cast<std::ptrdiff_t>(widths.size() / 2), widths.end());
    char cells[160];
    std::snprintf(cells, sizeof(cells), " %d | %d | %d | %d | %.2f |\n", pairs, behind, above, below,
                  widths[widths.size() / 2]);
    md << "| " << m.name << " |" << cells;
  }
  md << "\n| method | pair | own px | judge's median px | judge's range px (" << orderings
     << " orderings) |\n|---|---|---:|---:|---|\n";
  for (const Row& r : rows) {
    if (!counted(r) || r.own_corner_error <= r.spread->median + 0.5) continue;
    char cells[160];
    std::snprintf(cells, sizeof(cells), " %.2f | %.2f | %.2f–%.2f |\n", std::min(r.own_corner_error, 9999.0),
                  r.spread->median, r.spread->min, std::min(r.spread->max, 9999.0));
    md << "| " << r.method << " | " << r.pair << " |" << cells;
  }
  md << "\n";
}

/// --origins: per matcher method and subset, the returned matches within 3 px of the ground truth
/// by the stage that extracted the later of their two keypoints (0: both the images' own), summed
/// over the subset's pairs: which stage finds the correct matches.
void origin_table(const std::vector<Method>& methods, const std::vector<Row>& rows,
                  const std::vector<affine_orb::bench::ViewpointPair>& pairs,
                  const std::vector<std::pair<std::string, std::string>>& subset_names, std::ostringstream& md) {
  md << "| method | subset | correct matches by stage of origin (0, 1, 2, ...) | pairs solved by the own model |\n"
     << "|---|---|---|---:|\n";
  for (const Method& m : methods) {
    if (!m.matcher) continue;
    for (const auto& [key, title] : subset_names) {
      std::vector<long> by_stage(static_cast<std::size_t>(m.stages) + 1, 0);
      int solved = 0, run = 0;
      for (const Row& r : rows) {
        if (r.method != m.name || r.subset != key) continue;
        ++run;
        solved += r.own_corner_error <= affine_orb::bench::kSolvedCornerError;
        const cv::Matx33d& h = pair_named(pairs, r.pair).h;
        for (std::size_t i = 0; i < r.outcome.matches.size(); ++i) {
          const auto& [x1, x2] = r.outcome.matches[i];
          if (affine_orb::bench::match_residual(h, x1, x2) < affine_orb::bench::kCorrectMatchError) {
            ++by_stage[static_cast<std::size_t>(r.outcome.origins[i])];
          }
        }
      }
      if (run == 0) continue;
      md << "| " << m.name << " | " << title << " |";
      for (std::size_t k = 0; k < by_stage.size(); ++k) md << (k ? ", " : " ") << by_stage[k];
      md << " | " << solved << " / " << run << " |\n";
    }
  }
  md << "\n";
}

/// `method` run `repeats` times on a pair: the last run's outcome with the median of the times (the
/// upper of the two middle ones for an even count).
Outcome run_repeated(const Method& method, const cv::Mat& a, const cv::Mat& b,
                     const affine_orb::bench::ViewpointPair& pair, int repeats) {
  std::vector<double> ms;
  Outcome o;
  for (int r = 0; r < repeats; ++r) {
    o = method.run(a, b, pair);
    ms.push_back(o.ms);
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(ms.size() / 2), ms.end());
  o.ms = ms[ms.size() / 2];
  return o;
}

/// The command line (the file comment).
struct Arguments {
  std::string out_dir = ".";
  std::string sequences;                                   ///< ",a,b,"; empty: every sequence
  std::string subsets;                                     ///< ",oxford,evd,"; empty: every subset
  std::string methods;                                     ///< --methods' list; empty: every method
  std::string asift_sequences = ",graf,opencv-doc graf,";  ///< empty: every sequence
  std::string peer_cache;                                  ///< empty: no cache
  bool sweep = false;
  bool placement = false;
  bool origins = false;
  int repeats = 1;
  int judge_spread = 0;  ///< orderings of the MAGSAC++ judge; 0: none
  int seeds = 1;         ///< runs of our methods, each with other RANSAC seeds
};

/// The arguments of `argv`, or nullopt after the usage line on stderr for an unknown flag or a
/// missing or invalid value.
std::optional<Arguments> parse_arguments(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const bool has_value = i + 1 < argc;
    const bool has_count = has_value && std::atoi(argv[i + 1]) >= 1;
    if (flag == "--sweep") {
      a.sweep = true;
    } else if (flag == "--placement") {
      a.placement = true;
    } else if (flag == "--origins") {
      a.origins = true;
    } else if (flag == "--out" && has_value) {
      a.out_dir = argv[++i];
    } else if (flag == "--sequences" && has_value) {
      a.sequences = std::string(",") + argv[++i] + ",";
    } else if (flag == "--subsets" && has_value) {
      a.subsets = std::string(",") + argv[++i] + ",";
    } else if (flag == "--methods" && has_value) {
      a.methods = argv[++i];
    } else if (flag == "--repeats" && has_count) {
      a.repeats = std::atoi(argv[++i]);
    } else if (flag == "--judge-spread" && has_count) {
      a.judge_spread = std::atoi(argv[++i]);
    } else if (flag == "--seeds" && has_count) {
      a.seeds = std::atoi(argv[++i]);
    } else if (flag == "--peer-cache" && has_value) {
      a.peer_cache = argv[++i];
    } else if (flag == "--asift-sequences" && has_value) {
      const std::string value = argv[++i];
      a.asift_sequences = value == "all" ? "" : "," + value + ",";
    } else {
      std::fprintf(stderr,
                   "usage: eval_two_view [--out DIR] [--subsets oxford,hpatches,homogr,evd] [--sequences a,b] "
                   "[--methods SUBSTRING,...] [--asift-sequences a,b|all] [--peer-cache FILE] [--sweep] [--placement] "
                   "[--origins] [--repeats N] [--judge-spread N] [--seeds N]\n");
      return std::nullopt;
    }
  }
  return a;
}

/// `o` with the seeds of its RANSAC searches (model selection's, the last stage's) offset by `seed`;
/// 0 leaves them as they are.
affine_orb::TwoViewOptions with_seed(affine_orb::TwoViewOptions o, int seed) {
  o.model.ransac.seed += static_cast<std::uint64_t>(seed);
  if (o.last_stage_search) o.last_stage_search->ransac.seed += static_cast<std::uint64_t>(seed);
  return o;
}

/// `o` with sub-pixel keypoint positions (ExtractorOptions::subpixel).
affine_orb::ExtractorOptions with_subpixel(affine_orb::ExtractorOptions o) {
  o.subpixel = true;
  return o;
}

/// `o` with the precision test at another bound, or off (TwoViewOptions::max_half_disagreement).
affine_orb::TwoViewOptions with_precision_test(affine_orb::TwoViewOptions o, std::optional<double> pixels) {
  o.max_half_disagreement = pixels;
  return o;
}

/// `o` with image 2's points aligned with image 1's patches under the verified homography
/// (TwoViewOptions::align_correspondences).
affine_orb::TwoViewOptions with_alignment(affine_orb::TwoViewOptions o) {
  o.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
  return o;
}

/// `o` without guided matching of a verified homography (TwoViewOptions::guided_matching).
affine_orb::TwoViewOptions without_guided_matching(affine_orb::TwoViewOptions o) {
  o.guided_matching.reset();
  return o;
}

/// `o` without the final fit of the homography (TwoViewOptions::final_fit).
affine_orb::TwoViewOptions without_final_fit(affine_orb::TwoViewOptions o) {
  o.final_fit.reset();
  return o;
}

/// `o` as the matcher was before min_inliers 12 and the last stage's search: 15 inliers, no search.
affine_orb::TwoViewOptions before_search(affine_orb::TwoViewOptions o) {
  o.min_inliers = 15;
  o.last_stage_search.reset();
  return o;
}

/// An affine peer on `backend`: 18 views (tilts to 2.83, cv::AffineFeature's maxTilt 3) or 43 (tilts
/// to 5.66, maxTilt 5), rotation step 72°/t as ASIFT.
cv::Ptr<cv::Feature2D> affine_peer(cv::Ptr<cv::Feature2D> backend, int max_tilt) {
  return cv::AffineFeature::create(backend, max_tilt, 0, std::sqrt(2.0), 72);
}

/// The methods of every run (before --methods chooses among them): ours, the matcher and its
/// variants of record, the OpenCV peers.
std::vector<Method> standard_methods(const affine_orb::TwoViewOptions& defaults) {
  const affine_orb::ModelSelectionOptions& model = defaults.model;
  affine_orb::ExtractorOptions plain = affine_orb::TwoViewOptions::default_extractor();
  plain.views.max_tilt = 1.0;
  affine_orb::TwoViewOptions subpixel_views = defaults;
  subpixel_views.extractor.subpixel = true;
  affine_orb::ExtractorOptions affine;
  affine.spreading = affine_orb::Spreading::kStrongest;
  // The default stages and two more to extreme tilts (4 and 4√2, as MODS and ASIFT's maxTilt 5),
  // run only while the pair is not verified.
  affine_orb::TwoViewOptions extreme = defaults;
  extreme.extractor.views.max_tilt = 4.0 * std::sqrt(2.0);
  extreme.stages = affine_orb::stages_up_to(extreme.extractor.views);
  return {
      ours("ours plain 2000", plain, model),
      ours("ours plain 2000, sub-pixel", with_subpixel(plain), model),
      ours("ours affine default 1000 + 1000", affine, model),
      ours("ours affine default 1000 + 1000, sub-pixel", with_subpixel(affine), model),
      two_view("ours views on demand", defaults),
      two_view("ours views on demand, sub-pixel", subpixel_views),
      two_view("ours views on demand, aligned", with_alignment(defaults)),
      two_view("ours views on demand, sub-pixel, aligned", with_alignment(subpixel_views)),
      two_view("ours views on demand, stages to 5.66", extreme),
      two_view("ours views on demand, half disagreement 5 px", with_precision_test(defaults, 5.0)),
      two_view("ours views on demand, no precision test", with_precision_test(defaults, std::nullopt)),
      two_view("ours views on demand, no guided matching", without_guided_matching(defaults)),
      two_view("ours views on demand, no guided matching, no precision test",
               with_precision_test(without_guided_matching(defaults), std::nullopt)),
      two_view("ours views on demand, no final fit", without_final_fit(defaults)),
      two_view("ours views on demand, no guided matching, no final fit",
               without_final_fit(without_guided_matching(defaults))),
      two_view("ours views on demand, min_inliers 15, no last-stage search", before_search(defaults)),
      peer("cv::ORB 2000", cv::ORB::create(2000), model),
      peer("cv::AKAZE", cv::AKAZE::create(), model),
      peer("cv::SIFT", cv::SIFT::create(), model),
      peer("cv::AffineFeature(ORB)", affine_peer(cv::ORB::create(112), 3), model, affine_peer(cv::ORB::create(112), 5)),
      peer("ASIFT", affine_peer(cv::SIFT::create(), 3), model, affine_peer(cv::SIFT::create(), 5)),
  };
}

using Variant = std::function<void(const std::string&, const std::function<void(affine_orb::TwoViewOptions&)>&)>;

/// --sweep's variants of the stages, min_inliers and the support tests, each given to `variant`
/// as a name and a change of the default.
void stage_and_support_variants(const Variant& variant) {
  variant("one stage up to 2.83, +1000", [](auto& o) { o.stages = {{2.0 * std::sqrt(2.0), 0.5}}; });
  variant("stages 1.41 +250, 2 +250, 2.83 +500", [](auto& o) {
    o.stages = {{std::sqrt(2.0), 0.125}, {2.0, 0.125}, {2.0 * std::sqrt(2.0), 0.25}};
  });
  variant("stages 2 +500, 2.83 +1000", [](auto& o) { o.stages = {{2.0, 0.25}, {2.0 * std::sqrt(2.0), 0.5}}; });
  variant("stages 2 +1000, 2.83 +2000", [](auto& o) { o.stages = {{2.0, 0.5}, {2.0 * std::sqrt(2.0), 1.0}}; });
  variant("stages up to 4: 2 +500, 2.83 +1000, 4 +1000", [](auto& o) {
    o.extractor.views.max_tilt = 4.0;
    o.stages = {{2.0, 0.25}, {2.0 * std::sqrt(2.0), 0.5}, {4.0, 0.5}};
  });
  for (int n : {8, 10, 15, 20, 30}) variant("min_inliers " + std::to_string(n), [n](auto& o) { o.min_inliers = n; });
  for (int n : {8, 10, 12, 15}) {
    variant("min_inliers " + std::to_string(n) + ", no last-stage search", [n](auto& o) {
      o.min_inliers = n;
      o.last_stage_search.reset();
    });
  }
  for (double r : {0.05, 0.1, 0.2}) {
    variant("min_inlier_ratio " + std::to_string(r).substr(0, 4) + ", no false-alarm test", [r](auto& o) {
      o.min_inlier_ratio = r;
      o.max_false_alarms.reset();
    });
  }
  variant("no support test", [](auto& o) { o.max_false_alarms.reset(); });
  variant("max_false_alarms 0.01", [](auto& o) { o.max_false_alarms = 0.01; });
}

/// --sweep's variants of the estimation: the final fit's Cauchy scale and max_error, the RANSAC
/// searches, the last stage's search (its σ, samples and orientation test), aligned
/// correspondences with other CorrespondenceAlignmentOptions, a plain stage of 1000.
void estimation_variants(const Variant& variant) {
  for (const auto& [scale, bound] : std::vector<std::pair<double, double>>{{1.0, 2.0},
                                                                           {1.0, 2.4},
                                                                           {1.5, 2.4},
                                                                           {1.0, 3.0},
                                                                           {1.5, 3.0},
                                                                           {3.0, 3.0},
                                                                           {2.0, 4.0},
                                                                           {3.0, 4.0},
                                                                           {5.0, 3.0}}) {
    char name[64];
    std::snprintf(name, sizeof(name), "final fit, Cauchy %.1f px, max_error %.1f px", scale, bound);
    variant(name, [scale = scale, bound = bound](auto& o) {
      o.final_fit = affine_orb::HomographyRefinementOptions{};
      o.final_fit->cauchy_scale = scale;
      o.final_fit->max_error = bound;
    });
  }
  variant("PROSAC", [](auto& o) { o.model.ransac.progressive_sampling = true; });
  variant("PROSAC, up to 2000 iterations", [](auto& o) {
    o.model.ransac.progressive_sampling = true;
    o.model.ransac.max_iterations = 2000;
  });
  variant("RANSAC up to 2000 iterations", [](auto& o) { o.model.ransac.max_iterations = 2000; });
  variant("RANSAC up to 10000 iterations, confidence 0.999", [](auto& o) {
    o.model.ransac.max_iterations = 10000;
    o.model.ransac.confidence = 0.999;
  });
  for (double sigma : {1.0, 1.5, 2.0}) {
    char name[64];
    std::snprintf(name, sizeof(name), "last-stage search, sigma %.1f px", sigma);
    variant(name, [sigma](auto& o) {
      o.last_stage_search = affine_orb::LastStageSearchOptions{};
      o.last_stage_search->sigma = sigma;
    });
  }
  variant("last-stage search, no orientation test, up to 10000 samples", [](auto& o) {
    o.last_stage_search->max_orientation_difference.reset();
    o.last_stage_search->ransac.max_iterations = 10000;
  });
  for (const int samples : {10000, 100000}) {
    variant("last-stage search, up to " + std::to_string(samples) + " samples",
            [samples](auto& o) { o.last_stage_search->ransac.max_iterations = samples; });
  }
  for (const double angle : {30.0, 60.0}) {
    char name[64];
    std::snprintf(name, sizeof(name), "last-stage search, orientation test %.0f degrees", angle);
    variant(name, [angle](auto& o) { o.last_stage_search->max_orientation_difference = angle; });
  }
  const std::vector<std::pair<std::string, std::function<void(affine_orb::CorrespondenceAlignmentOptions&)>>> aligned =
      {{"patch_radius 4", [](auto& a) { a.patch_radius = 4; }},
       {"patch_radius 7", [](auto& a) { a.patch_radius = 7; }},
       {"min_correlation 0.9", [](auto& a) { a.min_correlation = 0.9; }},
       {"max_shift 1 px", [](auto& a) { a.max_shift = 1.0; }},
       {"min_texture 16", [](auto& a) { a.min_texture = 16.0; }}};
  for (const auto& [name, change] : aligned) {
    variant("aligned, " + name, [change = change](auto& o) {
      o.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
      change(*o.align_correspondences);
    });
  }
  variant("plain 1000 first", [](auto& o) {
    o.extractor.features = 1000;
    o.stages = {{2.0, 0.5}, {2.0 * std::sqrt(2.0), 1.0}};
  });
}

/// --sweep's variants of the choice between H and F (ModelSelectionOptions::rule): the other
/// rules and a laxer plane-and-parallax significance. Every pair here is planar, so these show
/// only the planar side of the choice; bench_model_selection measures the 3-D side.
void selection_variants(const Variant& variant) {
  using affine_orb::SelectionRule;
  variant("rule: eq. 22, R_H > 0.45", [](auto& o) { o.model.rule = SelectionRule::kScoreRatio; });
  variant("rule: GRIC, sigma 1 px", [](auto& o) { o.model.rule = SelectionRule::kGric; });
  variant("rule: inlier ratio 0.8", [](auto& o) { o.model.rule = SelectionRule::kInlierRatio; });
  for (double z : {6.0, 10.0}) {
    char name[64];
    std::snprintf(name, sizeof(name), "rule: plane-and-parallax, z <= %.0f", z);
    variant(name, [z](auto& o) { o.model.plane_parallax.significance = z; });
  }
}

/// --sweep: the matcher with 200 inliers, then every variant of the default, named "sweep: ...";
/// their RANSAC seeds offset by `seed` (with_seed()).
void add_sweep(const affine_orb::TwoViewOptions& defaults, int seed, std::vector<Method>& methods) {
  affine_orb::TwoViewOptions many = defaults;
  many.min_inliers = 200;
  methods.push_back(two_view("ours views on demand, min_inliers 200", with_seed(many, seed)));
  const Variant variant = [&](const std::string& name, const std::function<void(affine_orb::TwoViewOptions&)>& change) {
    affine_orb::TwoViewOptions o = defaults;
    change(o);
    methods.push_back(two_view("sweep: " + name, with_seed(o, seed)));
  };
  stage_and_support_variants(variant);
  estimation_variants(variant);
  selection_variants(variant);
}

/// Keeps the methods that --methods' comma-separated `filter` names: by a substring of the name,
/// or, for an entry starting with '=', by the whole name.
void keep_named(const std::string& filter, std::vector<Method>& methods) {
  const auto wanted = [&](const Method& m) {
    std::istringstream names(filter);
    std::string name;
    while (std::getline(names, name, ',')) {
      if (name.size() > 1 && name[0] == '=' && m.name == name.substr(1)) return true;
      if (!name.empty() && name[0] != '=' && m.name.find(name) != std::string::npos) return true;
    }
    return false;
  };
  methods.erase(std::remove_if(methods.begin(), methods.end(), [&](const Method& m) { return !wanted(m); }),
                methods.end());
}

/// The methods of the run (--sweep's added, --methods' kept) with their RANSAC seeds offset by
/// `seed`; the OpenCV peers only at seed 0.
std::vector<Method> methods_with_seed(const affine_orb::TwoViewOptions& defaults, const Arguments& args, int seed) {
  std::vector<Method> methods = standard_methods(with_seed(defaults, seed));
  if (args.sweep) add_sweep(defaults, seed, methods);
  if (!args.methods.empty()) keep_named(args.methods, methods);
  if (seed > 0) {
    methods.erase(std::remove_if(methods.begin(), methods.end(), [](const Method& m) { return m.peer; }),
                  methods.end());
  }
  return methods;
}

/// The pairs of --subsets and --sequences, Oxford and opencv-doc first, then the data pairs.
std::vector<affine_orb::bench::ViewpointPair> selected_pairs(const Arguments& args) {
  std::vector<affine_orb::bench::ViewpointPair> pairs;
  if (args.subsets.empty() || args.subsets.find(",oxford,") != std::string::npos) {
    pairs = affine_orb::bench::viewpoint_pairs(args.sequences);
  }
  for (auto& pair : affine_orb::bench::data_pairs(args.subsets)) {
    if (args.sequences.empty() || args.sequences.find("," + pair.sequence + ",") != std::string::npos) {
      pairs.push_back(std::move(pair));
    }
  }
  return pairs;
}

/// `method` on `pair` (images `a`, `b`), the pair's `index`-th in the run: its outcome, judged.
Row evaluate(const Method& method, const cv::Mat& a, const cv::Mat& b, const affine_orb::bench::ViewpointPair& pair,
             std::size_t index, const Arguments& args) {
  Row row;
  row.pair = pair.name();
  row.method = method.name;
  row.outcome = run_repeated(method, a, b, pair, args.repeats);
  row.matches = row.outcome.matches.size();
  row.correct = affine_orb::bench::correct_matches(row.outcome.matches, pair.h);
  const JudgeErrors judged = judge_errors(row.outcome.matches, pair, a.size(), b.size());
  row.corner_error = judged.ransac;
  row.magsac_error = judged.magsac;
  row.own_corner_error =
      row.outcome.homography_found ? pair_error(cv::Mat(row.outcome.homography), pair, a.size(), b.size()) : 1e9;
  row.solved = row.corner_error <= affine_orb::bench::kSolvedCornerError;
  if (method.matcher && args.judge_spread > 0) {
    row.spread = judge_spread(row.outcome.matches, pair, a.size(), b.size(), args.judge_spread,
                              static_cast<unsigned>(index + 1));
  }
  return row;
}

/// One line per row on stderr, as the run goes.
void print_progress(const Row& row) {
  std::fprintf(stderr,
               "%-24s %-46s kp %5d/%5d matches %5zu distinct %5zu %s (%.1f px, MAGSAC %.1f, own %.1f) stage %d "
               "%s%s %.0f ms\n",
               row.pair.c_str(), row.method.c_str(), row.outcome.keypoints1, row.outcome.keypoints2, row.matches,
               row.correct.distinct, row.solved ? "solved" : "------", std::min(row.corner_error, 9999.0),
               std::min(row.magsac_error, 9999.0), std::min(row.own_corner_error, 9999.0), row.outcome.stage,
               row.outcome.verified ? "verified" : "", row.outcome.stages.c_str(), row.outcome.ms);
}

/// Every method on every pair, pair after pair; the peers' rows from --peer-cache where it has
/// them, and appended to it where it does not.
std::vector<Row> run_methods(const std::vector<Method>& methods,
                             const std::vector<affine_orb::bench::ViewpointPair>& pairs, const Arguments& args) {
  const auto runs_on = [&](const Method& m, const std::string& sequence) {
    return m.name != "ASIFT" || args.asift_sequences.empty() ||
           args.asift_sequences.find("," + sequence + ",") != std::string::npos;
  };
  const std::map<std::string, Row> cache =
      args.peer_cache.empty() ? std::map<std::string, Row>{} : read_cache(args.peer_cache);
  std::ofstream cache_out;
  if (!args.peer_cache.empty()) cache_out.open(args.peer_cache, std::ios::app);
  std::vector<Row> rows;
  for (std::size_t index = 0; index < pairs.size(); ++index) {
    const affine_orb::bench::ViewpointPair& pair = pairs[index];
    const cv::Mat a = affine_orb::bench::read_gray(pair.path1);
    const cv::Mat b = affine_orb::bench::read_gray(pair.path2);
    for (const Method& method : methods) {
      if (!runs_on(method, pair.sequence)) continue;
      const auto cached = cache.find(pair.name() + '\t' + method.name);
      const bool from_cache = method.peer && cached != cache.end();
      Row row = from_cache ? cached->second : evaluate(method, a, b, pair, index, args);
      if (!from_cache && method.peer && cache_out.is_open()) cache_out << cache_line(row) << std::flush;
      row.subset = pair.subset;
      row.index = index;
      print_progress(row);
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

/// Per subset and method: pairs solved and total seconds; the last row, pairs any method solves.
void solved_table(const std::vector<Method>& methods, const std::vector<Row>& rows,
                  const std::vector<std::pair<std::string, std::string>>& subset_names, std::ostringstream& md) {
  md << "| method |";
  for (const auto& [key, title] : subset_names) md << " " << title << " solved | s |";
  md << "\n|---|";
  for (std::size_t i = 0; i < subset_names.size(); ++i) md << "---:|---:|";
  md << "\n";
  for (const Method& m : methods) {
    md << "| " << m.name << " |";
    for (const auto& [key, title] : subset_names) {
      int solved = 0, run = 0;
      double ms = 0.0;
      for (const Row& r : rows) {
        if (r.method != m.name || r.subset != key) continue;
        ++run;
        solved += r.solved;
        ms += r.outcome.ms;
      }
      char cell[96];
      std::snprintf(cell, sizeof(cell), run ? " %d / %d | %.1f |" : " | |", solved, run, ms / 1000.0);
      md << cell;
    }
    md << "\n";
  }
  md << "| any of them |";
  for (const auto& [key, title] : subset_names) {
    std::map<std::string, bool> solved;
    for (const Row& r : rows) {
      if (r.subset == key) solved[r.pair] = solved[r.pair] || r.solved;
    }
    int count = 0;
    for (const auto& [pair, s] : solved) count += s;
    md << " " << count << " / " << solved.size() << " | |";
  }
  md << "\n\n";
}

/// The row of `method` on `pair`, or nullptr when the run has none.
const Row* find_row(const std::vector<Row>& rows, const std::string& pair, const std::string& method) {
  for (const Row& r : rows) {
    if (r.pair == pair && r.method == method) return &r;
  }
  return nullptr;
}

/// `a` / `b` as "0.42x", empty when b is not positive.
std::string ratio(double a, double b) {
  char text[32] = "";
  if (b > 0) std::snprintf(text, sizeof(text), "%.2fx", a / b);
  return text;
}

/// One method's line of time_table().
void time_line(const Method& m, const std::vector<Row>& rows, std::ostringstream& md) {
  int solved = 0, pairs_run = 0, wrong = 0;
  std::size_t distinct = 0;
  double ms = 0.0, ms_default = 0.0, ms_easy = 0.0, ms_plain_easy = 0.0;
  std::map<int, int> stages;
  for (const Row& r : rows) {
    if (r.method != m.name) continue;
    ++pairs_run;
    solved += r.solved;
    distinct += r.correct.distinct;
    ms += r.outcome.ms;
    if (const Row* d = find_row(rows, r.pair, "ours affine default 1000 + 1000")) ms_default += d->outcome.ms;
    const Row* p = find_row(rows, r.pair, "ours plain 2000");
    if (p && p->solved) {
      ms_easy += r.outcome.ms;
      ms_plain_easy += p->outcome.ms;
    }
    if (m.matcher) {
      ++stages[r.outcome.stage];
      // Stopped early on a wrong model: verified before the last stage, and the matches do not
      // solve the pair.
      wrong += r.outcome.verified && !r.solved && r.outcome.stage < m.stages;
    }
  }
  std::string stage_text;
  for (const auto& [stage, count] : stages) {
    stage_text += (stage_text.empty() ? "" : ", ") + std::to_string(count) + "× " + std::to_string(stage);
  }
  char line[512];
  std::snprintf(line, sizeof(line), "| %s | %d / %d | %zu | %.0f | %s | %s | %s | %s |\n", m.name.c_str(), solved,
                pairs_run, distinct, ms, ratio(ms, ms_default).c_str(), ratio(ms_easy, ms_plain_easy).c_str(),
                m.matcher ? std::to_string(wrong).c_str() : "", stage_text.c_str());
  md << line;
}

/// Per method: pairs solved; total time over all pairs and over the pairs plain 2000 solves,
/// against plain 2000 and the affine default in the same run; pairs verified with a wrong model.
void time_table(const std::vector<Method>& methods, const std::vector<Row>& rows, std::ostringstream& md) {
  md << "| method | pairs solved | distinct correct matches | total ms | vs affine default, same pairs | "
        "vs plain 2000, pairs it solves | stopped early, unsolved | stages run (matcher) |\n"
     << "|---|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Method& m : methods) time_line(m, rows, md);
}

/// Every row, a line each: to the Markdown and to the CSV file at `csv_path`.
void write_rows(const std::vector<Row>& rows, const std::string& csv_path, std::ostringstream& md) {
  md << "\n| pair | method | kp1 | kp2 | matches | distinct correct | corner error px (RANSAC judge / MAGSAC++ judge / "
        "own) | solved | stage | ms |\n"
     << "|---|---|---:|---:|---:|---:|---:|---|---:|---:|\n";
  std::ofstream csv(csv_path);
  csv << "pair,method,keypoints1,keypoints2,matches,correct,distinct_correct,corner_error,own_corner_error,solved,"
         "stage,verified,ms,magsac_corner_error,pair_index,judge_spread_min,judge_spread_median,judge_spread_max,"
         "seed,failure\n";
  for (const Row& r : rows) {
    char line[512];
    std::snprintf(line, sizeof(line), "| %s | %s | %d | %d | %zu | %zu | %.1f / %.1f / %.1f | %s | %s | %.0f |\n",
                  r.pair.c_str(), r.method.c_str(), r.outcome.keypoints1, r.outcome.keypoints2, r.matches,
                  r.correct.distinct, std::min(r.corner_error, 9999.0), std::min(r.magsac_error, 9999.0),
                  std::min(r.own_corner_error, 9999.0), r.solved ? "yes" : "no",
                  r.outcome.stage >= 0 ? std::to_string(r.outcome.stage).c_str() : "", r.outcome.ms);
    if (r.seed == 0) md << line;
    std::snprintf(line, sizeof(line), "%s,\"%s\",%d,%d,%zu,%zu,%zu,%.2f,%.2f,%d,%d,%d,%.2f,%.2f,%zu,", r.pair.c_str(),
                  r.method.c_str(), r.outcome.keypoints1, r.outcome.keypoints2, r.matches, r.correct.correct,
                  r.correct.distinct, std::min(r.corner_error, 1e6), std::min(r.own_corner_error, 1e6), r.solved,
                  r.outcome.stage, r.outcome.verified, r.outcome.ms, std::min(r.magsac_error, 1e6), r.index);
    csv << line;
    if (r.spread) {
      std::snprintf(line, sizeof(line), "%.2f,%.2f,%.2f", std::min(r.spread->min, 1e6), std::min(r.spread->median, 1e6),
                    std::min(r.spread->max, 1e6));
      csv << line;
    } else {
      csv << ",,";
    }
    csv << ',' << r.seed << ',' << (r.outcome.failure ? affine_orb::verification_failure_name(*r.outcome.failure) : "")
        << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Arguments> args = parse_arguments(argc, argv);
  if (!args) return 2;
  std::error_code made;
  std::filesystem::create_directories(args->out_dir, made);
  if (made) {
    std::fprintf(stderr, "eval_two_view: cannot create %s: %s\n", args->out_dir.c_str(), made.message().c_str());
    return 2;
  }
  cv::setNumThreads(1);
  const affine_orb::TwoViewOptions defaults;
  const std::vector<Method> methods = methods_with_seed(defaults, *args, 0);
  const std::vector<affine_orb::bench::ViewpointPair> pairs = selected_pairs(*args);
  const std::vector<Row> rows = run_methods(methods, pairs, *args);
  std::vector<Row> seeded_rows = rows;
  for (int seed = 1; seed < args->seeds; ++seed) {
    for (Row& r : run_methods(methods_with_seed(defaults, *args, seed), pairs, *args)) {
      r.seed = seed;
      seeded_rows.push_back(std::move(r));
    }
  }

  const std::vector<std::pair<std::string, std::string>> subset_names = {
      {"oxford", "Oxford + opencv-doc"}, {"hpatches", "HPatches"}, {"homogr", "Homogr"}, {"evd", "EVD"}};
  std::ostringstream md;
  solved_table(methods, rows, subset_names, md);
  auc_tables(methods, rows, subset_names, md);
  verification_table(methods, rows, md);
  refusal_table(methods, rows, md);
  if (args->origins) origin_table(methods, rows, pairs, subset_names, md);
  if (args->judge_spread > 0) spread_tables(methods, rows, args->judge_spread, md);
  if (args->seeds > 1) seed_tables(methods, seeded_rows, args->seeds, auc_groups(subset_names), md);
  time_table(methods, rows, md);
  if (args->placement) {
    md << "\n| method | octave | image-1 octave: correct matches | median px | 90th percentile px | "
          "image-2 octave: correct matches | median px | 90th percentile px |\n"
       << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const char* method :
         {"ours plain 2000", "ours plain 2000, sub-pixel", "ours views on demand", "ours views on demand, sub-pixel"}) {
      placement_table(method, rows, pairs, md);
    }
  }
  write_rows(seeded_rows, args->out_dir + "/eval_two_view.csv", md);
  std::ofstream(args->out_dir + "/eval_two_view.md") << md.str();
  std::fputs(md.str().c_str(), stdout);
  return 0;
}
