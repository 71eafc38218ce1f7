// The Python module `affine_orb` (pybind11): Extractor, match and select_model over the C++
// library, with numpy arrays and cv2 objects at the boundary. No second implementation: every call
// forwards to the headers, so the bytes are the C++ extractor's.
//
// Conventions: images and masks are 2-D uint8 numpy arrays (any strides: a non-contiguous array is
// read in place when its rows are contiguous, copied otherwise); keypoints are cv2.KeyPoint;
// descriptors an N x 32 (rBRIEF) or N x 64 (BRISK) uint8 array, row i for keypoint i. The GIL is
// released while the library works. std::invalid_argument becomes ValueError (pybind11's
// translation); a wrong Python type TypeError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/descriptors/brisk.hpp"
#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/model_selection.hpp"
#include "affine_orb/matching/affine_matching.hpp"
#include "affine_orb/matching/matcher.hpp"
#include "affine_orb/two_view/two_view.hpp"
#include "affine_orb/version.hpp"

namespace py = pybind11;

namespace {

/// A cv::Mat header over a 2-D uint8 numpy array (no copy when each row is contiguous; a copy
/// otherwise, kept alive by `storage`).
cv::Mat as_gray(const py::handle& object, const char* what, py::array_t<std::uint8_t>& storage) {
  if (!py::isinstance<py::array>(object)) throw py::type_error(std::string(what) + " must be a numpy array");
  const py::array array = py::reinterpret_borrow<py::array>(object);
  if (!array.dtype().is(py::dtype::of<std::uint8_t>()))
    throw py::type_error(std::string(what) + " must have dtype uint8, got " +
                         py::str(array.dtype()).cast<std::string>());
  if (array.ndim() != 2)
    throw py::value_error(std::string(what) + " must be 2-D (a grey image), got " + std::to_string(array.ndim()) +
                          " dimensions");
  if (array.strides(1) == 1 && array.strides(0) >= array.shape(1)) {
    storage = py::reinterpret_borrow<py::array_t<std::uint8_t>>(array);
  } else {
    storage = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(array);
  }
  if (storage.shape(0) == 0 || storage.shape(1) == 0) return cv::Mat();
  return cv::Mat(static_cast<int>(storage.shape(0)), static_cast<int>(storage.shape(1)), CV_8UC1,
                 const_cast<std::uint8_t*>(storage.data()), static_cast<std::size_t>(storage.strides(0)));
}

template <std::size_t Words>
py::array_t<std::uint8_t> descriptor_array(const std::vector<std::array<std::uint64_t, Words>>& rows) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(8 * Words)});
  if (!rows.empty()) std::memcpy(out.mutable_data(), rows.data(), rows.size() * 8 * Words);
  return out;
}

py::list keypoint_list(const std::vector<cv::KeyPoint>& keypoints) {
  const py::object make = py::module_::import("cv2").attr("KeyPoint");
  py::list out(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    out[i] = make(k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave);
  }
  return out;
}

/// Descriptors from an N x (8k) uint8 array, as 64-bit words (Words per row).
template <std::size_t Words>
std::vector<std::array<std::uint64_t, Words>> descriptor_rows(const py::handle& object, const char* what) {
  py::array_t<std::uint8_t> storage;
  const cv::Mat mat = as_gray(object, what, storage);
  if (mat.empty()) return {};
  if (mat.cols != static_cast<int>(8 * Words))
    throw py::value_error(std::string(what) + " must have " + std::to_string(8 * Words) + " columns, got " +
                          std::to_string(mat.cols));
  std::vector<std::array<std::uint64_t, Words>> rows(static_cast<std::size_t>(mat.rows));
  for (int r = 0; r < mat.rows; ++r) std::memcpy(rows[static_cast<std::size_t>(r)].data(), mat.ptr(r), 8 * Words);
  return rows;
}

/// The SelectionRule named by `text` (its enumerator without the k, in snake case), or ValueError.
affine_orb::SelectionRule selection_rule(const std::string& text) {
  using affine_orb::SelectionRule;
  if (text == "plane_parallax") return SelectionRule::kPlaneParallax;
  if (text == "score_ratio") return SelectionRule::kScoreRatio;
  if (text == "gric") return SelectionRule::kGric;
  if (text == "inlier_ratio") return SelectionRule::kInlierRatio;
  throw py::value_error("rule must be \"plane_parallax\", \"score_ratio\", \"gric\" or \"inlier_ratio\", got \"" +
                        text + "\"");
}

