#pragma once
/// \file
/// The BRISK sampling-pattern descriptor (Leutenegger, Chli and Siegwart, "BRISK: Binary Robust
/// Invariant Scalable Keypoints", ICCV 2011, section 3.2, eqs. 1–7) as a descriptor policy for
/// Extractor<Brisk> (see descriptor.hpp).
///
/// Definition, for a keypoint at level pixel p, rounded to the nearest pixel c = ⌊p + ½⌋:
/// - Pattern (detail/brisk_pattern.hpp): N = 60 points on rings of radii pattern_scale ×
///   {0, 2.9, 4.9, 7.4, 10.8} level pixels with {1, 10, 14, 15, 20} points, point j of ring k at the
///   angle 2π·j/n_k (x right, y down, angle from +x towards +y).
/// - Smoothing: point i of ring k stands for the image smoothed by a Gaussian of
///   σ_k = sigma_factor · r_k · sin(π/n_k) (σ_0 = centre_sigma for the centre). Approximation: the
///   Gaussian is replaced by the mean over a box of s_k × s_k pixels, s_k the odd integer nearest to
///   √(12σ_k² + 1) (same variance; 3, 3, 5, 5, 7 with the defaults), read from an integral image.
///   The box mean at the rotated point q = c + R(θ)·p_i is interpolated bilinearly between the four
///   boxes centred on the pixels (X, Y), (X + 1, Y), (X, Y + 1), (X + 1, Y + 1) around q, with the
///   fraction of q quantised to the nearest 1/256 pixel:
///   q = (X + f_x/256, Y + f_y/256), X, Y integers, f in [0, 256), and
///   I_i = Σ_{a,b ∈ {0,1}} w_a(f_x) w_b(f_y) · box mean centred on (X + a, Y + b), w_0(f) = 256 − f,
///   w_1(f) = f (16 integral-image reads per point). The mean is the integer weighted sum divided by
///   area in double precision (the mean × 65536, below 2^24), which orders any two such means
///   exactly: equal means give equal doubles, and different ones differ by at least
///   1/(area_i · area_j), more than the spacing of doubles below 2^24 for box sides up to 127.
/// - Orientation (eqs. 5–6), on the unrotated pattern: g = mean over the long pairs (i, j), those
///   longer than δ_min, of (p_j − p_i)·(I_j − I_i)/‖p_j − p_i‖² with the exact (unrounded) point
///   positions; θ = atan2(g_y, g_x), radians in (−π, π].
/// - Descriptor (eq. 7): the pattern rotated by θ quantised to the nearest of kAngleSteps = 1024
///   steps (0.35°); bit b is 1 iff I(p_j^θ) > I(p_i^θ) for the b-th short pair (i < j), the pairs
///   shorter than δ_max taken in the order i = 0 … 59, then j = i+1 … 59 (points numbered ring by
///   ring, 0 = centre). With the defaults there are exactly 512 short pairs and 870 long pairs of the
///   1770.
///
/// The rotated sample positions for all 1024 steps are tabulated in the constructor (about 360 KB),
/// so orientation() and describe() do 16 integral-image reads, a few integer multiplications and one
/// division per point, then 512 comparisons, without allocating.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/descriptors/descriptor.hpp"
#include "affine_orb/descriptors/detail/brisk_pattern.hpp"

namespace affine_orb {

/// BRISK pattern parameters. The defaults are those of the BRISK paper and of its reference
/// implementation at its default pattern scale (OpenCV's cv::BRISK with patternScale = 1 and a
/// keypoint of scale 1).
struct BriskOptions {
  /// Scale at which the reference implementation states its pair thresholds and centre σ.
  static constexpr double kReferencePatternScale = 0.85;
  /// Largest smoothing box side (pixels) for which box means compare exactly in double precision.
  static constexpr int kMaxBoxSide = 127;

