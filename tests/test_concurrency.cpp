// Concurrency: many extractor instances used from several threads at once give exactly
// the results they give one after the other; an instance's own view threads do not change its
// output. One Extractor instance is not shared between threads (its documentation says so: it
// owns a workspace); separate instances share nothing. Also run under ThreadSanitizer.
#include <doctest/doctest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/detail/worker_pool.hpp"
#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "test_data.hpp"

namespace {

template <int Bits>
bool same(const affine_orb::Features<Bits>& a, const affine_orb::Features<Bits>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.keypoints[i].pt != b.keypoints[i].pt || a.keypoints[i].angle != b.keypoints[i].angle ||
        a.keypoints[i].octave != b.keypoints[i].octave || a.descriptors[i] != b.descriptors[i] ||
        a.views[i] != b.views[i]) {
      return false;
    }
  }
  return true;
}

affine_orb::ExtractorOptions options_for(int index) {
  affine_orb::ExtractorOptions options;
  options.features = 500;
  options.views.max_tilt = index % 2 ? 2.0 : 1.0;  // mixes plain and affine instances
  options.threads = 1 + index % 3;
  return options;
}

}  // namespace

TEST_CASE("extractor instances in several threads at once equal the serial results") {
  // Small crops of real frames keep the run short, also under ThreadSanitizer.
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) images.push_back(affine_orb::test::panning_frame(i * 10, cv::Size(400, 300)));
  const int workers = 4;
  const int rounds = 3;
  std::vector<std::vector<affine_orb::Features<256>>> serial(workers);
  for (int w = 0; w < workers; ++w) {
    affine_orb::Extractor<affine_orb::Rbrief> extractor(options_for(w));
    for (int r = 0; r < rounds; ++r)
      serial[static_cast<std::size_t>(w)].push_back(extractor.extract(images[static_cast<std::size_t>((w + r) % 4)]));
  }
  std::vector<std::vector<affine_orb::Features<256>>> parallel(workers);
  std::vector<std::thread> threads;
  for (int w = 0; w < workers; ++w) {
    threads.emplace_back([&, w] {
      affine_orb::Extractor<affine_orb::Rbrief> extractor(options_for(w));
      for (int r = 0; r < rounds; ++r) {
        parallel[static_cast<std::size_t>(w)].push_back(
            extractor.extract(images[static_cast<std::size_t>((w + r) % 4)]));
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int w = 0; w < workers; ++w) {
    for (int r = 0; r < rounds; ++r) {
      CAPTURE(w);
      CAPTURE(r);
      CHECK(same(serial[static_cast<std::size_t>(w)][static_cast<std::size_t>(r)],
                 parallel[static_cast<std::size_t>(w)][static_cast<std::size_t>(r)]));
      // 500 of the image, and as many again from the views of the affine instances (odd w).
      CHECK(serial[static_cast<std::size_t>(w)][static_cast<std::size_t>(r)].size() == (w % 2 ? 1000u : 500u));
    }
  }
}

TEST_CASE("a const descriptor policy may be shared by threads that have their own level data") {
  const cv::Mat image = affine_orb::test::textured_photo();
  const affine_orb::Brisk brisk;
  const std::vector<cv::Point2f> points = {{100, 100}, {200, 150}, {300, 300}, {400, 250}, {500, 400}};
  std::vector<affine_orb::BinaryDescriptor<512>> reference;
  {
    affine_orb::Brisk::LevelData data;
    brisk.prepare(image, data);
    for (const auto& p : points) reference.push_back(brisk.describe(data, p, brisk.orientation(data, p)));
  }
  std::vector<int> mismatches(3, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      affine_orb::Brisk::LevelData data;
      brisk.prepare(image, data);
      for (int round = 0; round < 20; ++round) {
        for (std::size_t i = 0; i < points.size(); ++i) {
          mismatches[static_cast<std::size_t>(t)] +=
              brisk.describe(data, points[i], brisk.orientation(data, points[i])) != reference[i];
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int m : mismatches) CHECK(m == 0);
}

TEST_CASE("the worker pool runs every index exactly once, reports worker numbers in range and rethrows") {
  for (int threads : {1, 2, 3, 8}) {
    affine_orb::detail::WorkerPool pool(threads);
    CHECK(pool.threads() == threads);
    for (int n : {0, 1, 2, 7, 100, 1000}) {
      std::vector<std::atomic<int>> calls(static_cast<std::size_t>(n));
      std::atomic<int> bad_worker{0};
      auto fn = [&](int i, int w) {
        ++calls[static_cast<std::size_t>(i)];
        if (w < 0 || w >= threads) ++bad_worker;
      };
      pool.run(n, fn);
      for (const std::atomic<int>& c : calls) CHECK(c == 1);
      CHECK(bad_worker == 0);
    }
    // An exception in any call reaches the caller; the pool stays usable.
    auto throwing = [](int i, int) {
      if (i == 37) throw std::runtime_error("call 37");
    };
    CHECK_THROWS_WITH_AS(pool.run(100, throwing), "call 37", std::runtime_error);
    std::atomic<int> total{0};
    auto count = [&](int, int) { ++total; };
    pool.run(50, count);
    CHECK(total == 50);
  }
}
