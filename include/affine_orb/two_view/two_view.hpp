#pragma once
/// \file
/// Two-view matching with views on demand: plain keypoints first, the affine views of stronger
/// tilts only while the pair is not verified. The escalation follows MODS (Mishkin, Matas, Perdoch,
/// "MODS: Fast and robust method for two-view matching", CVIU 141, 2015): after each stage the
/// correspondences are matched and verified, and matching stops as soon as enough of them fit a
/// geometric model, so that an easy pair costs one plain extraction per image and only a hard
/// (wide-baseline) pair pays for the views.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/a_contrario.hpp"
#include "affine_orb/geometry/fundamental.hpp"
#include "affine_orb/geometry/homography.hpp"
#include "affine_orb/geometry/homography_refinement.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/geometry/ransac.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "affine_orb/two_view/alignment.hpp"
#include "affine_orb/two_view/two_view_options.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {

/// The precision test of TwoViewOptions::max_half_disagreement: two homographies fitted (one
/// normalised DLT step from `homography`, the estimate of all inliers, as its local optimisation
/// does) to alternate halves of the inliers (`inliers[i]` != 0, in index order) of the
/// correspondences points1[i] ↔ points2[i] (pixels, x2 ~ H x1), and the mean distance between image
/// 1's four corners (an image of `size1`) mapped by the two, pixels of image 2. Infinity when a
/// half cannot give a homography (fewer than 4 usable points) or `homography` is singular. Throws
/// std::invalid_argument when the lists differ in length or a coordinate is not finite.
inline double half_disagreement(const std::vector<cv::Point2f>& points1, const std::vector<cv::Point2f>& points2,
                                const std::vector<std::uint8_t>& inliers, const Eigen::Matrix3d& homography,
                                cv::Size size1) {
  detail::require(inliers.size() == points1.size(), "half_disagreement: one inlier flag per correspondence needed");
  const HomographyEstimator estimator(points1, points2);
  std::vector<std::uint8_t> halves[2] = {std::vector<std::uint8_t>(inliers.size(), 0),
                                         std::vector<std::uint8_t>(inliers.size(), 0)};
  int seen = 0;
  for (std::size_t i = 0; i < inliers.size(); ++i) {
    if (inliers[i] != 0) halves[seen++ % 2][i] = 1;
  }
  const std::optional<HomographyModel> start = HomographyModel::from_pixels(homography);
  if (!start) return std::numeric_limits<double>::infinity();
  const std::optional<HomographyModel> a = estimator.refine(*start, halves[0]);
  const std::optional<HomographyModel> b = estimator.refine(*start, halves[1]);
  if (!a || !b) return std::numeric_limits<double>::infinity();
  const double w = size1.width - 1.0, h = size1.height - 1.0;
  double sum = 0.0;
  for (const Eigen::Vector2d& corner :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0), Eigen::Vector2d(0, h), Eigen::Vector2d(w, h)}) {
    sum += ((a->h * corner.homogeneous()).hnormalized() - (b->h * corner.homogeneous()).hnormalized()).norm();
  }
  return std::isfinite(sum) ? sum / 4.0 : std::numeric_limits<double>::infinity();
}

/// Matches two grey images, escalating from plain keypoints to affine views only while the pair is
/// not verified (TwoViewOptions). Per stage k = 0, 1, ...: both images get the keypoints of the
/// stage (stage 0: Extractor::extract_image(); then ViewSession::extend() with the stage's tilts
/// and budget), every keypoint so far of image 1 is matched against every keypoint so far of image 2
/// (match_features(), each stage computing only the descriptor distances of pairs with a new
/// keypoint: the same matches), and select_model() estimates H and F and chooses one (on the last stage,
/// when that model lacks support, TwoViewOptions::last_stage_search may replace it); a chosen homography
/// is put to the precision test (max_half_disagreement) and, with min_inliers inliers that pass
/// the support test (max_false_alarms, min_inlier_ratio), refined by
/// TwoViewOptions::guided_matching, then by TwoViewOptions::align_correspondences, then, when it
/// passed the precision test, fitted by TwoViewOptions::final_fit; the escalation stops when the
/// chosen model has that support and, for a homography, passed the precision test, or when the
/// stages run out. Stage k's keypoints and descriptors are
/// a superset of stage k − 1's.
///
/// Holds one Extractor per image with its workspace: reuse one matcher for many pairs. Not for use
/// by two threads at once.
template <class Descriptor = Rbrief>
class TwoViewMatcher {
 public:
  static constexpr int kBits = Descriptor::kBits;

