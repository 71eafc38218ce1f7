// bench_affine_speed [--rounds N] [--profile MODE N]: affine (18 views, max tilt 2√2)
// and plain extraction speed, side by side with the peers in one run, on two 640x480 images (the
// graf1 photo resized, KITTI 06 frame 10 scaled to cover 640x480 and centre-cropped):
//   ours affine rBRIEF, 2000 features, 1 and 2 threads
//   cv::AffineFeature(cv::ORB(2000/18 + 1)) with the same 18 views (maxTilt 3, tiltStep √2,
//     rotateStepBase 72), OpenCV on one thread
//   ours plain rBRIEF (max_tilt 1), 1000 features  vs  cv::ORB (1000, 1.2, 8 levels, FAST score)
// Methods run interleaved, round after round; medians and ratios are printed. Then the accuracy
// figure of the task: distinct correct matches graf 1 -> 3 (full resolution, 2000 features per
// image, DuplicatePolicy::kKeepAll, ratio 0.8; correct = ‖H x1 − x2‖ < 3 px; matches whose image-1
// points fall in the same 2-px cell count once).
//
// --profile affine|plain|orb|affine_feature N [--image graf|kitti]: runs only that extraction N
// times on one of the images (for instruction counts under callgrind).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"

namespace {

constexpr int kAffineFeatures = 2000;
constexpr int kPlainFeatures = 1000;

cv::Mat load(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    std::exit(1);
  }
  return image;
}

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
  options.features = kAffineFeatures;
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

cv::Matx33d read_homography(const std::string& path) {
  std::ifstream in(path);
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) {
    if (!(in >> h.val[i])) {
      std::fprintf(stderr, "cannot read %s\n", path.c_str());
      std::exit(1);
    }
  }
  return h;
}

// Distinct correct matches of two feature sets (see the file comment).
int distinct_correct(const affine_orb::Features<256>& a, const affine_orb::Features<256>& b, const cv::Matx33d& h) {
  const auto matches =
      affine_orb::match(affine_orb::descriptors_to_mat(a.descriptors), affine_orb::descriptors_to_mat(b.descriptors));
  std::set<std::pair<int, int>> cells;
  for (const auto& m : matches) {
    const cv::Point2f p = a.keypoints[static_cast<std::size_t>(m.query)].pt;
    const cv::Point2f q = b.keypoints[static_cast<std::size_t>(m.train)].pt;
    const cv::Vec3d x = h * cv::Vec3d(p.x, p.y, 1.0);
    if (std::hypot(x[0] / x[2] - q.x, x[1] / x[2] - q.y) < 3.0) {
      cells.emplace(static_cast<int>(std::floor(p.x / 2.0f)), static_cast<int>(std::floor(p.y / 2.0f)));
    }
  }
  return static_cast<int>(cells.size());
}

