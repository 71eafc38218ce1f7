// feature_hash: one line per (configuration, image) with the number of features and a 64-bit
// FNV-1a hash of every byte of the output (keypoint fields, descriptors, view indices; for
// two-view matching the stages, matches, inlier flags and both models). Two builds that print the
// same lines give the same bytes: run it before and after a change that must not change the
// output (a refactoring, a SIMD path, a compiler flag) and diff the two outputs.
//
//   feature_hash [--data DIR] [--samples DIR] > hashes.txt
//
// The images are opencv-doc's graf pair and real frames of ../shared/data (Oxford boat and bikes,
// KITTI 00); a missing image is reported and skipped, so the two runs to compare must see the same
// data.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "affine_orb/affine_orb.hpp"
#include "bench_common.hpp"

namespace {

using affine_orb::Brisk;
using affine_orb::Extractor;
using affine_orb::ExtractorOptions;
using affine_orb::Rbrief;

/// FNV-1a, 64 bits, over raw bytes.
class Hash {
 public:
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      value_ ^= p[i];
      value_ *= 1099511628211ull;
    }
  }
  template <class... T>
  void value(const T&... v) {
    (bytes(&v, sizeof(v)), ...);
  }
  template <class T>
  void vector(const std::vector<T>& v) {
    value(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  std::uint64_t get() const { return value_; }

 private:
  std::uint64_t value_ = 14695981039346656037ull;
};

template <int Bits>
void add_features(Hash& hash, const affine_orb::Features<Bits>& f) {
  hash.value(f.size());
  for (const cv::KeyPoint& k : f.keypoints)
    hash.value(k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave, k.class_id);
  hash.vector(f.descriptors);
  hash.vector(f.views);
}

void print(const std::string& configuration, const std::string& image, std::size_t count, const Hash& hash) {
  std::printf("%-34s %-14s %6zu %016llx\n", configuration.c_str(), image.c_str(), count,
              static_cast<unsigned long long>(hash.get()));
}

struct Image {
  std::string name;
  cv::Mat pixels;
};

std::vector<Image> load_images(const std::string& data, const std::string& samples) {
  const std::vector<std::pair<std::string, std::string>> files = {
      {"graf1", samples + "/graf1.png"},
      {"graf3", samples + "/graf3.png"},
      {"boat1", data + "/oxford/boat/img1.png"},
      {"bikes1", data + "/oxford/bikes/img1.png"},
      {"kitti00_10", data + "/kitti00/image_0/000010.png"},
  };
  std::vector<Image> images;
  for (const auto& [name, path] : files) {
    cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (image.empty()) {
      std::fprintf(stderr, "feature_hash: cannot read %s, skipped\n", path.c_str());
      continue;
    }
    images.push_back({name, image});
  }
  return images;
}

/// A mask that forbids the image's left quarter and a central square: the mask path runs too.
cv::Mat test_mask(const cv::Mat& image) {
  cv::Mat mask(image.size(), CV_8U, cv::Scalar(255));
  mask.colRange(0, image.cols / 4).setTo(0);
  const int side = std::min(image.cols, image.rows) / 4;
  mask(cv::Rect(image.cols / 2 - side / 2, image.rows / 2 - side / 2, side, side)).setTo(0);
  return mask;
}

template <class Descriptor>
void hash_extraction(const std::string& name, const ExtractorOptions& options, const std::vector<Image>& images,
                     bool masked = false) {
  Extractor<Descriptor> extractor(options);
  for (const Image& image : images) {
    const cv::Mat mask = masked ? test_mask(image.pixels) : cv::Mat();
    Hash hash;
    const auto features = extractor.extract(image.pixels, mask);
    add_features(hash, features);
    print(name, image.name, features.size(), hash);
  }
}

/// Views on demand: extract_image() and ViewSession::extend() up to each default stage of TwoViewOptions.
void hash_stages(const std::vector<Image>& images) {
  const affine_orb::TwoViewOptions two_view;
  Extractor<Rbrief> extractor(two_view.extractor);
  for (const Image& image : images) {
    Hash hash;
    auto [all, session] = extractor.extract_image(image.pixels);
    add_features(hash, all);
    std::size_t count = all.size();
    for (const affine_orb::ViewStage& stage : two_view.stages) {
      const auto more = session.extend(
          stage.max_tilt, static_cast<int>(std::lround(stage.view_features * two_view.extractor.features)));
      add_features(hash, more);
      count += more.size();
    }
    print("stages (extract_image, extend)", image.name, count, hash);
  }
}

void add_model(Hash& hash, const affine_orb::ModelSelectionResult& model) {
  hash.value(model.success);
  hash.value(model.model);
  hash.value(model.homography_found);
  hash.bytes(model.homography.data(), sizeof(double) * 9);
  hash.vector(model.homography_inliers);
  hash.value(model.homography_score);
  hash.value(model.fundamental_found);
  hash.bytes(model.fundamental.data(), sizeof(double) * 9);
  hash.vector(model.fundamental_inliers);
  hash.value(model.fundamental_score);
  hash.value(model.parallax_inlier_count);
}

void hash_two_view(const std::string& data, const std::string& samples) {
  struct Pair {
    std::string name, first, second;
  };
  const std::vector<Pair> pairs = {
      {"graf1-3", samples + "/graf1.png", samples + "/graf3.png"},
      {"boat1-4", data + "/oxford/boat/img1.png", data + "/oxford/boat/img4.png"},
      {"graf1-5", data + "/oxford/graf/img1.png", data + "/oxford/graf/img5.png"},
      {"kitti00_0-10", data + "/kitti00/image_0/000000.png", data + "/kitti00/image_0/000010.png"},
  };
  for (const bool all_stages : {false, true}) {
    affine_orb::TwoViewOptions options;
    options.all_stages = all_stages;
    affine_orb::TwoViewMatcher<Rbrief> matcher(options);
    for (const Pair& pair : pairs) {
      const cv::Mat a = cv::imread(pair.first, cv::IMREAD_GRAYSCALE);
      const cv::Mat b = cv::imread(pair.second, cv::IMREAD_GRAYSCALE);
      if (a.empty() || b.empty()) {
        std::fprintf(stderr, "feature_hash: cannot read pair %s, skipped\n", pair.name.c_str());
        continue;
      }
      const auto result = matcher.match(a, b);
      Hash hash;
      hash.value(result.verified, result.stage);
      add_features(hash, result.features1);
      add_features(hash, result.features2);
      for (const affine_orb::Match& m : result.matches) hash.value(m.query, m.train, m.distance);
      hash.vector(result.inliers);
      add_model(hash, result.model);
      for (const auto& s : result.stages)
        hash.value(s.max_tilt, s.keypoints1, s.keypoints2, s.matches, s.inliers, s.model);
      print(all_stages ? "two-view, all stages" : "two-view, default", pair.name, result.matches.size(), hash);

      // Every selection rule on the same matches, with and without octaves.
      const affine_orb::MatchedPoints points =
          affine_orb::matched_points(result.features1.keypoints, result.features2.keypoints, result.matches);
      const std::vector<cv::Point2f>& p1 = points.points1;
      const std::vector<cv::Point2f>& p2 = points.points2;
      std::vector<int> o1, o2;
      for (const affine_orb::Match& m : result.matches) {
        o1.push_back(result.features1.keypoints[static_cast<std::size_t>(m.query)].octave);
        o2.push_back(result.features2.keypoints[static_cast<std::size_t>(m.train)].octave);
      }
      if (all_stages || p1.size() < 8) continue;
      for (const auto rule : {affine_orb::SelectionRule::kScoreRatio, affine_orb::SelectionRule::kGric,
                              affine_orb::SelectionRule::kInlierRatio, affine_orb::SelectionRule::kPlaneParallax}) {
        affine_orb::ModelSelectionOptions model_options;
        model_options.rule = rule;
        Hash plain_hash;
        add_model(plain_hash, affine_orb::select_model(p1, p2, model_options));
        print("select_model rule " + std::to_string(static_cast<int>(rule)), pair.name, p1.size(), plain_hash);
        Hash octave_hash;
        add_model(octave_hash, affine_orb::select_model(p1, p2, o1, o2, model_options));
        print("select_model rule " + std::to_string(static_cast<int>(rule)) + ", octaves", pair.name, p1.size(),
              octave_hash);
      }
    }
  }
}

/// Every extraction the hashes cover: plain, affine and each fork's keypoints, rBRIEF and BRISK.
void hash_extractions(const std::vector<Image>& images) {
  ExtractorOptions plain;
  plain.views.max_tilt = 1.0;
  hash_extraction<Rbrief>("plain 1000, quadtree", plain, images);
  hash_extraction<Rbrief>("plain 1000, quadtree, masked", plain, images, true);
  ExtractorOptions strongest = plain;
  strongest.features = 2000;
  strongest.spreading = affine_orb::Spreading::kStrongest;
  hash_extraction<Rbrief>("plain 2000, strongest", strongest, images);

  const ExtractorOptions affine;
  hash_extraction<Rbrief>("affine default", affine, images);
  hash_extraction<Rbrief>("affine default, masked", affine, images, true);
  ExtractorOptions threaded = affine;
  threaded.threads = 2;
  hash_extraction<Rbrief>("affine default, 2 threads", threaded, images);
  ExtractorOptions area = affine;
  area.view_budget = affine_orb::AreaSplitBudget{};
  hash_extraction<Rbrief>("affine area split", area, images);
  ExtractorOptions keep_all = affine;
  keep_all.merge_duplicates.reset();
  keep_all.spreading = affine_orb::Spreading::kStrongest;
  hash_extraction<Rbrief>("affine keep all, strongest", keep_all, images);
  ExtractorOptions snapped = affine;
  snapped.snap_to_corners = affine_orb::CornerSnapOptions{};
  hash_extraction<Rbrief>("affine snapped to corners", snapped, images);

  ExtractorOptions orbslam2 = plain;
  orbslam2.image_keypoints = affine_orb::OrbSlam2Keypoints{};
  hash_extraction<Rbrief>("ORB-SLAM2 keypoints 1000", orbslam2, images);
  hash_extraction<Rbrief>("ORB-SLAM2 keypoints 1000, masked", orbslam2, images, true);
  ExtractorOptions orbslam3 = orbslam2;
  orbslam3.image_keypoints = affine_orb::OrbSlam3Keypoints{};
  orbslam3.features = 5000;
  orbslam3.views.max_tilt = 2.83;
  hash_extraction<Rbrief>("ORB-SLAM3 keypoints 5000 + views", orbslam3, images);
  ExtractorOptions stella = plain;
  stella.image_keypoints = affine_orb::StellaVslamKeypoints{};
  hash_extraction<Rbrief>("stella_vslam keypoints 800", stella, images);
  hash_extraction<Rbrief>("stella_vslam keypoints 800, masked", stella, images, true);
  std::get<affine_orb::StellaVslamKeypoints>(stella.image_keypoints).mask_rectangles = {{0.0f, 1.0f, 0.8f, 1.0f}};
  stella.views.max_tilt = 2.83;
  hash_extraction<Rbrief>("stella_vslam 800, rect. + views", stella, images);
  hash_extraction<Brisk>("BRISK plain 1000", plain, images);
  hash_extraction<Brisk>("BRISK affine default", affine, images);
}

/// The data and samples folders: the defaults, or --data and --samples; nothing on a bad argument.
std::optional<std::pair<std::string, std::string>> parse_dirs(int argc, char** argv) {
  std::string data = affine_orb::bench::data_dir();
  std::string samples = affine_orb::bench::opencv_samples_dir();
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--data" && i + 1 < argc) {
      data = argv[++i];
    } else if (arg == "--samples" && i + 1 < argc) {
      samples = argv[++i];
    } else {
      return std::nullopt;
    }
  }
  return std::make_pair(data, samples);
}

}  // namespace

int main(int argc, char** argv) {
  const auto dirs = parse_dirs(argc, argv);
  if (!dirs) {
    std::fprintf(stderr, "usage: feature_hash [--data DIR] [--samples DIR]\n");
    return 2;
  }
  const auto& [data, samples] = *dirs;
  const std::vector<Image> images = load_images(data, samples);
  hash_extractions(images);
  hash_stages(images);
  hash_two_view(data, samples);
  return 0;
}