  explicit TwoViewMatcher(TwoViewOptions options = {}, typename Descriptor::Options descriptor_options = {})
      : options_((options.check(), std::move(options))),
        extractor1_(options_.extractor, descriptor_options),
        extractor2_(options_.extractor, descriptor_options) {}

  const TwoViewOptions& options() const { return options_; }

  /// Matches image1 against image2 (CV_8UC1 each, any sizes). Masks: empty, or CV_8UC1 of their
  /// image's size (Extractor::extract()). Throws std::invalid_argument for an empty image, a wrong
  /// type or a wrong mask. Images without corners give no matches and verified = false after the
  /// last stage.
  TwoViewResult<kBits> match(const cv::Mat& image1, const cv::Mat& image2, const cv::Mat& mask1 = cv::Mat(),
                             const cv::Mat& mask2 = cv::Mat()) {
    TwoViewResult<kBits> result;
    const int n_stages = static_cast<int>(options_.stages.size());
    Clock::time_point start = Clock::now();
    StagedFeatures<Descriptor> staged1 = extractor1_.extract_image(image1, mask1);
    StagedFeatures<Descriptor> staged2 = extractor2_.extract_image(image2, mask2);
    result.features1 = std::move(staged1.features);
    result.features2 = std::move(staged2.features);
    detail::KnnSearches searches;  // each stage appends features: it searches only the new pairs
    for (int k = 0; k <= n_stages; ++k) {
      TwoViewStageReport report;
      if (k > 0) {
        start = Clock::now();
        const ViewStage& stage = options_.stages[static_cast<std::size_t>(k - 1)];
        const int budget = static_cast<int>(std::lround(stage.view_features * options_.extractor.features));
        append(result.features1, staged1.session.extend(stage.max_tilt, budget));
        append(result.features2, staged2.session.extend(stage.max_tilt, budget));
      }
      const Clock::time_point extracted = Clock::now();
      std::vector<Match> matches =
          detail::match_growing_features(result.features1, result.features2, options_.matching, searches);
      const Clock::time_point matched = Clock::now();
      StageModel verified = verify(result.features1, result.features2, std::move(matches), image1, image2,
                                   k == n_stages || options_.all_stages);
      const Clock::time_point verified_at = Clock::now();
      report.failure = failed_test(verified);
      result.verified = !report.failure;
      take_stage(result, std::move(verified), report);
      report.max_tilt = staged1.session.extracted_tilt();
      report.keypoints1 = static_cast<int>(result.features1.size());
      report.keypoints2 = static_cast<int>(result.features2.size());
      report.extract_ms = milliseconds(start, extracted);
      report.match_ms = milliseconds(extracted, matched);
      report.verify_ms = milliseconds(matched, verified_at);
      result.stages.push_back(report);
      result.stage = k;
      if (result.verified && !options_.all_stages) break;
    }
    return result;
  }

 private:
  using Clock = std::chrono::steady_clock;

  static double milliseconds(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  }

  static void append(Features<kBits>& all, const Features<kBits>& more) {
    all.keypoints.insert(all.keypoints.end(), more.keypoints.begin(), more.keypoints.end());
    all.descriptors.insert(all.descriptors.end(), more.descriptors.begin(), more.descriptors.end());
    all.views.insert(all.views.end(), more.views.begin(), more.views.end());
  }

  /// What verify() finds for one stage's matches.
  struct StageModel {
    std::vector<Match> matches;  ///< the stage's matches, or the last guided round's
    MatchedPoints points;        ///< their positions; points2 aligned where alignment accepted them
    ModelSelectionResult model;
    std::vector<std::uint8_t> inliers;  ///< of the chosen model, per match
    int inlier_count = 0;
    std::optional<double> half_disagreement;
    /// The chance that a wrong match is an inlier of the chosen model (the support test).
    double inlier_probability = 1.0;
    int guided_rounds = 0;
    int aligned_count = 0;
    bool searched = false;  ///< the chosen model is TwoViewOptions::last_stage_search's homography
  };

