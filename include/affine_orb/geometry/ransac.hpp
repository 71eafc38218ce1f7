#pragma once
/// \file
/// Generic, seeded RANSAC over a compile-time estimator interface (no virtual calls), with the
/// truncated χ² score of ORB-SLAM's initializer (paper eqs. 20–21) as the scoring rule of the
/// geometric estimators.
///
/// An estimator type `E` provides:
///
/// - `using Model = ...;` copyable and default-constructible;
/// - `static constexpr int kSampleSize;` correspondences per minimal sample;
/// - `static constexpr int kMaxModels;` most models one minimal sample can give;
/// - `std::size_t size() const;` number of correspondences;
/// - `ModelSet<Model, kMaxModels> generate(const std::array<int, kSampleSize>& sample) const;`
///   the models through the sampled correspondences (indices in [0, size())); zero models for a
///   degenerate sample (repeated or collinear points), never a non-finite model;
/// - `PointScore score(const Model& model, std::size_t index) const;` the score contribution of
///   one correspondence (larger is better) and whether it is an inlier;
/// - `double max_point_score() const;` an upper bound of `score(...).value`, used to stop scoring
///   a model as soon as it can no longer beat the best one (this never changes the result);
/// - optionally `std::optional<Model> refine(const Model& model, const std::vector<std::uint8_t>&
///   inliers) const;` a re-estimate from all inliers of `model` (mask of size() entries, non-zero
///   = inlier), or nullopt; ransac() calls it repeatedly (local optimisation), so one step of an
///   iterative method is enough.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/geometry/detail/ransac.hpp"
#include "affine_orb/geometry/detail/ransac_sampler.hpp"

namespace affine_orb {

/// Iteration control of ransac().
struct RansacOptions {
  /// Most minimal samples drawn. With adaptive termination at 99 % confidence, 500 covers 8-point
  /// samples (F) at up to ~44 % outliers: log(0.01) / log(1 − 0.56⁸) ≈ 474 (Hartley & Zisserman,
  /// Multiple View Geometry, 2nd ed., Table 4.3, lists 1177 at 50 %). ORB-SLAM2's initializer
  /// draws a fixed 200 (Initializer.cc, mMaxIterations).
  int max_iterations = 500;
  /// Fewest minimal samples drawn even when adaptive termination would stop earlier, so that a
  /// first model with nearly all points as inliers is still compared with a few others. 20 is a
  /// quarter of the ~78 8-point samples 30 % outliers call for.
  int min_iterations = 20;
  /// Probability that at least one drawn sample is outlier-free when the search stops: iterations
  /// N = log(1 − confidence) / log(1 − w^s) for inlier ratio w of the best model so far and sample
  /// size s (Fischler & Bolles 1981; Hartley & Zisserman eq. 4.18). 0.99 is the customary value
  /// (Hartley & Zisserman Sec. 4.7.1).
  double confidence = 0.99;
  /// PROSAC (Chum & Matas, CVPR 2005): the correspondences come ordered best first (e.g. by
  /// descriptor distance), and the samples are drawn from a leading subset that grows to all of
  /// them by max_iterations (detail::ProgressiveSampler), so that a model whose inliers are a few
  /// percent of the correspondences but rank high is drawn within hundreds of samples where a
  /// uniform draw needs ~1/w⁴. Default false: uniform draws (any order).
  bool progressive_sampling = false;
  /// Seed of the std::mt19937_64 that draws the samples: the same data, options and seed give the
  /// same result.
  std::uint64_t seed = 0x5eed;
  /// Adaptive termination treats the inlier ratio as at least this value (0 = off): the search
  /// stops once a model supported by this share of the correspondences would have been sampled
  /// with `confidence`, even when the best model so far has fewer inliers. For searches where only
  /// models at least that well supported matter (select_model() stops the search for H once no
  /// H that could change its decision can have been missed).
  double termination_inlier_ratio = 0.0;
  /// Local optimisation (LO-RANSAC, Chum, Matas & Kittler, DAGM 2003): every new best model is
  /// re-estimated from its inliers and re-scored, up to this many times while the score improves
  /// and the inlier set changes (0 = none). Only used when the estimator has refine(). A model from
  /// a noisy minimal sample can start with a fraction of the inliers; the set grows pass by pass and
  /// has settled after well under 10 passes in the tests and benchmarks.
  int refinement_passes = 10;

