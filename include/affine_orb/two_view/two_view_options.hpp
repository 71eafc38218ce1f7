#pragma once
/// \file
/// The options and the result of TwoViewMatcher (two_view.hpp): the escalation stages, guided
/// matching, the verification thresholds, and what each stage and the whole match report.

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/extraction/extractor_options.hpp"
#include "affine_orb/geometry/homography_refinement.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "affine_orb/two_view/alignment.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb {

/// One escalation stage of TwoViewMatcher: the tilted views it adds to both images.
struct ViewStage {
  /// The stage adds the views of ExtractorOptions::views with tilt t in (the previous stage's
  /// max_tilt, max_tilt] (1 before the first stage): with the default √2 series, 2 adds t = √2
  /// and 2, 2√2 adds t = 2√2.
  double max_tilt = 2.0 * std::sqrt(2.0);
  /// Keypoints the stage adds to each image, as a fraction of ExtractorOptions::features (the
  /// image's own budget), shared by its views in proportion to t^view_weight_exponent.
  double view_features = 0.5;
};

/// Guided matching of a homography a stage verifies (TwoViewOptions::guided_matching; Hartley &
/// Zisserman, Multiple View Geometry, 2nd ed., Alg. 4.6, step (v)). Each round predicts every
/// keypoint of image 1 in image 2 by the current homography, matches it within the gate
/// (match_guided()) and re-estimates the homography on the guided matches (TwoViewOptions::refit).
/// The result's matches, inliers and homography are the last round's; a round whose matches give
/// no homography of 4 or more inliers ends the rounds with the previous round's.
struct GuidedMatchingOptions {
  /// Rounds; [1, 10]; default 2, a wide gate, then a tight one (docs/two_view.md, "Reading").
  int rounds = 2;
  /// The gated matching of each round; its gate_radius is the first round's.
  GuidedMatchOptions matching;
  /// The gate of the rounds after the first, pixels of image 2; (0, 1000]; default 4: the inlier
  /// bound σ·√5.991 ≈ 2.4 px at σ = 1 plus a keypoint's ~1 px noise, Alg. 4.6's search region.
  double tight_gate_radius = 4.0;

  /// Throws std::invalid_argument for a value outside its range or invalid matching options.
  void check() const {
    matching.check();
    detail::require_range(rounds, {1.0, 10.0}, "GuidedMatchingOptions: rounds");
    detail::require_range(tight_gate_radius, {0.0, 1000.0, true}, "GuidedMatchingOptions: tight_gate_radius");
  }
};

/// The local optimisation (evaluate_model() from the current homography, then
/// optimise_locally()) that re-estimates a homography in the guided rounds and on aligned
/// correspondences.
struct RefitOptions {
  /// σ, pixels: a correspondence is an inlier when both transfer errors are below σ·√5.991
  /// (ModelSelectionOptions::homography_chi2); (0, inf); default 1, which keeps the inliers within
  /// 2.4 px, under the judge's 3 px (bench/eval_two_view).
  double sigma = 1.0;
  /// Local optimisation passes (RansacOptions::refinement_passes' meaning); [1, 100]; default 10.
  int passes = 10;

  /// Throws std::invalid_argument for a value outside its range.
  void check() const {
    detail::require_range(sigma, detail::kPositive, "RefitOptions: sigma");
    detail::require_range(passes, {1.0, 100.0}, "RefitOptions: passes");
  }
};