  /// select_model() on the matches; the chosen model's inlier flags and count; on a `reported`
  /// stage whose model lacks support, TwoViewOptions::last_stage_search; for a chosen
  /// homography under the precision test, the disagreement of its two half estimates; a chosen
  /// homography with enough support refined by guided matching and then by aligned
  /// correspondences, and then, when it passed the precision test and still has that support, by
  /// the final fit. Guided matching and alignment run on a homography that failed the precision
  /// test only when the stage is `reported` (the last one, or every one with all_stages): the
  /// next stage matches everything again and its result replaces this one.
  StageModel verify(const Features<kBits>& features1, const Features<kBits>& features2, std::vector<Match> matches,
                    const cv::Mat& image1, const cv::Mat& image2, bool reported) const {
    StageModel stage;
    stage.matches = std::move(matches);
    if (options_.model.ransac.progressive_sampling) {  // PROSAC draws from the best matches first
      std::stable_sort(stage.matches.begin(), stage.matches.end(),
                       [](const Match& a, const Match& b) { return a.distance < b.distance; });
    }
    matched_points(features1.keypoints, features2.keypoints, stage.matches, stage.points);
    stage.inliers.assign(stage.matches.size(), 0);
    if (stage.points.points1.size() < 8) return stage;
    stage.model = select_model(stage.points.points1, stage.points.points2, options_.model);
    stage.inliers = stage.model.chosen_inliers();
    stage.inlier_count = stage.model.chosen_inlier_count();
    stage.inlier_probability = inlier_probability(stage.model.model, image1.size(), image2.size());
    if (reported && options_.last_stage_search && !supported(stage) && search_homography(features1, features2, stage)) {
      stage.searched = true;
      stage.inlier_probability = inlier_probability(stage.model.model, image1.size(), image2.size());
    }
    const bool homography = stage.model.model == GeometricModel::kHomography;
    if (homography && options_.max_half_disagreement) {
      stage.half_disagreement = half_disagreement(stage.points.points1, stage.points.points2, stage.inliers,
                                                  stage.model.homography, image1.size());
    }
    const bool refinable = homography && (reported || precise(stage));
    const std::vector<Match> unguided = refinable && options_.final_fit ? stage.matches : std::vector<Match>{};
    if (refinable && options_.guided_matching && supported(stage)) match_guided_rounds(features1, features2, stage);
    if (refinable && options_.align_correspondences && supported(stage)) align(features1, image1, image2, stage);
    if (refinable && options_.final_fit && supported(stage) && (precise(stage) || stage.guided_rounds > 0)) {
      fit_final(features1, features2, unguided, stage, precise(stage));
    }
    return stage;
  }

  /// TwoViewOptions::last_stage_search on `stage`'s matches (of `features1` and `features2`): when
  /// it finds a homography that scores higher under its σ than the stage's estimated one, that
  /// homography, its inliers and score become the stage's chosen model; returns whether they did.
  bool search_homography(const Features<kBits>& features1, const Features<kBits>& features2, StageModel& stage) const {
    const LastStageSearchOptions& search = *options_.last_stage_search;
    const TruncatedChi2Score scoring = homography_scoring(search.sigma);
    if (!search.max_orientation_difference) {
      return take_search(HomographyEstimator(stage.points.points1, stage.points.points2, scoring), stage);
    }
    std::vector<float> angles1(stage.matches.size()), angles2(stage.matches.size());
    for (std::size_t i = 0; i < stage.matches.size(); ++i) {
      angles1[i] = features1.keypoints[static_cast<std::size_t>(stage.matches[i].query)].angle;
      angles2[i] = features2.keypoints[static_cast<std::size_t>(stage.matches[i].train)].angle;
    }
    return take_search(OrientedHomographyEstimator(stage.points.points1, stage.points.points2, angles1, angles2,
                                                   *search.max_orientation_difference, scoring),
                       stage);
  }

