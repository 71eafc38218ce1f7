// bench_stages [Google Benchmark flags]: one micro-benchmark per stage of the extraction and the
// two-view matching, each beside the peer's equivalent stage where OpenCV has one, on real images
// (the graf1 photo resized to 640x480 with INTER_AREA, as bench_extract and bench_affine_speed do;
// graf3 for the second image of the matching stages). OpenCV runs on one thread
// (cv::setNumThreads(1)); every affine_orb stage is single-threaded.
//
// Names are <stage>/<who>: "ours" or the peer's function. Stages and their inputs:
//   pyramid            8 levels, factor 1.2 from the 640x480 image   | cv::resize (INTER_LINEAR) level by level
//   fast_score         FAST-9 scores of every pixel, threshold 20     |
//   fast_detect        scores + non-maximum suppression               | cv::FAST (threshold 20, non-max)
//   orientation        intensity centroid (radius 15) of the level-0  |
//                      keypoints of the plain extraction
//   gaussian_q8        7x7, σ 2 smoothing of the whole level          | cv::GaussianBlur (same kernel)
//   rbrief             smoothing around the keypoints + 256 tests     | cv::ORB::compute, same keypoints
//   brisk              integral image + 512 BRISK tests               | cv::BRISK::compute, same keypoints
//   quadtree           1000 of the level-0 FAST corners spread        |
//   view_render        one view (tilt 2, 36°), antialias 0.8          | cv::warpAffine + GaussianBlur + resize
//                                                                       (render_view_reference())
//   knn2               2000 x 2000 ORB descriptors (graf1, graf3)     | cv::BFMatcher(NORM_HAMMING).knnMatch k=2
//   select_model       H and F by RANSAC on the ratio-tested matches  | cv::findHomography + cv::findFundamentalMat
//                      of graf1 -> graf3                                 (RANSAC, 3 px)
//   extract_plain      1000 features, no views                        | cv::ORB (1000, 1.2, 8, FAST score)
//   extract_affine     1000 + 1000 from 18 views                      | cv::AffineFeature(cv::ORB), 18 views
// Filters, repetitions and JSON output are Google Benchmark's (--benchmark_filter=rbrief,
// --benchmark_repetitions=5, --benchmark_out=stages.json --benchmark_out_format=json);
// bench/benchmark_table.py turns the JSON into docs/speed.md's table.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "affine_orb/descriptors/detail/gaussian_q8.hpp"
#include "bench_common.hpp"
#if AFFINE_ORB_HAVE_STOCK
#include "stock_extractor.hpp"
#endif

namespace {

constexpr int kThreshold = 20;
constexpr int kPlainFeatures = 1000;
constexpr int kMatchFeatures = 2000;

cv::Mat load_640x480(const std::string& name) {
  const std::string path = affine_orb::bench::data_dir() + "/oxford/graf/" + name;
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    std::exit(1);
  }
  cv::resize(image, image, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  return image;
}

/// The inputs every stage reads, built once.
struct Inputs {
  cv::Mat image;                           ///< graf1, 640x480
  cv::Mat image3;                          ///< graf3, 640x480
  std::vector<cv::KeyPoint> level0;        ///< the plain extraction's octave-0 keypoints
  std::vector<cv::Point2f> level0_points;  ///< their positions (level-0 pixels)
  std::vector<cv::Point2f> corners;        ///< FAST corners of the image (threshold 20, non-max)
  std::vector<float> corner_scores;
  cv::Mat orb1, orb3;                         ///< cv::ORB descriptors (2000) of graf1 and graf3
  std::vector<cv::Point2f> points1, points3;  ///< ratio-tested matches of our 2000 features

  Inputs() : image(load_640x480("img1.png")), image3(load_640x480("img3.png")) {
    affine_orb::ExtractorOptions plain;
    plain.features = kPlainFeatures;
    plain.views.max_tilt = 1.0;
    affine_orb::Extractor<affine_orb::Rbrief> extractor(plain);
    for (const cv::KeyPoint& kp : extractor.extract(image).keypoints) {
      if (kp.octave != 0) continue;
      level0.push_back(kp);
      level0_points.push_back(kp.pt);
    }
    for (const affine_orb::Corner& c : affine_orb::detect_fast(image, kThreshold)) {
      corners.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y));
      corner_scores.push_back(static_cast<float>(c.score));
    }
    const cv::Ptr<cv::ORB> orb = cv::ORB::create(kMatchFeatures);
    std::vector<cv::KeyPoint> kps;
    orb->detectAndCompute(image, cv::noArray(), kps, orb1);
    orb->detectAndCompute(image3, cv::noArray(), kps, orb3);

