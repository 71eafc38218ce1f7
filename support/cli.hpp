#pragma once
// Small helpers shared by the command-line examples: argument parsing with clear errors (every
// numeric value goes through Args::integer()/real(), which name the flag and the value), medians.
// Not part of the library.

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/views/affine_views.hpp"

namespace affine_orb::examples {

/// Command-line arguments: positional ones and `--name value` / `--flag` options.
class Args {
 public:
  Args(int argc, char** argv) : args_(argv + 1, argv + argc) {}

  /// True (and consumed) when `--name` is present.
  bool flag(const std::string& name) {
    const auto it = std::find(args_.begin(), args_.end(), name);
    if (it == args_.end()) return false;
    args_.erase(it);
    return true;
  }

  /// The value after `--name` (consumed), or `fallback` when absent.
  std::string value(const std::string& name, const std::string& fallback) {
    const auto it = std::find(args_.begin(), args_.end(), name);
    if (it == args_.end()) return fallback;
    if (it + 1 == args_.end()) throw std::invalid_argument(name + " needs a value");
    std::string v = *(it + 1);
    args_.erase(it, it + 2);
    return v;
  }

  /// The integer after `--name` (consumed), or `fallback` when absent. The whole value must be a
  /// decimal integer that fits an int: otherwise std::invalid_argument naming the flag and the value
  /// ("--features: expected an integer, got \"abc\""), which the examples turn into exit code 2.
  int integer(const std::string& name, int fallback) {
    const std::string v = value(name, "");
    if (v.empty()) return fallback;
    return parse_integer(name, v);
  }

  /// The number after `--name` (consumed), or `fallback` when absent; the whole value must be a
  /// finite decimal number, else std::invalid_argument as integer().
  double real(const std::string& name, double fallback) {
    const std::string v = value(name, "");
    if (v.empty()) return fallback;
    return parse_real(name, v);
  }

  /// `text` as an int, or std::invalid_argument("NAME: expected an integer, got \"TEXT\"").
  static int parse_integer(const std::string& name, const std::string& text) {
    errno = 0;
    char* end = nullptr;
    const long n = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || std::isspace(static_cast<unsigned char>(text.front())) || end != text.c_str() + text.size() ||
        errno == ERANGE || n < std::numeric_limits<int>::min() || n > std::numeric_limits<int>::max())
      throw std::invalid_argument(name + ": expected an integer, got \"" + text + "\"");
    return static_cast<int>(n);
  }

  /// `text` as a finite double, or std::invalid_argument("NAME: expected a number, got \"TEXT\"").
  static double parse_real(const std::string& name, const std::string& text) {
    errno = 0;
    char* end = nullptr;
    const double x = std::strtod(text.c_str(), &end);
    if (text.empty() || std::isspace(static_cast<unsigned char>(text.front())) || end != text.c_str() + text.size() ||
        errno == ERANGE || !std::isfinite(x))
      throw std::invalid_argument(name + ": expected a number, got \"" + text + "\"");
    return x;
  }

  /// The remaining arguments, after every option was consumed; an unknown `--option` is an error.
  std::vector<std::string> positional() const {
    for (const std::string& a : args_) {
      if (a.size() > 1 && a[0] == '-' && a[1] == '-') throw std::invalid_argument("unknown option " + a);
    }
    return args_;
  }

 private:
  std::vector<std::string> args_;
};

/// Consumes `--help`/`-h` (true when given) and the extractor flags shared by the examples:
/// --features N, --max-tilt T, --threads K, --spreading quadtree|strongest, starting from
/// `options`.
inline bool parse_common(Args& args, ExtractorOptions& options) {
  const bool help = args.flag("--help") || args.flag("-h");
  options.features = args.integer("--features", options.features);
  options.views.max_tilt = args.real("--max-tilt", options.views.max_tilt);
  options.threads = args.integer("--threads", options.threads);
  const std::string spreading =
      args.value("--spreading", options.spreading == Spreading::kQuadtree ? "quadtree" : "strongest");
  if (spreading == "quadtree") {
    options.spreading = Spreading::kQuadtree;
  } else if (spreading == "strongest") {
    options.spreading = Spreading::kStrongest;
  } else {
    throw std::invalid_argument("--spreading must be quadtree or strongest, got " + spreading);
  }
  return help;
}

/// Number of tilted views (all views but the image itself) that `options` simulate.
inline int tilted_views(const AffineViewOptions& options) {
  return static_cast<int>(view_parameters(options).size()) - 1;
}

/// The keypoints an extraction with `options` returns from an image with enough corners: `features`
/// from the image itself, plus round(view_features · features) from the tilted views when there are
/// any and the budget is additive (AdditiveBudget::view_features).
inline int keypoint_budget(const ExtractorOptions& options) {
  const AdditiveBudget* additive = options.additive_budget();
  if (!additive || tilted_views(options.views) == 0) return options.features;
  return options.features + static_cast<int>(std::lround(additive->view_features * options.features));
}

/// "2000 keypoints: 1000 from the image + 1000 from 17 tilted views" for keypoints whose view
/// indices are `views` (Features::views, 0 = the image) out of `view_count` simulated views.
inline std::string keypoint_summary(const std::vector<int>& views, std::size_t view_count) {
  const auto from_image = static_cast<std::size_t>(std::count(views.begin(), views.end(), 0));
  const std::size_t tilted = view_count > 0 ? view_count - 1 : 0;
  std::string text = std::to_string(views.size()) + " keypoints: " + std::to_string(from_image) + " from the image";
  if (tilted == 0) return text + ", no tilted views";
  return text + " + " + std::to_string(views.size() - from_image) + " from " + std::to_string(tilted) + " tilted view" +
         (tilted == 1 ? "" : "s");
}

/// `text` shortened from the front ("..." + its tail, the informative end of a path) until it is at
/// most `max_width` pixels wide in the given cv::putText font; unchanged when it already fits.
inline std::string fit_text(const std::string& text, int max_width, int font, double scale, int thickness = 1) {
  auto width = [&](const std::string& t) {
    int baseline = 0;
    return cv::getTextSize(t, font, scale, thickness, &baseline).width;
  };
  if (width(text) <= max_width) return text;
  for (std::size_t cut = 1; cut < text.size(); ++cut) {
    const std::string shorter = "..." + text.substr(cut);
    if (width(shorter) <= max_width) return shorter;
  }
  return "...";
}

inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// Milliseconds elapsed since `start`.
inline double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace affine_orb::examples
