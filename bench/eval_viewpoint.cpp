// eval_viewpoint [--out DIR] [--features N] [--view-features F] [--threads K] [--sequences a,b,...]
//                [--methods SUBSTRING] [--shortlist F] [--asift-sequences a,b,...|all] [--markdown]
//
// The SPEC §7 evaluation on image pairs with ground-truth homographies: every pair 1->2 ... 1->6 of
// every sequence in ../shared/data/oxford, and Debian opencv-doc's graf1/graf3 pair, for every
// method, in one run:
//   ours plain rBRIEF at the image budget N (what the affine default keeps of the image) and at the
//   affine default's total N·(1 + F), ours plain BRISK, ours affine rBRIEF/BRISK (the default:
//   additive budget, N image keypoints plus N·F from the 18 views), ours affine rBRIEF with the
//   former area split (2N in total), the strongest-N selection for some of them, cv::ORB 1000 and
//   2000, cv::BRISK, cv::AKAZE, cv::SIFT, cv::AffineFeature(cv::ORB) and cv::AffineFeature(cv::SIFT)
//   (ASIFT itself) with the same 18 views. ASIFT gives ~29 000 128-float descriptors per image; its
//   brute-force matching takes tens of seconds a pair, so it runs on the graf pairs only unless
//   --asift-sequences says otherwise.
// Binary descriptors are matched with affine_orb::match_features (ratio 0.8, location-aware ratio
// test, duplicate removal), float ones (SIFT, ASIFT) with the same rules on L2 distances
// (cv::BFMatcher k-nearest), and all are verified with the same estimator (cv::findHomography,
// RANSAC, 3 px).
// Per pair and method: keypoints, matches, correct (‖H x1 − x2‖ < 3 px), distinct correct (image-1
// points collapsed to 2-px cells), precision, RANSAC inliers and the fraction of them that are
// correct, repeatability (image-1 keypoints in the common region with an image-2 keypoint within
// 3 px after mapping), distinct correct per 1000 keypoints (of the mean of the two images' counts)
// and extraction time per image (single thread unless --threads).
// Writes DIR/eval_viewpoint.md, DIR/eval_viewpoint.csv and DIR/eval_viewpoint.png (distinct
// correct matches per 1000 keypoints against the graf viewpoint angle per method) and prints the
// full table; with --markdown it prints the summary table of the README instead: per method the
// distinct correct matches of graf 1->2 ... 1->6, their sum over every pair of the run, and the
// median extraction time per image relative to cv::ORB 2000 in the same run.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "bench_common.hpp"
#include "viewpoint_pairs.hpp"

