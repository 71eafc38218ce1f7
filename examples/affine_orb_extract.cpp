// affine_orb_extract IMAGE [--features N] [--view-features F] [--descriptor rbrief|brisk] [--max-tilt T]
//                    [--threads K] [--spreading quadtree|strongest] [--repeat R] [--out PNG] [--json]
//
// Extracts features from one image and reports how many were found, from the image itself and from
// its tilted views (--features 1000 gives 1000 + 1000 by default), and how long it took: the
// extractor's first call (which sizes its workspace) is timed apart, then --repeat R further calls
// with the same extractor give the steady-state time (the median);
// --out draws the keypoints (circle = support size, line = orientation; green = level 0, orange =
// coarser levels).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "cli.hpp"

namespace {

std::string usage() {
  const affine_orb::ExtractorOptions defaults;
  char options[1024];
  std::snprintf(options, sizeof options,
                "  --features N        keypoints from the image itself (default %d); the tilted views add\n"
                "                      --view-features x N more: %d keypoints in all by default\n"
                "  --view-features F   tilted views' keypoints as a multiple of --features (default %g, 0 = none)\n"
                "  --max-tilt T        largest simulated tilt (1 = no tilted views; default %.3f = %d tilted views)\n",
                defaults.features, affine_orb::examples::keypoint_budget(defaults),
                defaults.additive_budget()->view_features, defaults.views.max_tilt,
                affine_orb::examples::tilted_views(defaults.views));
  return std::string(
             "usage: affine_orb_extract IMAGE [--features N] [--view-features F] [--descriptor rbrief|brisk]\n"
             "                          [--max-tilt T] [--threads K] [--spreading quadtree|strongest]\n"
             "                          [--repeat R] [--out PNG] [--json]\n") +
         options;
}

struct Report {
  std::size_t views = 0;  ///< simulated views, the image included
  std::size_t keypoints = 0;
  std::size_t image_keypoints = 0;  ///< those from the image itself (view 0)
  std::string summary;              ///< keypoint_summary()
  int descriptor_bytes = 0;
  double ms_first_extract = 0.0;  ///< the extractor's first call
  double ms_extract = 0.0;        ///< median of the calls after it
  std::vector<int> per_level;
};

template <class Descriptor>
Report run(const cv::Mat& image, affine_orb::ExtractorOptions options, int repeat, const std::string& out) {
  affine_orb::Extractor<Descriptor> extractor(options);
  std::vector<double> times;
  const auto first = std::chrono::steady_clock::now();
  affine_orb::Features<Descriptor::kBits> result = extractor.extract(image);
  const double ms_first = affine_orb::examples::ms_since(first);
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    result = extractor.extract(image);
    times.push_back(affine_orb::examples::ms_since(start));
  }
  Report report;
  report.views = extractor.views().size();
  report.keypoints = result.size();
  report.image_keypoints = static_cast<std::size_t>(std::count(result.views.begin(), result.views.end(), 0));
  report.summary = affine_orb::examples::keypoint_summary(result.views, report.views);
  report.descriptor_bytes = Descriptor::kBits / 8;
  report.ms_extract = affine_orb::examples::median(times);
  report.ms_first_extract = ms_first;
  report.per_level.assign(static_cast<std::size_t>(options.pyramid.levels), 0);
  for (const auto& kp : result.keypoints) ++report.per_level[static_cast<std::size_t>(kp.octave)];
  if (!out.empty()) {
    cv::Mat canvas;
    cv::cvtColor(image, canvas, cv::COLOR_GRAY2BGR);
    for (const cv::KeyPoint& kp : result.keypoints) {
      const float radius = kp.size / 2;
      const float angle = kp.angle * static_cast<float>(CV_PI / 180.0);
      const cv::Point2f tip = kp.pt + radius * cv::Point2f(std::cos(angle), std::sin(angle));
      const cv::Scalar colour = kp.octave == 0 ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 160, 255);
      cv::circle(canvas, kp.pt, cvRound(radius), colour, 1, cv::LINE_AA);
      cv::line(canvas, kp.pt, tip, colour, 1, cv::LINE_AA);
    }
    if (!cv::imwrite(out, canvas)) throw std::runtime_error("cannot write " + out);
  }
  return report;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    affine_orb::examples::Args args(argc, argv);
    affine_orb::ExtractorOptions options;
    const bool help = affine_orb::examples::parse_common(args, options);
    affine_orb::AdditiveBudget& additive = std::get<affine_orb::AdditiveBudget>(options.view_budget);
    additive.view_features = args.real("--view-features", additive.view_features);
    if (help) {
      std::fputs(usage().c_str(), stdout);
      return 0;
    }
    const std::string descriptor = args.value("--descriptor", "rbrief");
    const int repeat = args.integer("--repeat", 1);
    const std::string out = args.value("--out", "");
    const bool json = args.flag("--json");
    const std::vector<std::string> positional = args.positional();
    if (positional.size() != 1) throw std::invalid_argument("expected exactly one IMAGE");
    if (repeat < 1) throw std::invalid_argument("--repeat must be >= 1");
    const cv::Mat image = cv::imread(positional[0], cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw std::runtime_error("cannot read image " + positional[0]);

    Report report;
    if (descriptor == "rbrief") {
      report = run<affine_orb::Rbrief>(image, options, repeat, out);
    } else if (descriptor == "brisk") {
      report = run<affine_orb::Brisk>(image, options, repeat, out);
    } else {
      throw std::invalid_argument("--descriptor must be rbrief or brisk, got " + descriptor);
    }
    if (json) {
      std::printf(
          "{\"image\": \"%s\", \"width\": %d, \"height\": %d, \"descriptor\": \"%s\", \"keypoints\": %zu, "
          "\"image_keypoints\": %zu, "
          "\"descriptor_bytes\": %d, \"views\": %zu, \"max_tilt\": %.4f, \"threads\": %d, \"repeat\": %d, "
          "\"ms_first_extract\": %.3f, \"ms_extract\": %.3f, \"per_level\": [",
          positional[0].c_str(), image.cols, image.rows, descriptor.c_str(), report.keypoints, report.image_keypoints,
          report.descriptor_bytes, report.views, options.views.max_tilt, options.threads, repeat,
          report.ms_first_extract, report.ms_extract);
      for (std::size_t l = 0; l < report.per_level.size(); ++l) std::printf("%s%d", l ? ", " : "", report.per_level[l]);
      std::printf("]}\n");
    } else {
      std::printf("%s: %dx%d, %s\n", positional[0].c_str(), image.cols, image.rows, report.summary.c_str());
      std::printf(
          "%s, %d-byte descriptors: %.2f ms per extraction (median of %d after the extractor's first call, "
          "%.2f ms; %d thread(s))\n",
          descriptor.c_str(), report.descriptor_bytes, report.ms_extract, repeat, report.ms_first_extract,
          options.threads);
      if (!out.empty()) std::printf("keypoints drawn to %s\n", out.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "affine_orb_extract: %s\n%s", e.what(), usage().c_str());
    return 2;
  }
}
