#pragma once
/// \file
/// The options and the result of TwoViewMatcher (two_view.hpp): the escalation stages, the guided
/// rounds, the verification thresholds, and what each stage and the whole match report.

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/extraction/extractor_options.hpp"
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

/// Refinement of a homography a stage verifies: guided matching and local optimisation (Hartley &
/// Zisserman, Multiple View Geometry, 2nd ed., Alg. 4.6, step (v)).
struct GuidedRefinementOptions {
  /// Rounds (0 = off): each predicts every keypoint of image 1 in image 2 by the current
  /// homography, matches it within the gate (match_guided(); `matching.gate_radius` in the first
  /// round, `refined_gate_radius` after), and re-estimates the homography on
  /// the guided matches by local optimisation (evaluate_model() from the current homography, then
  /// optimise_locally()) under `sigma`. The result's matches, inliers and homography are the last
  /// round's. A round whose matches give no homography of 4 or more inliers ends the refinement
  /// with the previous round's. In [0, 10]. Default 2 (a wide gate, then a tight one): it solves
  /// more pairs of bench/eval_two_view than no refinement, no subset fewer, with more distinct
  /// correct matches, for little time (docs/two_view.md, "Reading").
  int iterations = 2;
  /// The gated matching of each round; its gate_radius is the first round's.
  GuidedMatchOptions matching;
  /// The gate of the rounds after the first, pixels of image 2: once a round has refined the
  /// homography its predictions are good to about a pixel, and a wide gate only adds wrong
  /// partners near the true ones (with the first round's gate in every round bench/eval_two_view's
  /// judge, cv::findHomography on all matches, loses pairs the matcher itself fits well).
  /// 4 px: the inlier bound σ·√5.991 ≈ 2.4 px at σ = 1 plus a keypoint's ~1 px noise, the search
  /// region of guided matching in Hartley & Zisserman (Multiple View Geometry, 2nd ed., Alg. 4.6).
  /// In (0, 1000].
  double refined_gate_radius = 4.0;
  /// σ of the local optimisation, pixels: a correspondence is an inlier when both transfer errors
  /// are below σ·√5.991 (ModelSelectionOptions::homography_chi2). Tighter than model selection's
  /// 2 px, which lets the 4.9 px errors of coarse-octave keypoints weigh on the fit: 1 px keeps the
  /// inliers within 2.4 px, under the judge's 3 px (bench/eval_two_view). Positive and finite.
  double sigma = 1.0;
  /// Local optimisation passes per round (RansacOptions::refinement_passes' meaning). In [1, 100].
  int refinement_passes = 10;

