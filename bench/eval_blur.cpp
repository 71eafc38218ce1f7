// eval_blur DIR [--features N] [--step K]: what each extractor delivers frame after frame in a
// sequence with motion blur (a TUM-layout folder: DIR/rgb.txt, e.g. a sequence rendered by
// ../shared/slam/synth_rgbd.py, whose "fast" and "shake" sequences carry blur of up to 44 px).
// For every pair of frames (i, i + K): the sharpness of frame i + K (variance of its Laplacian),
// then per method the keypoints of frame i + K, their spread (share of the 16 x 12 cells of the
// image holding one), the matches as ORB-SLAM2's monocular initialisation takes them (nearest
// neighbour by Hamming distance <= 50 with ratio 0.9, cv::BFMatcher) and how many of those a
// fundamental matrix explains (cv::findFundamentalMat, RANSAC, 1 px, 0.99): the correspondences
// tracking and initialisation live on. Frames are grouped into thirds by sharpness; medians per
// third, peers in the same run:
//   ours (adapter defaults: FAST 20/7, quadtree, views off) at N and 2N keypoints, ours with FAST
//   10/4, ours with the 18 views (N + N), cv::ORB N.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"
#include "sequence_io.hpp"

namespace {

struct Extracted {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

struct Method {
  std::string name;
  std::function<Extracted(const cv::Mat&)> run;
};

Method ours(const std::string& name, const affine_orb::ExtractorOptions& options) {
  auto extractor = std::make_shared<affine_orb::Extractor<affine_orb::Rbrief>>(options);
  return {name, [extractor](const cv::Mat& image) {
            const auto f = extractor->extract(image);
            return Extracted{f.keypoints, affine_orb::descriptors_to_mat(f.descriptors)};
          }};
}

double sharpness(const cv::Mat& image) {
  cv::Mat laplacian;
  cv::Laplacian(image, laplacian, CV_64F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  return deviation[0] * deviation[0];
}

double coverage(const std::vector<cv::KeyPoint>& keypoints, cv::Size size) {
  std::vector<char> cell(16 * 12, 0);
  for (const cv::KeyPoint& k : keypoints) {
    const int cx = std::clamp(static_cast<int>(k.pt.x * 16 / size.width), 0, 15);
    const int cy = std::clamp(static_cast<int>(k.pt.y * 12 / size.height), 0, 11);
    cell[static_cast<std::size_t>(cy * 16 + cx)] = 1;
  }
  return std::count(cell.begin(), cell.end(), 1) / 192.0;
}

/// Initialisation-style matches and those a fundamental matrix explains.
std::pair<int, int> matches(const Extracted& a, const Extracted& b) {
  if (a.keypoints.size() < 2 || b.keypoints.size() < 2) return {0, 0};
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(a.descriptors, b.descriptors, knn, 2);
  std::vector<cv::Point2f> p, q;
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance > 50 || m[0].distance >= 0.9f * m[1].distance) continue;
    p.push_back(a.keypoints[static_cast<std::size_t>(m[0].queryIdx)].pt);
    q.push_back(b.keypoints[static_cast<std::size_t>(m[0].trainIdx)].pt);
  }
  if (p.size() < 8) return {static_cast<int>(p.size()), 0};
  std::vector<unsigned char> inliers;
  cv::findFundamentalMat(p, q, cv::FM_RANSAC, 1.0, 0.99, inliers);
  return {static_cast<int>(p.size()), static_cast<int>(std::count(inliers.begin(), inliers.end(), 1))};
}

/// The command line: the sequence's folder, the keypoints per frame, the frame step.
struct Args {
  std::string dir;
  int features = 1000;
  int step = 1;
};

/// Reads the flags; prints why and gives nothing when one is wrong.
std::optional<Args> parse_args(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: eval_blur DIR [--features N] [--step K]\n");
    return std::nullopt;
  }
  Args args;
  args.dir = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--features") {
      args.features = std::atoi(argv[i + 1]);
    } else if (flag == "--step") {
      args.step = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return std::nullopt;
    }
  }
  if (args.features < 1 || args.step < 1) {
    std::fprintf(stderr, "eval_blur: --features and --step must be >= 1\n");
    return std::nullopt;
  }
  return args;
}

