// bench_affine_speed [--rounds N] [--no-instructions] [--no-memory] [--profile MODE N [--image graf|kitti]]
//                    [--peak MODE WxH]:
// affine (18 views, max tilt 2√2) and plain extraction speed, side by side with the peers in one
// run, on two 640x480 images (the graf1 photo resized, KITTI 06 frame 10 scaled to cover 640x480
// and centre-cropped):
//   ours affine rBRIEF, 2000 features, 1 and 2 threads
//   cv::AffineFeature(cv::ORB(2000/18 + 1)) with the same 18 views (maxTilt 3, tiltStep √2,
//     rotateStepBase 72), OpenCV on one thread
//   ours plain rBRIEF (max_tilt 1), 1000 features  vs  cv::ORB (1000, 1.2, 8 levels, FAST score)
// Methods run interleaved, round after round; medians and ratios are printed as Markdown tables (the
// README's), with each method's operator-new calls per frame after warm-up and, when valgrind is on
// the PATH, its instructions per frame: the program runs itself under callgrind (--profile,
// collecting only inside the frames after a warm-up frame). Then one accuracy figure: distinct
// correct matches graf 1 -> 3 (full resolution, 2000 features per image, merge_duplicates off, ratio 0.8;
// correct = ‖H x1 − x2‖ < 3 px; matches whose image-1 points fall in the same 2-px cell count once).
//
// Then the peak resident memory of one process per method and image size (graf1 resized to
// 640x480 and 2560x1920; three frames each), the program running itself with --peak, beside the
// baseline of a process that only loads and resizes the image (OpenCV's libraries are most of it).
//
// --profile affine|affine2|plain|orb|affine_feature N [--image graf|kitti]: runs one warm-up frame,
// then that extraction N times inside profiled_frames() (for callgrind --toggle-collect).
// --peak baseline|affine|affine2|plain|orb|affine_feature WxH: prints the process's peak resident
// memory (VmHWM, kB) after three frames of that extraction on graf1 resized to WxH.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <new>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"
#include "viewpoint_pairs.hpp"

// Counts operator-new calls of the whole process (ours and OpenCV's C++ allocations).
std::atomic<long> g_new_calls{0};

// The replacement's own malloc/free pair; GCC 12 flags free() in a replacement operator delete as
// mismatched (-Wmismatched-new-delete), a false positive here.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
  ++g_new_calls;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

constexpr int kAffineFeatures = 2000;
constexpr int kPlainFeatures = 1000;