  /// Throws std::invalid_argument for a value outside its range or invalid matching options.
  void check() const {
    matching.check();
    detail::require(iterations >= 0 && iterations <= 10,
                    "GuidedRefinementOptions: iterations must be in [0, 10], got " + std::to_string(iterations));
    detail::require(detail::positive_finite(sigma),
                    "GuidedRefinementOptions: sigma must be positive and finite, got " + std::to_string(sigma));
    detail::require(std::isfinite(refined_gate_radius) && refined_gate_radius > 0.0 && refined_gate_radius <= 1000.0,
                    "GuidedRefinementOptions: refined_gate_radius must be in (0, 1000], got " +
                        std::to_string(refined_gate_radius));
    detail::require(
        refinement_passes >= 1 && refinement_passes <= 100,
        "GuidedRefinementOptions: refinement_passes must be in [1, 100], got " + std::to_string(refinement_passes));
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
  /// A stage whose chosen model has at least this many inliers ends the escalation: the pair is
  /// verified. Range [8, 1000000]. 15 as MODS (10–15 verified inliers); 10 lets wrong stage-0
  /// models through and solves fewer pairs, 20 and 30 solve the same (bench/eval_two_view
  /// --sweep). Larger values (200, say) buy more matches for the time of the views.
  int min_inliers = 15;
  /// And at least this share of the stage's matches must be inliers of the chosen model, so that a
  /// random consensus among mostly wrong matches (repetitive texture) does not end the
  /// escalation. Range [0, 1]; values from 0 to 0.2 verify the same pairs of bench/eval_two_view
  /// --sweep, 0.1 is a guard, not a tuned value.
  double min_inlier_ratio = 0.1;
  /// Precision test of a chosen homography, pixels of image 2 (0 = off): the stage verifies only
  /// when two homographies fitted to the two halves of its inliers (alternate inliers in match
  /// order, linear fit of each) map image 1's four corners within this distance of each other,
  /// mean of the four. Two independent estimates from half the data each differ by about twice the
  /// full estimate's random error, so a value of 2·e rejects models whose corners are predicted
  /// less precisely than about e pixels; a model supported only near one part of the image fails
  /// it, as its extrapolation to the far corners disagrees. The test judges the stage's RANSAC
  /// model, before the guided rounds: those match within a gate around the model's own predictions
  /// and fill both halves with matches that confirm it, right or wrong (graf 1→4: 44 px apart
  /// before them, 2.8 px after, on a model 26 px off). F models are not tested. Default 10 px
  /// (e ≈ the judge's 5 px): against no test, bench/eval_two_view stops on fewer unsolved pairs
  /// and verifies fewer imprecise homographies, solving as many pairs, for the time of the
  /// escalations it causes (docs/two_view.md, "Reading").
  double max_half_disagreement = 10.0;
  /// Guided matching and local optimisation of a homography that has min_inliers inliers making up
  /// min_inlier_ratio of the matches, after the precision test and before the stopping rule counts
  /// its inliers (on by default: GuidedRefinementOptions::iterations).
  GuidedRefinementOptions guided;
  /// Sub-pixel correspondences (refine_correspondences()) for a homography that has min_inliers
  /// inliers making up min_inlier_ratio of the matches, after the guided rounds: image 2's point of
  /// every match is aligned with image 1's patch under the homography, the homography is
  /// re-estimated on the aligned points by local optimisation (GuidedRefinementOptions' σ and
  /// passes), and TwoViewResult::points2 holds them. Off by default: on bench/eval_two_view it
  /// lowers the judge's corner error (cv::findHomography on the correspondences) on most pairs but
  /// barely moves the matcher's own homography or the pairs solved, and the alignment makes the
  /// pairs plain extraction solves markedly slower (docs/two_view.md, "Reading"). On where the
  /// correspondences themselves must be precise (mosaics, calibration; test_refinement checks the
  /// aligned points on a known warp).
  bool refine = false;
  /// The alignment of `refine`.
  CorrespondenceRefinementOptions refinement;
  /// Run every stage whatever stage 0 verified (the views on for every pair); the result is then
  /// that of the last stage.
  bool all_stages = false;

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
  /// outside [0, 16], a ViewBudget other than kAdditive, or min_inliers / min_inlier_ratio out of
  /// range.
  void check() const {
    extractor.check();
    matching.check();
    model.check();
    guided.check();
    refinement.check();
    detail::require(extractor.view_budget == ViewBudget::kAdditive,
                    "TwoViewOptions: views on demand need ExtractorOptions::view_budget = kAdditive");
    double previous = 1.0;
    for (const ViewStage& stage : stages) {
      detail::require(
          std::isfinite(stage.max_tilt) && stage.max_tilt > previous * (1.0 + 1e-3),
          "TwoViewOptions: stage max_tilt values must increase from above 1, got " + std::to_string(stage.max_tilt));
      detail::require(stage.max_tilt <= extractor.views.max_tilt * (1.0 + 1e-3),
                      "TwoViewOptions: a stage's max_tilt exceeds extractor.views.max_tilt (" +
                          std::to_string(stage.max_tilt) + " > " + std::to_string(extractor.views.max_tilt) + ")");
      detail::require(
          std::isfinite(stage.view_features) && stage.view_features >= 0.0 && stage.view_features <= 16.0,
          "TwoViewOptions: a stage's view_features must be in [0, 16], got " + std::to_string(stage.view_features));
      previous = stage.max_tilt;
    }
    detail::require(min_inliers >= 8 && min_inliers <= 1000000,
                    "TwoViewOptions: min_inliers must be in [8, 1000000], got " + std::to_string(min_inliers));
    detail::require(std::isfinite(min_inlier_ratio) && min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0,
                    "TwoViewOptions: min_inlier_ratio must be in [0, 1], got " + std::to_string(min_inlier_ratio));
    detail::require(
        std::isfinite(max_half_disagreement) && max_half_disagreement >= 0.0,
        "TwoViewOptions: max_half_disagreement must be finite and >= 0, got " + std::to_string(max_half_disagreement));
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
  /// Rounds of guided matching run on the stage's homography (TwoViewOptions::guided; 0 when none,
  /// and on a homography that failed the precision test when a further stage follows).
  int guided_rounds = 0;
  /// Matches whose image-2 point was aligned (TwoViewOptions::refine; 0 when it did not run, as for
  /// guided_rounds).
  int refined = 0;
  double extract_ms = 0.0;  ///< the stage's extraction of both images, milliseconds
  double match_ms = 0.0;    ///< matching, milliseconds
  double verify_ms = 0.0;   ///< RANSAC and model selection, milliseconds
};

/// The outcome of TwoViewMatcher::match().
template <int Bits>
struct TwoViewResult {
  /// True when the last stage run verified the pair: its chosen model has at least
  /// TwoViewOptions::min_inliers inliers making up at least min_inlier_ratio of the matches.
  bool verified = false;
  /// The last stage run: 0 = the images alone, k = after TwoViewOptions::stages[k − 1].
  int stage = 0;
  /// Every keypoint extracted up to `stage`, original pixels of each image (Features::views
  /// index Extractor::views()).
  Features<Bits> features1;
  Features<Bits> features2;
  /// Correspondences of the last stage: Match::query indexes features1, Match::train features2.
  std::vector<Match> matches;
  /// Per match, image 2's point of the correspondence, pixels of image 2: aligned with image 1's
  /// patch around the query keypoint where TwoViewOptions::refine accepted it, else the train
  /// keypoint's position.
  std::vector<cv::Point2f> points2;
  /// Matches whose points2 entry was aligned (TwoViewOptions::refine).
  int refined_count = 0;
  /// Per match, 1 = inlier of the chosen model (model.model; all 0 when none was chosen).
  std::vector<std::uint8_t> inliers;
  int inlier_count = 0;
  /// The last stage's TwoViewStageReport::half_disagreement, pixels (nullopt when not measured).
  std::optional<double> half_disagreement;
  /// Both estimates and the choice of the last stage: x2 ~ H x1 and x2ᵀ F x1 = 0, pixels. After
  /// guided rounds (TwoViewOptions::guided) the homography, its score, inlier flags and count are
  /// the last round's, on `matches`; fundamental_inliers is then empty (its flags indexed the
  /// stage's own matches), the fundamental matrix and its inlier count stay the stage's.
  ModelSelectionResult model;
  /// One report per stage run, stage 0 first.
  std::vector<TwoViewStageReport> stages;
};

}  // namespace affine_orb
