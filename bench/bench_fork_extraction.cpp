// bench_fork_extraction [--rounds N] [--profile orbslam2|orbslam3|stella N [--features F]]:
// affine_orb's extraction of a fork's own keypoints
// (ExtractorOptions::image_keypoints, what the ORB-SLAM adapters return by default) against that
// fork's ORBextractor compiled from ../shared/slam/stock_extractors, one thread, interleaved frame by
// frame, on the KITTI 00 frames (every 10th of 160, 1241x376) at ORB-SLAM's KITTI budget (2000) and
// its monocular initialiser's (2x, 5x), and on the six Oxford first images at 1000.
// stella_vslam's rows (where its extractor was built, tests/stock/stock_stella.hpp) compare
// StellaVslamKeypoints with its orb_extractor on the same frames at its default min_size
// (800) and smaller ones (more keypoints); its extraction does not depend on the heap.
// Per row: median milliseconds per frame of each over the rounds, their ratio, and how many of the
// fork's keypoints affine_orb returns identically (position, octave, angle, size, response, row, at
// the same index) with the fork's octree ordering nodes of equal size by creation (tests/stock:
// growing heap), and how many it shares (same position, octave and row, any order) with the fork
// on the system heap, where ORB-SLAM2 orders them by address; "stock vs itself" is the same share
// between two system-heap runs of the fork on the same frame.
// --profile FORK N: after a warm-up frame, only affine_orb's extraction of the KITTI frames for that
// fork (nfeatures F, default 2000; stella: min_size F, default 800), N rounds inside
// profiled_frames(), for `valgrind --tool=callgrind --toggle-collect='*profiled_frames*'`; prints
// the frames extracted and their keypoints.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "bench_common.hpp"
#include "stock_extractor.hpp"
#if AFFINE_ORB_STOCK_STELLA
#include "stock_stella.hpp"
#endif

namespace {

using affine_orb::stock::Fork;
using affine_orb::stock::Heap;
using affine_orb::stock::StockFrame;

struct Workload {
  std::string name;
  std::vector<cv::Mat> frames;
  int features;
};

std::vector<cv::Mat> kitti00() {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 160; i += 10) {
    char name[40];
    std::snprintf(name, sizeof(name), "/kitti00/image_0/%06d.png", i);
    frames.push_back(affine_orb::bench::read_gray_or_exit(affine_orb::bench::data_dir() + name));
  }
  return frames;
}

std::vector<cv::Mat> oxford() {
  std::vector<cv::Mat> frames;
  for (const char* sequence : {"graf", "boat", "bark", "bikes", "trees", "leuven"}) {
    frames.push_back(
        affine_orb::bench::read_gray_or_exit(affine_orb::bench::data_dir() + "/oxford/" + sequence + "/img1.png"));
  }
  return frames;
}

using Key = std::tuple<int, float, float, std::string>;

std::vector<Key> keys(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& rows) {
  std::vector<Key> out;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    out.emplace_back(k.octave, k.pt.x, k.pt.y, std::string(rows.ptr<char>(static_cast<int>(i)), 32));
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// How many of `a`'s keypoints `b` has (same octave, position and row).
std::size_t shared(const std::vector<Key>& a, const std::vector<Key>& b) {
  std::size_t n = 0;
  for (const Key& k : a) n += std::binary_search(b.begin(), b.end(), k);
  return n;
}

/// Keypoints equal field by field at the same index, with equal rows.
std::size_t identical(const StockFrame& stock, const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& rows) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < std::min(stock.keypoints.size(), keypoints.size()); ++i) {
    const cv::KeyPoint& a = stock.keypoints[i];
    const cv::KeyPoint& b = keypoints[i];
    n += a.pt == b.pt && a.octave == b.octave && a.angle == b.angle && a.size == b.size && a.response == b.response &&
         std::memcmp(stock.descriptors.ptr(static_cast<int>(i)), rows.ptr(static_cast<int>(i)), 32) == 0;
  }
  return n;
}