// Scales the image so that it covers 640x480, then crops the centre.
cv::Mat to_640x480(const cv::Mat& image) {
  const double scale = std::max(640.0 / image.cols, 480.0 / image.rows);
  cv::Mat scaled;
  const cv::Size size(std::max(640, static_cast<int>(std::lround(image.cols * scale))),
                      std::max(480, static_cast<int>(std::lround(image.rows * scale))));
  cv::resize(image, scaled, size, 0, 0, scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
  return scaled(cv::Rect((scaled.cols - 640) / 2, (scaled.rows - 480) / 2, 640, 480)).clone();
}

affine_orb::ExtractorOptions affine_options(int threads) {
  affine_orb::ExtractorOptions options;
  // The additive budget: half from the image, as many again from the views (view_features 1),
  // kAffineFeatures in all like the peer.
  options.features = kAffineFeatures / 2;
  options.threads = threads;
  return options;
}

affine_orb::ExtractorOptions plain_options() {
  affine_orb::ExtractorOptions options;
  options.features = kPlainFeatures;
  options.views.max_tilt = 1.0;
  return options;
}

// CPU time of the calling thread in milliseconds.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

cv::Ptr<cv::Feature2D> affine_feature_peer(int views) {
  return cv::AffineFeature::create(cv::ORB::create(kAffineFeatures / views + 1), 3, 0, std::sqrt(2.0f), 72.0f);
}

// Distinct correct matches of two feature sets (see the file comment).
int distinct_correct(const affine_orb::Features<256>& a, const affine_orb::Features<256>& b, const cv::Matx33d& h) {
  std::vector<std::pair<cv::Point2f, cv::Point2f>> pairs;
  for (const auto& m : affine_orb::match(affine_orb::descriptors_to_mat(a.descriptors),
                                         affine_orb::descriptors_to_mat(b.descriptors))) {
    pairs.emplace_back(a.keypoints[static_cast<std::size_t>(m.query)].pt,
                       b.keypoints[static_cast<std::size_t>(m.train)].pt);
  }
  return static_cast<int>(affine_orb::bench::correct_matches(pairs, h).distinct);
}

/// The five extractions of the bench on one image, each with its --profile mode name.
struct Extractions {
  explicit Extractions(const cv::Mat& frame)
      : image(frame),
        affine1(affine_options(1)),
        affine2(affine_options(2)),
        plain(plain_options()),
        views(static_cast<int>(affine_orb::view_parameters(affine_orb::AffineViewOptions{}).size())),
        peer(affine_feature_peer(views)),
        orb(cv::ORB::create(kPlainFeatures, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE)) {}

  /// Mode name, table label and the extraction (returning the number of keypoints).
  struct Entry {
    std::string mode;
    std::string label;
    std::function<std::size_t()> run;
  };

  std::vector<Entry> entries() {
    auto opencv = [this](cv::Feature2D& f) {
      f.detectAndCompute(image, cv::noArray(), keypoints, descriptors);
      return keypoints.size();
    };
    return {{"affine", "ours affine, 1 thread", [this] { return affine1.extract(image).size(); }},
            {"affine_feature", "cv::AffineFeature(ORB), 1 thread", [this, opencv] { return opencv(*peer); }},
            {"affine2", "ours affine, 2 threads", [this] { return affine2.extract(image).size(); }},
            {"plain", "ours plain (1000)", [this] { return plain.extract(image).size(); }},
            {"orb", "cv::ORB (1000)", [this, opencv] { return opencv(*orb); }}};
  }

  const cv::Mat& image;
  affine_orb::Extractor<affine_orb::Rbrief> affine1;
  affine_orb::Extractor<affine_orb::Rbrief> affine2;
  affine_orb::Extractor<affine_orb::Rbrief> plain;
  int views;
  cv::Ptr<cv::Feature2D> peer;
  cv::Ptr<cv::ORB> orb;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// Peak resident set of this process in kB (VmHWM of /proc/self/status), 0 when unknown.
long peak_resident_kb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return 0;
}

/// Runs this program with --peak `mode` WxH and returns the peak it reports in MB (0 on failure).
double peak_memory_mb(const std::string& mode, cv::Size size) {
  char self[4096] = {};
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length <= 0) return 0.0;
  const std::string command = "'" + std::string(self, static_cast<std::size_t>(length)) + "' --peak " + mode + " " +
                              std::to_string(size.width) + "x" + std::to_string(size.height);
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return 0.0;
  char line[256];
  long kb = 0;
  while (std::fgets(line, sizeof(line), pipe) != nullptr) {
    if (std::strncmp(line, "peak_kb ", 8) == 0) kb = std::atol(line + 8);
  }
  return pclose(pipe) == 0 ? kb / 1024.0 : 0.0;
}

/// The peak memory table: one process per method and image size.
void memory_table() {
  const std::vector<std::pair<std::string, std::string>> modes = {{"baseline", "image loaded, nothing extracted"},
                                                                  {"affine", "ours affine, 1 thread"},
                                                                  {"affine2", "ours affine, 2 threads"},
                                                                  {"affine_feature", "cv::AffineFeature(ORB)"},
                                                                  {"plain", "ours plain (1000)"},
                                                                  {"orb", "cv::ORB (1000)"}};
  std::printf("Peak resident memory of one process (MB, VmHWM after three frames of graf1 resized):\n\n");
  std::printf("| method | 640x480 | 2560x1920 |\n|---|---:|---:|\n");
  for (const auto& [mode, label] : modes) {
    std::printf("| %s | %.1f | %.1f |\n", label.c_str(), peak_memory_mb(mode, {640, 480}),
                peak_memory_mb(mode, {2560, 1920}));
  }
  std::printf("\n");
}

/// The frames measured under callgrind (--toggle-collect=*profiled_frames*).
__attribute__((noinline)) std::size_t profiled_frames(const std::function<std::size_t()>& run, int frames) {
  std::size_t total = 0;
  for (int r = 0; r < frames; ++r) total += run();
  return total;
}

/// Instructions per frame of `mode` on `image_name`, by running this program under callgrind
/// (collecting inside profiled_frames() only, after a warm-up frame); 0 when valgrind fails.
double instructions_per_frame(const std::string& mode, const std::string& image_name) {
  constexpr int kFrames = 3;
  char self[4096] = {};
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length <= 0) return 0.0;
  const std::string command =
      "valgrind --tool=callgrind --callgrind-out-file=/dev/null "
      "--toggle-collect='*profiled_frames*' '" +
      std::string(self, static_cast<std::size_t>(length)) + "' --profile " + mode + " " + std::to_string(kFrames) +
      " --image " + image_name + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return 0.0;
  char line[1024];
  double collected = 0.0;
  while (std::fgets(line, sizeof(line), pipe) != nullptr) {
    const std::string text(line);
    const std::size_t at = text.find("Collected :");
    if (at == std::string::npos) continue;
    std::string digits;
    for (char c : text.substr(at + 11)) {
      if (c >= '0' && c <= '9') digits += c;
    }
    if (!digits.empty()) collected = std::stod(digits);
  }
  return pclose(pipe) == 0 ? collected / kFrames : 0.0;
}