std::vector<cv::Point2f> point_list(const py::handle& object, const char* what) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> array =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  if (!array || array.ndim() != 2 || array.shape(1) != 2)
    throw py::value_error(std::string(what) + " must be an N x 2 array of pixel coordinates");
  std::vector<cv::Point2f> points;
  for (py::ssize_t i = 0; i < array.shape(0); ++i)
    points.emplace_back(static_cast<float>(array.at(i, 0)), static_cast<float>(array.at(i, 1)));
  return points;
}

/// Emplaces into `holder`, a std::variant of a class template over Rbrief (index 0) and Brisk (index
/// 1), the alternative that `descriptor` names ("rbrief" or "brisk"), built from `options`;
/// ValueError for another name.
template <class Variant, class Options>
void emplace_descriptor(Variant& holder, const std::string& descriptor, const Options& options) {
  if (descriptor == "rbrief") {
    holder.template emplace<0>(options);
  } else if (descriptor == "brisk") {
    holder.template emplace<1>(options);
  } else {
    throw py::value_error("descriptor must be \"rbrief\" or \"brisk\", got \"" + descriptor + "\"");
  }
}

/// The Python Extractor: an affine_orb::Extractor of either descriptor. A mutex makes calls from
/// several Python threads take turns (the C++ extractor is not for two threads at once); it is
/// taken with the GIL released.
class PyExtractor {
 public:
  PyExtractor(const affine_orb::ExtractorOptions& options, const std::string& descriptor) : options_(options) {
    emplace_descriptor(extractor_, descriptor, options);
  }

  /// (keypoints, descriptors, views).
  py::tuple extract(const py::handle& image, const py::handle& mask) {
    py::array_t<std::uint8_t> image_storage;
    py::array_t<std::uint8_t> mask_storage;
    const cv::Mat frame = as_gray(image, "image", image_storage);
    cv::Mat mask_mat;
    if (!mask.is_none()) {
      mask_mat = as_gray(mask, "mask", mask_storage);
      if (mask_mat.empty()) throw py::value_error("mask must not be empty (pass None for no mask)");
    }
    return std::visit(
        [&](auto& extractor) {
          using Result = decltype(extractor.extract(frame, mask_mat));
          Result features;
          {
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);
            features = extractor.extract(frame, mask_mat);
          }
          py::array_t<int> views(static_cast<py::ssize_t>(features.views.size()));
          if (!features.views.empty())
            std::memcpy(views.mutable_data(), features.views.data(), features.views.size() * sizeof(int));
          return py::make_tuple(keypoint_list(features.keypoints), descriptor_array(features.descriptors), views);
        },
        extractor_);
  }

  py::tuple detect_and_compute(const py::handle& image, const py::handle& mask) {
    const py::tuple all = extract(image, mask);
    return py::make_tuple(all[0], all[1]);
  }

  int descriptor_size() const {
    return std::holds_alternative<affine_orb::Extractor<affine_orb::Rbrief>>(extractor_) ? 32 : 64;
  }
  const affine_orb::ExtractorOptions& options() const { return options_; }

 private:
  std::variant<affine_orb::Extractor<affine_orb::Rbrief>, affine_orb::Extractor<affine_orb::Brisk>> extractor_{
      std::in_place_index<0>};
  affine_orb::ExtractorOptions options_;
  std::mutex mutex_;
};

/// The enum value named by `text` among two, or ValueError naming the argument and both choices.
template <class Enum>
Enum one_of(const std::string& text, const char* argument, const char* first_name, Enum first, const char* second_name,
            Enum second) {
  if (text == first_name) return first;
  if (text == second_name) return second;
  throw py::value_error(std::string(argument) + " must be \"" + first_name + "\" or \"" + second_name + "\", got \"" +
                        text + "\"");
}

