#pragma once
/// \file
/// Affine view simulation (paper eqs. 13–16; the ASIFT sampling of Morel & Yu, SIAM J. Imaging
/// Sciences 2009): the set of simulated camera tilts and rotations, the warp that produces each view,
/// and the maps between view and original pixel coordinates.
///
/// A view simulates the affine camera A = T_t R(φ) (eq. 13 with μ = 1, ψ = 0): the image is rotated
/// by φ, low-pass filtered along x, then subsampled along x by the tilt t = 1/cos θ (θ = latitude).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/core/detail/buffer.hpp"
#include "affine_orb/core/detail/check.hpp"
#include "affine_orb/core/row_spans.hpp"
#include "affine_orb/views/detail/view_render.hpp"

namespace affine_orb {

/// How the set of simulated views is built.
struct AffineViewOptions {
  /// Largest simulated tilt t = 1/cos θ. 1 turns the views off (only the original image). The
  /// default 2√2 (θ up to 69°) gives 18 views, the set docs/algorithm.md §1 describes and cv::AffineFeature builds
  /// with maxTilt 3; 4√2 (θ up to 80°) gives 43.
  double max_tilt = 2.0 * std::sqrt(2.0);
  /// Ratio a of the geometric tilt series t_k = a^k (eq. 15); ASIFT uses √2.
  double tilt_ratio = std::sqrt(2.0);
  /// Rotation step base b in degrees: a tilt t gets the rotations φ = 0, b/t, 2b/t, ... < 180°
  /// (eq. 16); ASIFT uses 72°.
  double rotation_base_degrees = 72.0;
  /// Anti-aliasing constant c: before subsampling by t, the rotated image is blurred along x with a
  /// Gaussian of σ = c·√(t² − 1) pixels; ASIFT's value 0.8 (Morel & Yu 2009, section 5).
  double antialias = 0.8;

  void check() const {
    detail::require_range(max_tilt, {1, 16}, "AffineViewOptions::max_tilt");
    detail::require_range(tilt_ratio, {1, 4, true}, "AffineViewOptions::tilt_ratio");
    detail::require_range(rotation_base_degrees, {1, 180}, "AffineViewOptions::rotation_base_degrees");
    detail::require_range(antialias, {0, 4}, "AffineViewOptions::antialias");
  }
};

/// One simulated view of tilt t >= 1 and rotation φ (degrees). The image is first rotated into a
/// canvas, x_c = R(φ) x_o + offset with R(φ) = [cos φ, −sin φ; sin φ, cos φ] acting on pixel
/// coordinates (x right, y down) and the offset that puts the rotated image's bounding box at the
/// origin; the canvas is then resized along x from its width W_c to the view width
/// W_v = round(W_c / t) (OpenCV's pixel-centre convention: x_v = (x_c + 0.5)·W_v/W_c − 0.5), so the
/// x scale is W_v/W_c ≈ 1/t. (The paper writes T_t = diag(t, 1) for the camera; simulating it
/// shrinks x by t.)
struct AffineView {
  double tilt = 1.0;
  double rotation_degrees = 0.0;
  /// 2x3 map from original pixel coordinates to view pixel coordinates (pixel centres at integers).
  cv::Matx23d to_view = cv::Matx23d(1, 0, 0, 0, 1, 0);
  /// 2x3 inverse map, from view pixel coordinates to original pixel coordinates.
  cv::Matx23d to_original = cv::Matx23d(1, 0, 0, 0, 1, 0);
  /// 2x3 rotation from original pixel coordinates into the canvas.
  cv::Matx23d to_canvas = cv::Matx23d(1, 0, 0, 0, 1, 0);
  /// Size of the rotated canvas and of the view image, in pixels.
  cv::Size canvas_size;
  cv::Size size;