namespace {

using Clock = std::chrono::steady_clock;

/// Features of one image by one method, in a form every method shares.
struct Extracted {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // CV_8U rows
  std::vector<int> views;
  double ms = 0.0;
};

struct Method {
  std::string name;
  std::function<Extracted(const cv::Mat&)> extract;
};

struct Row {
  std::string sequence;
  int image = 0;
  std::string method;
  std::size_t keypoints1 = 0, keypoints2 = 0, matches = 0, correct = 0, distinct = 0, inliers = 0, inliers_correct = 0;
  double precision = 0.0, repeatability = 0.0, ms = 0.0;
  /// Share of image-1 keypoints within 2 px of another image-1 keypoint (the same corner found
  /// twice, at neighbouring levels or in several views).
  double crowded = 0.0;
  /// Distinct correct matches per 1000 keypoints (of the mean of the two images' counts).
  double per_1000() const {
    const double mean = 0.5 * static_cast<double>(keypoints1 + keypoints2);
    return mean > 0.0 ? 1000.0 * static_cast<double>(distinct) / mean : 0.0;
  }
};

/// Our extractor with the options `base` but for `features`, `max_tilt` and what `configure` changes.
template <class Descriptor>
Method ours(const affine_orb::ExtractorOptions& base, const std::string& name, int features, double max_tilt,
            int threads, const std::function<void(affine_orb::ExtractorOptions&)>& configure = {}) {
  affine_orb::ExtractorOptions options = base;
  options.features = features;
  options.views.max_tilt = max_tilt;
  options.threads = threads;
  if (configure) configure(options);
  auto extractor = std::make_shared<affine_orb::Extractor<Descriptor>>(options);
  return {name, [extractor](const cv::Mat& image) {
            const auto start = Clock::now();
            const auto f = extractor->extract(image);
            Extracted e;
            e.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            e.keypoints = f.keypoints;
            e.descriptors = affine_orb::descriptors_to_mat(f.descriptors);
            e.views = f.views;
            return e;
          }};
}

Method peer(const std::string& name, cv::Ptr<cv::Feature2D> detector) {
  return {name, [detector](const cv::Mat& image) {
            Extracted e;
            const auto start = Clock::now();
            detector->detectAndCompute(image, cv::noArray(), e.keypoints, e.descriptors);
            e.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            return e;
          }};
}

template <int Bits>
affine_orb::Features<Bits> as_features(const Extracted& e) {
  affine_orb::Features<Bits> f;
  f.keypoints = e.keypoints;
  f.views = e.views.empty() ? std::vector<int>(e.keypoints.size(), 0) : e.views;
  f.descriptors.resize(e.keypoints.size());
  for (int i = 0; i < e.descriptors.rows; ++i)
    std::memcpy(f.descriptors[static_cast<std::size_t>(i)].data(), e.descriptors.ptr(i), Bits / 8);
  return f;
}

std::vector<affine_orb::Match> match(const Extracted& a, const Extracted& b) {
  if (a.keypoints.empty() || b.keypoints.empty()) return {};
  if (a.descriptors.type() == CV_32F)
    return affine_orb::bench::match_float(a.keypoints, a.descriptors, b.keypoints, b.descriptors);
  if (a.descriptors.cols == 32) return affine_orb::match_features(as_features<256>(a), as_features<256>(b));
  return affine_orb::match_features(as_features<512>(a), as_features<512>(b));
}

Row evaluate(const Extracted& a, const Extracted& b, const cv::Matx33d& h, cv::Size size2) {
  Row row;
  row.keypoints1 = a.keypoints.size();
  row.keypoints2 = b.keypoints.size();
  row.ms = 0.5 * (a.ms + b.ms);
  const auto matches = match(a, b);
  row.matches = matches.size();
  std::set<std::pair<int, int>> cells;
  std::vector<char> correct(matches.size(), 0);
  std::vector<cv::Point2f> p1, p2;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const cv::Point2f x1 = a.keypoints[static_cast<std::size_t>(matches[k].query)].pt;
    const cv::Point2f x2 = b.keypoints[static_cast<std::size_t>(matches[k].train)].pt;
    correct[k] = affine_orb::bench::match_residual(h, x1, x2) < affine_orb::bench::kCorrectMatchError;
    if (correct[k]) cells.insert({static_cast<int>(std::floor(x1.x / 2)), static_cast<int>(std::floor(x1.y / 2))});
    p1.push_back(x1);
    p2.push_back(x2);
  }
  row.correct = static_cast<std::size_t>(std::count(correct.begin(), correct.end(), 1));
  row.distinct = cells.size();
  row.precision = matches.empty() ? 0.0 : static_cast<double>(row.correct) / static_cast<double>(matches.size());
  if (matches.size() >= 4) {
    cv::Mat inlier_mask;
    const cv::Mat found = cv::findHomography(p1, p2, cv::RANSAC, 3.0, inlier_mask, 2000, 0.995);
    if (!found.empty()) {
      for (std::size_t k = 0; k < matches.size(); ++k) {
        if (inlier_mask.at<uchar>(static_cast<int>(k))) {
          ++row.inliers;
          row.inliers_correct += correct[k] != 0;
        }
      }
    }
  }
  std::size_t crowded = 0;
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    for (std::size_t j = 0; j < a.keypoints.size(); ++j) {
      const cv::Point2f d = a.keypoints[i].pt - a.keypoints[j].pt;
      if (i != j && d.x * d.x + d.y * d.y < 4.0f) {
        ++crowded;
        break;
      }
    }
  }
  row.crowded = a.keypoints.empty() ? 0.0 : static_cast<double>(crowded) / static_cast<double>(a.keypoints.size());
  // Repeatability over image-1 keypoints whose mapping falls inside image 2.
  std::size_t common = 0, repeated = 0;
  for (const auto& k1 : a.keypoints) {
    const cv::Point2d y = affine_orb::bench::map_point(h, k1.pt);
    if (y.x < 0 || y.y < 0 || y.x > size2.width - 1 || y.y > size2.height - 1) continue;
    ++common;
    for (const auto& k2 : b.keypoints) {
      if (std::hypot(y.x - k2.pt.x, y.y - k2.pt.y) < 3.0) {
        ++repeated;
        break;
      }
    }
  }
  row.repeatability = common ? static_cast<double>(repeated) / static_cast<double>(common) : 0.0;
  return row;
}

