#pragma once
// Shared by the benchmarks: interleaved timing of several methods in one run, medians, and the
// data paths. Every method is run in turn, round after round, so that machine noise hits all of
// them alike; the figures to quote are medians and ratios, not single absolute times.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace affine_orb::bench {

inline std::string data_dir() { return AFFINE_ORB_DATA_DIR; }
inline std::string opencv_samples_dir() { return AFFINE_ORB_OPENCV_SAMPLES_DIR; }

/// An image of the evaluation data as CV_8UC1; exits with a message when it cannot be read.
inline cv::Mat read_gray_or_exit(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    std::exit(1);
  }
  return image;
}

inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// Wall-clock milliseconds that f() takes.
template <class F>
double milliseconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

struct Method {
  std::string name;
  std::function<void()> run;
  std::vector<double> ms;
};

/// Runs every method once as a warm-up, then `rounds` interleaved rounds; fills Method::ms.
inline void time_interleaved(std::vector<Method>& methods, int rounds) {
  for (Method& m : methods) m.run();
  for (int r = 0; r < rounds; ++r) {
    for (Method& m : methods) {
      m.ms.push_back(milliseconds(m.run));
    }
  }
}

}  // namespace affine_orb::bench