affine_orb::ExtractorOptions make_options(int features, double max_tilt, int threads, double view_features,
                                          const std::string& view_budget, const std::string& spreading,
                                          const std::string& duplicates, int levels, double scale_factor,
                                          int initial_threshold, int min_threshold, bool subpixel,
                                          bool carry_shortfalls) {
  affine_orb::ExtractorOptions o;
  o.features = features;
  o.views.max_tilt = max_tilt;
  o.threads = threads;
  if (one_of(view_budget, "view_budget", "additive", true, "area_split", false)) {
    affine_orb::AdditiveBudget additive;
    additive.view_features = view_features;
    o.view_budget = additive;
  } else {
    o.view_budget = affine_orb::AreaSplitBudget{};
  }
  o.spreading = one_of(spreading, "spreading", "quadtree", affine_orb::Spreading::kQuadtree, "strongest",
                       affine_orb::Spreading::kStrongest);
  if (!one_of(duplicates, "duplicates", "merge", true, "keep", false)) o.merge_duplicates.reset();
  o.pyramid.levels = levels;
  o.pyramid.scale_factor = scale_factor;
  o.detector.initial_threshold = initial_threshold;
  o.detector.min_threshold = min_threshold;
  o.subpixel = subpixel;
  o.carry_shortfalls = carry_shortfalls;
  o.check();
  return o;
}

/// A 3 x 3 float64 array of an Eigen matrix.
py::array_t<double> matrix_array(const Eigen::Matrix3d& e) {
  py::array_t<double> out({3, 3});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.mutable_at(i, j) = e(i, j);
  return out;
}

py::array_t<bool> flag_array(const std::vector<std::uint8_t>& v) {
  py::array_t<bool> out(static_cast<py::ssize_t>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) out.mutable_at(static_cast<py::ssize_t>(i)) = v[i] != 0;
  return out;
}

/// A TwoViewMatcher's result as the Python dict of TwoViewMatcher.match().
template <int kBits>
py::dict result_dict(const affine_orb::TwoViewResult<kBits>& r) {
  const auto views = [](const std::vector<int>& v) {
    py::array_t<int> out(static_cast<py::ssize_t>(v.size()));
    if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(int));
    return out;
  };
  const py::object make_match = py::module_::import("cv2").attr("DMatch");
  py::list matches(r.matches.size());
  for (std::size_t i = 0; i < r.matches.size(); ++i)
    matches[i] = make_match(r.matches[i].query, r.matches[i].train, static_cast<float>(r.matches[i].distance));
  py::list stages;
  for (const affine_orb::TwoViewStageReport& s : r.stages) {
    py::dict stage;
    stage["max_tilt"] = s.max_tilt;
    stage["keypoints1"] = s.keypoints1;
    stage["keypoints2"] = s.keypoints2;
    stage["matches"] = s.matches;
    stage["inliers"] = s.inliers;
    stage["homography_inlier_count"] = s.homography_inlier_count;
    stage["fundamental_inlier_count"] = s.fundamental_inlier_count;
    stage["model"] = affine_orb::model_name(s.model);
    stage["half_disagreement"] = s.half_disagreement ? py::object(py::float_(*s.half_disagreement)) : py::none();
    stage["log10_false_alarms"] = s.log10_false_alarms ? py::object(py::float_(*s.log10_false_alarms)) : py::none();
    stage["guided_rounds"] = s.guided_rounds;
    stage["aligned"] = s.aligned;
    stage["last_stage_search"] = s.last_stage_search;
    stage["failure"] = s.failure ? py::object(py::str(affine_orb::verification_failure_name(*s.failure))) : py::none();
    stage["extract_ms"] = s.extract_ms;
    stage["match_ms"] = s.match_ms;
    stage["verify_ms"] = s.verify_ms;
    stages.append(stage);
  }
  py::dict out;
  out["verified"] = r.verified;
  out["stage"] = r.stage;
  out["keypoints1"] = keypoint_list(r.features1.keypoints);
  out["descriptors1"] = descriptor_array(r.features1.descriptors);
  out["views1"] = views(r.features1.views);
  out["keypoints2"] = keypoint_list(r.features2.keypoints);
  out["descriptors2"] = descriptor_array(r.features2.descriptors);
  out["views2"] = views(r.features2.views);
  out["matches"] = matches;
  out["inliers"] = flag_array(r.inliers);
  py::array_t<float> points2({static_cast<py::ssize_t>(r.points2.size()), static_cast<py::ssize_t>(2)});
  for (std::size_t i = 0; i < r.points2.size(); ++i) {
    points2.mutable_at(static_cast<py::ssize_t>(i), 0) = r.points2[i].x;
    points2.mutable_at(static_cast<py::ssize_t>(i), 1) = r.points2[i].y;
  }
  out["points2"] = points2;
  out["model"] = affine_orb::model_name(r.model.model);
  out["homography"] = r.model.homography_found ? py::object(matrix_array(r.model.homography)) : py::none();
  out["fundamental"] = r.model.fundamental_found ? py::object(matrix_array(r.model.fundamental)) : py::none();
  out["stages"] = stages;
  return out;
}

