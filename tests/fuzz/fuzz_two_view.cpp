// libFuzzer target: two-view matching with views on demand (TwoViewMatcher). The input bytes choose
// two small images (up to 48x40; the second may be the first shifted, so that pairs do verify),
// masks and the options: image keypoints, stages (tilts and budgets), min_inliers, the support
// tests (max_false_alarms, min_inlier_ratio), PROSAC (progressive_sampling), all_stages, the precision test
// (max_half_disagreement), guided matching (rounds, gate radius, ratio), the aligned correspondences
// (align_correspondences), the final fit (final_fit: Cauchy scale, max_error, iterations, some invalid), the last
// stage's search (last_stage_search: σ and the orientation test, some invalid), stages to the extreme tilts 4 and 4√2,
// given or from stages_up_to(). Invalid options must end in std::invalid_argument, valid ones in a result that keeps
// every documented invariant: stage reports, the stopping rule, inlier flags, match indices, keypoints inside their
// image and mask, image-2 points of the correspondences within max_shift of their keypoints, each stage's keypoints a
// superset of the stage before; anything else (a crash, a sanitizer report, another exception, a broken invariant) is a
// finding.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "affine_orb/two_view/two_view.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::Bytes;
using affine_orb::fuzz::require;

void check_features(const affine_orb::Features<256>& f, const cv::Mat& image, const cv::Mat& mask) {
  require(f.descriptors.size() == f.size() && f.views.size() == f.size());
  for (const cv::KeyPoint& k : f.keypoints) {
    require(std::isfinite(k.pt.x) && std::isfinite(k.pt.y));
    require(k.pt.x >= 0 && k.pt.y >= 0 && k.pt.x <= image.cols - 1 && k.pt.y <= image.rows - 1);
    if (!mask.empty()) require(mask.at<std::uint8_t>(cvRound(k.pt.y), cvRound(k.pt.x)) != 0);
  }
}

cv::Mat read_image(Bytes& bytes, int width, int height) {
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at<std::uint8_t>(y, x) = bytes.next();
  }
  return image;
}

/// The stages: none to three from the bytes (tilts and budgets, some invalid), or stages_up_to().
void read_stages(Bytes& bytes, std::uint8_t flags, affine_orb::TwoViewOptions& options) {
  // Tilts: 0.9 is invalid (not above 1), 4 and 4√2 exceed the default max_tilt unless flag 32
  // raises it; the stages may also not increase.
  constexpr double kTilts[] = {0.9, 1.42, 2.01, 2.83, 4.01, 5.66};
  if (flags & 32) options.extractor.views.max_tilt = 5.66;
  options.stages.clear();
  const int stages = bytes.next() % 5;  // 4: the stages of stages_up_to()
  if (stages == 4) {
    options.stages = affine_orb::stages_up_to(options.extractor.views);
    return;
  }
  for (int s = 0; s < stages; ++s) {
    const std::uint8_t b = bytes.next();
    options.stages.push_back({kTilts[b % 6], (b >> 3) * 0.125 - 0.25});  // view_features may be < 0
  }
}

/// The support tests, all_stages, the precision test, the spreading and guided matching.
void read_verification(Bytes& bytes, std::uint8_t flags, affine_orb::TwoViewOptions& options) {
  options.min_inliers = bytes.next() % 40;  // < 8 is invalid
  // The support tests: the a-contrario bound (default 1, off, 1e-6, or 0: invalid) and the inlier
  // share (off, or 0 to 1.1: > 1 is invalid); PROSAC on or off.
  const std::uint8_t support = bytes.next();
  constexpr std::optional<double> kFalseAlarms[] = {1.0, std::nullopt, 1e-6, 0.0};
  options.max_false_alarms = kFalseAlarms[support & 3];
  if (support & 4) options.min_inlier_ratio = ((support >> 3) % 12) * 0.1;
  options.model.ransac.progressive_sampling = (support & 128) != 0;
  options.all_stages = (flags & 1) != 0;
  // The precision test: the default, off, at 3 px, or at 0 (invalid).
  constexpr std::optional<double> kHalfDisagreements[] = {10.0, std::nullopt, 3.0, 0.0};
  options.max_half_disagreement = kHalfDisagreements[(flags >> 6) & 3];
  if (flags & 2) options.extractor.spreading = affine_orb::Spreading::kQuadtree;
  // Guided matching: off or 1 to 3 rounds, gate radius 0 (invalid) to 12 px, the ratio 0.5 to 1.25.
  const std::uint8_t guided = bytes.next();
  if (guided % 4 == 0) {
    options.guided_matching.reset();
  } else {
    options.guided_matching->rounds = guided % 4;
    options.guided_matching->matching.gate_radius = 2.0 * ((guided >> 2) % 7);
    options.guided_matching->matching.ratio = 0.5f + 0.25f * static_cast<float>(guided >> 5);
  }
}

