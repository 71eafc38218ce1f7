// Long run (issue 8): 1000 frames through one extractor with flat memory. The workspace is reused
// across frames, so once the first frames have sized it the resident set must stop growing.
// Not run under AddressSanitizer, whose quarantine holds freed memory on purpose.
#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <unistd.h>

#include <opencv2/core.hpp>

#include "affine_orb/extractor.hpp"
#include "affine_orb/rbrief.hpp"
#include "test_data.hpp"

namespace {

/// Resident set size in KiB (Linux /proc/self/statm, field 2, in pages).
long resident_kib() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

}  // namespace

TEST_CASE("1000 frames through one extractor: resident memory stays flat") {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 20; ++i) frames.push_back(affine_orb::test::kitti_frame(i)(cv::Rect(200, 20, 640, 330)).clone());
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
    if (frame % 10 == 0) CHECK(affine_extractor.extract(image).size() == 1000);
    if (frame == 100) after_warm_up = resident_kib();
    if (frame > 100) peak = std::max(peak, resident_kib());
  }
  MESSAGE("resident after 100 frames: " << after_warm_up << " KiB, peak over frames 101-999: " << peak << " KiB");
  // A leak of even one small buffer per frame (a keypoint vector, 24 KiB) would add about 20 MiB.
  CHECK(peak - after_warm_up < 4096);
}