void plot(const std::vector<Row>& rows, const std::vector<Method>& methods, const std::string& path) {
  const int width = 1000, height = 560, left = 80, right = 300, top = 40, bottom = 60;
  cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int angles[] = {20, 30, 40, 50, 60};  // graf img2..img6 (approximate viewpoint change)
  // Distinct correct matches per 1000 keypoints: methods with 1000 and with 29 000 keypoints on one
  // scale.
  std::size_t ymax = 10;
  for (const Row& r : rows) {
    if (r.sequence == "graf") ymax = std::max(ymax, static_cast<std::size_t>(std::ceil(r.per_1000())));
  }
  ymax = (ymax / 50 + 1) * 50;
  auto to_px = [&](double angle, double value) {
    return cv::Point(left + static_cast<int>((angle - 15.0) / 50.0 * (width - left - right)),
                     height - bottom - static_cast<int>(value / static_cast<double>(ymax) * (height - top - bottom)));
  };
  cv::line(canvas, to_px(15, 0), to_px(65, 0), cv::Scalar(0, 0, 0));
  cv::line(canvas, to_px(15, 0), to_px(15, static_cast<double>(ymax)), cv::Scalar(0, 0, 0));
  for (int a : angles) {
    cv::putText(canvas, std::to_string(a), to_px(a, 0) + cv::Point(-8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(0, 0, 0));
  }
  for (std::size_t v = 0; v <= ymax; v += ymax / 5) {
    cv::putText(canvas, std::to_string(v), to_px(15, static_cast<double>(v)) + cv::Point(-50, 5),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
  }
  cv::putText(canvas, "viewpoint change (degrees), graf 1->2 ... 1->6", cv::Point(left + 120, height - 15),
              cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0));
  cv::putText(canvas, "distinct correct matches per 1000 keypoints", cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0));
  const cv::Scalar colours[] = {{200, 120, 0}, {120, 60, 0},    {0, 160, 0},   {0, 90, 0},    {230, 180, 90},
                                {90, 220, 90}, {0, 60, 0},      {0, 0, 220},   {0, 0, 130},   {150, 0, 150},
                                {0, 140, 255}, {120, 120, 120}, {255, 0, 255}, {0, 200, 200}, {60, 60, 200}};
  for (std::size_t m = 0; m < methods.size(); ++m) {
    const cv::Scalar colour = colours[m % (sizeof(colours) / sizeof(colours[0]))];
    cv::Point previous(-1, -1);
    for (int image = 2; image <= 6; ++image) {
      for (const Row& r : rows) {
        if (r.sequence != "graf" || r.image != image || r.method != methods[m].name) continue;
        const cv::Point p = to_px(angles[image - 2], r.per_1000());
        cv::circle(canvas, p, 4, colour, cv::FILLED, cv::LINE_AA);
        if (previous.x >= 0) cv::line(canvas, previous, p, colour, 2, cv::LINE_AA);
        previous = p;
      }
    }
    const cv::Point legend(width - right + 15, top + 20 + static_cast<int>(m) * 24);
    cv::line(canvas, legend, legend + cv::Point(25, 0), colour, 3, cv::LINE_AA);
    cv::putText(canvas, methods[m].name, legend + cv::Point(32, 5), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(0, 0, 0));
  }
  cv::imwrite(path, canvas);
}