void bench_image(const char* name, const std::string& image_name, const cv::Mat& image, int rounds, bool instructions) {
  Extractions extractions(image);
  const std::vector<Extractions::Entry> entries = extractions.entries();
  const std::size_t n = entries.size();
  std::vector<std::size_t> counts(n, 0);
  std::vector<long> news(n, 0);
  std::vector<std::vector<double>> wall(n);
  std::vector<std::vector<double>> cpu(n);
  for (std::size_t i = 0; i < n; ++i) entries[i].run();
  // Wall time for every method, and the calling thread's CPU time, which a loaded machine disturbs
  // less, for the single-threaded ones.
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t i = 0; i < n; ++i) {
      const long news_before = g_new_calls;
      const double cpu_start = thread_cpu_ms();
      const auto start = std::chrono::steady_clock::now();
      counts[i] = entries[i].run();
      wall[i].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      cpu[i].push_back(thread_cpu_ms() - cpu_start);
      news[i] = g_new_calls - news_before;
    }
  }
  std::vector<double> instr(n, 0.0);
  if (instructions) {
    // Not for 2 threads: callgrind would count only the calling thread's share.
    for (std::size_t i = 0; i < n; ++i) {
      if (entries[i].mode != "affine2") instr[i] = instructions_per_frame(entries[i].mode, image_name);
    }
  }
  auto med = [&](std::size_t i) { return affine_orb::bench::median(wall[i]); };
  auto med_cpu = [&](std::size_t i) { return affine_orb::bench::median(cpu[i]); };
  std::printf("%s (%dx%d), %d views, medians of %d interleaved rounds:\n\n", name, image.cols, image.rows,
              extractions.views, rounds);
  std::printf(
      "| method | keypoints | median wall ms | median thread CPU ms | instructions per frame (M) | operator new "
      "per frame |\n|---|---:|---:|---:|---:|---:|\n");
  for (std::size_t i = 0; i < n; ++i) {
    std::printf("| %s | %zu | %.2f | %.2f | %s | %ld |\n", entries[i].label.c_str(), counts[i], med(i), med_cpu(i),
                instr[i] > 0.0 ? std::to_string(static_cast<long>(std::lround(instr[i] / 1e6))).c_str() : "-", news[i]);
  }
  auto ratio = [&](std::size_t a, std::size_t b) {
    return instr[a] > 0.0 && instr[b] > 0.0 ? std::to_string(instr[a] / instr[b]).substr(0, 5) : std::string("-");
  };
  // Indices in entries(): 0 affine, 1 AffineFeature, 2 affine 2 threads, 3 plain, 4 ORB.
  std::printf("\n| ratio | wall | CPU | instructions |\n|---|---:|---:|---:|\n");
  std::printf("| ours affine / cv::AffineFeature(ORB) | %.3f | %.3f | %s |\n", med(0) / med(1), med_cpu(0) / med_cpu(1),
              ratio(0, 1).c_str());
  std::printf("| ours affine / cv::ORB(1000) | %.2f | %.2f | %s |\n", med(0) / med(4), med_cpu(0) / med_cpu(4),
              ratio(0, 4).c_str());
  std::printf("| ours affine, 2 threads (wall) / cv::ORB(1000) | %.2f | | |\n", med(2) / med(4));
  std::printf("| ours plain / cv::ORB(1000) | %.3f | %.3f | %s |\n\n", med(3) / med(4), med_cpu(3) / med_cpu(4),
              ratio(3, 4).c_str());
}

/// The command line (see the top of this file).
struct Args {
  int rounds = 21;
  bool instructions = true;
  bool memory = true;
  std::string profile;  ///< --profile's mode, empty without it
  int profile_runs = 0;
  std::string profile_image = "graf";
  std::string peak_mode;  ///< --peak's mode, empty without it
  cv::Size peak_size;
};

