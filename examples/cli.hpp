#pragma once
// Small helpers shared by the command-line examples: argument parsing with clear errors, medians,
// and JSON number formatting. Not part of the library.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "affine_orb/extractor.hpp"

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

  int integer(const std::string& name, int fallback) {
    const std::string v = value(name, "");
    if (v.empty()) return fallback;
    std::size_t used = 0;
    const int n = std::stoi(v, &used);
    if (used != v.size()) throw std::invalid_argument(name + ": not an integer: " + v);
    return n;
  }

  double real(const std::string& name, double fallback) {
    const std::string v = value(name, "");
    if (v.empty()) return fallback;
    std::size_t used = 0;
    const double x = std::stod(v, &used);
    if (used != v.size()) throw std::invalid_argument(name + ": not a number: " + v);
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