/// The README's table: per method, distinct correct matches (per 1000 keypoints) on graf 1->2 ...
/// 1->6, distinct correct matches summed over the `pairs` pairs of the run ("–" for a method that
/// ran on fewer), and its median extraction time per image over cv::ORB 2000's.
std::string summary_table(const std::vector<Row>& rows, const std::vector<Method>& methods, std::size_t pairs) {
  auto median_ms = [&](const std::string& method) {
    std::vector<double> times;
    for (const Row& r : rows) {
      if (r.method == method) times.push_back(r.ms);
    }
    return affine_orb::bench::median(times);
  };
  const double reference_ms = median_ms("cv::ORB 2000");
  std::ostringstream out;
  out << "| distinct correct matches (per 1000 keypoints) | graf 1→2 (20°) | 1→3 (30°) | 1→4 (40°) | 1→5 (50°) | "
         "1→6 (60°) | all "
      << pairs << " pairs | time / cv::ORB 2000 |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Method& m : methods) {
    out << "| " << m.name;
    std::size_t total = 0, counted = 0;
    for (int image = 2; image <= 6; ++image) {
      const auto row = std::find_if(rows.begin(), rows.end(), [&](const Row& r) {
        return r.sequence == "graf" && r.image == image && r.method == m.name;
      });
      char cell[64] = " | –";
      if (row != rows.end()) std::snprintf(cell, sizeof(cell), " | %zu (%.0f)", row->distinct, row->per_1000());
      out << cell;
    }
    for (const Row& r : rows) {
      if (r.method != m.name) continue;
      total += r.distinct;
      ++counted;
    }
    char tail[96];
    if (reference_ms > 0.0) {
      std::snprintf(tail, sizeof(tail), " | %.2f |\n", median_ms(m.name) / reference_ms);
    } else {
      std::snprintf(tail, sizeof(tail), " | – |\n");
    }
    out << " | " << (counted == pairs ? std::to_string(total) : std::string("–")) << tail;
  }
  return out.str();
}

/// The command line; parse_args() gives it or nothing when it is wrong.
struct Args {
  std::string out_dir = ".";
  int features = 1000;
  double view_features = affine_orb::AdditiveBudget{}.view_features;
  affine_orb::ExtractorOptions base;
  int threads = 1;
  std::string only;
  std::string method_filter;
  std::string asift_only = ",graf,opencv-doc graf,";
  bool summary = false;
};

/// Reads the flags (see the top of this file); prints why and gives nothing when one is wrong.
std::optional<Args> parse_args(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--markdown") {
      args.summary = true;
      --i;
    } else if (i + 1 >= argc) {
      std::fprintf(stderr, "eval_viewpoint: %s needs a value\n", argv[i]);
      return std::nullopt;
    } else if (flag == "--out")
      args.out_dir = argv[i + 1];
    else if (flag == "--features")
      args.features = std::atoi(argv[i + 1]);
    else if (flag == "--view-features")
      args.view_features = std::atof(argv[i + 1]);
    else if (flag == "--threads")
      args.threads = std::atoi(argv[i + 1]);
    else if (flag == "--sequences")
      args.only = std::string(",") + argv[i + 1] + ",";
    else if (flag == "--shortlist")
      args.base.shortlist = std::atof(argv[i + 1]);
    else if (flag == "--methods")
      args.method_filter = argv[i + 1];
    else if (flag == "--asift-sequences")
      args.asift_only = std::string(argv[i + 1]) == "all" ? "" : std::string(",") + argv[i + 1] + ",";
    else {
      std::fprintf(stderr,
                   "usage: eval_viewpoint [--out DIR] [--features N] [--view-features F] [--threads K] "
                   "[--sequences a,b] [--methods SUBSTRING] [--shortlist F] [--asift-sequences a,b|all] "
                   "[--markdown]\n");
      return std::nullopt;
    }
  }
  try {
    args.base.check();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "eval_viewpoint: %s\n", e.what());
    return std::nullopt;
  }
  if (args.features < 1 || args.threads < 1 || !(args.view_features >= 0.0)) {
    std::fprintf(stderr, "eval_viewpoint: --features and --threads must be >= 1, --view-features >= 0\n");
    return std::nullopt;
  }
  return args;
}