/// The TwoViewOptions of the Python matcher's arguments (two_view_arguments()); ValueError for an
/// invalid value.
affine_orb::TwoViewOptions two_view_options(int features, double max_tilt,
                                            const std::optional<std::vector<std::pair<double, double>>>& stages,
                                            int min_inliers, std::optional<double> max_false_alarms,
                                            std::optional<double> min_inlier_ratio, int guided_rounds,
                                            std::optional<double> max_half_disagreement, bool align_correspondences,
                                            bool final_fit, bool last_stage_search, bool progressive_sampling,
                                            bool all_stages, const std::string& spreading, int threads) {
  affine_orb::TwoViewOptions options;
  options.extractor.features = features;
  options.extractor.views.max_tilt = max_tilt;
  options.extractor.threads = threads;
  options.extractor.spreading = one_of(spreading, "spreading", "quadtree", affine_orb::Spreading::kQuadtree,
                                       "strongest", affine_orb::Spreading::kStrongest);
  if (stages) {
    options.stages.clear();
    for (const auto& [tilt, view_features] : *stages) options.stages.push_back({tilt, view_features});
  } else {
    options.stages = affine_orb::stages_up_to(options.extractor.views);
  }
  options.min_inliers = min_inliers;
  options.max_false_alarms = max_false_alarms;
  options.min_inlier_ratio = min_inlier_ratio;
  if (guided_rounds == 0) {
    options.guided_matching.reset();
  } else {
    options.guided_matching->rounds = guided_rounds;
  }
  options.max_half_disagreement = max_half_disagreement;
  if (align_correspondences) options.align_correspondences = affine_orb::CorrespondenceAlignmentOptions{};
  if (!final_fit) options.final_fit.reset();
  if (!last_stage_search) options.last_stage_search.reset();
  options.model.ransac.progressive_sampling = progressive_sampling;
  options.all_stages = all_stages;
  options.check();
  return options;
}

/// The keyword arguments of TwoViewMatcher() and match_images() with their defaults, in
/// two_view_options()'s order with `descriptor` before `spreading`: one list for both.
auto two_view_arguments() {
  const affine_orb::TwoViewOptions d;
  return std::make_tuple(
      py::arg("features") = d.extractor.features, py::arg("max_tilt") = d.extractor.views.max_tilt,
      py::arg("stages") = py::none(), py::arg("min_inliers") = d.min_inliers,
      py::arg("max_false_alarms") = d.max_false_alarms, py::arg("min_inlier_ratio") = d.min_inlier_ratio,
      py::arg("guided_rounds") = d.guided_matching->rounds, py::arg("max_half_disagreement") = d.max_half_disagreement,
      py::arg("align_correspondences") = false, py::arg("final_fit") = d.final_fit.has_value(),
      py::arg("last_stage_search") = d.last_stage_search.has_value(),
      py::arg("progressive_sampling") = d.model.ransac.progressive_sampling, py::arg("all_stages") = d.all_stages,
      py::arg("descriptor") = "rbrief", py::arg("spreading") = "strongest", py::arg("threads") = d.extractor.threads);
}

/// The Python TwoViewMatcher: an affine_orb::TwoViewMatcher of either descriptor, which keeps its
/// extractors' buffers from call to call. A mutex makes calls from several Python threads take
/// turns (the C++ matcher is not for two threads at once); it is taken with the GIL released.
class PyTwoViewMatcher {
 public:
  PyTwoViewMatcher(const affine_orb::TwoViewOptions& options, const std::string& descriptor) {
    emplace_descriptor(matcher_, descriptor, options);
  }