  /// Throws std::invalid_argument unless 1 <= max_iterations, 0 <= min_iterations <=
  /// max_iterations, 0 < confidence < 1, 0 <= termination_inlier_ratio <= 1 and
  /// refinement_passes >= 0.
  void check() const {
    detail::require_range(max_iterations, detail::kPositive, "RansacOptions: max_iterations");
    detail::require(
        min_iterations >= 0 && min_iterations <= max_iterations,
        "RansacOptions: min_iterations must be in [0, max_iterations], got " + std::to_string(min_iterations));
    detail::require_range(confidence, {0, 1, true, true}, "RansacOptions: confidence");
    detail::require_range(termination_inlier_ratio, {0, 1}, "RansacOptions: termination_inlier_ratio");
    detail::require_range(refinement_passes, detail::kNonNegative, "RansacOptions: refinement_passes");
  }
};

/// Truncated χ² score of one measurement direction (ORB-SLAM initializer; paper eqs. 20–21):
/// a squared error d² (pixels²) contributes score_constant − d²/σ² when d²/σ² < chi2_threshold and
/// nothing otherwise.
struct TruncatedChi2Score {
  /// Standard deviation σ of the measurement, pixels (ORB-SLAM2: 1 px at pyramid level 0).
  double sigma = 1.0;
  /// Rejection threshold T_m on d²/σ². 5.991 is the 95 % quantile of χ² with 2 degrees of freedom
  /// (homography transfer error); use 3.841 (1 degree of freedom) for epipolar distances.
  double chi2_threshold = 5.991;
  /// Scoring constant T (ORB-SLAM2 uses 5.991 for both models so that their scores compare).
  double score_constant = 5.991;

  /// Throws std::invalid_argument unless sigma and chi2_threshold are positive and finite and
  /// chi2_threshold <= score_constant < infinity (so that every inlier term is positive).
  void check() const {
    detail::require_range(sigma, detail::kPositive, "TruncatedChi2Score: sigma");
    detail::require_range(chi2_threshold, detail::kPositive, "TruncatedChi2Score: chi2_threshold");
    detail::require(std::isfinite(score_constant) && score_constant >= chi2_threshold,
                    "TruncatedChi2Score: score_constant must be finite and >= chi2_threshold, got " +
                        std::to_string(score_constant));
  }
};

/// Per-correspondence multipliers of a score's σ, one list per image: an error measured in image k
/// (the distance of a point of image k to its predicted position or epipolar line) of
/// correspondence i is divided by (σ · image_k[i])² instead of σ². For keypoints detected at
/// different pyramid levels: a keypoint of octave o is located to about s^o level-0 pixels (scale
/// factor s), so image_k[i] = s^o of its keypoint. Empty lists mean 1 for every correspondence.
struct SigmaScales {
  std::vector<double> image1;  ///< multiplier of σ for errors measured in image 1, unitless
  std::vector<double> image2;  ///< multiplier of σ for errors measured in image 2, unitless

  /// Throws std::invalid_argument unless both lists are empty, or both have `count` entries that
  /// are all positive and finite.
  void check(std::size_t count) const {
    detail::require((image1.empty() && image2.empty()) || (image1.size() == count && image2.size() == count),
                    "SigmaScales: image1 and image2 must both be empty or both have one entry per correspondence (" +
                        std::to_string(count) + "), got " + std::to_string(image1.size()) + " and " +
                        std::to_string(image2.size()));
    for (const std::vector<double>* list : {&image1, &image2}) {
      for (const double v : *list) {
        detail::require_range(v, detail::kPositive, "SigmaScales: every multiplier");
      }
    }
  }
};

/// Score contribution of one correspondence under one model.
struct PointScore {
  double value = 0.0;   ///< added to the model's score; larger is better
  bool inlier = false;  ///< whether the correspondence supports the model
};

/// A checked TruncatedChi2Score with 1/σ² computed once, as the estimators apply it to every
/// squared residual of every model.
class Chi2Scorer {
 public:
  /// Throws std::invalid_argument when `scoring` fails its check().
  explicit Chi2Scorer(const TruncatedChi2Score& scoring)
      : inv_sigma_squared_((scoring.check(), 1.0 / (scoring.sigma * scoring.sigma))),
        threshold_(scoring.chi2_threshold),
        constant_(scoring.score_constant) {}