/// Every method of the run, in the order of the tables, those --methods names only.
std::vector<Method> make_methods(const Args& args) {
  const affine_orb::ExtractorOptions& base = args.base;
  const int features = args.features, threads = args.threads;
  const double view_features = args.view_features;
  const double max_tilt = 2.0 * std::sqrt(2.0);
  const int total = features + static_cast<int>(std::lround(view_features * features));
  const int per_view = (total + 17) / 18;
  const std::string n_image = std::to_string(features);
  const std::string n_total = std::to_string(total);
  // Matching two images: the strongest corners (Spreading::kStrongest, the choice of
  // affine_orb_match); the quadtree rows show the SLAM spreading.
  auto strongest = [view_features](affine_orb::ExtractorOptions& o) {
    std::get<affine_orb::AdditiveBudget>(o.view_budget).view_features = view_features;
    o.spreading = affine_orb::Spreading::kStrongest;
  };
  auto area_split = [](affine_orb::ExtractorOptions& o) {
    o.view_budget = affine_orb::AreaSplitBudget{};
    o.spreading = affine_orb::Spreading::kStrongest;
  };
  auto quadtree = [view_features](affine_orb::ExtractorOptions& o) {
    std::get<affine_orb::AdditiveBudget>(o.view_budget).view_features = view_features;
  };
  auto repeats = [strongest](affine_orb::ExtractorOptions& o) {
    strongest(o);
    o.merge_duplicates->repeat_levels = 1;
  };
  std::vector<Method> methods = {
      ours<affine_orb::Rbrief>(base, "ours plain rBRIEF " + n_image, features, 1.0, threads, strongest),
      ours<affine_orb::Rbrief>(base, "ours plain rBRIEF " + n_total, total, 1.0, threads, strongest),
      ours<affine_orb::Rbrief>(base, "ours affine rBRIEF", features, max_tilt, threads, strongest),
      ours<affine_orb::Rbrief>(base, "ours affine rBRIEF area split " + n_total, total, max_tilt, threads, area_split),
      ours<affine_orb::Rbrief>(base, "ours affine rBRIEF repeats +-1 level", features, max_tilt, threads, repeats),
      ours<affine_orb::Brisk>(base, "ours plain BRISK " + n_total, total, 1.0, threads, strongest),
      ours<affine_orb::Brisk>(base, "ours affine BRISK", features, max_tilt, threads, strongest),
      ours<affine_orb::Rbrief>(base, "ours plain rBRIEF quadtree " + n_total, total, 1.0, threads, quadtree),
      ours<affine_orb::Rbrief>(base, "ours affine rBRIEF quadtree", features, max_tilt, threads, quadtree),
      peer("cv::ORB 1000", cv::ORB::create(1000)),
      peer("cv::ORB 2000", cv::ORB::create(2000)),
      peer("cv::BRISK", cv::BRISK::create()),
      peer("cv::AKAZE", cv::AKAZE::create()),
      peer("cv::SIFT", cv::SIFT::create()),
      peer("cv::AffineFeature(ORB)", cv::AffineFeature::create(cv::ORB::create(per_view), 3, 0, std::sqrt(2.0), 72)),
      peer("cv::AffineFeature(SIFT)", cv::AffineFeature::create(cv::SIFT::create(), 3, 0, std::sqrt(2.0), 72)),
  };
  methods.erase(std::remove_if(methods.begin(), methods.end(),
                               [&](const Method& m) { return m.name.find(args.method_filter) == std::string::npos; }),
                methods.end());
  return methods;
}

/// Every method on every pair, image 1's features extracted once per method and first image;
/// ASIFT (cv::AffineFeature(SIFT)) only on the sequences of `asift_only` (all when empty).
std::vector<Row> evaluate_pairs(const std::vector<affine_orb::bench::ViewpointPair>& pairs,
                                const std::vector<Method>& methods, const std::string& asift_only) {
  auto runs_on = [&](const Method& m, const std::string& sequence) {
    return m.name != "cv::AffineFeature(SIFT)" || asift_only.empty() ||
           asift_only.find("," + sequence + ",") != std::string::npos;
  };
  std::vector<Row> rows;
  std::map<std::string, Extracted> first;  // image-1 features per (path, method)
  for (const affine_orb::bench::ViewpointPair& pair : pairs) {
    const cv::Mat a = affine_orb::bench::read_gray(pair.path1);
    const cv::Mat b = affine_orb::bench::read_gray(pair.path2);
    for (const Method& method : methods) {
      if (!runs_on(method, pair.sequence)) continue;
      const std::string key = pair.path1 + "|" + method.name;
      if (!first.count(key)) first[key] = method.extract(a);
      const Extracted eb = method.extract(b);
      Row row = evaluate(first[key], eb, pair.h, b.size());
      row.sequence = pair.sequence;
      row.image = pair.image;
      row.method = method.name;
      rows.push_back(row);
      std::fprintf(stderr,
                   "%s 1->%d %-36s kp %zu/%zu matches %zu correct %zu distinct %zu (%.0f per 1000) inliers %zu (%zu "
                   "correct) %.0f ms\n",
                   pair.sequence.c_str(), pair.image, method.name.c_str(), row.keypoints1, row.keypoints2, row.matches,
                   row.correct, row.distinct, row.per_1000(), row.inliers, row.inliers_correct, row.ms);
    }
  }
  return rows;
}