  py::dict match(const py::handle& image1, const py::handle& image2, const py::handle& mask1, const py::handle& mask2) {
    py::array_t<std::uint8_t> s1, s2, s3, s4;
    const cv::Mat a = as_gray(image1, "image1", s1);
    const cv::Mat b = as_gray(image2, "image2", s2);
    const cv::Mat ma = mask1.is_none() ? cv::Mat() : as_gray(mask1, "mask1", s3);
    const cv::Mat mb = mask2.is_none() ? cv::Mat() : as_gray(mask2, "mask2", s4);
    return std::visit(
        [&](auto& matcher) {
          decltype(matcher.match(a, b, ma, mb)) r;
          {
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(mutex_);
            r = matcher.match(a, b, ma, mb);
          }
          return result_dict(r);
        },
        matcher_);
  }

  int descriptor_size() const {
    return std::holds_alternative<affine_orb::TwoViewMatcher<affine_orb::Rbrief>>(matcher_) ? 32 : 64;
  }

 private:
  std::variant<affine_orb::TwoViewMatcher<affine_orb::Rbrief>, affine_orb::TwoViewMatcher<affine_orb::Brisk>> matcher_{
      std::in_place_index<0>};
  std::mutex mutex_;
};

/// Extractor: keypoints and descriptors of one image.
void bind_extractor(py::module_& m) {
  const affine_orb::ExtractorOptions defaults;
  py::class_<PyExtractor>(m, "Extractor",
                          "Extracts keypoints and binary descriptors from grey images (affine_orb::Extractor).")
      .def(py::init([](int features, double max_tilt, const std::string& descriptor, int threads, double view_features,
                       const std::string& view_budget, const std::string& spreading, const std::string& duplicates,
                       int levels, double scale_factor, int initial_threshold, int min_threshold, bool subpixel,
                       bool carry_shortfalls) {
             return std::make_unique<PyExtractor>(
                 make_options(features, max_tilt, threads, view_features, view_budget, spreading, duplicates, levels,
                              scale_factor, initial_threshold, min_threshold, subpixel, carry_shortfalls),
                 descriptor);
           }),
           py::arg("features") = defaults.features, py::arg("max_tilt") = defaults.views.max_tilt,
           py::arg("descriptor") = "rbrief", py::arg("threads") = defaults.threads,
           py::arg("view_features") = defaults.additive_budget()->view_features, py::arg("view_budget") = "additive",
           py::arg("spreading") = "quadtree", py::arg("duplicates") = "merge",
           py::arg("levels") = defaults.pyramid.levels, py::arg("scale_factor") = defaults.pyramid.scale_factor,
           py::arg("initial_threshold") = defaults.detector.initial_threshold,
           py::arg("min_threshold") = defaults.detector.min_threshold, py::arg("subpixel") = defaults.subpixel,
           py::arg("carry_shortfalls") = defaults.carry_shortfalls,
           "Options as in affine_orb::ExtractorOptions (features = keypoints from the image; with max_tilt > 1 "
           "the 18 default views add view_features x features more; subpixel: positions at the vertex of the "
           "FAST score parabolas instead of whole level pixels as ORB's; carry_shortfalls=False: a pyramid "
           "level with fewer corners than its share keeps the shortfall, as ORB-SLAM's extractor does, instead "
           "of passing it to the other levels, so an image short of corners gives fewer than `features`). "
           "descriptor: \"rbrief\" (32 bytes) or \"brisk\" (64 bytes). Invalid values raise ValueError.")
      .def("detect_and_compute", &PyExtractor::detect_and_compute, py::arg("image"), py::arg("mask") = py::none(),
           "(keypoints, descriptors) of a 2-D uint8 image: a list of cv2.KeyPoint (original pixels) and an "
           "N x 32 (or 64) uint8 array, row i for keypoint i. mask: None or a 2-D uint8 array of the image size "
           "(non-zero = allowed).")
      .def("extract", &PyExtractor::extract, py::arg("image"), py::arg("mask") = py::none(),
           "(keypoints, descriptors, views): detect_and_compute() plus the index of the simulated view each "
           "keypoint was found in (0 = the image itself), an int32 array.")
      .def_property_readonly("descriptor_size", &PyExtractor::descriptor_size, "Bytes per descriptor row.")
      .def_property_readonly(
          "features", [](const PyExtractor& e) { return e.options().features; }, "Keypoints from the image.")
      .def_property_readonly(
          "max_tilt", [](const PyExtractor& e) { return e.options().views.max_tilt; }, "Largest simulated tilt.")
      .def_property_readonly(
          "threads", [](const PyExtractor& e) { return e.options().threads; }, "Worker threads.")
      .def_property_readonly(
          "carry_shortfalls", [](const PyExtractor& e) { return e.options().carry_shortfalls; },
          "Whether a level's shortfall of corners passes to the other levels.");
}