/// The search for a homography alone on the last stage's matches when its chosen model lacks
/// support (TwoViewOptions::last_stage_search). select_model()'s 500 samples rarely draw four
/// correct matches among a few percent of correct ones (w⁴ per sample), so the homography an
/// unverified pair returns is often far off where a longer search on the same matches finds one.
struct LastStageSearchOptions {
  /// Samples and termination of the search; default up to 30 000 samples at confidence 0.999
  /// (search_ransac()).
  RansacOptions ransac = search_ransac();
  /// σ of its truncated χ² score, pixels: inliers within σ·√χ² (ModelSelectionOptions::
  /// homography_chi2); (0, inf); default 1.5, between the refit's 1 and model selection's 2: on
  /// bench/eval_two_view 1 left EVD adam 13.4 px off, 2 lowered the MAGSAC++ judge there
  /// (docs/two_view.md, "Fewer inliers and the last stage's search"; chosen on those pairs).
  double sigma = 1.5;
  /// The orientation test of a sample, degrees: a sample's homography is scored only when it maps
  /// each of its four keypoints' orientations in image 1 to within this angle of the matched
  /// keypoint's in image 2 (OrientedHomographyEstimator). A sample of wrong matches passes with
  /// probability (angle/180)⁴, so most samples are refused before they are scored, and 30 000
  /// cost about 1.4 times the instructions of 10 000 untested ones. (0, 180]; default 45: 30°
  /// and 60° lie at or below it over all pairs on every seed of bench/eval_two_view --sweep
  /// (docs/two_view.md, "The orientation test of the last stage's search"); nullopt: every
  /// sample scored.
  std::optional<double> max_orientation_difference = 45.0;

  /// RansacOptions with 30 000 samples at most and confidence 0.999, the rest as its defaults:
  /// with the orientation test, 30 000 raise AUC@5 of the own homography over 10 000 untested
  /// samples over all pairs of bench/eval_two_view and lower no subset on any seed; 100 000 lose
  /// one pair on one seed (docs/two_view.md, "The orientation test of the last stage's search").
  static RansacOptions search_ransac() {
    RansacOptions options;
    options.max_iterations = 30000;
    options.confidence = 0.999;
    return options;
  }

  /// Throws std::invalid_argument for invalid RANSAC options, a sigma outside its range or a
  /// max_orientation_difference outside (0, 180].
  void check() const {
    ransac.check();
    detail::require_range(sigma, detail::kPositive, "LastStageSearchOptions: sigma");
    if (max_orientation_difference) {
      detail::require_range(*max_orientation_difference, {0.0, 180.0, true},
                            "LastStageSearchOptions: max_orientation_difference");
    }
  }
};

