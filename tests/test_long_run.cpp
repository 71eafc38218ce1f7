// Long run: 1000 frames through one extractor with flat memory, and no allocation
// per frame once the workspace has grown. The workspace is reused across frames, so once the first
// frames have sized it the resident set must stop growing and only the returned Features allocate.
// Not run under AddressSanitizer, whose quarantine holds freed memory on purpose.
#include <doctest/doctest.h>

#include <unistd.h>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <new>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "test_data.hpp"

namespace {

/// Calls of the global operator new (every std::vector and std::string buffer) in this program.
std::atomic<long> g_new_calls{0};

/// Counts cv::Mat buffer allocations (cv::Mat::create() uses the default MatAllocator, not
/// operator new), delegating to OpenCV's standard allocator.
class CountingMatAllocator : public cv::MatAllocator {
 public:
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, size_t* step, cv::AccessFlag flags,
                         cv::UMatUsageFlags usage) const override {
    ++calls;
    return base->allocate(dims, sizes, type, data, step, flags, usage);
  }
  bool allocate(cv::UMatData* data, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override {
    return base->allocate(data, flags, usage);
  }
  void deallocate(cv::UMatData* data) const override { base->deallocate(data); }
  cv::MatAllocator* base = cv::Mat::getDefaultAllocator();
  mutable std::atomic<long> calls{0};
};

/// Resident set size in KiB (Linux /proc/self/statm, field 2, in pages).
long resident_kib() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

}  // namespace

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

TEST_CASE("after one pass over the frames, extract() allocates only the three vectors it returns") {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 10; ++i) frames.push_back(affine_orb::test::panning_frame(i, cv::Size(640, 330)));
  CountingMatAllocator mats;
  cv::MatAllocator* const previous = cv::Mat::getDefaultAllocator();
  cv::Mat::setDefaultAllocator(&mats);
  // One pass to size the buffers, then every frame again: the output's vectors and nothing else.
  const auto check_flat = [&](const affine_orb::ExtractorOptions& options, std::size_t expected_size) {
    affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
    for (const cv::Mat& frame : frames) extractor.extract(frame);
    for (const cv::Mat& frame : frames) {
      const long news = g_new_calls;
      const long mat_buffers = mats.calls;
      const auto features = extractor.extract(frame);
      CHECK(g_new_calls - news == 3);  // keypoints, descriptors, views
      CHECK(mats.calls - mat_buffers == 0);
      if (expected_size > 0) CHECK(features.size() == expected_size);
    }
  };
  for (const double max_tilt : {1.0, 2.0 * std::sqrt(2.0)}) {
    for (const auto spreading : {affine_orb::Spreading::kQuadtree, affine_orb::Spreading::kStrongest}) {
      CAPTURE(max_tilt);
      affine_orb::ExtractorOptions options;
      options.features = 1000;
      options.views.max_tilt = max_tilt;
      options.spreading = spreading;
      check_flat(options, max_tilt > 1.0 ? 2000u : 1000u);  // the views add as many (additive budget)
    }
  }
  // A fork's own keypoints: its pyramid and cell FAST write into kept buffers too (its octree
  // ends a level within a few nodes of its budget, stella's grid keeps what its cells hold, so the
  // count is not checked here); stella's rectangle mask is built for the first frame only.
  affine_orb::StellaVslamKeypoints masked_stella;
  masked_stella.mask_rectangles = {{0.0f, 1.0f, 0.8f, 1.0f}};
  for (const affine_orb::ImageKeypoints& fork :
       {affine_orb::ImageKeypoints{affine_orb::OrbSlam2Keypoints{}},
        affine_orb::ImageKeypoints{affine_orb::OrbSlam3Keypoints{}},
        affine_orb::ImageKeypoints{affine_orb::StellaVslamKeypoints{}}, affine_orb::ImageKeypoints{masked_stella}}) {
    affine_orb::ExtractorOptions options;
    options.features = 1000;
    options.views.max_tilt = 1.0;
    options.image_keypoints = fork;
    check_flat(options, 0);
  }
  cv::Mat::setDefaultAllocator(previous);
}

TEST_CASE("1000 frames through one extractor: resident memory stays flat") {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 20; ++i) frames.push_back(affine_orb::test::panning_frame(i, cv::Size(640, 330)));
  affine_orb::ExtractorOptions options;
  options.features = 1000;
  options.views.max_tilt = 1.0;  // plain, so that 1000 frames take seconds
  affine_orb::Extractor<affine_orb::Rbrief> extractor(options);
  affine_orb::ExtractorOptions affine = options;
  affine.views.max_tilt = 2.0;  // 10 views
  affine.threads = 2;
  affine_orb::Extractor<affine_orb::Rbrief> affine_extractor(affine);

  long after_warm_up = 0;
  long peak = 0;
  for (int frame = 0; frame < 1000; ++frame) {
    const cv::Mat& image = frames[static_cast<std::size_t>(frame % 20)];
    CHECK(extractor.extract(image).size() == 1000);
    if (frame % 10 == 0) CHECK(affine_extractor.extract(image).size() == 2000);  // 1000 + 1000 from the views
    if (frame == 100) after_warm_up = resident_kib();
    if (frame > 100) peak = std::max(peak, resident_kib());
  }
  MESSAGE("resident after 100 frames: " << after_warm_up << " KiB, peak over frames 101-999: " << peak << " KiB");
  // A leak of even one small buffer per frame (a keypoint vector, 24 KiB) would add about 20 MiB.
  CHECK(peak - after_warm_up < 4096);
}