double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// Median milliseconds per frame of `stock` and `ours` over `rounds`, frame by frame interleaved.
template <class Stock, class Ours>
std::pair<double, double> time_interleaved(const std::vector<cv::Mat>& frames, int rounds, Stock stock, Ours ours) {
  std::vector<double> stock_ms, ours_ms;
  for (int r = 0; r < rounds; ++r) {
    double s = 0.0, o = 0.0;
    for (const cv::Mat& frame : frames) {
      auto start = std::chrono::steady_clock::now();
      stock(frame);
      s += elapsed_ms(start);
      start = std::chrono::steady_clock::now();
      ours(frame);
      o += elapsed_ms(start);
    }
    stock_ms.push_back(s / static_cast<double>(frames.size()));
    ours_ms.push_back(o / static_cast<double>(frames.size()));
  }
  return {affine_orb::bench::median(stock_ms), affine_orb::bench::median(ours_ms)};
}

void print_row(const char* fork, const Workload& w, std::pair<double, double> ms, std::size_t total, std::size_t same,
               std::size_t common, std::size_t self) {
  const auto percent = [total](std::size_t n) { return 100.0 * static_cast<double>(n) / static_cast<double>(total); };
  std::printf("| %s | %s, %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", fork, w.name.c_str(), w.features, ms.first,
              ms.second, ms.second / ms.first, percent(same), percent(common), percent(self));
}

/// The image alone with `fork`'s keypoints at nfeatures `features`: what the ORB-SLAM adapters extract.
affine_orb::ExtractorOptions fork_options(Fork fork, int features) {
  affine_orb::ExtractorOptions options;
  options.features = features;
  options.views.max_tilt = 1.0;
  if (fork == Fork::kOrbSlam2) {
    options.image_keypoints = affine_orb::OrbSlam2Keypoints{};
  } else {
    options.image_keypoints = affine_orb::OrbSlam3Keypoints{};
  }
  return options;
}

/// The image alone with stella_vslam's keypoints at `min_size`: what its adapter extracts.
affine_orb::ExtractorOptions stella_options(int min_size) {
  affine_orb::ExtractorOptions options;
  options.views.max_tilt = 1.0;
  affine_orb::StellaVslamKeypoints stella;
  stella.min_size = min_size;
  options.image_keypoints = stella;
  return options;
}

void run(Fork fork, const Workload& w, int rounds) {
  affine_orb::Extractor<affine_orb::Rbrief> ours(fork_options(fork, w.features));
  affine_orb::stock::StockExtractor stock(fork, w.features, 1.2f, 8, 20, 7);
  std::size_t total = 0, same = 0, common = 0, self = 0;
  for (const cv::Mat& frame : w.frames) {
    const affine_orb::Features<256> f = ours.extract(frame);
    const cv::Mat rows = affine_orb::descriptors_to_mat(f.descriptors);
    const StockFrame growing = stock.extract(frame, Heap::kGrowing);
    const StockFrame system1 = stock.extract(frame, Heap::kSystem);
    const StockFrame system2 = stock.extract(frame, Heap::kSystem);
    const std::vector<Key> mine = keys(f.keypoints, rows);
    total += growing.keypoints.size();
    same += identical(growing, f.keypoints, rows);
    common += shared(keys(system1.keypoints, system1.descriptors), mine);
    self += shared(keys(system1.keypoints, system1.descriptors), keys(system2.keypoints, system2.descriptors));
  }
  const auto ms = time_interleaved(
      w.frames, rounds, [&](const cv::Mat& f) { stock.extract(f); }, [&](const cv::Mat& f) { ours.extract(f); });
  print_row(fork == Fork::kOrbSlam2 ? "ORB-SLAM2" : "ORB-SLAM3", w, ms, total, same, common, self);
}

