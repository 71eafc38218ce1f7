// Brute-force k = 2 Hamming matching: affine_orb::knn2 against cv::BFMatcher(NORM_HAMMING).knnMatch
// with k = 2, side by side and interleaved in one run, on
//   1. 2000 x 2000 random 256-bit descriptors,
//   2. real ORB descriptors: cv::ORB (2000 features) on Oxford graf img1 and img3.
// Prints a Markdown table (the README's): the median time of each over the runs, the ratio ours /
// peer, and for how many queries the two agree on the nearest and second-nearest distance.
//
// OpenCV's matcher runs on its parallel framework (all cores by default); it is also timed with
// cv::setNumThreads(1) for a single-thread comparison. affine_orb's knn2 is single-threaded.
//
// Usage: bench_matcher [runs (default 21)] [data dir (default the configured AFFINE_ORB_DATA_DIR)]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "affine_orb/core/detail/simd.hpp"
#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/matcher.hpp"
#include "bench_common.hpp"

namespace {

using affine_orb::bench::median;
using affine_orb::bench::milliseconds;
using Descriptors = std::vector<affine_orb::BinaryDescriptor<256>>;

Descriptors from_mat(const cv::Mat& mat) {
  Descriptors d(static_cast<std::size_t>(mat.rows));
  for (int r = 0; r < mat.rows; ++r) std::memcpy(d[static_cast<std::size_t>(r)].data(), mat.ptr(r), 32);
  return d;
}

void run(const char* name, const cv::Mat& query_mat, const cv::Mat& train_mat, int runs) {
  const Descriptors query = from_mat(query_mat);
  const Descriptors train = from_mat(train_mat);
  const int default_threads = cv::getNumThreads();
  cv::BFMatcher peer(cv::NORM_HAMMING);
  std::vector<double> ours_ms;
  std::vector<double> peer_ms;
  std::vector<double> peer1_ms;
  std::vector<affine_orb::KnnMatch> ours;
  std::vector<std::vector<cv::DMatch>> theirs;
  for (int r = 0; r < runs; ++r) {
    ours_ms.push_back(milliseconds([&] { ours = affine_orb::knn2(query, train); }));
    cv::setNumThreads(default_threads);
    peer_ms.push_back(milliseconds([&] { peer.knnMatch(query_mat, train_mat, theirs, 2); }));
    cv::setNumThreads(1);
    peer1_ms.push_back(milliseconds([&] { peer.knnMatch(query_mat, train_mat, theirs, 2); }));
    cv::setNumThreads(default_threads);
  }
  int nearest_agree = 0;
  int second_agree = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    const auto& t = theirs[i];
    if (!t.empty() && ours[i].best.distance == static_cast<int>(t[0].distance)) ++nearest_agree;
    if (t.size() >= 2 && ours[i].count == 2 && ours[i].second.distance == static_cast<int>(t[1].distance)) {
      ++second_agree;
    }
  }
  const double ours_median = median(ours_ms);
  const double peer_median = median(peer_ms);
  const double peer1_median = median(peer1_ms);
  std::printf("| %s, %zu x %zu | %.3f | %.3f | %.3f | %.3f | %.3f | %d / %d of %zu |\n", name, query.size(),
              train.size(), ours_median, peer1_median, peer_median, ours_median / peer1_median,
              ours_median / peer_median, nearest_agree, second_agree, ours.size());
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 21;
  const std::string data_dir = argc > 2 ? argv[2] : affine_orb::bench::data_dir();
  const std::string search = std::string("bit-sliced search, ") +
                             (AFFINE_ORB_KNN2_LANES256 && affine_orb::detail::cpu_has_avx2() ? "256" : "128") +
                             "-bit lanes";
  std::printf(
      "knn2: %s; hardware popcount in hamming_distance: %s; extraction kernels: %s; medians of %d interleaved "
      "runs\n\n",
      search.c_str(), AFFINE_ORB_HARDWARE_POPCOUNT ? "yes" : "no", affine_orb::detail::simd_path(), runs);
  std::printf(
      "| k = 2 Hamming matching | affine_orb::knn2, 1 thread, ms | cv::BFMatcher knnMatch, 1 thread, ms | the same, %d "
      "threads, ms | ours / peer, 1 thread | ours / peer, %d threads | nearest / second distances equal |\n"
      "|---|---:|---:|---:|---:|---:|---:|\n",
      cv::getNumThreads(), cv::getNumThreads());

  std::mt19937_64 rng(2024);
  cv::Mat random_query(2000, 32, CV_8U);
  cv::Mat random_train(2000, 32, CV_8U);
  for (cv::Mat* m : {&random_query, &random_train}) {
    for (int r = 0; r < m->rows; ++r) {
      for (int c = 0; c < m->cols; ++c) m->at<unsigned char>(r, c) = static_cast<unsigned char>(rng() & 0xff);
    }
  }
  run("random 256-bit", random_query, random_train, runs);

  const std::string graf = data_dir + "/oxford/graf/";
  const cv::Mat img1 = affine_orb::bench::read_gray_or_exit(graf + "img1.png");
  const cv::Mat img3 = affine_orb::bench::read_gray_or_exit(graf + "img3.png");
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(2000);
  std::vector<cv::KeyPoint> keypoints1;
  std::vector<cv::KeyPoint> keypoints3;
  cv::Mat descriptors1;
  cv::Mat descriptors3;
  orb->detectAndCompute(img1, cv::noArray(), keypoints1, descriptors1);
  orb->detectAndCompute(img3, cv::noArray(), keypoints3, descriptors3);
  run("cv::ORB graf img1 vs img3", descriptors1, descriptors3, runs);
  return 0;
}