/// Writes one CSV line per row to `path`.
void write_csv(const std::vector<Row>& rows, const std::string& path) {
  std::ofstream csv(path);
  csv << "sequence,pair,method,keypoints1,keypoints2,matches,correct,distinct_correct,precision,inliers,"
         "inliers_correct,repeatability,distinct_per_1000,within_2px,ms_extract\n";
  for (const Row& r : rows) {
    char line[512];
    std::snprintf(line, sizeof(line), "%s,1-%d,%s,%zu,%zu,%zu,%zu,%zu,%.4f,%zu,%zu,%.4f,%.1f,%.4f,%.2f\n",
                  r.sequence.c_str(), r.image, r.method.c_str(), r.keypoints1, r.keypoints2, r.matches, r.correct,
                  r.distinct, r.precision, r.inliers, r.inliers_correct, r.repeatability, r.per_1000(), r.crowded,
                  r.ms);
    csv << line;
  }
}

/// The full Markdown report: one line per row, then each method's median extraction time per
/// image over every image of the run.
std::string full_table(const std::vector<Row>& rows, const std::vector<Method>& methods, const Args& args) {
  std::ostringstream md;
  md << "# Viewpoint evaluation (SPEC §7)\n\n"
     << args.features << " image features for ours, plus " << args.view_features
     << " x as many from the 18 views (tilts up to 2√2) for the affine rows; " << args.threads
     << " thread(s); correct = ‖H x1 − x2‖ < 3 px; distinct = image-1 points in distinct 2-px cells; /1000 = "
     << "distinct per 1000 keypoints; inliers = cv::findHomography RANSAC 3 px on the matches (share correct); "
     << "2 px = share of image-1 keypoints within 2 px of another; ms = mean extraction time per image of the pair.\n\n"
     << "| pair | method | kp1 | kp2 | matches | correct | distinct | /1000 | precision | inliers (correct) | repeat. "
        "| 2 px | ms |\n"
     << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows) {
    char line[512];
    std::snprintf(line, sizeof(line),
                  "| %s 1→%d | %s | %zu | %zu | %zu | %zu | %zu | %.0f | %.2f | %zu (%.0f%%) | %.2f | %.2f | %.1f |\n",
                  r.sequence.c_str(), r.image, r.method.c_str(), r.keypoints1, r.keypoints2, r.matches, r.correct,
                  r.distinct, r.per_1000(), r.precision, r.inliers,
                  r.inliers ? 100.0 * r.inliers_correct / r.inliers : 0.0, r.repeatability, r.crowded, r.ms);
    md << line;
  }
  md << "\n| method | median ms per image |\n|---|---:|\n";
  for (const Method& m : methods) {
    std::vector<double> times;
    for (const Row& r : rows) {
      if (r.method == m.name) times.push_back(r.ms);
    }
    char line[256];
    std::snprintf(line, sizeof(line), "| %s | %.1f |\n", m.name.c_str(), affine_orb::bench::median(times));
    md << line;
  }
  return md.str();
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Args> args = parse_args(argc, argv);
  if (!args) return 2;
  cv::setNumThreads(args->threads);
  const std::vector<Method> methods = make_methods(*args);
  const std::vector<affine_orb::bench::ViewpointPair> pairs = affine_orb::bench::viewpoint_pairs(args->only);
  const std::vector<Row> rows = evaluate_pairs(pairs, methods, args->asift_only);
  write_csv(rows, args->out_dir + "/eval_viewpoint.csv");
  const std::string md = full_table(rows, methods, *args);
  std::ofstream(args->out_dir + "/eval_viewpoint.md") << md;
  plot(rows, methods, args->out_dir + "/eval_viewpoint.png");
  std::fputs(args->summary ? summary_table(rows, methods, pairs.size()).c_str() : md.c_str(), stdout);
  return 0;
}
