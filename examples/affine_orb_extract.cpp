// affine_orb_extract IMAGE [--features N] [--descriptor rbrief|brisk] [--max-tilt T] [--threads K]
//                    [--repeat R] [--out PNG] [--json]
//
// Extracts features from one image and reports how many were found and how long it took: the
// extractor's first call (which sizes its workspace) is timed apart, then --repeat R further calls
// with the same extractor give the steady-state time (the median);
// --out draws the keypoints (circle = support size, line = orientation; green = level 0, orange =
// coarser levels).
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

const char* const kUsage =
    "usage: affine_orb_extract IMAGE [--features N] [--descriptor rbrief|brisk] [--max-tilt T] [--threads K]\n"
    "                          [--spreading quadtree|strongest]\n"
    "                          [--repeat R] [--out PNG] [--json]\n"
    "  --max-tilt T  largest simulated tilt (1 = no affine views; default 2.828 = 18 views)\n";

struct Report {
  std::size_t views = 0;
  std::size_t keypoints = 0;
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
    if (affine_orb::examples::parse_common(args, options)) {
      std::fputs(kUsage, stdout);
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
          "\"descriptor_bytes\": %d, \"views\": %zu, \"max_tilt\": %.4f, \"threads\": %d, \"repeat\": %d, "
          "\"ms_first_extract\": %.3f, \"ms_extract\": %.3f, \"per_level\": [",
          positional[0].c_str(), image.cols, image.rows, descriptor.c_str(), report.keypoints, report.descriptor_bytes,
          report.views, options.views.max_tilt, options.threads, repeat, report.ms_first_extract, report.ms_extract);
      for (std::size_t l = 0; l < report.per_level.size(); ++l) std::printf("%s%d", l ? ", " : "", report.per_level[l]);
      std::printf("]}\n");
    } else {
      std::printf(
          "%s: %dx%d, %zu keypoints from %zu views (%s, %d-byte descriptors), %.2f ms per extraction "
          "(median of %d after the extractor's first call, %.2f ms; %d thread(s))\n",
          positional[0].c_str(), image.cols, image.rows, report.keypoints, report.views, descriptor.c_str(),
          report.descriptor_bytes, report.ms_extract, repeat, report.ms_first_extract, options.threads);
      if (!out.empty()) std::printf("keypoints drawn to %s\n", out.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "affine_orb_extract: %s\n%s", e.what(), kUsage);
    return 2;
  }
}