  bool is_identity() const { return tilt == 1.0 && rotation_degrees == 0.0; }
  /// The inverse of to_canvas: from canvas pixel coordinates to original pixel coordinates.
  cv::Matx23d to_original_canvas() const {
    cv::Matx23d inverse;
    cv::invertAffineTransform(to_canvas, inverse);
    return inverse;
  }
  bool is_unrotated() const { return rotation_degrees == 0.0; }
};

/// The (t, φ) pairs of eqs. 15–16 in order: t = 1 (φ = 0 only), then t = a, a², ... <= max_tilt
/// (within 0.1 %),
/// each with φ = 0, b/t, 2b/t, ... < 180°. Tilts {1, √2, 2, 2√2} give 1 + 4 + 5 + 8 = 18 views.
inline std::vector<std::pair<double, double>> view_parameters(const AffineViewOptions& options) {
  options.check();
  std::vector<std::pair<double, double>> params{{1.0, 0.0}};
  // A relative tolerance of 0.1 % so that max_tilt = 2√2, or 2.828 typed on a command line,
  // includes a³ = 2.8284... computed in floating point.
  for (double t = options.tilt_ratio; t <= options.max_tilt * (1.0 + 1e-3); t *= options.tilt_ratio) {
    const double step = options.rotation_base_degrees / t;
    for (int k = 0; k * step < 180.0 - 1e-9; ++k) params.emplace_back(t, k * step);
  }
  return params;
}

/// The view of tilt t and rotation φ (degrees) for an image of size `image_size`.
inline AffineView make_view(double tilt, double rotation_degrees, cv::Size image_size) {
  detail::require_range(tilt, {1, 64}, "make_view: tilt");
  detail::require(std::isfinite(rotation_degrees), "make_view: the rotation must be finite");
  detail::require(image_size.width > 0 && image_size.height > 0, "make_view: the image size must be positive");
  AffineView view;
  view.tilt = tilt;
  view.rotation_degrees = rotation_degrees;
  const double phi = rotation_degrees * CV_PI / 180.0;
  const double c = rotation_degrees == 0.0 ? 1.0 : std::cos(phi);
  const double s = rotation_degrees == 0.0 ? 0.0 : std::sin(phi);
  // Bounding box of the four rotated image corners (pixel centres).
  const double w = image_size.width - 1.0;
  const double h = image_size.height - 1.0;
  double min_x = 1e300, min_y = 1e300, max_x = -1e300, max_y = -1e300;
  for (const cv::Vec2d& corner : {cv::Vec2d(0, 0), cv::Vec2d(w, 0), cv::Vec2d(0, h), cv::Vec2d(w, h)}) {
    const double x = c * corner[0] - s * corner[1];
    const double y = s * corner[0] + c * corner[1];
    min_x = std::min(min_x, x);
    min_y = std::min(min_y, y);
    max_x = std::max(max_x, x);
    max_y = std::max(max_y, y);
  }
  // Every rotated pixel centre lies in [0, size − 1]; the tolerance keeps rounding noise in the
  // rotation from adding a column.
  view.canvas_size = cv::Size(static_cast<int>(std::ceil(max_x - min_x - 1e-6)) + 1,
                              static_cast<int>(std::ceil(max_y - min_y - 1e-6)) + 1);
  view.to_canvas = cv::Matx23d(c, -s, -min_x, s, c, -min_y);
  view.size =
      cv::Size(std::max(1, static_cast<int>(std::lround(view.canvas_size.width / tilt))), view.canvas_size.height);
  const double r = static_cast<double>(view.size.width) / view.canvas_size.width;
  const cv::Matx23d& k = view.to_canvas;
  view.to_view = cv::Matx23d(r * k(0, 0), r * k(0, 1), r * (k(0, 2) + 0.5) - 0.5, k(1, 0), k(1, 1), k(1, 2));
  cv::invertAffineTransform(view.to_view, view.to_original);
  return view;
}

/// All views of `options` for an image of size `image_size`, in view_parameters() order.
inline std::vector<AffineView> make_views(const AffineViewOptions& options, cv::Size image_size) {
  std::vector<AffineView> views;
  for (const auto& [t, phi] : view_parameters(options)) views.push_back(make_view(t, phi, image_size));
  return views;
}

/// Maps a point through a 2x3 affine matrix.
inline cv::Point2d apply_affine(const cv::Matx23d& m, cv::Point2d p) {
  return {m(0, 0) * p.x + m(0, 1) * p.y + m(0, 2), m(1, 0) * p.x + m(1, 1) * p.y + m(1, 2)};
}

/// The view pipeline written with OpenCV calls, step by step: cv::warpAffine into the canvas
/// (bilinear, BORDER_REPLICATE; skipped for φ = 0), cv::GaussianBlur along x with σ =
/// antialias·√(t² − 1) and radius max(1, ⌈3σ⌉) (BORDER_REPLICATE; none for σ = 0), cv::resize to
/// the view width (INTER_LINEAR). The reference render_view() is tested against, and its fallback
/// for images it does not handle itself.
inline void render_view_reference(const cv::Mat& image, const AffineView& view, double antialias, cv::Mat& canvas,
                                  cv::Mat& out) {
  detail::require_gray8(image, "render_view_reference");
  if (view.is_identity()) {
    image.copyTo(out);
    return;
  }
  const double sigma = antialias * std::sqrt(view.tilt * view.tilt - 1.0);
  const cv::Mat* source = &image;
  if (!view.is_unrotated()) {
    cv::warpAffine(image, canvas, view.to_canvas, view.canvas_size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    source = &canvas;
  }
  if (sigma > 0.0) {
    const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
    cv::GaussianBlur(*source, canvas, cv::Size(2 * radius + 1, 1), sigma, 0.0, cv::BORDER_REPLICATE);
    source = &canvas;
  }
  cv::resize(*source, out, view.size, 0.0, 0.0, cv::INTER_LINEAR);
}

/// Renders one view of many images with render_view()'s arithmetic (views/detail/view_render.hpp), the
/// resampling weights computed once. Images wider or taller than the fixed-point ranges allow (W +
/// H > 16000, a row step above 32767 bytes) or smaller than 2x2 go through render_view_reference().
class ViewRenderer {
 public:
  ViewRenderer() = default;
  ViewRenderer(const AffineView& view, double antialias)
      : view_(view),
        antialias_(antialias),
        resampler_(view.canvas_size.width, view.size.width, antialias * std::sqrt(view.tilt * view.tilt - 1.0)) {}

  const AffineView& view() const { return view_; }

  /// Renders `image` into `out` (view.size, CV_8UC1, its buffer reused). With `region`, only the
  /// columns of each row's run are computed (the whole row where the run is empty), and the other
  /// pixels of the row repeat the nearest computed one. `scratch` holds one canvas row (grown to the
  /// widest row it has held, so that views of several sizes share it without reallocating).
  void render(const cv::Mat& image, const RowSpans* region, cv::Mat& scratch, cv::Mat& out) const {
    detail::require_gray8(image, "render_view");
    if (view_.is_identity()) {
      image.copyTo(out);
      return;
    }
    if (image.cols < 2 || image.rows < 2 || image.cols + image.rows > 16000 || image.step[0] > 32767) {
      render_view_reference(image, view_, antialias_, scratch, out);
      return;
    }
    out.create(view_.size, CV_8UC1);
    const detail::CanvasSampler sampler(view_.to_original_canvas(), image.size());
    const int canvas_width = view_.canvas_size.width;
    const int width = view_.size.width;
    // The widest row: every view column computed (in `scratch`, grown to the widest row seen).
    cv::Mat row_buffer = detail::fit_buffer(
        scratch, cv::Size(resampler_.first.back() + resampler_.stride - resampler_.first.front(), 1), CV_8UC1);
    std::uint8_t* row = row_buffer.ptr<std::uint8_t>(0);
    for (int y = 0; y < view_.size.height; ++y) {
      int x0 = 0;
      int x1 = width;
      if (region != nullptr) {
        const auto [b, e] = region->run(y);
        if (b < e) {
          x0 = std::max(b, 0);
          x1 = std::min(e, width);
        }
      }
      // Canvas columns read for view columns [x0, x1), the last resampler round included.
      const int first = resampler_.first[static_cast<std::size_t>(x0)];
      const int last = resampler_.first[static_cast<std::size_t>(x1 - 1)] + resampler_.stride - 1;
      const int c0 = std::clamp(first, 0, canvas_width - 1);
      const int c1 = std::clamp(last, 0, canvas_width - 1) + 1;
      if (view_.is_unrotated()) {
        std::memcpy(row + (c0 - first), image.ptr<std::uint8_t>(y) + c0, static_cast<std::size_t>(c1 - c0));
      } else {
        detail::sample_canvas_row(image, sampler, y, c0, c1, row + (c0 - first));
      }
      // Canvas columns outside the canvas repeat its edge (BORDER_REPLICATE of the blur).
      std::memset(row, row[c0 - first], static_cast<std::size_t>(c0 - first));
      std::memset(row + (c1 - first), row[c1 - 1 - first], static_cast<std::size_t>(last + 1 - c1));
      std::uint8_t* target = out.ptr<std::uint8_t>(y);
      detail::resample_row(resampler_, row, first, x0, x1, target);
      std::memset(target, target[x0], static_cast<std::size_t>(x0));
      std::memset(target + x1, target[x1 - 1], static_cast<std::size_t>(width - x1));
    }
  }

 private:
  AffineView view_;
  double antialias_ = 0.0;
  detail::ViewResampler resampler_;
};

/// Renders a view of a CV_8UC1 image into `out` (reusing its buffer): the image rotated into the
/// canvas (bilinear, borders replicated so that no artificial edge appears; no resampling for φ =
/// 0), blurred along x with a Gaussian of σ = antialias·√(t² − 1) and radius max(1, ⌈3σ⌉) (none
/// for t = 1), then resampled along x to the view width (bilinear); the identity view is a plain
/// copy. Fixed-point arithmetic, defined in detail/view_render.hpp: bilinear fractions rounded to
/// 1/128 px, weights to 2^-14: within one grey level of the same pipeline evaluated in double
/// precision, and within 3 of render_view_reference() (OpenCV's warpAffine, GaussianBlur and
/// resize; warpAffine interpolates at 1/32 px).
/// `canvas` is a caller-owned scratch buffer.
inline void render_view(const cv::Mat& image, const AffineView& view, double antialias, cv::Mat& canvas, cv::Mat& out) {
  ViewRenderer(view, antialias).render(image, nullptr, canvas, out);
}

}  // namespace affine_orb