/// match(): Hamming matching of two descriptor arrays.
void bind_match(py::module_& m) {
  m.def(
      "match",
      [](const py::handle& descriptors1, const py::handle& descriptors2, float ratio, bool cross_check,
         std::optional<int> max_distance) {
        affine_orb::MatcherOptions options;
        options.ratio = ratio;
        options.cross_check = cross_check;
        if (max_distance) options.max_distance = *max_distance;
        options.check();
        py::array_t<std::uint8_t> s1, s2;
        const cv::Mat a = as_gray(descriptors1, "descriptors1", s1);
        const cv::Mat b = as_gray(descriptors2, "descriptors2", s2);
        std::vector<affine_orb::Match> matches;
        {
          py::gil_scoped_release release;
          matches = affine_orb::match(a, b, options);
        }
        const py::object make = py::module_::import("cv2").attr("DMatch");
        py::list out(matches.size());
        for (std::size_t i = 0; i < matches.size(); ++i)
          out[i] = make(matches[i].query, matches[i].train, static_cast<float>(matches[i].distance));
        return out;
      },
      py::arg("descriptors1"), py::arg("descriptors2"), py::arg("ratio") = affine_orb::MatcherOptions{}.ratio,
      py::arg("cross_check") = false, py::arg("max_distance") = py::none(),
      "Nearest-neighbour Hamming matches (affine_orb::match) of two uint8 descriptor arrays with the same number "
      "of columns, as a list of cv2.DMatch (queryIdx, trainIdx, distance in bits): Lowe's ratio test, optional "
      "mutual check and maximum distance.");
}

/// select_model(): H or F for two point arrays.
void bind_select_model(py::module_& m) {
  m.def(
      "select_model",
      [](const py::handle& points1, const py::handle& points2, double sigma, double homography_ratio_threshold,
         int max_iterations, std::uint64_t seed, const std::string& rule,
         const std::optional<std::vector<int>>& octaves1, const std::optional<std::vector<int>>& octaves2) {
        affine_orb::ModelSelectionOptions options;
        options.sigma = sigma;
        options.score_ratio.threshold = homography_ratio_threshold;
        options.rule = selection_rule(rule);
        if (octaves1.has_value() != octaves2.has_value())
          throw py::value_error("octaves1 and octaves2 must be given together");
        options.ransac.max_iterations = max_iterations;
        options.ransac.min_iterations = std::min(options.ransac.min_iterations, max_iterations);
        options.ransac.seed = seed;
        const std::vector<cv::Point2f> p1 = point_list(points1, "points1");
        const std::vector<cv::Point2f> p2 = point_list(points2, "points2");
        affine_orb::ModelSelectionResult r;
        {
          py::gil_scoped_release release;
          r = octaves1 ? affine_orb::select_model(p1, p2, *octaves1, *octaves2, options)
                       : affine_orb::select_model(p1, p2, options);
        }
        py::dict out;
        out["success"] = r.success;
        out["model"] = affine_orb::model_name(r.model);
        out["homography_ratio"] = r.homography_ratio;
        out["parallax_significance"] = r.parallax_significance;
        out["homography"] = r.homography_found ? py::object(matrix_array(r.homography)) : py::none();
        out["fundamental"] = r.fundamental_found ? py::object(matrix_array(r.fundamental)) : py::none();
        out["homography_inliers"] = flag_array(r.homography_inliers);
        out["fundamental_inliers"] = flag_array(r.fundamental_inliers);
        return out;
      },
      py::arg("points1"), py::arg("points2"), py::arg("sigma") = affine_orb::ModelSelectionOptions{}.sigma,
      py::arg("homography_ratio_threshold") = affine_orb::ModelSelectionOptions{}.score_ratio.threshold,
      py::arg("max_iterations") = affine_orb::RansacOptions{}.max_iterations,
      py::arg("seed") = affine_orb::RansacOptions{}.seed, py::arg("rule") = "plane_parallax",
      py::arg("octaves1") = py::none(), py::arg("octaves2") = py::none(),
      "Homography or fundamental matrix for N x 2 point arrays (paper eqs. 17-22, affine_orb::select_model): a "
      "dict with success, model (\"homography\", \"fundamental\" or \"none\"), homography_ratio (R_H), "
      "parallax_significance (the plane-and-parallax z-score; 0 under the other rules), homography and fundamental (3 "
      "x 3 arrays, x2 ~ H "
      "x1 and x2^T F x1 = 0, or None) and the inlier flags. rule: \"plane_parallax\" (the default), "
      "\"score_ratio\" (eq. 22), \"gric\" or \"inlier_ratio\" (affine_orb::SelectionRule). octaves1, "
      "octaves2: the keypoints' pyramid octaves (cv2.KeyPoint.octave), which scale each point's sigma by "
      "1.2^octave; both or neither.");
}

