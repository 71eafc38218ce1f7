// bench_extract [--rounds N]: plain (untilted) extraction at 640x480 (the graf1 photo resized),
// single thread, side by side with the peers in one run:
//   ours rBRIEF (1000 features)  vs cv::ORB (1000 features, 8 levels, 1.2, FAST score as ours)
//   ours BRISK  (1000 features)  vs cv::BRISK (detect + compute)
//   description only, same keypoints: our BRISK vs cv::BRISK::compute
// and checks that our rBRIEF bits equal cv::ORB::compute on our level-0 keypoints. Prints a Markdown
// table (the README's).
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"

namespace {

/// Plain extraction of 1000 features: the options of both our extractors.
affine_orb::ExtractorOptions plain_options() {
  affine_orb::ExtractorOptions options;
  options.features = 1000;
  options.views.max_tilt = 1.0;
  return options;
}

/// Everything the timed methods run and what they count, kept alive across the rounds.
struct Contenders {
  explicit Contenders(const cv::Mat& input) : image(input) {
    // Keypoints for the description-only comparison: our BRISK keypoints of level 0 (size set to
    // cv::BRISK's pattern scale 1 for a fair comparison: cv::BRISK picks its pattern from the size).
    for (const auto& kp : brisk.extract(image).keypoints) {
      if (kp.octave == 0) level0.push_back(kp);
    }
    brisk_out.resize(level0.size());
  }
  cv::Mat image;
  affine_orb::Extractor<affine_orb::Rbrief> rbrief{plain_options()};
  affine_orb::Extractor<affine_orb::Brisk> brisk{plain_options()};
  cv::Ptr<cv::ORB> orb = cv::ORB::create(1000, 1.2f, 8, 31, 0, 2, cv::ORB::FAST_SCORE);
  cv::Ptr<cv::BRISK> cv_brisk = cv::BRISK::create();
  std::vector<cv::KeyPoint> level0;
  affine_orb::Brisk::LevelData level_data;
  std::vector<affine_orb::BinaryDescriptor<512>> brisk_out;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  /// Keypoints each method gave in its last run, in the order of the methods.
  std::size_t counts[6] = {};
};

/// The timed methods in pairs, ours then its peer: extraction with rBRIEF and cv::ORB, with BRISK
/// and cv::BRISK, then BRISK description alone on the same keypoints.
std::vector<affine_orb::bench::Method> timed_methods(Contenders& c) {
  const affine_orb::Brisk& policy = c.brisk.descriptor();
  return {
      {"ours rBRIEF extract", [&c] { c.counts[0] = c.rbrief.extract(c.image).size(); }, {}},
      {"cv::ORB extract",
       [&c] {
         c.orb->detectAndCompute(c.image, cv::noArray(), c.keypoints, c.descriptors);
         c.counts[1] = c.keypoints.size();
       },
       {}},
      {"ours BRISK extract", [&c] { c.counts[2] = c.brisk.extract(c.image).size(); }, {}},
      {"cv::BRISK extract",
       [&c] {
         c.cv_brisk->detectAndCompute(c.image, cv::noArray(), c.keypoints, c.descriptors);
         c.counts[3] = c.keypoints.size();
       },
       {}},
      {"ours BRISK describe",
       [&c, &policy] {
         policy.prepare(c.image, c.level_data);
         for (std::size_t i = 0; i < c.level0.size(); ++i) {
           const float angle = policy.orientation(c.level_data, c.level0[i].pt);
           c.brisk_out[i] = policy.describe(c.level_data, c.level0[i].pt, angle);
         }
         c.counts[4] = c.level0.size();
       },
       {}},
      {"cv::BRISK describe",
       [&c] {
         std::vector<cv::KeyPoint> kps = c.level0;
         c.cv_brisk->compute(c.image, kps, c.descriptors);
         c.counts[5] = c.level0.size();
       },
       {}},
  };
}

/// Prints the README's table: per method its keypoints, median time and, on our rows, the ratio
/// to the peer below it.
void print_timing(const std::vector<affine_orb::bench::Method>& methods, const Contenders& c, int rounds) {
  auto med = [&](std::size_t i) { return affine_orb::bench::median(methods[i].ms); };
  std::printf("Plain extraction, 640x480 (graf1 resized), single thread, medians of %d interleaved rounds\n\n", rounds);
  std::printf("| method | keypoints | median ms | ours / peer |\n|---|---:|---:|---:|\n");
  for (std::size_t i = 0; i < methods.size(); ++i) {
    char ratio[32] = "";
    if (i % 2 == 0) std::snprintf(ratio, sizeof(ratio), "%.2f", med(i) / med(i + 1));
    std::printf("| %s | %zu | %.3f | %s |\n", methods[i].name.c_str(), c.counts[i], med(i), ratio);
  }
  std::printf("\n");
}

/// Bit compatibility with ORB: cv::ORB::compute with our level-0 keypoints (angles provided) must
/// give our bits. Prints how many rows are identical of those cv::ORB keeps.
void print_bit_compatibility(Contenders& c) {
  const auto ours = c.rbrief.extract(c.image);
  std::vector<cv::KeyPoint> kps;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    if (ours.keypoints[i].octave == 0) {
      kps.push_back(ours.keypoints[i]);
      index.push_back(i);
    }
  }
  std::vector<cv::KeyPoint> computed = kps;
  cv::Mat descriptors;
  c.orb->detectAndCompute(c.image, cv::noArray(), computed, descriptors, true);
  const cv::Mat mine = affine_orb::descriptors_to_mat(ours.descriptors);
  std::size_t equal_rows = 0, compared = 0;
  for (std::size_t i = 0; i < computed.size(); ++i) {
    // cv::ORB may drop keypoints near its own border; match rows by position.
    for (std::size_t j = 0; j < kps.size(); ++j) {
      if (computed[i].pt == kps[j].pt) {
        ++compared;
        equal_rows += std::memcmp(descriptors.ptr(static_cast<int>(i)), mine.ptr(static_cast<int>(index[j])), 32) == 0;
        break;
      }
    }
  }
  // The other rows differ in a bit or two: cv::ORB smooths a ROI of its padded pyramid, and
  // OpenCV's GaussianBlur on a non-isolated ROI rounds differently by one grey level at about 3 % of
  // the pixels; ORB-SLAM2, whose vocabulary the rows must match, smooths a continuous copy as we do.
  std::printf("rBRIEF rows bit-identical to cv::ORB::compute on our level-0 keypoints: %zu of %zu\n", equal_rows,
              compared);
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 31;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--rounds") rounds = std::max(1, std::atoi(argv[i + 1]));
  }
  cv::setNumThreads(1);
  const std::string path = affine_orb::bench::data_dir() + "/oxford/graf/img1.png";
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    return 1;
  }
  cv::resize(image, image, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  Contenders contenders(image);
  std::vector<affine_orb::bench::Method> methods = timed_methods(contenders);
  affine_orb::bench::time_interleaved(methods, rounds);
  print_timing(methods, contenders, rounds);
  print_bit_compatibility(contenders);
  return 0;
}