/// RANSAC's iterations, the aligned correspondences, the final fit and the last stage's search.
void read_estimation(Bytes& bytes, affine_orb::TwoViewOptions& options) {
  // RANSAC iterations 1 to 64; the aligned correspondences on or off, max_shift 0 (invalid) or 2 px.
  const std::uint8_t verification = bytes.next();
  options.model.ransac.max_iterations = 1 + verification % 64;
  if (verification & 64) options.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
  if ((verification & 64) && (verification & 128)) options.align_correspondences->max_shift = 0.0;
  options.model.ransac.min_iterations =
      std::min(options.model.ransac.min_iterations, options.model.ransac.max_iterations);
  // The final fit off or on; Cauchy scale 0 (invalid) to 3 px, max_error 0 (invalid) to 6 px,
  // iterations 0 (invalid) to 3.
  const std::uint8_t fit = bytes.next();
  if (fit & 1) {
    options.final_fit = affine_orb::HomographyRefinementOptions{};
    options.final_fit->cauchy_scale = 1.5 * ((fit >> 1) & 3);
    options.final_fit->max_error = 3.0 * ((fit >> 3) & 3);
    options.final_fit->iterations = (fit >> 5) & 3;
  }
  // The last stage's search off or on, with as many samples as model selection, σ 0 (invalid)
  // to 2.25 px, and the orientation test off, at 0° (invalid), 45° or 180°.
  if (fit & 128) {
    options.last_stage_search = affine_orb::LastStageSearchOptions{};
    options.last_stage_search->ransac = options.model.ransac;
    options.last_stage_search->sigma = 0.75 * ((fit >> 1) & 3);
    static constexpr std::optional<double> kOrientation[4] = {std::nullopt, 0.0, 45.0, 180.0};
    options.last_stage_search->max_orientation_difference = kOrientation[(fit >> 5) & 3];
  } else {
    options.last_stage_search.reset();
  }
}

/// The two images and their masks.
struct Pair {
  cv::Mat image1, image2, mask1, mask2;
};

/// The first image from the bytes; the second the first shifted (flag 4) or another; the masks of
/// flags 8 and 16.
Pair read_pair(Bytes& bytes, std::uint8_t flags) {
  Pair p;
  const int width1 = 1 + bytes.next() % 48;
  const int height1 = 1 + bytes.next() % 40;
  p.image1 = read_image(bytes, width1, height1);
  if (flags & 4) {
    // The first image shifted: the pair has a true homography (a translation).
    const int dx = std::min(bytes.next() % 5, width1 - 1);
    const int dy = std::min(bytes.next() % 5, height1 - 1);
    p.image2 = cv::Mat(height1, width1, CV_8UC1, cv::Scalar(0));
    p.image1(cv::Rect(0, 0, width1 - dx, height1 - dy)).copyTo(p.image2(cv::Rect(dx, dy, width1 - dx, height1 - dy)));
  } else {
    const int width2 = 1 + bytes.next() % 48;
    const int height2 = 1 + bytes.next() % 40;
    p.image2 = read_image(bytes, width2, height2);
  }
  if (flags & 8) {
    p.mask1 = cv::Mat(p.image1.size(), CV_8UC1, cv::Scalar(0));
    p.mask1(cv::Rect(0, 0, (p.image1.cols + 1) / 2, p.image1.rows)).setTo(255);
  }
  if (flags & 16) p.mask2 = cv::Mat(p.image1.size(), CV_8UC1, cv::Scalar(255));  // wrong size unless the images agree
  return p;
}

using Result = affine_orb::TwoViewResult<affine_orb::Rbrief::kBits>;

/// The stopping rule and the tests a verified result passed; what each report measures.
void check_verification(const Result& r, const affine_orb::TwoViewOptions& options) {
  const int n_stages = static_cast<int>(options.stages.size());
  require(r.stage >= 0 && r.stage <= n_stages);
  require(r.stages.size() == static_cast<std::size_t>(r.stage) + 1);
  // The stopping rule: a verified stage ends the escalation unless all_stages; an unverified
  // result has run out of stages.
  if (!r.verified || options.all_stages) require(r.stage == n_stages);
  if (r.verified) {
    require(r.inlier_count >= options.min_inliers);
    if (options.min_inlier_ratio)
      require(r.inlier_count >= *options.min_inlier_ratio * static_cast<double>(r.matches.size()));
    if (options.max_false_alarms)
      require(r.log10_false_alarms && *r.log10_false_alarms <= std::log10(*options.max_false_alarms));
    if (options.max_half_disagreement && r.model.model == affine_orb::GeometricModel::kHomography)
      require(r.half_disagreement && *r.half_disagreement <= *options.max_half_disagreement);
  }
  // The number of false alarms is measured only when the test is on and a model was chosen.
  require(r.log10_false_alarms.has_value() ==
          (options.max_false_alarms.has_value() && r.model.model != affine_orb::GeometricModel::kNone));
  // The precision test is measured only when on and a homography was chosen.
  if (!options.max_half_disagreement || r.model.model != affine_orb::GeometricModel::kHomography)
    require(!r.half_disagreement);
  // Every stage but a verified last one names the test its model failed, and the last stage's
  // failure is what its numbers show.
  using Failure = affine_orb::VerificationFailure;
  require(r.verified == !r.stages.back().failure);
  for (std::size_t k = 0; k + 1 < r.stages.size(); ++k) require(r.stages[k].failure || options.all_stages);
  if (const std::optional<Failure> f = r.stages.back().failure) {
    require((*f == Failure::kNoModel) == (r.model.model == affine_orb::GeometricModel::kNone));
    if (*f == Failure::kFewInliers) require(r.inlier_count < options.min_inliers);
    if (*f == Failure::kFalseAlarms)
      require(r.log10_false_alarms && *r.log10_false_alarms > std::log10(*options.max_false_alarms));
    if (*f == Failure::kInlierRatio) require(options.min_inlier_ratio.has_value());
    if (*f == Failure::kImprecise)
      require(r.inlier_count >= options.min_inliers && r.model.model == affine_orb::GeometricModel::kHomography);
  }
  // The last stage's search replaces a model only when on, on a reported stage, by a homography.
  for (std::size_t k = 0; k < r.stages.size(); ++k) {
    const affine_orb::TwoViewStageReport& s = r.stages[k];
    if (!s.last_stage_search) continue;
    require(options.last_stage_search.has_value() && s.model == affine_orb::GeometricModel::kHomography);
    require(options.all_stages || k == static_cast<std::size_t>(n_stages));
  }
}