/// Options of TwoViewMatcher. The defaults are chosen on the Oxford pairs and opencv-doc's pairs
/// with ground-truth homographies by bench/eval_two_view, which prints, per pair and method,
/// whether the pair is solved, its distinct correct matches and the total time.
struct TwoViewOptions {
  /// Extraction of both images. Stage 0 extracts the images alone (`features` keypoints each);
  /// views.max_tilt must cover the last stage. The default differs from ExtractorOptions' in two
  /// values: 2000 image keypoints, so that an easy pair finds as many correct matches as plain
  /// extraction with 2000 keypoints does, and the strongest corners (Spreading::kStrongest), which
  /// repeat better between two wide-baseline images than spread ones (bench/eval_viewpoint).
  ExtractorOptions extractor = default_extractor();
  /// The stages after stage 0, in increasing max_tilt; empty: plain matching only. The default
  /// (+0.25 N up to tilt 2, +0.5 N up to 2√2) solves as many pairs as one stage of every view, or
  /// three stages, or stages up to tilt 4 do, with the fewest views run; doubling the stages'
  /// budgets solves fewer (bench/eval_two_view --sweep). stages_up_to(extractor.views) gives the
  /// stages for another view set (to 4√2 for views at 70–85°).
  std::vector<ViewStage> stages = {{2.0, 0.25}, {2.0 * std::sqrt(2.0), 0.5}};
  /// Matching after each stage: every keypoint so far of image 1 against every keypoint so far of
  /// image 2 (location-aware ratio test, duplicate removal; affine_matching.hpp).
  AffineMatchOptions matching;
  /// Verification after each stage: RANSAC for H and F and the choice between them
  /// (select_model()).
  ModelSelectionOptions model;
  /// A stage whose chosen model has at least this many inliers, and passes the support and
  /// precision tests below, ends the escalation: the pair is verified. Range [8, 1000000].
  /// Default 12, within MODS's 10–15 verified inliers, chosen with last_stage_search by the
  /// decision rule of docs/two_view.md ("Fewer inliers and the last stage's search"): the
  /// a-contrario test judges the support, and this count only keeps a few chance inliers from
  /// deciding; at 10 an unverified last stage of 11 inliers counts as supported and its guided
  /// matches loosen the returned ones (bench/eval_two_view --sweep). Larger values (200, say) buy
  /// more matches for the time of the views.
  int min_inliers = 12;
  /// The a-contrario support test (log10_false_alarms(), geometry/a_contrario.hpp): the chosen
  /// model's number of false alarms among the stage's matches, with model selection's inlier bound
  /// (σ·√χ², 4.9 px by default: a point within that of a homography's prediction, or of an epipolar
  /// line, in the smaller image), must be at most this, so that a chance consensus among wrong
  /// matches (repetitive texture) does not end the escalation, while a correct model supported by a
  /// few percent of many matches does. (0, inf); default 1, the meaningful models of Moisan &
  /// Stival; nullopt: no test. It refuses F models with few inliers, e.g. 16 of 79, which an 8-point
  /// sample explains by chance (docs/two_view.md, "How the matcher decides to stop").
  std::optional<double> max_false_alarms = 1.0;
  /// The earlier support test, a bound on the share of the stage's matches that are inliers of the
  /// chosen model; [0, 1]; default nullopt (no bound): 0.1 refused correct models supported by a
  /// few percent of the matches (day/night pairs) and changed no outcome of bench/eval_two_view.
  std::optional<double> min_inlier_ratio;
  /// Precision test of a chosen homography, pixels of image 2: the stage verifies only when two
  /// homographies fitted to alternate halves of its inliers map image 1's four corners within this
  /// mean distance of each other (half_disagreement()). Two half-data estimates differ by about
  /// twice the full estimate's error, so 2·e rejects models whose corners are less precise than
  /// about e pixels, and a model supported near one part of the image only fails. It judges the
  /// RANSAC model, before guided matching (whose gate fills both halves with confirming matches,
  /// right or wrong); F models are not tested. (0, inf); default 10 (e ≈ the judge's 5 px,
  /// docs/two_view.md, "Reading"); nullopt: no test.
  std::optional<double> max_half_disagreement = 10.0;
  /// Guided matching of a homography that has min_inliers inliers and passes the support test,
  /// after the precision test and before the stopping rule counts its inliers; default
  /// GuidedMatchingOptions{} (on); nullopt: off.
  std::optional<GuidedMatchingOptions> guided_matching = GuidedMatchingOptions{};
  /// Sub-pixel correspondences for such a homography, after guided matching: image 2's point of
  /// every match is aligned with image 1's patch under the homography (align_correspondences()),
  /// the homography is fitted again on them (`refit`), and TwoViewResult::points2 holds them.
  /// Default nullopt (off): it lowers the judge's corner error on most pairs of bench/eval_two_view
  /// but barely moves the matcher's own homography, and slows the easy pairs (docs/two_view.md,
  /// "Reading"); for mosaics and calibration, where the correspondences must be precise.
  std::optional<CorrespondenceAlignmentOptions> align_correspondences;
  /// The re-estimation of guided matching and of aligned correspondences.
  RefitOptions refit;
  /// The final fit of a chosen homography that passed the precision test and has min_inliers
  /// inliers and passes the support test, after guided matching and alignment:
  /// refine_homography() (IRLS of the Sampson error, Cauchy weights, over every correspondence
  /// within max_error, 4 px by default) on the stage's own matches and the last guided round's.
  /// The result's homography is the fit; its matches are the stage's own (unguided) matches and
  /// the guided matches the fit accepts, so that they are never looser than the unguided ones; its
  /// inliers are the matches the fit accepts (both transfer errors within max_error). The guided
  /// rounds then only feed the estimate. Default on: it raises AUC@5 of the own homography over
  /// all pairs of bench/eval_two_view, on both halves and on no subset less (docs/two_view.md,
  /// "AUC of the own model and of two judges"); nullopt: the homography, matches and inliers of
  /// the last guided round (or of the local optimisation) as they are.
  std::optional<HomographyRefinementOptions> final_fit = HomographyRefinementOptions{};
  /// Run every stage whatever stage 0 verified (the views on for every pair); the result is then
  /// that of the last stage.
  bool all_stages = false;
  /// When the last stage's chosen model has fewer than min_inliers inliers or fails the support
  /// test, a longer RANSAC for a homography alone on its matches; a homography that scores higher
  /// than the stage's becomes the chosen model, with its inliers at LastStageSearchOptions::sigma,
  /// and goes through the stopping rule's tests, guided matching and the final fit as the stage's
  /// own would. Default on, with min_inliers 12: together they raise AUC@5 of the own homography
  /// over all pairs of bench/eval_two_view, on both halves and on no subset less (docs/two_view.md,
  /// "Fewer inliers and the last stage's search"); it runs only on pairs no stage verified, after
  /// their views. nullopt: the last stage's model as select_model() chose it.
  std::optional<LastStageSearchOptions> last_stage_search = LastStageSearchOptions{};