    affine_orb::ExtractorOptions options;
    options.features = kMatchFeatures;
    options.views.max_tilt = 1.0;
    affine_orb::Extractor<affine_orb::Rbrief> ours(options);
    const auto f1 = ours.extract(image);
    const auto f3 = ours.extract(image3);
    for (const affine_orb::Match& m : affine_orb::match(f1.descriptors, f3.descriptors)) {
      points1.push_back(f1.keypoints[static_cast<std::size_t>(m.query)].pt);
      points3.push_back(f3.keypoints[static_cast<std::size_t>(m.train)].pt);
    }
  }
};

const Inputs& inputs() {
  static const Inputs data;
  return data;
}

void set_items(benchmark::State& state, std::size_t items) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * items));
}

// ---- pyramid
void pyramid_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  affine_orb::Pyramid pyramid;
  for (auto _ : state) {
    pyramid.build(image);
    benchmark::DoNotOptimize(pyramid.level(7).data);
  }
}
void pyramid_cv_resize(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const affine_orb::PyramidOptions options;
  std::vector<cv::Mat> levels(static_cast<std::size_t>(options.levels));
  for (auto _ : state) {
    image.copyTo(levels[0]);
    for (int l = 1; l < options.levels; ++l) {
      const std::size_t i = static_cast<std::size_t>(l);
      cv::resize(levels[i - 1], levels[i], affine_orb::pyramid_level_size(image.size(), options, l), 0, 0,
                 cv::INTER_LINEAR);
    }
    benchmark::DoNotOptimize(levels.back().data);
  }
}
BENCHMARK(pyramid_ours)->Name("pyramid/ours");
BENCHMARK(pyramid_cv_resize)->Name("pyramid/cv::resize");

// ---- FAST
void fast_score_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  cv::Mat scores;
  for (auto _ : state) {
    affine_orb::fast_score_map(image, cv::Rect(0, 0, image.cols, image.rows), kThreshold, scores);
    benchmark::DoNotOptimize(scores.data);
  }
  set_items(state, image.total());
}
void fast_detect_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const cv::Rect all(0, 0, image.cols, image.rows);
  const affine_orb::RowSpans region = affine_orb::RowSpans::rectangle(all);
  cv::Mat scores;
  std::vector<affine_orb::Corner> corners;
  for (auto _ : state) {
    affine_orb::fast_score_map(image, all, kThreshold, scores);
    corners.clear();
    affine_orb::non_max_suppression(scores, region, kThreshold, corners);
    benchmark::DoNotOptimize(corners.data());
  }
  set_items(state, image.total());
}
void fast_detect_cv(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  std::vector<cv::KeyPoint> keypoints;
  for (auto _ : state) {
    cv::FAST(image, keypoints, kThreshold, true, cv::FastFeatureDetector::TYPE_9_16);
    benchmark::DoNotOptimize(keypoints.data());
  }
  set_items(state, image.total());
}
BENCHMARK(fast_score_ours)->Name("fast_score/ours");
BENCHMARK(fast_detect_ours)->Name("fast_detect/ours");
BENCHMARK(fast_detect_cv)->Name("fast_detect/cv::FAST");

// ---- orientation, smoothing, description
void orientation_ours(benchmark::State& state) {
  const Inputs& in = inputs();
  const affine_orb::Rbrief rbrief;
  affine_orb::Rbrief::LevelData data;
  data.image = in.image;
  float sum = 0.0f;
  for (auto _ : state) {
    for (const cv::Point2f& p : in.level0_points) sum += rbrief.orientation(data, p);
    benchmark::DoNotOptimize(sum);
  }
  set_items(state, in.level0_points.size());
}
BENCHMARK(orientation_ours)->Name("orientation/ours");

void gaussian_q8_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const std::vector<std::uint16_t> kernel = affine_orb::detail::gaussian_kernel_q8(7, 2.0);
  affine_orb::detail::GaussianQ8Work work;
  cv::Mat out(image.size(), CV_8UC1);
  for (auto _ : state) {
    affine_orb::detail::smooth_square_q8(image, cv::Rect(0, 0, image.cols, image.rows), kernel, work, out);
    benchmark::DoNotOptimize(out.data);
  }
  set_items(state, image.total());
}
void gaussian_q8_cv(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  cv::Mat out;
  for (auto _ : state) {
    cv::GaussianBlur(image, out, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101);
    benchmark::DoNotOptimize(out.data);
  }
  set_items(state, image.total());
}
BENCHMARK(gaussian_q8_ours)->Name("gaussian_q8/ours");
BENCHMARK(gaussian_q8_cv)->Name("gaussian_q8/cv::GaussianBlur");