  /// Multiplier from the published ring radii {0, 2.9, 4.9, 7.4, 10.8} to level pixels. 0.85 is the
  /// reference implementation's factor (outer ring radius 9.18 px).
  double pattern_scale = 0.85;
  /// σ_k = sigma_factor · r_k · sin(π/n_k): proportional to the distance 2 r_k sin(π/n_k) between
  /// neighbouring points of ring k, so that neighbouring samples overlap without aliasing; 1.3 is the
  /// reference implementation's factor.
  double sigma_factor = 1.3;
  /// σ of the centre point in level pixels at pattern_scale 0.85, scaled with pattern_scale:
  /// 0.65 = 1.3 · 0.5, the reference implementation's value.
  double centre_sigma = 0.65;
  /// The keypoint scale t of the paper's thresholds δ_max = 9.75 t, δ_min = 13.67 t, in level pixels
  /// at pattern_scale 0.85 (scaled with pattern_scale): 0.6, because the reference implementation
  /// uses δ_max = 5.85 = 9.75 · 0.6 and δ_min = 8.2 ≈ 13.67 · 0.6 with the radii × 0.85.
  double pair_scale = 0.6;
  /// δ_max / t for the short pairs, which give the bits (paper, section 3.2.1: 9.75).
  double short_pair_factor = 9.75;
  /// δ_min / t for the long pairs, which give the orientation (paper, section 3.2.1: 13.67).
  double long_pair_factor = 13.67;

  /// δ_max in level pixels.
  double max_short_distance() const { return short_pair_factor * pair_scale * pattern_scale / kReferencePatternScale; }
  /// δ_min in level pixels.
  double min_long_distance() const { return long_pair_factor * pair_scale * pattern_scale / kReferencePatternScale; }
  /// σ of the centre point in level pixels.
  double centre_sigma_pixels() const { return centre_sigma * pattern_scale / kReferencePatternScale; }

  /// The sampling pattern these options define.
  detail::BriskPattern pattern() const {
    return detail::make_brisk_pattern(pattern_scale, sigma_factor, centre_sigma_pixels(), max_short_distance(),
                                      min_long_distance());
  }

  /// Throws std::invalid_argument for a zero, negative or non-finite value, for a combination that
  /// does not give exactly 512 short pairs (the descriptor width is fixed at compile time) or no
  /// long pair, and for a pattern whose boxes exceed 127 pixels (the limit of the exact comparison of
  /// box means) or whose radius exceeds 30000 pixels (16-bit offsets); use the pyramid for scale.
  void check() const {
    detail::require_range(pattern_scale, detail::kPositive, "BriskOptions::pattern_scale");
    detail::require_range(sigma_factor, detail::kPositive, "BriskOptions::sigma_factor");
    detail::require_range(centre_sigma, detail::kPositive, "BriskOptions::centre_sigma");
    detail::require_range(pair_scale, detail::kPositive, "BriskOptions::pair_scale");
    detail::require_range(short_pair_factor, detail::kPositive, "BriskOptions::short_pair_factor");
    detail::require_range(long_pair_factor, detail::kPositive, "BriskOptions::long_pair_factor");
    const detail::BriskPattern p = pattern();
    detail::require(p.short_pairs.size() == 512,
                    "BriskOptions: the pattern has " + std::to_string(p.short_pairs.size()) +
                        " short pairs (shorter than δ_max = " + std::to_string(max_short_distance()) +
                        " px) but the descriptor has 512 bits; keep short_pair_factor · pair_scale at 5.85");
    detail::require(!p.long_pairs.empty(), "BriskOptions: no pair is longer than δ_min = " +
                                               std::to_string(min_long_distance()) + " px, so no orientation");
    for (std::size_t k = 0; k < p.ring_radius.size(); ++k) {
      detail::require(p.ring_box[k] <= kMaxBoxSide && p.ring_radius[k] < 30000.0,
                      "BriskOptions: ring " + std::to_string(k) + " has radius " + std::to_string(p.ring_radius[k]) +
                          " px and a smoothing box of " + std::to_string(p.ring_box[k]) + " px (at most " +
                          std::to_string(kMaxBoxSide) + "); use the pyramid for scale");
    }
  }
};

/// The BRISK-512 descriptor policy (see the file comment for the definition).
class Brisk {
 public:
  static constexpr int kBits = 512;
  /// Diameter in level pixels of the smoothed support with the default options, 2 · (9.18 + 3.5):
  /// outer ring radius plus half the outer ring's 7-pixel box; reported as cv::KeyPoint::size times
  /// the keypoint scale. Fixed at compile time: other pattern scales change the support but not this
  /// value.
  static constexpr float kPatchSize = 25.36f;
  /// Number of discretised pattern rotations; angular resolution 2π / 1024 (0.35°).
  static constexpr int kAngleSteps = 1024;
  /// Number of pattern points.
  static constexpr int kPoints = detail::kBriskPointCount;
  using Options = BriskOptions;