  /// ransac() of the last stage's search with `estimator` (a HomographyEstimator, or an
  /// OrientedHomographyEstimator under LastStageSearchOptions::max_orientation_difference; both
  /// score alike) on `stage`'s matches; its homography becomes the stage's chosen model when it
  /// scores higher than the stage's own. Returns whether it did.
  template <class Estimator>
  bool take_search(const Estimator& estimator, StageModel& stage) const {
    const RansacResult<HomographyModel> found = ransac(estimator, options_.last_stage_search->ransac);
    if (!found.success) return false;
    const std::optional<HomographyModel> current = HomographyModel::from_pixels(stage.model.homography);
    if (current && evaluate_model(estimator, *current).score >= found.score) return false;
    stage.model.success = true;
    stage.model.model = GeometricModel::kHomography;
    take_homography(stage, found);
    return true;
  }

  /// TwoViewOptions::final_fit on the chosen homography of `stage`: with `fit`, refine_homography()
  /// on the stage's matches (the last guided round's, with their aligned points) and the `unguided`
  /// matches not among them, and its homography becomes the fit (unchanged when the fit fails);
  /// without (a homography that failed the precision test, reported as the last stage's), the
  /// homography stays. Either way the stage keeps the unguided matches and the others that the
  /// homography accepts, and its inliers become the matches it accepts
  /// (HomographyRefinementOptions::max_error), so that the returned matches are never looser than
  /// the unguided ones.
  void fit_final(const Features<kBits>& features1, const Features<kBits>& features2, const std::vector<Match>& unguided,
                 StageModel& stage, bool fit) const {
    const auto key = [](const Match& m) { return std::make_pair(m.query, m.train); };
    const auto sorted_keys = [&](const std::vector<Match>& matches) {
      std::vector<std::pair<int, int>> keys(matches.size());
      std::transform(matches.begin(), matches.end(), keys.begin(), key);
      std::sort(keys.begin(), keys.end());
      return keys;
    };
    const std::vector<std::pair<int, int>> own = sorted_keys(unguided), present = sorted_keys(stage.matches);
    const auto holds = [&](const std::vector<std::pair<int, int>>& keys, const Match& m) {
      return std::binary_search(keys.begin(), keys.end(), key(m));
    };
    std::vector<Match> candidates = stage.matches;
    MatchedPoints points = stage.points;
    for (const Match& m : unguided) {
      if (holds(present, m)) continue;
      candidates.push_back(m);
      points.points1.push_back(features1.keypoints[static_cast<std::size_t>(m.query)].pt);
      points.points2.push_back(features2.keypoints[static_cast<std::size_t>(m.train)].pt);
    }
    if (candidates.size() < 4) return;
    RefinedHomography fitted;
    if (fit) {
      fitted = refine_homography(points.points1, points.points2, stage.model.homography, *options_.final_fit);
      if (!fitted.success) return;
    } else {
      fitted.homography = stage.model.homography;
      fitted.inliers =
          transfer_inliers(points.points1, points.points2, fitted.homography, options_.final_fit->max_error);
      fitted.inlier_count = static_cast<int>(std::count(fitted.inliers.begin(), fitted.inliers.end(), 1));
    }
    stage.matches.clear();
    stage.points = MatchedPoints{};
    stage.inliers.clear();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      if (fitted.inliers[i] == 0 && !holds(own, candidates[i])) continue;
      stage.matches.push_back(candidates[i]);
      stage.points.points1.push_back(points.points1[i]);
      stage.points.points2.push_back(points.points2[i]);
      stage.inliers.push_back(fitted.inliers[i]);
    }
    stage.inlier_count = fitted.inlier_count;
    stage.model.homography = fitted.homography;
    stage.model.homography_inliers = stage.inliers;
    stage.model.homography_inlier_count = fitted.inlier_count;
    stage.model.fundamental_inliers.clear();
  }

  /// `result`'s matches, model, inliers and positions become `stage`'s, and `report` counts them.
  void take_stage(TwoViewResult<kBits>& result, StageModel stage, TwoViewStageReport& report) const {
    result.log10_false_alarms = false_alarms(stage);
    result.matches = std::move(stage.matches);
    result.points2 = std::move(stage.points.points2);
    result.model = std::move(stage.model);
    result.inliers = std::move(stage.inliers);
    result.inlier_count = stage.inlier_count;
    result.half_disagreement = stage.half_disagreement;
    result.aligned_count = stage.aligned_count;
    report.matches = static_cast<int>(result.matches.size());
    report.inliers = result.inlier_count;
    report.homography_inlier_count = result.model.homography_inlier_count;
    report.fundamental_inlier_count = result.model.fundamental_inlier_count;
    report.model = result.model.model;
    report.half_disagreement = result.half_disagreement;
    report.log10_false_alarms = result.log10_false_alarms;
    report.guided_rounds = stage.guided_rounds;
    report.aligned = stage.aligned_count;
    report.last_stage_search = stage.searched;
  }

  /// TwoViewOptions::align_correspondences on the chosen homography of `stage`: its points2
  /// become the aligned points, and the homography, its score, inlier flags and count the local
  /// optimisation's on them (kept as they were when it finds no homography).
  void align(const Features<kBits>& features1, const cv::Mat& image1, const cv::Mat& image2, StageModel& stage) const {
    std::vector<float> scales(stage.matches.size());
    for (std::size_t i = 0; i < stage.matches.size(); ++i) {
      const cv::KeyPoint& k = features1.keypoints[static_cast<std::size_t>(stage.matches[i].query)];
      scales[i] = std::max(1.0f, k.size / Descriptor::kPatchSize);
    }
    AlignedCorrespondences aligned =
        align_correspondences(image1, image2, stage.points.points1, stage.points.points2, scales,
                              stage.model.homography, *options_.align_correspondences);
    stage.aligned_count = aligned.aligned_count;
    stage.points.points2 = std::move(aligned.points2);
    const std::optional<HomographyModel> current = HomographyModel::from_pixels(stage.model.homography);
    if (!current) return;
    const RansacResult<HomographyModel> fitted = refit(stage.points, *current);
    if (fitted.success) take_homography(stage, fitted);
  }

  /// The local optimisation of `start` on `points` (TwoViewOptions::refit).
  RansacResult<HomographyModel> refit(const MatchedPoints& points, const HomographyModel& start) const {
    const HomographyEstimator estimator(points.points1, points.points2, homography_scoring(options_.refit.sigma));
    return optimise_locally(estimator, evaluate_model(estimator, start), options_.refit.passes);
  }

  /// The model selection's homography score (ModelSelectionOptions::homography_scoring) at the
  /// noise `sigma`, pixels.
  TruncatedChi2Score homography_scoring(double sigma) const {
    TruncatedChi2Score scoring = options_.model.homography_scoring();
    scoring.sigma = sigma;
    return scoring;
  }

  /// `stage`'s chosen homography, its score, inlier flags and count become `fitted`'s, on
  /// `stage.matches`; fundamental_inliers is emptied (its flags indexed other matches).
  static void take_homography(StageModel& stage, const RansacResult<HomographyModel>& fitted) {
    stage.inliers = fitted.inliers;
    stage.inlier_count = fitted.inlier_count;
    stage.model.homography = fitted.model.h;
    stage.model.homography_score = fitted.score;
    stage.model.homography_inliers = fitted.inliers;
    stage.model.homography_inlier_count = fitted.inlier_count;
    stage.model.fundamental_inliers.clear();
  }

  /// The rounds of TwoViewOptions::guided_matching on the chosen homography of `stage`: its
  /// matches, positions, inliers and homography become the last successful round's.
  void match_guided_rounds(const Features<kBits>& features1, const Features<kBits>& features2,
                           StageModel& stage) const {
    const GuidedMatchingOptions& guided = *options_.guided_matching;
    std::optional<HomographyModel> current = HomographyModel::from_pixels(stage.model.homography);
    std::vector<cv::Point2f> predicted(features1.size());
    GuidedMatchOptions gated = guided.matching;
    MatchedPoints points;
    for (int round = 0; round < guided.rounds && current; ++round) {
      for (std::size_t i = 0; i < predicted.size(); ++i) {
        const cv::Point2f& p = features1.keypoints[i].pt;
        const Eigen::Vector2d q = (current->h * Eigen::Vector3d(p.x, p.y, 1.0)).hnormalized();
        predicted[i] = cv::Point2f(static_cast<float>(q.x()), static_cast<float>(q.y()));
      }
      gated.gate_radius = round == 0 ? guided.matching.gate_radius : guided.tight_gate_radius;
      std::vector<Match> matches = match_guided(features1, features2, predicted, gated);
      matched_points(features1.keypoints, features2.keypoints, matches, points);
      if (points.points1.size() < 8) break;
      const RansacResult<HomographyModel> fitted = refit(points, *current);
      if (!fitted.success) break;
      current = fitted.model;
      stage.matches = std::move(matches);
      std::swap(stage.points, points);
      take_homography(stage, fitted);
      ++stage.guided_rounds;
    }
  }

  /// The chance that a wrong match falls within model selection's inlier bound σ·√χ² of a model's
  /// prediction in the smaller image: near a point for a homography, a line for F.
  double inlier_probability(GeometricModel model, cv::Size size1, cv::Size size2) const {
    const cv::Size smaller = size1.area() <= size2.area() ? size1 : size2;
    const ModelSelectionOptions& m = options_.model;
    return model == GeometricModel::kHomography
               ? point_inlier_probability(m.sigma * std::sqrt(m.homography_chi2), smaller)
               : line_inlier_probability(m.sigma * std::sqrt(m.fundamental_chi2), smaller);
  }

  /// log10 of the chosen model's number of false alarms among the stage's matches (nullopt when no
  /// model was chosen or TwoViewOptions::max_false_alarms is off).
  std::optional<double> false_alarms(const StageModel& stage) const {
    if (!options_.max_false_alarms || stage.model.model == GeometricModel::kNone) return std::nullopt;
    const int sample = stage.model.model == GeometricModel::kHomography ? HomographyEstimator::kSampleSize
                                                                        : FundamentalEstimator::kSampleSize;
    return log10_false_alarms(static_cast<int>(stage.matches.size()), stage.inlier_count, sample,
                              stage.inlier_probability);
  }

  /// The first support test the chosen model fails: a model, min_inliers inliers, max_false_alarms,
  /// min_inlier_ratio (nullopt: it has the support).
  std::optional<VerificationFailure> failed_support(const StageModel& stage) const {
    if (stage.model.model == GeometricModel::kNone) return VerificationFailure::kNoModel;
    if (stage.inlier_count < options_.min_inliers) return VerificationFailure::kFewInliers;
    const std::optional<double> log10_nfa = false_alarms(stage);
    if (log10_nfa && *log10_nfa > std::log10(*options_.max_false_alarms)) return VerificationFailure::kFalseAlarms;
    const double matches = static_cast<double>(stage.matches.size());
    if (options_.min_inlier_ratio && stage.inlier_count < *options_.min_inlier_ratio * matches) {
      return VerificationFailure::kInlierRatio;
    }
    return std::nullopt;
  }

  bool supported(const StageModel& stage) const { return !failed_support(stage); }

  /// The first verification test the chosen model fails: the support tests, then the precision
  /// test (nullopt: the stage verifies the pair).
  std::optional<VerificationFailure> failed_test(const StageModel& stage) const {
    if (const std::optional<VerificationFailure> support = failed_support(stage)) return support;
    if (!precise(stage)) return VerificationFailure::kImprecise;
    return std::nullopt;
  }

  /// The chosen model passes the precision test (TwoViewOptions::max_half_disagreement; an F model
  /// and a test that is off always do).
  bool precise(const StageModel& stage) const {
    return !options_.max_half_disagreement || stage.model.model != GeometricModel::kHomography ||
           (stage.half_disagreement && *stage.half_disagreement <= *options_.max_half_disagreement);
  }

  TwoViewOptions options_;
  Extractor<Descriptor> extractor1_;
  Extractor<Descriptor> extractor2_;
};

/// TwoViewMatcher<Rbrief>(options).match(image1, image2): two-view matching with views on demand
/// in one call. Keep a TwoViewMatcher to reuse its workspaces over many pairs.
inline TwoViewResult<Rbrief::kBits> match_images(const cv::Mat& image1, const cv::Mat& image2,
                                                 const TwoViewOptions& options = {}) {
  return TwoViewMatcher<Rbrief>(options).match(image1, image2);
}

}  // namespace affine_orb