/// What TwoViewMatcher's and match_images()' options do, for their docstrings.
std::string two_view_options_doc() {
  return "Two-view matching with views on demand (affine_orb::TwoViewMatcher): stage 0 matches the images' own "
         "`features` keypoints; while the pair is not verified, each stage (max_tilt, view_features) adds the views of "
         "tilts up to max_tilt with view_features x features keypoints per image, and matching and H/F selection run "
         "again. stages=None: the stages up to max_tilt (affine_orb::stages_up_to: (2, 0.25) and (2.83, 0.5), then one "
         "stage of 0.5 per further factor sqrt(2), e.g. (4, 0.5) and (5.66, 0.5) for max_tilt=5.66). A stage verifies "
         "the pair when its chosen model has min_inliers inliers, chance explains it at most max_false_alarms times "
         "(the a-contrario test: number of false alarms among the matches; None = no test), at least min_inlier_ratio "
         "of the matches are its inliers (None, the default = no bound) and, for a homography, homographies fitted to "
         "the two halves of its RANSAC inliers map image 1's corners within max_half_disagreement pixels of each other "
         "(None = no precision test; 10 by default, twice the 5 px a solved pair may be off). A supported homography "
         "is refined by guided_rounds rounds of matching within a gate around its predictions and re-estimation (0 = "
         "off); with align_correspondences, image 2's point of every match is aligned with image 1's patch under it "
         "(sub-pixel correspondences) and the homography re-estimated on them; with final_fit (the default), a "
         "homography that passed the precision test is fitted to all its correspondences within 4 px (IRLS of the "
         "Sampson error), and the returned matches are the stage's own matches plus the guided ones that homography "
         "accepts, never looser than the unguided ones. last_stage_search (on by default): when the last stage's model "
         "lacks support, a RANSAC of up to 30 000 samples (each scored only when its homography maps the four "
         "keypoints' orientations within 45 degrees of their matches') for a homography alone on its matches, whose "
         "homography replaces the stage's when it scores higher (affine_orb::LastStageSearchOptions). "
         "progressive_sampling: RANSAC draws from the matches of smallest descriptor distance first (PROSAC), for "
         "pairs whose correct matches are a few percent. ";
}

/// What TwoViewMatcher.match() and match_images() return, for their docstrings.
std::string two_view_result_doc() {
  return "Returns a dict: verified, stage (the last stage run, 0 = no views), keypoints1/2 (cv2.KeyPoint lists, "
         "original pixels), descriptors1/2, views1/2, matches (cv2.DMatch list: queryIdx into keypoints1, trainIdx "
         "into keypoints2), inliers (bool per match, of the chosen model), points2 (N x 2 float32: per match, image "
         "2's point of the correspondence, aligned with align_correspondences, else the train keypoint's position), "
         "model (\"homography\", \"fundamental\" or \"none\"), homography and fundamental (3 x 3, x2 ~ H x1 and x2^T F "
         "x1 = 0, or None) and stages (one dict per stage run: max_tilt, keypoints, matches, inliers, model, "
         "half_disagreement (pixels, or None when not measured), log10_false_alarms (or None), guided_rounds, aligned "
         "(matches aligned), last_stage_search (the model is the last stage's search's), failure (the first test its "
         "model failed: \"no model\", \"few inliers\", \"false alarms\", \"inlier ratio\" or \"imprecise\"; None "
         "when it verified the pair), milliseconds). Invalid "
         "options raise ValueError, wrong types TypeError.";
}