/// The matches, their inlier flags and image-2 points.
void check_matches(const Result& r, const affine_orb::TwoViewOptions& options) {
  require(r.inliers.size() == r.matches.size());
  // Guided rounds run only when on and on a homography; their matches carry flags of the
  // refined homography, which the result's H fields describe.
  const int rounds = options.guided_matching ? options.guided_matching->rounds : 0;
  for (const affine_orb::TwoViewStageReport& s : r.stages) require(s.guided_rounds <= rounds);
  if (r.stages.back().guided_rounds > 0) {
    require(r.model.model == affine_orb::GeometricModel::kHomography);
    require(r.model.homography_inlier_count == r.inlier_count);
    require(r.model.homography_inliers == r.inliers);
    require(r.model.fundamental_inliers.empty());
  }
  require(std::count(r.inliers.begin(), r.inliers.end(), 1) == r.inlier_count);
  for (const affine_orb::Match& m : r.matches) {
    require(m.query >= 0 && static_cast<std::size_t>(m.query) < r.features1.size());
    require(m.train >= 0 && static_cast<std::size_t>(m.train) < r.features2.size());
  }
  // Image 2's point of each correspondence: the train keypoint's, or aligned within max_shift of it.
  require(r.points2.size() == r.matches.size());
  require(r.aligned_count >= 0 && r.aligned_count <= static_cast<int>(r.matches.size()));
  if (!options.align_correspondences) require(r.aligned_count == 0);
  for (std::size_t i = 0; i < r.matches.size(); ++i) {
    const cv::Point2f q = r.features2.keypoints[static_cast<std::size_t>(r.matches[i].train)].pt;
    require(std::isfinite(r.points2[i].x) && std::isfinite(r.points2[i].y));
    const double moved = std::hypot(r.points2[i].x - q.x, r.points2[i].y - q.y);
    require(options.align_correspondences ? moved <= options.align_correspondences->max_shift + 1e-3 : moved == 0.0);
  }
}

/// The keypoints: inside their image and mask, each stage's a superset of the stage before's, each
/// stage adding at most its budget.
void check_keypoints(const Result& r, const affine_orb::TwoViewOptions& options, const Pair& p) {
  check_features(r.features1, p.image1, p.mask1);
  check_features(r.features2, p.image2, p.mask2);
  long bound = options.extractor.features;
  require(std::count(r.features1.views.begin(), r.features1.views.end(), 0) <= bound);
  for (std::size_t k = 0; k < r.stages.size(); ++k) {
    if (k > 0) {
      require(r.stages[k].keypoints1 >= r.stages[k - 1].keypoints1);
      require(r.stages[k].max_tilt >= r.stages[k - 1].max_tilt);
      bound += std::lround(options.stages[k - 1].view_features * options.extractor.features);
    }
    require(r.stages[k].keypoints1 <= bound && r.stages[k].keypoints2 <= bound);
  }
  require(r.stages.back().keypoints1 == static_cast<int>(r.features1.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes bytes(data, size);
  const std::uint8_t flags = bytes.next();
  affine_orb::TwoViewOptions options;
  options.extractor.features = static_cast<int>(bytes.next()) * 2 - 4;  // may be <= 0: invalid
  read_stages(bytes, flags, options);
  read_verification(bytes, flags, options);
  read_estimation(bytes, options);
  const Pair pair = read_pair(bytes, flags);
  try {
    affine_orb::TwoViewMatcher<affine_orb::Rbrief> matcher(options);
    const Result r = matcher.match(pair.image1, pair.image2, pair.mask1, pair.mask2);
    check_verification(r, options);
    check_matches(r, options);
    check_keypoints(r, options, pair);
  } catch (const std::invalid_argument&) {
    // Rejected options or input: the documented outcome.
  }
  return 0;
}