#if AFFINE_ORB_STOCK_STELLA
/// stella_vslam's row: Workload::features is its min_size.
void run_stella(const Workload& w, int rounds) {
  affine_orb::Extractor<affine_orb::Rbrief> ours(stella_options(w.features));
  affine_orb::stock::StockStellaExtractor stock(1.2f, 8, 20, 7, static_cast<unsigned>(w.features));
  std::size_t total = 0, same = 0, common = 0, self = 0;
  for (const cv::Mat& frame : w.frames) {
    const affine_orb::Features<256> f = ours.extract(frame);
    const cv::Mat rows = affine_orb::descriptors_to_mat(f.descriptors);
    const StockFrame first = stock.extract(frame);
    const StockFrame second = stock.extract(frame);
    total += first.keypoints.size();
    same += identical(first, f.keypoints, rows);
    common += shared(keys(first.keypoints, first.descriptors), keys(f.keypoints, rows));
    self += shared(keys(first.keypoints, first.descriptors), keys(second.keypoints, second.descriptors));
  }
  const auto ms = time_interleaved(
      w.frames, rounds, [&](const cv::Mat& f) { stock.extract(f); }, [&](const cv::Mat& f) { ours.extract(f); });
  print_row("stella_vslam", w, ms, total, same, common, self);
}
#endif

/// The frames measured under callgrind (--toggle-collect=*profiled_frames*): `rounds` extractions
/// of every frame; returns the keypoints extracted.
__attribute__((noinline)) std::size_t profiled_frames(affine_orb::Extractor<affine_orb::Rbrief>& ours,
                                                      const std::vector<cv::Mat>& frames, int rounds) {
  std::size_t keypoints = 0;
  for (int r = 0; r < rounds; ++r) {
    for (const cv::Mat& frame : frames) keypoints += ours.extract(frame).keypoints.size();
  }
  return keypoints;
}

/// --profile: affine_orb's extraction of `fork`'s keypoints ("orbslam2", "orbslam3", "stella")
/// on `frames`, `rounds` times inside profiled_frames() after a warm-up frame.
int profile(const std::string& fork, int features, int rounds, const std::vector<cv::Mat>& frames) {
  affine_orb::ExtractorOptions options;
  if (fork == "orbslam2") {
    options = fork_options(Fork::kOrbSlam2, features > 0 ? features : 2000);
  } else if (fork == "orbslam3") {
    options = fork_options(Fork::kOrbSlam3, features > 0 ? features : 2000);
  } else if (fork == "stella") {
    options = stella_options(features > 0 ? features : 800);
  } else {
    std::fprintf(stderr, "--profile takes orbslam2, orbslam3 or stella, got %s\n", fork.c_str());
    return 2;
  }
  affine_orb::Extractor<affine_orb::Rbrief> ours(options);
  ours.extract(frames.front());
  const std::size_t keypoints = profiled_frames(ours, frames, rounds);
  std::printf("%s: %zu frames, %zu keypoints\n", fork.c_str(), frames.size() * static_cast<std::size_t>(rounds),
              keypoints);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 15;
  std::string profiled;
  int profile_rounds = 0;
  int features = 0;
  for (int i = 1; i + 1 < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rounds") rounds = std::max(1, std::atoi(argv[i + 1]));
    if (arg == "--features") features = std::atoi(argv[i + 1]);
    if (arg == "--profile" && i + 2 < argc) {
      profiled = argv[i + 1];
      profile_rounds = std::max(1, std::atoi(argv[i + 2]));
    }
  }
  cv::setNumThreads(1);
  const std::vector<cv::Mat> kitti = kitti00();
  if (!profiled.empty()) return profile(profiled, features, profile_rounds, kitti);
  const std::vector<Workload> workloads = {
      {"KITTI 00", kitti, 2000}, {"KITTI 00", kitti, 4000}, {"KITTI 00", kitti, 10000}, {"Oxford", oxford(), 1000}};
  std::printf(
      "| fork | frames, nfeatures (stella: min_size) | fork ms | affine_orb ms | ratio | identical %% | shared %% | "
      "stock vs itself %% |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Fork fork : {Fork::kOrbSlam2, Fork::kOrbSlam3}) {
    for (const Workload& w : workloads) run(fork, w, rounds);
  }
#if AFFINE_ORB_STOCK_STELLA
  const std::vector<Workload> stella = {
      {"KITTI 00", kitti, 800}, {"KITTI 00", kitti, 200}, {"KITTI 00", kitti, 50}, {"Oxford", oxford(), 800}};
  for (const Workload& w : stella) run_stella(w, rounds);
#endif
  return 0;
}