/// The methods of the table (see the top of this file) at `features` keypoints.
std::vector<Method> make_methods(int features) {
  affine_orb::ExtractorOptions plain;
  plain.features = features;
  plain.views.max_tilt = 1.0;
  affine_orb::ExtractorOptions twice = plain;
  twice.features = 2 * features;
  affine_orb::ExtractorOptions low = plain;
  low.detector.initial_threshold = 10;
  low.detector.min_threshold = 4;
  affine_orb::ExtractorOptions views = plain;
  views.views.max_tilt = 2.0 * std::sqrt(2.0);
  const std::string n = std::to_string(features);
  return {ours("ours " + n, plain),
          ours("ours " + std::to_string(2 * features), twice),
          ours("ours " + n + ", FAST 10/4", low),
          ours("ours " + n + " + views " + n, views),
          {"cv::ORB " + n, [orb = cv::ORB::create(features)](const cv::Mat& image) {
             Extracted e;
             orb->detectAndCompute(image, cv::noArray(), e.keypoints, e.descriptors);
             return e;
           }}};
}

/// One frame pair: the second frame's sharpness and, per method, its figures.
struct Row {
  double sharpness;
  std::vector<double> keypoints, spread, matched, explained;
};

/// Every method on frames 0, step, 2 step, ... of `sequence`, each frame matched with the one
/// before it; one row per pair.
std::vector<Row> measure(const affine_orb::examples::Sequence& sequence, const std::vector<Method>& methods, int step) {
  std::vector<Row> rows;
  std::vector<Extracted> previous(methods.size());
  for (std::size_t f = 0; f < sequence.frames.size(); f += static_cast<std::size_t>(step)) {
    const cv::Mat image = affine_orb::examples::load_frame(sequence.frames[f]);
    Row row{sharpness(image), {}, {}, {}, {}};
    for (std::size_t m = 0; m < methods.size(); ++m) {
      Extracted e = methods[m].run(image);
      const auto [matched, explained] = matches(previous[m], e);
      row.keypoints.push_back(static_cast<double>(e.keypoints.size()));
      row.spread.push_back(coverage(e.keypoints, image.size()));
      row.matched.push_back(matched);
      row.explained.push_back(explained);
      previous[m] = std::move(e);
    }
    if (f > 0) rows.push_back(row);
  }
  return rows;
}

/// Prints the table: per method and third of the rows by sharpness (`rows` sorted by it), the
/// medians of every figure.
void print_thirds(const std::vector<Row>& rows, const std::vector<Method>& methods, const Args& args) {
  std::printf("# %s: %zu frame pairs (step %d), medians per third by sharpness of the second frame\n\n",
              args.dir.c_str(), rows.size(), args.step);
  std::printf("| method | third (variance of Laplacian) | keypoints | spread | matches | explained by F |\n");
  std::printf("|---|---|---:|---:|---:|---:|\n");
  const std::size_t third = std::max<std::size_t>(rows.size() / 3, 1);
  for (std::size_t m = 0; m < methods.size(); ++m) {
    for (int t = 0; t < 3; ++t) {
      const std::size_t begin = std::min(rows.size(), t * third);
      const std::size_t end = t == 2 ? rows.size() : std::min(rows.size(), (t + 1) * third);
      if (begin >= end) continue;
      std::vector<double> k, s, a, e;
      for (std::size_t r = begin; r < end; ++r) {
        k.push_back(rows[r].keypoints[m]);
        s.push_back(rows[r].spread[m]);
        a.push_back(rows[r].matched[m]);
        e.push_back(rows[r].explained[m]);
      }
      const char* names[] = {"blurred", "middle", "sharp"};
      std::printf("| %s | %s (%.0f–%.0f) | %.0f | %.2f | %.0f | %.0f |\n", methods[m].name.c_str(), names[t],
                  rows[begin].sharpness, rows[end - 1].sharpness, affine_orb::bench::median(k),
                  affine_orb::bench::median(s), affine_orb::bench::median(a), affine_orb::bench::median(e));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Args> args = parse_args(argc, argv);
  if (!args) return 2;
  try {
    const affine_orb::examples::Sequence sequence = affine_orb::examples::read_tum(args->dir);
    const std::vector<Method> methods = make_methods(args->features);
    std::vector<Row> rows = measure(sequence, methods, args->step);
    std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.sharpness < b.sharpness; });
    print_thirds(rows, methods, *args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "eval_blur: %s\n", e.what());
    return 1;
  }
  return 0;
}