  /// Adds the term of one squared residual (pixels²) to `s`: T − d²/σ² when d²/σ² < T_m, else
  /// marks the correspondence an outlier (also for NaN, an undefined residual).
  /// `inverse_scale_squared` is 1/m² for a σ multiplied by m for this correspondence (SigmaScales;
  /// 1 for σ itself).
  void add(double squared, double inverse_scale_squared, PointScore& s) const {
    const double chi2 = squared * inv_sigma_squared_ * inverse_scale_squared;
    if (chi2 < threshold_) {
      s.value += constant_ - chi2;
    } else {
      s.inlier = false;
    }
  }

  /// Score of a correspondence with `residuals` residuals at zero.
  double max_score(int residuals) const { return residuals * constant_; }

 private:
  double inv_sigma_squared_;
  double threshold_;
  double constant_;
};

/// SigmaScales as the factors 1/m² the squared errors are multiplied by (1 when the lists are empty).
class InverseScaleSquares {
 public:
  InverseScaleSquares() = default;
  /// Throws std::invalid_argument when `scales` fails check(count).
  InverseScaleSquares(const SigmaScales& scales, std::size_t count) {
    scales.check(count);
    for (const double m : scales.image1) image1_.push_back(1.0 / (m * m));
    for (const double m : scales.image2) image2_.push_back(1.0 / (m * m));
  }
  /// 1/m² of correspondence i for an error measured in image 1 (image1()) or image 2 (image2()).
  double image1(std::size_t i) const { return image1_.empty() ? 1.0 : image1_[i]; }
  double image2(std::size_t i) const { return image2_.empty() ? 1.0 : image2_[i]; }

 private:
  std::vector<double> image1_, image2_;
};

/// Up to `Capacity` models from one minimal sample, stored inline (no allocation).
template <class Model, int Capacity>
struct ModelSet {
  std::array<Model, static_cast<std::size_t>(Capacity)> models{};
  int count = 0;