/// TwoViewMatcher: two-view matching that keeps its buffers over many pairs.
void bind_two_view_matcher(py::module_& m, const std::string& options_doc, const std::string& result_doc) {
  auto matcher_class = py::class_<PyTwoViewMatcher>(
      m, "TwoViewMatcher",
      "Two-view matcher (affine_orb::TwoViewMatcher) that keeps its buffers from call to call: build one and "
      "call match() on many pairs. match_images(image1, image2, **options) is TwoViewMatcher(**options)"
      ".match(image1, image2).");
  std::apply(
      [&](auto... arguments) {
        matcher_class.def(
            py::init([](int features, double max_tilt,
                        const std::optional<std::vector<std::pair<double, double>>>& stages, int min_inliers,
                        std::optional<double> max_false_alarms, std::optional<double> min_inlier_ratio,
                        int guided_rounds, std::optional<double> max_half_disagreement, bool align_correspondences,
                        bool final_fit, bool last_stage_search, bool progressive_sampling, bool all_stages,
                        const std::string& descriptor, const std::string& spreading, int threads) {
              return std::make_unique<PyTwoViewMatcher>(
                  two_view_options(features, max_tilt, stages, min_inliers, max_false_alarms, min_inlier_ratio,
                                   guided_rounds, max_half_disagreement, align_correspondences, final_fit,
                                   last_stage_search, progressive_sampling, all_stages, spreading, threads),
                  descriptor);
            }),
            arguments..., options_doc.c_str());
      },
      two_view_arguments());
  matcher_class
      .def("match", &PyTwoViewMatcher::match, py::arg("image1"), py::arg("image2"), py::arg("mask1") = py::none(),
           py::arg("mask2") = py::none(),
           ("Matches two 2-D uint8 grey images (any sizes); mask1, mask2: None or a 2-D uint8 array of their "
            "image's size (non-zero = allowed). " +
            result_doc)
               .c_str())
      .def_property_readonly("descriptor_size", &PyTwoViewMatcher::descriptor_size, "Bytes per descriptor row.");
}

/// match_images(): TwoViewMatcher for one pair.
void bind_match_images(py::module_& m, const std::string& options_doc, const std::string& result_doc) {
  std::apply(
      [&](auto... arguments) {
        m.def(
            "match_images",
            [](const py::handle& image1, const py::handle& image2, int features, double max_tilt,
               const std::optional<std::vector<std::pair<double, double>>>& stages, int min_inliers,
               std::optional<double> max_false_alarms, std::optional<double> min_inlier_ratio, int guided_rounds,
               std::optional<double> max_half_disagreement, bool align_correspondences, bool final_fit,
               bool last_stage_search, bool progressive_sampling, bool all_stages, const std::string& descriptor,
               const std::string& spreading, int threads, const py::handle& mask1, const py::handle& mask2) {
              PyTwoViewMatcher matcher(
                  two_view_options(features, max_tilt, stages, min_inliers, max_false_alarms, min_inlier_ratio,
                                   guided_rounds, max_half_disagreement, align_correspondences, final_fit,
                                   last_stage_search, progressive_sampling, all_stages, spreading, threads),
                  descriptor);
              return matcher.match(image1, image2, mask1, mask2);
            },
            py::arg("image1"), py::arg("image2"), arguments..., py::arg("mask1") = py::none(),
            py::arg("mask2") = py::none(),
            (options_doc +
             " Builds a TwoViewMatcher for the one pair: to match many pairs, build a TwoViewMatcher "
             "once and call its match(). " +
             result_doc)
                .c_str());
      },
      two_view_arguments());
}

}  // namespace

PYBIND11_MODULE(affine_orb, m) {
  m.doc() = "Affine-ORB feature extraction, Hamming matching and H/F model selection (C++ library affine_orb).";
  // The version of the headers the module was compiled with (include/affine_orb/version.hpp).
  m.attr("__version__") = affine_orb::version();
  bind_extractor(m);
  bind_match(m);
  bind_select_model(m);
  const std::string options_doc = two_view_options_doc();
  const std::string result_doc = two_view_result_doc();
  bind_two_view_matcher(m, options_doc, result_doc);
  bind_match_images(m, options_doc, result_doc);
}