/// Reads the flags; prints why and gives nothing when one is wrong.
std::optional<Args> parse_args(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rounds" && i + 1 < argc) {
      args.rounds = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--no-instructions") {
      args.instructions = false;
    } else if (arg == "--no-memory") {
      args.memory = false;
    } else if (arg == "--peak" && i + 2 < argc) {
      args.peak_mode = argv[++i];
      cv::Size& size = args.peak_size;
      if (std::sscanf(argv[++i], "%dx%d", &size.width, &size.height) != 2 || size.width < 64 || size.height < 64) {
        std::fprintf(stderr, "--peak: expected a size WxH of at least 64x64, got %s\n", argv[i]);
        return std::nullopt;
      }
    } else if (arg == "--image" && i + 1 < argc) {
      args.profile_image = argv[++i];
    } else if (arg == "--profile" && i + 2 < argc) {
      args.profile = argv[++i];
      args.profile_runs = std::max(0, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: %s [--rounds N] [--no-instructions] [--no-memory] [--profile affine|affine2|plain|orb|"
                   "affine_feature N [--image graf|kitti]] [--peak baseline|affine|affine2|plain|orb|affine_feature "
                   "WxH]\n",
                   argv[0]);
      return std::nullopt;
    }
  }
  return args;
}

/// --peak: prints the peak resident memory after three frames of `mode` on graf1 resized to `size`.
int print_peak(const std::string& mode, cv::Size size) {
  const cv::Mat photo = affine_orb::bench::read_gray_or_exit(affine_orb::bench::data_dir() + "/oxford/graf/img1.png");
  cv::Mat image;
  cv::resize(photo, image, size, 0, 0, size.width < photo.cols ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (mode == "baseline") {
    std::printf("peak_kb %ld\n", peak_resident_kb());
    return 0;
  }
  Extractions extractions(image);
  for (const Extractions::Entry& entry : extractions.entries()) {
    if (entry.mode != mode) continue;
    for (int frame = 0; frame < 3; ++frame) entry.run();
    std::printf("peak_kb %ld\n", peak_resident_kb());
    return 0;
  }
  std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
  return 2;
}

/// --profile: one warm-up frame of `mode` on `image`, then `runs` frames inside profiled_frames().
int run_profile(const std::string& mode, int runs, const cv::Mat& image) {
  Extractions extractions(image);
  for (const Extractions::Entry& entry : extractions.entries()) {
    if (entry.mode != mode) continue;
    entry.run();
    std::printf("%s: %d runs, %zu keypoints\n", mode.c_str(), runs, profiled_frames(entry.run, runs));
    return 0;
  }
  std::fprintf(stderr, "unknown profile mode %s\n", mode.c_str());
  return 2;
}

/// Prints the accuracy figure: distinct correct matches of graf 1 -> 3 at full size.
void print_accuracy() {
  const std::string data = affine_orb::bench::data_dir();
  affine_orb::ExtractorOptions options = affine_options(1);
  options.merge_duplicates.reset();
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  const auto f1 = extractor.extract(affine_orb::bench::read_gray_or_exit(data + "/oxford/graf/img1.png"));
  const auto f3 = extractor.extract(affine_orb::bench::read_gray_or_exit(data + "/oxford/graf/img3.png"));
  std::printf("Accuracy, graf 1 -> 3 at full size, %d affine features per image, duplicates kept, ratio 0.8: ",
              kAffineFeatures);
  std::printf("%d distinct correct matches (< 3 px, 2-px cells)\n",
              distinct_correct(f1, f3, affine_orb::bench::read_oxford_homography(data + "/oxford/graf/H1to3p")));
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<Args> args = parse_args(argc, argv);
  if (!args) return 2;
  cv::setNumThreads(1);
  const std::string data = affine_orb::bench::data_dir();
  const cv::Mat graf = to_640x480(affine_orb::bench::read_gray_or_exit(data + "/oxford/graf/img1.png"));
  const cv::Mat kitti = to_640x480(affine_orb::bench::read_gray_or_exit(data + "/kitti06/image_0/000010.png"));
  if (!args->peak_mode.empty()) return print_peak(args->peak_mode, args->peak_size);
  if (!args->profile.empty()) {
    return run_profile(args->profile, args->profile_runs, args->profile_image == "kitti" ? kitti : graf);
  }
  if (args->instructions && std::system("valgrind --version > /dev/null 2>&1") != 0) {
    std::printf("(valgrind not found: no instruction counts)\n\n");
    args->instructions = false;
  }
  bench_image("graf1", "graf", graf, args->rounds, args->instructions);
  bench_image("KITTI 06 frame 10", "kitti", kitti, args->rounds, args->instructions);
  if (args->memory) memory_table();
  print_accuracy();
  return 0;
}