  /// Per-level data: the integral image of the level. One LevelData serves levels of any size in
  /// turn without reallocating once it has held the largest.
  struct LevelData {
    /// (rows + 1) x (cols + 1) CV_32S, the top-left part of `storage`; read as unsigned 32-bit
    /// numbers whose differences are exact box sums (the sums wrap modulo 2^32 on levels larger
    /// than 8.4 Mpixels).
    cv::Mat integral;
    cv::Mat storage;  ///< grown to the largest level seen, never shrunk
    /// Size of the level image.
    cv::Size size;
  };

  /// Checks the options (std::invalid_argument) and tabulates the pattern for every rotation step.
  explicit Brisk(const Options& options = {}) : options_((options.check(), options)), pattern_(options_.pattern()) {
    for (int k = 0; k < kPoints; ++k) {
      const auto ring = static_cast<std::size_t>(pattern_.points[static_cast<std::size_t>(k)].ring);
      const int side = pattern_.ring_box[ring];
      side_[static_cast<std::size_t>(k)] = side;
      area_[static_cast<std::size_t>(k)] = static_cast<double>(side) * side;
    }
    for (int b = 0; b < kBits; ++b) {
      const auto& pair = pattern_.short_pairs[static_cast<std::size_t>(b)];
      short_i_[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(pair.i);
      short_j_[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(pair.j);
    }
    // g is linear in the intensities: Σ_long (p_j − p_i)(I_j − I_i)/d² / count = Σ_k c_k I_k. The
    // coefficients also divide out the 65536 of the interpolation weights: g is in grey levels per pixel.
    const double norm = 1.0 / (static_cast<double>(pattern_.long_pairs.size()) * 65536.0);
    for (const auto& pair : pattern_.long_pairs) {
      const auto& a = pattern_.points[static_cast<std::size_t>(pair.i)];
      const auto& b = pattern_.points[static_cast<std::size_t>(pair.j)];
      const double w = norm / (pair.distance * pair.distance);
      gradient_x_[static_cast<std::size_t>(pair.j)] += (b.x - a.x) * w;
      gradient_x_[static_cast<std::size_t>(pair.i)] -= (b.x - a.x) * w;
      gradient_y_[static_cast<std::size_t>(pair.j)] += (b.y - a.y) * w;
      gradient_y_[static_cast<std::size_t>(pair.i)] -= (b.y - a.y) * w;
    }
    // The rotation table depends on the options only: the default options' table is built once
    // per process and shared (an immutable function-local static: 61440 taps, about 2 ms to build),
    // other options build their own.
    rotated_ = is_default(options_) ? default_rotation(pattern_, side_) : rotate(pattern_, side_);
  }

  const Options& options() const { return options_; }
  /// The sampling pattern (points, σ and box per ring, short and long pairs).
  const detail::BriskPattern& pattern() const { return pattern_; }

  /// Minimal distance in level pixels between a keypoint and the level border: the farthest pixel
  /// read at any rotation (13 px with the defaults: outer radius 9.18 lies between pixels 9 and 10,
  /// plus the 3-pixel half box) plus one pixel, so that every real position in
  /// [border(), size − border()) is safe after rounding to the nearest pixel. 14 with the defaults.
  int border() const { return rotated_->extent + 1; }

  /// The same as prepare(level, data): the integral image costs one pass whatever the keypoints.
  void prepare(const cv::Mat& level, const std::vector<cv::Point2f>& /*points*/, LevelData& data) const {
    prepare(level, data);
  }

  /// Fills `data` with the integral image of `level` (CV_8UC1, else std::invalid_argument), in
  /// its storage (no allocation for a level no larger than one it held before).
  void prepare(const cv::Mat& level, LevelData& data) const {
    detail::require_gray8(level, "Brisk::prepare");
    data.size = level.size();
    data.integral = detail::fit_buffer(data.storage, cv::Size(level.cols + 1, level.rows + 1), CV_32S);
    const std::int64_t largest_sum = std::int64_t{255} * level.rows * level.cols;
    if (largest_sum <= std::numeric_limits<std::int32_t>::max()) {
      cv::integral(level, data.integral, CV_32S);
    } else {
      wrapping_integral(level, data.integral);
    }
  }

  /// Orientation θ (eqs. 5–6) in radians, (−π, π], level pixel frame (x right, y down, from +x
  /// towards +y), of the keypoint at `pt` (level pixels). Throws std::invalid_argument when `data`
  /// was not prepared or when pt, rounded to the nearest pixel, is closer than border() − 1 to an
  /// edge (any pt with border() <= x < width − border(), likewise y, is accepted).
  float orientation(const LevelData& data, cv::Point2f pt) const {
    const cv::Point c = checked_centre(data, pt);
    std::array<double, kPoints> values;
    sample(data, c, 0, values);
    // The coefficients sum to zero, so subtracting the centre's value changes nothing but makes g
    // exactly 0 (θ = 0) on a uniform patch instead of rounding noise.
    double gx = 0.0;
    double gy = 0.0;
    for (std::size_t k = 1; k < values.size(); ++k) {
      const double v = values[k] - values[0];
      gx += gradient_x_[k] * v;
      gy += gradient_y_[k] * v;
    }
    return static_cast<float>(std::atan2(gy, gx));
  }

  /// The 512-bit descriptor (eq. 7) of the keypoint at `pt` (level pixels) with the pattern rotated
  /// by `angle` (radians, same frame as orientation(); quantised to angle_step()). Throws
  /// std::invalid_argument for a non-finite angle and in the cases of orientation().
  BinaryDescriptor<kBits> describe(const LevelData& data, cv::Point2f pt, float angle) const {
    const cv::Point c = checked_centre(data, pt);
    if (!std::isfinite(angle)) detail::require(false, "Brisk::describe: the angle is not finite");
    std::array<double, kPoints> values;
    sample(data, c, angle_step(angle), values);
    BinaryDescriptor<kBits> descriptor;
    for (std::size_t w = 0; w < descriptor.size(); ++w) {
      std::uint64_t word = 0;
      for (std::size_t b = 0; b < 64; ++b) {
        const std::size_t pair = w * 64 + b;
        word |= static_cast<std::uint64_t>(values[short_j_[pair]] > values[short_i_[pair]]) << b;
      }
      descriptor[w] = word;
    }
    return descriptor;
  }

  /// The rotation step used for `angle` (radians, finite): the nearest multiple of 2π/kAngleSteps,
  /// as an index in [0, kAngleSteps).
  static int angle_step(float angle) {
    const double turns = static_cast<double>(angle) / (2.0 * CV_PI);
    const double fraction = turns - std::floor(turns);
    const int step = static_cast<int>(std::floor(fraction * kAngleSteps + 0.5));
    return step >= kAngleSteps ? step - kAngleSteps : step;
  }

 private:
  // The pixel nearest to pt after checking that every box of every rotation around it is inside.
  cv::Point checked_centre(const LevelData& data, cv::Point2f pt) const {
    if (data.integral.empty()) detail::require(false, "Brisk: the LevelData is empty; call prepare() first");
    const float low = static_cast<float>(rotated_->extent) - 0.5f;
    const bool inside = pt.x >= low && pt.y >= low && pt.x < static_cast<float>(data.size.width) - low - 1.0f &&
                        pt.y < static_cast<float>(data.size.height) - low - 1.0f;
    if (!inside) {
      detail::require(false, "Brisk: keypoint (" + std::to_string(pt.x) + ", " + std::to_string(pt.y) +
                                 ") is closer than border() = " + std::to_string(border()) + " px to an edge of the " +
                                 std::to_string(data.size.width) + "x" + std::to_string(data.size.height) + " level");
    }
    return {static_cast<int>(std::floor(pt.x + 0.5f)), static_cast<int>(std::floor(pt.y + 0.5f))};
  }

  // Interpolated box means × 65536 of the 60 points rotated by `step`, around the pixel c.
  void sample(const LevelData& data, cv::Point c, int step, std::array<double, kPoints>& values) const {
    const auto stride = static_cast<std::ptrdiff_t>(data.integral.step1());
    const auto* centre = reinterpret_cast<const std::uint32_t*>(data.integral.ptr<std::int32_t>(c.y)) + c.x;
    const Tap* tap = rotated_->taps.data() + static_cast<std::size_t>(step) * kPoints;
    for (std::size_t k = 0; k < values.size(); ++k, ++tap) {
      const std::ptrdiff_t side = side_[k];
      // Rows y0, y0 + 1, y0 + side, y0 + side + 1 of the integral image, from column x0.
      const std::uint32_t* r0 = centre + tap->y0 * stride + tap->x0;
      const std::uint32_t* r1 = r0 + stride;
      const std::uint32_t* r2 = r0 + side * stride;
      const std::uint32_t* r3 = r2 + stride;
      const std::uint32_t s00 = r2[side] - r2[0] - r0[side] + r0[0];
      const std::uint32_t s10 = r2[side + 1] - r2[1] - r0[side + 1] + r0[1];
      const std::uint32_t s01 = r3[side] - r3[0] - r1[side] + r1[0];
      const std::uint32_t s11 = r3[side + 1] - r3[1] - r1[side + 1] + r1[1];
      const std::int64_t fx = tap->fx;
      const std::int64_t fy = tap->fy;
      const std::int64_t top = (256 - fx) * s00 + fx * s10;
      const std::int64_t bottom = (256 - fx) * s01 + fx * s11;
      values[k] = static_cast<double>((256 - fy) * top + fy * bottom) / area_[k];
    }
  }

  // Splits a coordinate into its integer part and its fraction in 1/256 pixel, rounded to nearest
  // (a fraction that rounds to 256 carries into the integer part).
  static std::pair<int, int> split_position(double v) {
    int whole = static_cast<int>(std::floor(v));
    int fraction = static_cast<int>(std::floor((v - whole) * 256.0 + 0.5));
    if (fraction == 256) {
      fraction = 0;
      ++whole;
    }
    return {whole, fraction};
  }

  // Integral image of a level too large for cv::integral's 32-bit sums: unsigned 32-bit arithmetic
  // wraps modulo 2^32, and differences of wrapped sums are still the exact box sums.
  static void wrapping_integral(const cv::Mat& level, cv::Mat& integral) {
    integral.create(level.rows + 1, level.cols + 1, CV_32S);
    auto* first = reinterpret_cast<std::uint32_t*>(integral.ptr<std::int32_t>(0));
    std::fill(first, first + integral.cols, 0u);
    for (int y = 0; y < level.rows; ++y) {
      const std::uint8_t* source = level.ptr<std::uint8_t>(y);
      const auto* above = reinterpret_cast<const std::uint32_t*>(integral.ptr<std::int32_t>(y));
      auto* row = reinterpret_cast<std::uint32_t*>(integral.ptr<std::int32_t>(y + 1));
      std::uint32_t running = 0;
      row[0] = 0;
      for (int x = 0; x < level.cols; ++x) {
        running += source[x];
        row[x + 1] = above[x + 1] + running;
      }
    }
  }

  Options options_;
  detail::BriskPattern pattern_;
  std::array<int, kPoints> side_{};
  std::array<double, kPoints> area_{};
  std::array<double, kPoints> gradient_x_{};
  std::array<double, kPoints> gradient_y_{};
  std::array<std::uint8_t, kBits> short_i_{};
  std::array<std::uint8_t, kBits> short_j_{};
  // One sample position: top-left pixel (x0, y0) of the first of the four interpolated boxes,
  // relative to the keypoint pixel, and the fraction (fx, fy) in 1/256 pixel.
  struct Tap {
    std::int16_t x0;
    std::int16_t y0;
    std::uint8_t fx;
    std::uint8_t fy;
  };
  // The pattern at every rotation step: kPoints taps per step, and the farthest pixel offset read
  // from the keypoint pixel at any step.
  struct Rotation {
    std::vector<Tap> taps;
    int extent = 0;
  };

  static bool is_default(const Options& o) {
    const Options d;
    return o.pattern_scale == d.pattern_scale && o.sigma_factor == d.sigma_factor && o.centre_sigma == d.centre_sigma &&
           o.pair_scale == d.pair_scale && o.short_pair_factor == d.short_pair_factor &&
           o.long_pair_factor == d.long_pair_factor;
  }

  // The table of the default options (the arguments must be theirs), built at the first call.
  static std::shared_ptr<const Rotation> default_rotation(const detail::BriskPattern& pattern,
                                                          const std::array<int, kPoints>& side) {
    static const std::shared_ptr<const Rotation> table = rotate(pattern, side);
    return table;
  }

  static std::shared_ptr<const Rotation> rotate(const detail::BriskPattern& pattern,
                                                const std::array<int, kPoints>& side) {
    auto rotation = std::make_shared<Rotation>();
    rotation->taps.resize(static_cast<std::size_t>(kAngleSteps) * kPoints);
    for (int step = 0; step < kAngleSteps; ++step) {
      const double theta = 2.0 * CV_PI * step / kAngleSteps;
      for (int k = 0; k < kPoints; ++k) {
        const auto& point = pattern.points[static_cast<std::size_t>(k)];
        const double radius = pattern.ring_radius[static_cast<std::size_t>(point.ring)];
        const double alpha =
            2.0 * CV_PI * point.index_on_ring / detail::kBriskRingPoints[static_cast<std::size_t>(point.ring)];
        const int half = (side[static_cast<std::size_t>(k)] - 1) / 2;
        const auto [x, fx] = split_position(radius * std::cos(alpha + theta));
        const auto [y, fy] = split_position(radius * std::sin(alpha + theta));
        Tap& tap = rotation->taps[static_cast<std::size_t>(step) * kPoints + static_cast<std::size_t>(k)];
        tap.x0 = static_cast<std::int16_t>(x - half);
        tap.y0 = static_cast<std::int16_t>(y - half);
        tap.fx = static_cast<std::uint8_t>(fx);
        tap.fy = static_cast<std::uint8_t>(fy);
        // Pixels read: x − half … x + 1 + half (the second box of the interpolation), likewise y.
        rotation->extent = std::max({rotation->extent, half - x, half - y, x + 1 + half, y + 1 + half});
      }
    }
    return rotation;
  }

  std::shared_ptr<const Rotation> rotated_;
};

}  // namespace affine_orb