  /// The extractor options of the default: ExtractorOptions with 2000 keypoints and the strongest
  /// corners per level.
  static ExtractorOptions default_extractor() {
    ExtractorOptions options;
    options.features = 2000;
    options.spreading = Spreading::kStrongest;
    return options;
  }

  /// Throws std::invalid_argument for invalid extractor, matching or model options, stages whose
  /// max_tilt does not increase from above 1 or exceeds extractor.views.max_tilt, a view_features
  /// outside [0, 16], a ViewBudget other than kAdditive, or min_inliers, max_false_alarms,
  /// min_inlier_ratio or max_half_disagreement out of range, or invalid last_stage_search options.
  void check() const {
    extractor.check();
    matching.check();
    model.check();
    if (guided_matching) guided_matching->check();
    if (align_correspondences) align_correspondences->check();
    refit.check();
    if (final_fit) final_fit->check();
    if (last_stage_search) last_stage_search->check();
    detail::require(extractor.additive_budget() != nullptr,
                    "TwoViewOptions: views on demand need the AdditiveBudget extractor.view_budget");
    double previous = 1.0;
    for (const ViewStage& stage : stages) {
      detail::require_range(stage.max_tilt, {previous * (1.0 + 1e-3), extractor.views.max_tilt * (1.0 + 1e-3), true},
                            "TwoViewOptions: a stage's max_tilt (increasing, within extractor.views.max_tilt)");
      detail::require_range(stage.view_features, {0.0, 16.0}, "TwoViewOptions: a stage's view_features");
      previous = stage.max_tilt;
    }
    detail::require_range(min_inliers, {8.0, 1000000.0}, "TwoViewOptions: min_inliers");
    if (max_false_alarms) {
      detail::require_range(*max_false_alarms, detail::kPositive, "TwoViewOptions: max_false_alarms");
    }
    if (min_inlier_ratio) detail::require_range(*min_inlier_ratio, {0.0, 1.0}, "TwoViewOptions: min_inlier_ratio");
    if (max_half_disagreement) {
      detail::require_range(*max_half_disagreement, detail::kPositive, "TwoViewOptions: max_half_disagreement");
    }
  }
};

