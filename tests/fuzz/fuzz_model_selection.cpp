// libFuzzer target: RANSAC and H/F model selection on arbitrary correspondences. The bytes give up
// to 32 point pairs (coordinates from a 16-bit grid, plus NaN, infinities and duplicates), σ, the
// selection rule, whether keypoint octaves (0-7, from the coordinates' low bits) scale σ, the
// iteration cap and the seed. select_model() must end in std::invalid_argument exactly for
// non-finite coordinates, and otherwise in a result that keeps its documented invariants: one
// inlier flag per correspondence, counts that agree with the flags, finite unit-norm models when
// found, a model chosen only with success, parallax statistics only under the plane-and-parallax
// rule and consistent with its decision, GRIC values only under the GRIC rule.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/geometry/model_selection.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::require;

/// A coordinate from two bytes: mostly a grid value in [−64, 960), sometimes a special value.
float coordinate(std::uint8_t hi, std::uint8_t lo) {
  switch (hi) {
    case 255:
      return std::numeric_limits<float>::quiet_NaN();
    case 254:
      return std::numeric_limits<float>::infinity();
    case 253:
      return -std::numeric_limits<float>::infinity();
    case 252:
      return 1e30f;
    default:
      return static_cast<float>(hi * 4 + lo / 64.0) - 64.0f;
  }
}

bool finite_unit(const Eigen::Matrix3d& m) { return m.allFinite() && std::abs(m.norm() - 1.0) < 1e-6; }

/// The result's inlier flags and counts agree, the models it reports are finite and normalised,
/// the chosen one was found, and only the chosen rule's fields are set.
void require_consistent(const affine_orb::ModelSelectionResult& result,
                        const affine_orb::ModelSelectionOptions& options, std::size_t n) {
  require(result.homography_inliers.size() == n && result.fundamental_inliers.size() == n);
  int h = 0, f = 0;
  for (std::size_t i = 0; i < n; ++i) {
    require(result.homography_inliers[i] <= 1 && result.fundamental_inliers[i] <= 1);
    h += result.homography_inliers[i];
    f += result.fundamental_inliers[i];
  }
  require(h == result.homography_inlier_count && f == result.fundamental_inlier_count);
  if (result.homography_found) require(finite_unit(result.homography) && std::isfinite(result.homography_score));
  if (result.fundamental_found) require(finite_unit(result.fundamental) && std::isfinite(result.fundamental_score));
  if (!result.success) require(result.model == affine_orb::GeometricModel::kNone);
  if (result.model == affine_orb::GeometricModel::kHomography) require(result.homography_found);
  if (result.model == affine_orb::GeometricModel::kFundamental) require(result.fundamental_found);
  if (options.rule != affine_orb::SelectionRule::kGric) {
    require(result.homography_gric == 0.0 && result.fundamental_gric == 0.0);
  }
  if (options.rule != affine_orb::SelectionRule::kPlaneParallax) {
    require(result.parallax_inlier_count == 0 && result.parallax_expected_count == 0.0);
  } else {
    require(result.parallax_inlier_count >= 0 &&
            result.parallax_inlier_count <= static_cast<int>(n) - result.homography_inlier_count);
    require(std::isfinite(result.parallax_expected_count) && result.parallax_expected_count >= 0.0);
    require(std::isfinite(result.parallax_significance));
    if (result.success) {
      require((result.model == affine_orb::GeometricModel::kHomography) ==
              (result.homography_found && result.parallax_significance <= options.plane_parallax.significance));
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  affine_orb::ModelSelectionOptions options;
  options.sigma = 0.25 + data[0] % 16 * 0.25;
  constexpr std::array<affine_orb::SelectionRule, 4> kRules = {
      affine_orb::SelectionRule::kScoreRatio, affine_orb::SelectionRule::kGric, affine_orb::SelectionRule::kInlierRatio,
      affine_orb::SelectionRule::kPlaneParallax};
  options.rule = kRules[static_cast<std::size_t>(data[0] >> 4 & 3)];
  const bool with_octaves = (data[0] & 0x40) != 0;
  options.ransac.max_iterations = 1 + data[1] % 16;
  options.ransac.min_iterations = std::min(options.ransac.max_iterations, static_cast<int>(data[2] % 8));
  options.ransac.seed = data[3];
  const std::size_t n = std::min<std::size_t>((size - 4) / 8, 32);
  std::vector<cv::Point2f> p1, p2;
  std::vector<int> octaves1, octaves2;
  bool finite = true;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* b = data + 4 + 8 * i;
    p1.emplace_back(coordinate(b[0], b[1]), coordinate(b[2], b[3]));
    p2.emplace_back(coordinate(b[4], b[5]), coordinate(b[6], b[7]));
    octaves1.push_back(b[1] & 7);
    octaves2.push_back(b[5] & 7);
    for (float v : {p1.back().x, p1.back().y, p2.back().x, p2.back().y}) finite = finite && std::isfinite(v);
  }
  affine_orb::ModelSelectionResult result;
  try {
    result = with_octaves ? affine_orb::select_model(p1, p2, octaves1, octaves2, options)
                          : affine_orb::select_model(p1, p2, options);
  } catch (const std::invalid_argument&) {
    require(!finite);
    return 0;
  }
  require(finite);
  require_consistent(result, options, n);
  return 0;
}