template <class Policy>
void describe_ours(benchmark::State& state) {
  const Inputs& in = inputs();
  const Policy policy;
  typename Policy::LevelData data;
  std::vector<affine_orb::BinaryDescriptor<Policy::kBits>> out(in.level0.size());
  for (auto _ : state) {
    policy.prepare(in.image, in.level0_points, data);
    for (std::size_t i = 0; i < in.level0.size(); ++i) {
      out[i] = policy.describe(data, in.level0_points[i], in.level0[i].angle * static_cast<float>(CV_PI / 180.0));
    }
    benchmark::DoNotOptimize(out.data());
  }
  set_items(state, in.level0.size());
}
void describe_cv(benchmark::State& state, const cv::Ptr<cv::Feature2D>& peer, float size) {
  const Inputs& in = inputs();
  std::vector<cv::KeyPoint> keypoints = in.level0;
  for (cv::KeyPoint& kp : keypoints) kp.size = size;
  cv::Mat descriptors;
  for (auto _ : state) {
    std::vector<cv::KeyPoint> kps = keypoints;
    peer->compute(in.image, kps, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  set_items(state, in.level0.size());
}
BENCHMARK_TEMPLATE(describe_ours, affine_orb::Rbrief)->Name("rbrief/ours");
BENCHMARK_CAPTURE(describe_cv, orb, cv::ORB::create(kPlainFeatures, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE), 31.0f)
    ->Name("rbrief/cv::ORB::compute");
BENCHMARK_TEMPLATE(describe_ours, affine_orb::Brisk)->Name("brisk/ours");
BENCHMARK_CAPTURE(describe_cv, brisk, cv::BRISK::create(), 12.0f)->Name("brisk/cv::BRISK::compute");

// ---- quadtree
void quadtree_ours(benchmark::State& state) {
  const Inputs& in = inputs();
  const cv::Rect2f region(0.0f, 0.0f, static_cast<float>(in.image.cols), static_cast<float>(in.image.rows));
  affine_orb::QuadtreeWorkspace work;
  std::vector<int> kept;
  for (auto _ : state) {
    affine_orb::distribute_quadtree(in.corners, in.corner_scores, region, kPlainFeatures, work, kept);
    benchmark::DoNotOptimize(kept.data());
  }
  set_items(state, in.corners.size());
}
BENCHMARK(quadtree_ours)->Name("quadtree/ours");

// ---- view rendering
affine_orb::AffineView bench_view(const cv::Mat& image) { return affine_orb::make_view(2.0, 36.0, image.size()); }
void view_render_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const affine_orb::AffineViewOptions options;
  const affine_orb::ViewRenderer renderer(bench_view(image), options.antialias);
  cv::Mat scratch, out;
  for (auto _ : state) {
    renderer.render(image, nullptr, scratch, out);
    benchmark::DoNotOptimize(out.data);
  }
  set_items(state, image.total());
}
void view_render_cv(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const affine_orb::AffineViewOptions options;
  const affine_orb::AffineView view = bench_view(image);
  cv::Mat canvas, out;
  for (auto _ : state) {
    affine_orb::render_view_reference(image, view, options.antialias, canvas, out);
    benchmark::DoNotOptimize(out.data);
  }
  set_items(state, image.total());
}
BENCHMARK(view_render_ours)->Name("view_render/ours");
BENCHMARK(view_render_cv)->Name("view_render/cv::warpAffine+GaussianBlur+resize");

// ---- matching
void knn2_ours(benchmark::State& state) {
  const Inputs& in = inputs();
  const auto query = affine_orb::descriptors_from_mat<4>(in.orb1);
  const auto train = affine_orb::descriptors_from_mat<4>(in.orb3);
  for (auto _ : state) {
    const auto result = affine_orb::knn2(query, train);
    benchmark::DoNotOptimize(result.data());
  }
  set_items(state, query.size() * train.size());
}
void knn2_cv(benchmark::State& state) {
  const Inputs& in = inputs();
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> result;
  for (auto _ : state) {
    matcher.knnMatch(in.orb1, in.orb3, result, 2);
    benchmark::DoNotOptimize(result.data());
  }
  set_items(state, static_cast<std::size_t>(in.orb1.rows) * static_cast<std::size_t>(in.orb3.rows));
}
BENCHMARK(knn2_ours)->Name("knn2/ours");
BENCHMARK(knn2_cv)->Name("knn2/cv::BFMatcher");

// ---- model selection
void select_model_ours(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) {
    const affine_orb::ModelSelectionResult r = affine_orb::select_model(in.points1, in.points3);
    benchmark::DoNotOptimize(r.success);
  }
  set_items(state, in.points1.size());
}
void select_model_cv(benchmark::State& state) {
  const Inputs& in = inputs();
  for (auto _ : state) {
    cv::Mat h = cv::findHomography(in.points1, in.points3, cv::RANSAC, 3.0);
    cv::Mat f = cv::findFundamentalMat(in.points1, in.points3, cv::FM_RANSAC, 3.0, 0.99);
    benchmark::DoNotOptimize(h.data);
    benchmark::DoNotOptimize(f.data);
  }
  set_items(state, in.points1.size());
}
BENCHMARK(select_model_ours)->Name("select_model/ours")->Unit(benchmark::kMillisecond);
BENCHMARK(select_model_cv)->Name("select_model/cv::findHomography+findFundamentalMat")->Unit(benchmark::kMillisecond);