/// The stages of views on demand for the view set `views`, as far as it goes: TwoViewOptions'
/// default stages (+0.25 N up to tilt 2, +0.5 N up to 2√2) that hold a tilt of the views' series
/// t = a, a², ... (AffineViewOptions::tilt_ratio a), a stage cut at views.max_tilt ending on the
/// largest tilt below it, then one stage per further tilt of the series up to views.max_tilt,
/// adding 0.5 N each (N the image budget, ExtractorOptions::features); none for max_tilt 1. With
/// the default series and max_tilt 4√2: the default stages, then 4 and 4√2, as MODS escalates to
/// tilts near 9 (Mishkin, Matas, Perdoch, CVIU 2015) and ASIFT simulates with maxTilt 5. Stages
/// past 2√2 run only while a pair is not verified: on bench/eval_two_view ("stages to 5.66") they
/// solve and verify pairs the default stages leave unverified, for more time over all pairs (each
/// pair they do not verify runs two more stages; docs/two_view.md, "Reading"); a plane at tilt 8
/// is verified at stage 3 (test_two_view). Set `options.extractor.views` first, then
/// `options.stages = stages_up_to(options.extractor.views)`. Throws std::invalid_argument for
/// invalid view options.
inline std::vector<ViewStage> stages_up_to(const AffineViewOptions& views) {
  const double tolerance = 1.0 + 1e-3;  // view_parameters()'
  const double cap = views.max_tilt * tolerance;
  std::vector<double> series;  // the tilts above 1 of the view set, increasing
  for (const auto& [tilt, rotation] : view_parameters(views)) {
    if (tilt > 1.0 && (series.empty() || tilt != series.back())) series.push_back(tilt);
  }
  std::vector<ViewStage> stages;
  double lower = 1.0;
  for (const ViewStage& stage : TwoViewOptions{}.stages) {
    double top = 0.0;
    for (const double t : series) {
      if (t > lower * tolerance && t <= stage.max_tilt * tolerance) top = t;
    }
    if (top > 0.0) stages.push_back({stage.max_tilt <= cap ? stage.max_tilt : top, stage.view_features});
    lower = stage.max_tilt;
  }
  for (const double t : series) {
    if (t > lower * tolerance) stages.push_back({t, 0.5});
  }
  return stages;
}

/// Why a stage of TwoViewMatcher::match() did not verify the pair: the first test its chosen model
/// fails, in this order (TwoViewStageReport::failure).
enum class VerificationFailure {
  kNoModel,      ///< no model chosen: fewer than 8 matches, or select_model() found neither H nor F
  kFewInliers,   ///< fewer than TwoViewOptions::min_inliers inliers
  kFalseAlarms,  ///< more false alarms than TwoViewOptions::max_false_alarms (the a-contrario support test)
  kInlierRatio,  ///< inliers below TwoViewOptions::min_inlier_ratio of the matches
  kImprecise,    ///< a homography whose halves disagree by more than TwoViewOptions::max_half_disagreement
};

/// A short lowercase name of `failure`: "no model", "few inliers", "false alarms", "inlier ratio",
/// "imprecise".
inline const char* verification_failure_name(VerificationFailure failure) {
  switch (failure) {
    case VerificationFailure::kNoModel:
      return "no model";
    case VerificationFailure::kFewInliers:
      return "few inliers";
    case VerificationFailure::kFalseAlarms:
      return "false alarms";
    case VerificationFailure::kInlierRatio:
      return "inlier ratio";
    default:
      return "imprecise";
  }
}