void bench_image(const char* name, const cv::Mat& image, int rounds) {
  affine_orb::Extractor<affine_orb::Rbrief> affine1(affine_options(1));
  affine_orb::Extractor<affine_orb::Rbrief> affine2(affine_options(2));
  affine_orb::Extractor<affine_orb::Rbrief> plain(plain_options());
  const int views = static_cast<int>(affine_orb::view_parameters(affine_orb::AffineViewOptions{}).size());
  const cv::Ptr<cv::Feature2D> peer = affine_feature_peer(views);
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(kPlainFeatures, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE);

  std::size_t counts[5] = {};
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<affine_orb::bench::Method> methods = {
      {"ours affine, 1 thread", [&] { counts[0] = affine1.extract(image).size(); }, {}},
      {"cv::AffineFeature(ORB), 1 thread",
       [&] {
         peer->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
         counts[1] = keypoints.size();
       },
       {}},
      {"ours affine, 2 threads", [&] { counts[2] = affine2.extract(image).size(); }, {}},
      {"ours plain (1000)", [&] { counts[3] = plain.extract(image).size(); }, {}},
      {"cv::ORB (1000)",
       [&] {
         orb->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
         counts[4] = keypoints.size();
       },
       {}},
  };
  // Wall time for every method, and the calling thread's CPU time, which a loaded machine disturbs
  // less, for the single-threaded ones.
  std::vector<std::vector<double>> cpu(methods.size());
  for (affine_orb::bench::Method& m : methods) m.run();
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t i = 0; i < methods.size(); ++i) {
      const double cpu_start = thread_cpu_ms();
      const auto start = std::chrono::steady_clock::now();
      methods[i].run();
      methods[i].ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      cpu[i].push_back(thread_cpu_ms() - cpu_start);
    }
  }
  auto med = [&](int i) { return affine_orb::bench::median(methods[static_cast<std::size_t>(i)].ms); };
  auto med_cpu = [&](int i) { return affine_orb::bench::median(cpu[static_cast<std::size_t>(i)]); };
  std::printf("## %s (%dx%d), %d views, medians of %d interleaved rounds\n\n", name, image.cols, image.rows, views,
              rounds);
  std::printf("| method | keypoints | median wall ms | median thread CPU ms |\n|---|---:|---:|---:|\n");
  for (std::size_t i = 0; i < methods.size(); ++i) {
    std::printf("| %s | %zu | %.2f | %.2f |\n", methods[i].name.c_str(), counts[i], med(static_cast<int>(i)),
                med_cpu(static_cast<int>(i)));
  }
  std::printf("\n| ratio | wall | CPU | goal |\n|---|---:|---:|---|\n");
  std::printf("| ours affine / cv::AffineFeature(ORB) | %.3f | %.3f | <= 0.5, then 0.2 |\n", med(0) / med(1),
              med_cpu(0) / med_cpu(1));
  std::printf("| ours affine / cv::ORB(1000) | %.2f | %.2f | <= 5 |\n", med(0) / med(4), med_cpu(0) / med_cpu(4));
  std::printf("| ours plain / cv::ORB(1000) | %.3f | %.3f | <= 1.0 |\n", med(3) / med(4), med_cpu(3) / med_cpu(4));
  std::printf("| ours affine 2 threads (wall) / cv::ORB(1000) | %.2f | | <= 3 |\n\n", med(2) / med(4));
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 21;
  std::string profile;
  std::string profile_image = "graf";
  int profile_runs = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rounds" && i + 1 < argc) {
      rounds = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--image" && i + 1 < argc) {
      profile_image = argv[++i];
    } else if (arg == "--profile" && i + 2 < argc) {
      profile = argv[++i];
      profile_runs = std::max(0, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: %s [--rounds N] [--profile affine|plain|orb|affine_feature N [--image graf|kitti]]\n",
                   argv[0]);
      return 2;
    }
  }
  cv::setNumThreads(1);
  const std::string data = affine_orb::bench::data_dir();
  const cv::Mat graf = to_640x480(load(data + "/oxford/graf/img1.png"));
  const cv::Mat kitti = to_640x480(load(data + "/kitti06/image_0/000010.png"));

  if (!profile.empty()) {
    const cv::Mat& profiled = profile_image == "kitti" ? kitti : graf;
    std::size_t total = 0;
    if (profile == "orb" || profile == "affine_feature") {
      const int views = static_cast<int>(affine_orb::view_parameters(affine_orb::AffineViewOptions{}).size());
      const cv::Ptr<cv::Feature2D> peer =
          profile == "orb"
              ? cv::Ptr<cv::Feature2D>(cv::ORB::create(kPlainFeatures, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE))
              : affine_feature_peer(views);
      std::vector<cv::KeyPoint> keypoints;
      cv::Mat descriptors;
      for (int r = 0; r < profile_runs; ++r) {
        peer->detectAndCompute(profiled, cv::noArray(), keypoints, descriptors);
        total += keypoints.size();
      }
    } else {
      affine_orb::Extractor<affine_orb::Rbrief> extractor(profile == "plain" ? plain_options() : affine_options(1));
      for (int r = 0; r < profile_runs; ++r) total += extractor.extract(profiled).size();
    }
    std::printf("%s: %d runs, %zu keypoints\n", profile.c_str(), profile_runs, total);
    return 0;
  }

  bench_image("graf1", graf, rounds);
  bench_image("KITTI 06 frame 10", kitti, rounds);

  affine_orb::ExtractorOptions options = affine_options(1);
  options.duplicates = affine_orb::DuplicatePolicy::kKeepAll;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  const auto f1 = extractor.extract(load(data + "/oxford/graf/img1.png"));
  const auto f3 = extractor.extract(load(data + "/oxford/graf/img3.png"));
  std::printf("## Accuracy: graf 1 -> 3, %d affine features per image, kKeepAll, ratio 0.8\n\n", kAffineFeatures);
  std::printf("distinct correct matches (< 3 px, 2-px cells): %d\n",
              distinct_correct(f1, f3, read_homography(data + "/oxford/graf/H1to3p")));
  return 0;
}