  /// Appends a model (ignored when full).
  void push(const Model& model) {
    if (count < Capacity) models[static_cast<std::size_t>(count++)] = model;
  }
};

/// Outcome of ransac().
template <class Model>
struct RansacResult {
  /// True when a model supported by at least a minimal sample's worth of inliers was found.
  bool success = false;
  /// The best model (after refinement); value-initialised when !success.
  Model model{};
  /// One entry per correspondence, 1 = inlier of `model`.
  std::vector<std::uint8_t> inliers;
  int inlier_count = 0;
  /// Sum of the per-correspondence scores of `model`.
  double score = 0.0;
  /// Minimal samples drawn.
  int iterations = 0;
};

/// `model` scored on every correspondence: its score, inliers and their count; success when it has
/// at least Estimator::kSampleSize inliers (iterations 0).
template <class Estimator>
RansacResult<typename Estimator::Model> evaluate_model(const Estimator& estimator,
                                                       const typename Estimator::Model& model) {
  RansacResult<typename Estimator::Model> result;
  result.inliers.assign(estimator.size(), 0);
  const auto scored = detail::score_model(estimator, model, -std::numeric_limits<double>::infinity(), result.inliers);
  result.model = model;
  result.score = scored->first;
  result.inlier_count = scored->second;
  result.success = result.inlier_count >= Estimator::kSampleSize;
  return result;
}

/// Local optimisation (LO-RANSAC, Chum, Matas & Kittler, DAGM 2003) of a scored model: `start`
/// (model, score, inliers and inlier count on every correspondence, as evaluate_model() gives) is
/// re-estimated from its inliers with estimator.refine() and re-scored, up to `passes` times while
/// the score improves and the inlier set changes. Returns `start` with the last improving model,
/// its score, inliers and count (iterations and success as given); `start` itself when the
/// estimator has no refine() or no pass improves. ransac() applies it to every new best sample
/// model; select_model() to the plane-and-parallax completion of F.
template <class Estimator>
RansacResult<typename Estimator::Model> optimise_locally(const Estimator& estimator,
                                                         RansacResult<typename Estimator::Model> start, int passes) {
  if constexpr (detail::HasRefine<Estimator>::value) {
    std::vector<std::uint8_t> mask(estimator.size(), 0);
    for (int pass = 0; pass < passes; ++pass) {
      const auto refined = estimator.refine(start.model, start.inliers);
      if (!refined) break;
      const auto scored = detail::score_model(estimator, *refined, start.score, mask);
      if (!scored) break;
      start.model = *refined;
      start.score = scored->first;
      start.inlier_count = scored->second;
      start.inliers.swap(mask);
      if (start.inliers == mask) break;  // same inliers: the next pass would refit the same set
    }
  }
  return start;
}

namespace detail {

/// Iterations ransac() needs at `inlier_ratio` (adaptive_iterations(), the ratio never below
/// options.termination_inlier_ratio).
inline int needed_iterations(const RansacOptions& options, int sample_size, double inlier_ratio) {
  return adaptive_iterations(std::max(inlier_ratio, options.termination_inlier_ratio), sample_size, options.confidence,
                             options.max_iterations);
}

/// The models of one ransac() iteration: draws drawn.size() distinct indices into `drawn` and
/// hands the first Estimator::kSampleSize of them to estimator.generate().
template <class Estimator, class Sampler>
auto sample_models(const Estimator& estimator, Sampler& sampler, std::vector<int>& drawn) {
  std::array<int, static_cast<std::size_t>(Estimator::kSampleSize)> sample{};
  sampler.draw(drawn.data(), static_cast<int>(drawn.size()));
  std::copy_n(drawn.begin(), Estimator::kSampleSize, sample.begin());
  return estimator.generate(sample);
}

/// A sample model that beat every earlier sample, locally optimised (optimise_locally()):
/// `candidate`, its buffers reused, takes `model`, its score and inlier count `scored`, and the
/// inliers in `mask`, whose buffer it swaps for its own.
template <class Estimator>
RansacResult<typename Estimator::Model> optimised_sample(const Estimator& estimator,
                                                         const typename Estimator::Model& model,
                                                         std::pair<double, int> scored, std::vector<std::uint8_t>& mask,
                                                         RansacResult<typename Estimator::Model> candidate,
                                                         int passes) {
  candidate.model = model;
  candidate.score = scored.first;
  candidate.inlier_count = scored.second;
  candidate.inliers.swap(mask);
  return optimise_locally(estimator, std::move(candidate), passes);
}

/// Makes `candidate` the result: copies its model, score and inlier count into `result` and swaps
/// their inlier buffers.
template <class Model>
void adopt_candidate(RansacResult<Model>& candidate, RansacResult<Model>& result) {
  result.model = candidate.model;
  result.score = candidate.score;
  result.inlier_count = candidate.inlier_count;
  result.inliers.swap(candidate.inliers);
}

/// ransac()'s search with the samples `sampler` draws (IndexSampler or ProgressiveSampler).
template <class Estimator, class Sampler>
RansacResult<typename Estimator::Model> search(const Estimator& estimator, const RansacOptions& options,
                                               Sampler& sampler, int draw_size) {
  using Model = typename Estimator::Model;
  constexpr int kSampleSize = Estimator::kSampleSize;
  const std::size_t n = estimator.size();
  RansacResult<Model> result;
  result.inliers.assign(n, 0);
  std::vector<int> drawn(static_cast<std::size_t>(draw_size));
  std::vector<std::uint8_t> mask(n, 0);
  int needed = needed_iterations(options, kSampleSize, 0.0);

  // Minimal-sample models compete with each other (best_sample_score); each new best one is
  // locally optimised (LO-RANSAC, Chum, Matas & Kittler, DAGM 2003): re-estimated from its
  // inliers and re-scored while the score improves. The best optimised model is the result, and
  // termination counts its inliers, which noisy minimal samples underestimate. Comparing samples
  // with samples keeps a sample near the optimum from being shadowed by an optimised mediocre one.
  RansacResult<Model> candidate;
  candidate.inliers.assign(n, 0);
  double best_sample_score = -std::numeric_limits<double>::infinity();
  bool found = false;

  int iteration = 0;
  while (iteration < options.max_iterations && (iteration < options.min_iterations || iteration < needed)) {
    ++iteration;
    const auto models = sample_models(estimator, sampler, drawn);
    for (int m = 0; m < models.count; ++m) {
      const Model& model = models.models[static_cast<std::size_t>(m)];
      const auto scored = score_model(estimator, model, best_sample_score, mask);
      if (!scored || !(scored->first > best_sample_score)) continue;
      best_sample_score = scored->first;
      candidate = optimised_sample(estimator, model, *scored, mask, std::move(candidate), options.refinement_passes);
      if (found && !(candidate.score > result.score)) continue;
      found = true;
      adopt_candidate(candidate, result);
      needed =
          needed_iterations(options, kSampleSize, static_cast<double>(result.inlier_count) / static_cast<double>(n));
    }
  }
  result.iterations = iteration;
  if (!found) return result;
  result.success = result.inlier_count >= kSampleSize;
  return result;
}

}  // namespace detail

/// RANSAC with the estimator's score (MSAC-style when the score is the truncated χ² one):
/// draws `draw_size` distinct correspondence indices per iteration from a std::mt19937_64 seeded
/// with options.seed (uniformly, or progressively: RansacOptions::progressive_sampling), hands the
/// first Estimator::kSampleSize of them to estimator.generate(), locally optimises every model that
/// beats all earlier sample models (see RansacOptions::refinement_passes), keeps the optimised
/// model of highest score and stops adaptively (see RansacOptions).
///
/// `draw_size` (>= kSampleSize) exists so that two estimators can be run on the same sample sets:
/// runs with the same seed, number of correspondences and draw_size see the same index sets in the
/// same order (a run that terminates earlier sees a prefix of the other's sets).
///
/// Throws std::invalid_argument for invalid options or draw_size < kSampleSize. Fewer
/// correspondences than draw_size, or no sample giving a model, is not an error: success = false.
template <class Estimator>
RansacResult<typename Estimator::Model> ransac(const Estimator& estimator, const RansacOptions& options,
                                               int draw_size) {
  using Model = typename Estimator::Model;
  constexpr int kSampleSize = Estimator::kSampleSize;
  static_assert(kSampleSize >= 1, "an estimator needs a positive sample size");
  options.check();
  detail::require_range(draw_size, {static_cast<double>(kSampleSize), std::numeric_limits<int>::max()},
                        "ransac: draw_size (at least the estimator's sample size)");

  const std::size_t n = estimator.size();
  if (n < static_cast<std::size_t>(draw_size) || n > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    RansacResult<Model> none;
    none.inliers.assign(n, 0);
    return none;
  }
  if (options.progressive_sampling) {
    detail::ProgressiveSampler sampler(n, draw_size, options.max_iterations, options.seed);
    return detail::search(estimator, options, sampler, draw_size);
  }
  detail::IndexSampler sampler(n, options.seed);
  return detail::search(estimator, options, sampler, draw_size);
}

/// ransac() drawing exactly the estimator's minimal sample size per iteration.
template <class Estimator>
RansacResult<typename Estimator::Model> ransac(const Estimator& estimator, const RansacOptions& options = {}) {
  return ransac(estimator, options, Estimator::kSampleSize);
}

}  // namespace affine_orb