/// What one stage of TwoViewMatcher::match() did.
struct TwoViewStageReport {
  double max_tilt = 1.0;             ///< largest tilt extracted so far (1: the images alone)
  int keypoints1 = 0;                ///< keypoints of image 1 so far
  int keypoints2 = 0;                ///< keypoints of image 2 so far
  int matches = 0;                   ///< correspondences after the stage
  int inliers = 0;                   ///< inliers of the chosen model (0 when none was chosen)
  int homography_inlier_count = 0;   ///< inliers of the estimated H (0 when none was found)
  int fundamental_inlier_count = 0;  ///< inliers of the estimated F (0 when none was found)
  GeometricModel model = GeometricModel::kNone;
  /// Mean distance between image 1's corners mapped by the homographies of the two halves of the
  /// RANSAC model's inliers (before the guided rounds), pixels of image 2
  /// (TwoViewOptions::max_half_disagreement); measured only when the test is on and a homography
  /// was chosen.
  std::optional<double> half_disagreement;
  /// log10 of the chosen model's number of false alarms among the stage's matches
  /// (TwoViewOptions::max_false_alarms; nullopt when no model was chosen or the test is off).
  std::optional<double> log10_false_alarms;
  /// Rounds of guided matching run on the stage's homography (TwoViewOptions::guided_matching; 0 when none,
  /// and on a homography that failed the precision test when a further stage follows).
  int guided_rounds = 0;
  /// Matches whose image-2 point was aligned (TwoViewOptions::align_correspondences; 0 when it did
  /// not run, as for guided_rounds).
  int aligned = 0;
  /// The chosen model is the homography of TwoViewOptions::last_stage_search, which replaced
  /// select_model()'s choice (false when the search did not run or found nothing better).
  bool last_stage_search = false;
  /// The first verification test the stage's chosen model fails (VerificationFailure); nullopt when
  /// the stage verified the pair.
  std::optional<VerificationFailure> failure;
  double extract_ms = 0.0;  ///< the stage's extraction of both images, milliseconds
  double match_ms = 0.0;    ///< matching, milliseconds
  double verify_ms = 0.0;   ///< RANSAC and model selection, milliseconds
};

/// The outcome of TwoViewMatcher::match().
template <int Bits>
struct TwoViewResult {
  /// True when the last stage run verified the pair: its chosen model has at least
  /// TwoViewOptions::min_inliers inliers, passes the support tests (max_false_alarms,
  /// min_inlier_ratio) and, for a homography, the precision test (max_half_disagreement);
  /// stages.back().failure says which test failed when it is false.
  bool verified = false;
  /// The last stage run: 0 = the images alone, k = after TwoViewOptions::stages[k − 1].
  int stage = 0;
  /// Every keypoint extracted up to `stage`, original pixels of each image (Features::views
  /// index Extractor::views()).
  Features<Bits> features1;
  Features<Bits> features2;
  /// Correspondences of the last stage: Match::query indexes features1, Match::train features2.
  /// After guided rounds, the last round's; with TwoViewOptions::final_fit, the stage's own matches
  /// and the guided ones the final homography accepts.
  std::vector<Match> matches;
  /// Per match, image 2's point of the correspondence, pixels of image 2: aligned with image 1's
  /// patch around the query keypoint where TwoViewOptions::align_correspondences accepted it, else the train
  /// keypoint's position.
  std::vector<cv::Point2f> points2;
  /// Matches whose points2 entry was aligned (TwoViewOptions::align_correspondences).
  int aligned_count = 0;
  /// Per match, 1 = inlier of the chosen model (model.model; all 0 when none was chosen).
  std::vector<std::uint8_t> inliers;
  int inlier_count = 0;
  /// The last stage's TwoViewStageReport::half_disagreement, pixels (nullopt when not measured).
  std::optional<double> half_disagreement;
  /// The last stage's TwoViewStageReport::log10_false_alarms (nullopt when not measured).
  std::optional<double> log10_false_alarms;
  /// Both estimates and the choice of the last stage: x2 ~ H x1 and x2ᵀ F x1 = 0, pixels. After
  /// guided rounds (TwoViewOptions::guided_matching) the homography, its score, inlier flags and count are
  /// the last round's, on `matches`; fundamental_inliers is then empty (its flags indexed the
  /// stage's own matches), the fundamental matrix and its inlier count stay the stage's. After
  /// the final fit (TwoViewOptions::final_fit) the homography, inlier flags and count are the
  /// fit's; the score stays the local optimisation's.
  ModelSelectionResult model;
  /// One report per stage run, stage 0 first.
  std::vector<TwoViewStageReport> stages;
};

}  // namespace affine_orb