// ---- whole extractions, for scale
void extract_plain_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  affine_orb::ExtractorOptions options;
  options.features = kPlainFeatures;
  options.views.max_tilt = 1.0;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image).size());
}
void extract_plain_cv(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(kPlainFeatures, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    orb->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}
void extract_affine_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  affine_orb::ExtractorOptions options;
  options.features = kPlainFeatures;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image).size());
}
void extract_affine_cv(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  constexpr int kViews = 18;
  const cv::Ptr<cv::Feature2D> peer =
      cv::AffineFeature::create(cv::ORB::create(2 * kPlainFeatures / kViews + 1), 3, 0, std::sqrt(2.0f), 72.0f);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    peer->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
}
BENCHMARK(extract_plain_ours)->Name("extract_plain/ours")->Unit(benchmark::kMillisecond);
BENCHMARK(extract_plain_cv)->Name("extract_plain/cv::ORB")->Unit(benchmark::kMillisecond);
BENCHMARK(extract_affine_ours)->Name("extract_affine/ours")->Unit(benchmark::kMillisecond);
BENCHMARK(extract_affine_cv)->Name("extract_affine/cv::AffineFeature(ORB)")->Unit(benchmark::kMillisecond);

// ---- a fork's own keypoints (ExtractorOptions::image_keypoints) against the fork's ORBextractor,
// where it was found (cmake/stock_extractors.cmake): the cell FAST, the octree, the whole extraction
void fork_cells_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const affine_orb::detail::ForkCells cells(image.size(), 30);
  affine_orb::detail::ForkImageWork work;
  for (auto _ : state) {
    affine_orb::detail::detect_in_fork_cells(image, cells, kThreshold, 7, work.score_storage, work.maxima, work.points,
                                             work.responses);
    benchmark::DoNotOptimize(work.points.data());
  }
  set_items(state, image.total());
}
void fork_octree_ours(benchmark::State& state) {
  const cv::Mat& image = inputs().image;
  const affine_orb::detail::ForkCells cells(image.size(), 30);
  affine_orb::detail::ForkImageWork work;
  affine_orb::detail::detect_in_fork_cells(image, cells, kThreshold, 7, work.score_storage, work.maxima, work.points,
                                           work.responses);
  for (auto _ : state) {
    affine_orb::detail::distribute_octree(work.points, work.responses, cells.width, cells.height, 217,
                                          affine_orb::detail::OctreeTieOrder::kCreation, work.octree, work.kept);
    benchmark::DoNotOptimize(work.kept.data());
  }
  set_items(state, work.points.size());
}
BENCHMARK(fork_cells_ours)->Name("fork_cells/ours");
BENCHMARK(fork_octree_ours)->Name("fork_octree/ours");
#if AFFINE_ORB_HAVE_STOCK
void extract_fork_ours(benchmark::State& state, affine_orb::ImageKeypoints keypoints) {
  const cv::Mat& image = inputs().image;
  affine_orb::ExtractorOptions options;
  options.features = kPlainFeatures;
  options.views.max_tilt = 1.0;
  options.image_keypoints = keypoints;
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image).size());
}
void extract_fork_stock(benchmark::State& state, affine_orb::stock::Fork fork) {
  const cv::Mat& image = inputs().image;
  affine_orb::stock::StockExtractor extractor(fork, kPlainFeatures, 1.2f, 8, kThreshold, 7);
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image).keypoints.size());
}
BENCHMARK_CAPTURE(extract_fork_ours, orbslam2, affine_orb::ImageKeypoints{affine_orb::OrbSlam2Keypoints{}})
    ->Name("extract_orbslam2/ours")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(extract_fork_stock, orbslam2, affine_orb::stock::Fork::kOrbSlam2)
    ->Name("extract_orbslam2/ORB_SLAM2::ORBextractor")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(extract_fork_ours, orbslam3, affine_orb::ImageKeypoints{affine_orb::OrbSlam3Keypoints{}})
    ->Name("extract_orbslam3/ours")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(extract_fork_stock, orbslam3, affine_orb::stock::Fork::kOrbSlam3)
    ->Name("extract_orbslam3/ORB_SLAM3::ORBextractor")
    ->Unit(benchmark::kMillisecond);
#endif

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("affine_orb SIMD path", affine_orb::detail::simd_path());
  inputs();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
