// affine_orb_sequence DIR [--format auto|kitti|tum|folder] [--step K] [--max-tilt T] [--features N]
//                     [--threads K] [--frames N] [--calib FILE] [--poses FILE] [--min-inliers N]
//                     [--keyframe-ratio R] [--max-lost M] [--json] [--plot PNG]
//
// Frame loss and keyframes on a real image sequence (paper Sec. 4, eq. 22; SPEC §7), measured by
// KeyframeTracker (keyframe_tracker.hpp): Affine-ORB features (rBRIEF) of every frame are matched
// to the last keyframe and verified by H/F model selection. With ground-truth poses and intrinsics
// (KITTI), the frame-to-frame rotation recovered from H or F is compared with the truth.
//
// --step K keeps every K-th frame: the same path at K times the camera speed, the paper's
// experiment. --plot runs K = 1…5 for plain features (max tilt 1) and for affine features (the
// given max tilt), prints the table and draws frame loss rate and keyframes against K.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "affine_orb/descriptors/rbrief.hpp"
#include "affine_orb/extraction/extractor.hpp"
#include "affine_orb/geometry/relative_pose.hpp"
#include "cli.hpp"
#include "keyframe_tracker.hpp"
#include "sequence_io.hpp"

namespace {

namespace ex = affine_orb::examples;
using Features = affine_orb::Features<affine_orb::Rbrief::kBits>;
using Tracker = affine_orb::KeyframeTracker<affine_orb::Rbrief::kBits>;

const char* const kUsage =
    "usage: affine_orb_sequence DIR [--format auto|kitti|tum|folder] [--step K] [--max-tilt T] [--features N]\n"
    "                           [--threads K] [--frames N] [--calib FILE] [--poses FILE] [--min-inliers N]\n"
    "                           [--keyframe-ratio R] [--max-lost M] [--json] [--plot PNG]\n"
    "  DIR                KITTI odometry (image_0/, times.txt, poses.txt, calib.txt), TUM RGB-D (rgb.txt,\n"
    "                     groundtruth.txt) or a folder of images in name order; --format auto guesses\n"
    "  --step K           keep every K-th frame: K times the camera speed (default 1)\n"
    "  --max-tilt T       largest simulated tilt, 1 = plain ORB-style features (default 2√2: 18 views;\n"
    "                     tilts are powers of √2, so 2.8284 < 2√2 gives 10 views and 2.83 gives 18)\n"
    "  --features N       features per frame (default 1000)\n"
    "  --threads K        extraction threads (default 2)\n"
    "  --frames N         use only the first N frames of the sequence (before --step)\n"
    "  --calib FILE       intrinsics (\"P0: ...\" KITTI line, fx= fy= cx= cy=, or \"fx fy cx cy\"); needed for\n"
    "                     rotations on TUM and folders\n"
    "  --poses FILE       KITTI ground truth when it is not DIR/poses.txt (e.g. poses/06.txt)\n"
    "  --min-inliers N, --keyframe-ratio R, --max-lost M   KeyframeTrackerOptions (keyframe_tracker.hpp)\n"
    "  --json             one JSON object instead of text\n"
    "  --plot PNG         run K = 1..5 with plain (max tilt 1) and affine features, print the table and draw\n"
    "                     frame loss rate and keyframes against K\n";

/// Features of one frame and the time their extraction took.
struct Extracted {
  Features features;
  double ms = 0.0;
};

/// One frame of a run.
struct FrameRecord {
  int sequence_index = 0;  // index in the full sequence
  double timestamp = 0.0;
  double ms_extract = 0.0;
  double ms_track = 0.0;
  int matches = 0;  // to the keyframe (tracked.matches is dropped to save memory)
  affine_orb::TrackedFrame tracked;
  std::optional<double> truth_angle;     // ground-truth rotation to the previous kept frame, degrees
  std::optional<double> rotation_error;  // recovered vs ground truth, degrees
};

/// Totals of one run.
struct Summary {
  int step = 1;
  double max_tilt = 1.0;
  int views = 1;  // simulated views of the extractor
  int frames = 0, lost = 0, keyframes = 0;
  double loss_rate = 0.0;
  /// Steady-state extraction: the extractor's first call (which sizes its workspace) is made
  /// before tracking, timed apart as ms_first_extract and not counted in the mean and median.
  double ms_extract_mean = 0.0, ms_extract_median = 0.0, ms_track_mean = 0.0, ms_first_extract = 0.0;
  int truth_pairs = 0;  // consecutive kept frames with ground truth (and intrinsics)
  int rotations = 0;    // relative rotations recovered
  int compared = 0;     // ... of which have ground truth
  double rotation_error_median = 0.0, rotation_error_mean = 0.0, truth_angle_median = 0.0;
};

struct Run {
  Summary summary;
  std::vector<FrameRecord> frames;
};

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_number(std::optional<double> v, const char* format = "%.4f") {
  if (!v || !std::isfinite(*v)) return "null";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, *v);
  return buffer;
}

/// The extractor's first call, on the first frame (its result discarded), in milliseconds; it
/// sizes the extractor's workspace, which later frames reuse.
double warm_up(affine_orb::Extractor<affine_orb::Rbrief>& extractor, const ex::Sequence& sequence) {
  if (sequence.frames.empty()) return 0.0;
  const cv::Mat image = ex::load_frame(sequence.frames.front());
  const auto start = std::chrono::steady_clock::now();
  extractor.extract(image);
  return ex::ms_since(start);
}

Extracted extract(affine_orb::Extractor<affine_orb::Rbrief>& extractor, const ex::SequenceFrame& frame) {
  const cv::Mat image = ex::load_frame(frame);
  const auto start = std::chrono::steady_clock::now();
  Extracted e;
  e.features = extractor.extract(image);
  e.ms = ex::ms_since(start);
  return e;
}

/// Tracks the frames `indices` of `sequence`; `features_of(i)` gives frame i's features.
template <class FeaturesOf>
Run track(const ex::Sequence& sequence, const std::vector<int>& indices, int step, double max_tilt,
          const affine_orb::KeyframeTrackerOptions& options, const std::optional<affine_orb::PinholeCamera>& camera,
          FeaturesOf features_of) {
  Tracker tracker(options, camera);
  Run run;
  const ex::SequenceFrame* previous = nullptr;
  std::vector<double> extract_ms, track_ms, errors, truth_angles;
  for (const int i : indices) {
    const ex::SequenceFrame& frame = sequence.frames[static_cast<std::size_t>(i)];
    Extracted e = features_of(i);
    FrameRecord r;
    r.sequence_index = i;
    r.timestamp = frame.timestamp;
    r.ms_extract = e.ms;
    const auto start = std::chrono::steady_clock::now();
    r.tracked = tracker.track(std::move(e.features));
    r.ms_track = ex::ms_since(start);
    if (previous && previous->pose && frame.pose) {
      const Eigen::Matrix3d truth = ex::relative_rotation(*previous->pose, *frame.pose);
      r.truth_angle = affine_orb::rotation_angle_degrees(Eigen::Matrix3d::Identity(), truth);
      truth_angles.push_back(*r.truth_angle);
      if (camera) ++run.summary.truth_pairs;
      if (r.tracked.relative_pose.success) {
        r.rotation_error = affine_orb::rotation_angle_degrees(r.tracked.relative_pose.rotation, truth);
        errors.push_back(*r.rotation_error);
      }
    }
    if (r.tracked.relative_pose.success) ++run.summary.rotations;
    extract_ms.push_back(r.ms_extract);
    track_ms.push_back(r.ms_track);
    // Keep the counts, drop the per-match vectors.
    r.matches = static_cast<int>(r.tracked.matches.size());
    r.tracked.matches = {};
    r.tracked.inlier_mask = {};
    run.frames.push_back(std::move(r));
    previous = &frame;
  }
  Summary& s = run.summary;
  s.step = step;
  s.max_tilt = max_tilt;
  s.frames = tracker.frames();
  s.lost = tracker.lost_frames();
  s.keyframes = tracker.keyframes();
  s.loss_rate = tracker.frame_loss_rate();
  const auto mean = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
  };
  s.ms_extract_mean = mean(extract_ms);
  s.ms_extract_median = ex::median(extract_ms);
  s.ms_track_mean = mean(track_ms);
  s.compared = static_cast<int>(errors.size());
  s.rotation_error_median = ex::median(errors);
  s.rotation_error_mean = mean(errors);
  s.truth_angle_median = ex::median(truth_angles);
  return run;
}

std::vector<int> kept_indices(int count, int step) {
  std::vector<int> out;
  for (int i = 0; i < count; i += step) out.push_back(i);
  return out;
}

std::string summary_json(const Summary& s, bool with_rotation) {
  char buffer[1024];
  std::snprintf(
      buffer, sizeof(buffer),
      "{\"step\": %d, \"max_tilt\": %.4f, \"views\": %d, \"frames\": %d, \"lost\": %d, \"frame_loss_rate\": %.4f, "
      "\"keyframes\": %d, \"ms_first_extract\": %.2f, \"ms_extract_mean\": %.2f, \"ms_extract_median\": %.2f, "
      "\"ms_track_mean\": %.2f, ",
      s.step, s.max_tilt, s.views, s.frames, s.lost, s.loss_rate, s.keyframes, s.ms_first_extract, s.ms_extract_mean,
      s.ms_extract_median, s.ms_track_mean);
  std::string out = buffer;
  if (with_rotation) {
    const bool any = s.compared > 0;
    out += "\"truth_pairs\": " + std::to_string(s.truth_pairs) +
           ", \"rotations_recovered\": " + std::to_string(s.rotations) +
           ", \"rotations_compared\": " + std::to_string(s.compared) + ", \"rotation_error_median_deg\": " +
           json_number(any ? std::optional<double>(s.rotation_error_median) : std::nullopt) +
           ", \"rotation_error_mean_deg\": " +
           json_number(any ? std::optional<double>(s.rotation_error_mean) : std::nullopt) +
           ", \"truth_rotation_median_deg\": " + json_number(s.truth_angle_median) + "}";
  } else {
    out += "\"truth_pairs\": 0, \"rotations_recovered\": " + std::to_string(s.rotations) +
           ", \"rotations_compared\": 0, \"rotation_error_median_deg\": null, \"rotation_error_mean_deg\": null, "
           "\"truth_rotation_median_deg\": null}";
  }
  return out;
}

std::string frame_json(const FrameRecord& r) {
  const affine_orb::TrackedFrame& t = r.tracked;
  char buffer[768];
  std::snprintf(buffer, sizeof(buffer),
                "{\"index\": %d, \"timestamp\": %.6f, \"features\": %d, \"reference_keyframe\": %d, \"matches\": %d, "
                "\"inliers\": %d, \"model\": \"%s\", \"homography_ratio\": %.4f, \"inlier_ratio\": %.4f, "
                "\"lost\": %s, \"keyframe\": %s, \"initialised\": %s, \"previous_matches\": %d, "
                "\"previous_inliers\": %d, \"previous_model\": \"%s\", \"rotation_recovered\": %s, ",
                r.sequence_index, r.timestamp, t.features, t.reference_keyframe, r.matches, t.inliers,
                affine_orb::model_name(t.model), t.homography_ratio, t.inlier_ratio, t.lost ? "true" : "false",
                t.keyframe ? "true" : "false", t.initialised ? "true" : "false", t.previous_matches, t.previous_inliers,
                affine_orb::model_name(t.previous_model), t.relative_pose.success ? "true" : "false");
  return std::string(buffer) + "\"truth_rotation_deg\": " + json_number(r.truth_angle) +
         ", \"rotation_error_deg\": " + json_number(r.rotation_error) +
         ", \"ms_extract\": " + json_number(r.ms_extract, "%.2f") +
         ", \"ms_track\": " + json_number(r.ms_track, "%.2f") + "}";
}

/// Draws one bar panel: for each K, the plain value and the affine value side by side.
/// `frames[k]`: frames at step k + 1, written under each group.
void draw_panel(cv::Mat& canvas, const cv::Rect& area, const std::string& title, const std::vector<double>& plain,
                const std::vector<double>& affine, const std::vector<int>& frames, bool percent) {
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200), plain_colour(180, 120, 60), affine_colour(40, 140, 240);
  const int left = area.x + 60, right = area.x + area.width - 15, top = area.y + 55, bottom = area.y + area.height - 60;
  double top_value = 0.0;
  for (double v : plain) top_value = std::max(top_value, v);
  for (double v : affine) top_value = std::max(top_value, v);
  // A round axis maximum: 1, 2 or 5 times a power of ten, at least 15 % above the largest bar.
  const double wanted = std::max(top_value * 1.15, percent ? 5.0 : 1.0);
  const double magnitude = std::pow(10.0, std::floor(std::log10(wanted)));
  double axis_max = magnitude;
  for (double f : {1.0, 2.0, 5.0, 10.0}) {
    if (f * magnitude >= wanted) {
      axis_max = f * magnitude;
      break;
    }
  }
  cv::putText(canvas, title, {area.x + 10, area.y + 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, black, 1, cv::LINE_AA);
  const auto y_of = [&](double v) { return static_cast<int>(std::lround(bottom - (bottom - top) * v / axis_max)); };
  for (int tick = 0; tick <= 5; ++tick) {
    const double v = axis_max * tick / 5.0;
    const int y = y_of(v);
    cv::line(canvas, {left, y}, {right, y}, tick == 0 ? black : grey, 1);
    char label[32];
    std::snprintf(label, sizeof(label), percent ? "%.0f%%" : "%.0f", v);
    if (percent && axis_max < 10.0) std::snprintf(label, sizeof(label), "%.1f%%", v);
    cv::putText(canvas, label, {area.x + 5, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black, 1, cv::LINE_AA);
  }
  const int groups = static_cast<int>(plain.size());
  const double group_width = static_cast<double>(right - left) / groups;
  for (int k = 0; k < groups; ++k) {
    const int x0 = left + static_cast<int>(group_width * k + group_width * 0.15);
    const int bar = static_cast<int>(group_width * 0.33);
    const double values[2] = {plain[static_cast<std::size_t>(k)], affine[static_cast<std::size_t>(k)]};
    for (int b = 0; b < 2; ++b) {
      const int x = x0 + b * bar;
      const int y = y_of(values[b]);
      cv::rectangle(canvas, cv::Rect(x, y, bar - 2, std::max(1, bottom - y)), b == 0 ? plain_colour : affine_colour,
                    cv::FILLED);
      char label[32];
      std::snprintf(label, sizeof(label), percent ? "%.1f" : "%.0f", values[b]);
      cv::putText(canvas, label, {x, y - 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35, black, 1, cv::LINE_AA);
    }
    cv::putText(canvas, "K=" + std::to_string(k + 1), {x0 + bar / 2, bottom + 17}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
                black, 1, cv::LINE_AA);
    cv::putText(canvas, std::to_string(frames[static_cast<std::size_t>(k)]) + " frames", {x0, bottom + 32},
                cv::FONT_HERSHEY_SIMPLEX, 0.35, black, 1, cv::LINE_AA);
  }
  cv::putText(canvas, "frame step K (K times the camera speed)", {left + 40, bottom + 50}, cv::FONT_HERSHEY_SIMPLEX,
              0.45, black, 1, cv::LINE_AA);
}

void draw_plot(const std::string& path, const std::string& name, const std::vector<Summary>& plain,
               const std::vector<Summary>& affine) {
  cv::Mat canvas(480, 1100, CV_8UC3, cv::Scalar::all(255));
  std::vector<double> loss_plain, loss_affine, kf_plain, kf_affine;
  std::vector<int> frames;
  for (const Summary& s : plain) {
    loss_plain.push_back(100.0 * s.loss_rate);
    kf_plain.push_back(s.keyframes);
    frames.push_back(s.frames);
  }
  for (const Summary& s : affine) {
    loss_affine.push_back(100.0 * s.loss_rate);
    kf_affine.push_back(s.keyframes);
  }
  draw_panel(canvas, cv::Rect(0, 30, 550, 450), "frame loss rate (lost / frames, eq. 22)", loss_plain, loss_affine,
             frames, true);
  draw_panel(canvas, cv::Rect(550, 30, 550, 450), "keyframes", kf_plain, kf_affine, frames, false);
  // The legend starts at x = 640: the title (the sequence path) is shortened to end 20 px before it.
  cv::putText(canvas, ex::fit_text(name, 610, cv::FONT_HERSHEY_SIMPLEX, 0.5), {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::rectangle(canvas, cv::Rect(640, 10, 14, 14), cv::Scalar(180, 120, 60), cv::FILLED);
  cv::rectangle(canvas, cv::Rect(820, 10, 14, 14), cv::Scalar(40, 140, 240), cv::FILLED);
  cv::putText(canvas, "plain (max tilt 1)", {660, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  char legend[64];
  std::snprintf(legend, sizeof(legend), "affine (max tilt %.2f, %d views)", affine.front().max_tilt,
                affine.front().views);
  cv::putText(canvas, legend, {840, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  if (!cv::imwrite(path, canvas)) throw std::runtime_error("cannot write " + path);
}

void print_summary_text(const Summary& s, bool rotation) {
  std::printf("frames %d, lost %d (frame loss rate %.1f %%), keyframes %d\n", s.frames, s.lost, 100.0 * s.loss_rate,
              s.keyframes);
  std::printf(
      "extraction %.1f ms/frame (median %.1f; the extractor's first call, not counted: %.1f ms), tracking %.1f "
      "ms/frame\n",
      s.ms_extract_mean, s.ms_extract_median, s.ms_first_extract, s.ms_track_mean);
  if (!rotation) return;
  if (s.compared > 0) {
    std::printf(
        "rotation error vs ground truth: median %.3f deg, mean %.3f deg, recovered for %d of %d frame pairs "
        "(true rotation: median %.2f deg)\n",
        s.rotation_error_median, s.rotation_error_mean, s.compared, s.truth_pairs, s.truth_angle_median);
  } else {
    std::printf("rotation error vs ground truth: no rotation recovered for %d frame pairs\n", s.truth_pairs);
  }
}

/// The command line, checked.
struct Settings {
  std::string dir;
  std::string format;
  int step = 1;
  bool step_given = false;
  int frame_limit = 0;
  std::string calib;
  std::string poses;
  bool json = false;
  std::string plot;
  affine_orb::ExtractorOptions extractor;
  affine_orb::KeyframeTrackerOptions tracker;
};

Settings parse_settings(ex::Args& args) {
  Settings s;
  s.format = args.value("--format", "auto");
  const std::string step_text = args.value("--step", "");
  s.step_given = !step_text.empty();
  s.step = step_text.empty() ? 1 : ex::Args::parse_integer("--step", step_text);
  s.extractor.views.max_tilt = args.real("--max-tilt", s.extractor.views.max_tilt);
  s.extractor.features = args.integer("--features", 1000);
  s.extractor.threads = args.integer("--threads", 2);
  s.frame_limit = args.integer("--frames", 0);
  s.calib = args.value("--calib", "");
  s.poses = args.value("--poses", "");
  s.tracker.min_inliers = args.integer("--min-inliers", s.tracker.min_inliers);
  s.tracker.keyframe_inlier_ratio = args.real("--keyframe-ratio", s.tracker.keyframe_inlier_ratio);
  s.tracker.max_lost_frames = args.integer("--max-lost", s.tracker.max_lost_frames);
  s.json = args.flag("--json");
  s.plot = args.value("--plot", "");
  const std::vector<std::string> positional = args.positional();
  if (positional.size() != 1) throw std::invalid_argument("expected one sequence directory");
  if (s.step < 1) throw std::invalid_argument("--step must be >= 1, got " + std::to_string(s.step));
  if (s.frame_limit < 0) throw std::invalid_argument("--frames must be >= 0");
  if (!s.plot.empty() && s.step_given) throw std::invalid_argument("--plot runs K = 1..5 itself; drop --step");
  if (!s.plot.empty() && !(s.extractor.views.max_tilt > 1.0)) {
    throw std::invalid_argument("--plot compares max tilt 1 with --max-tilt: give a tilt > 1");
  }
  s.extractor.check();
  s.tracker.check();
  s.dir = positional[0];
  return s;
}

/// The sequence (its first --frames frames) and the camera that rotations are recovered with.
struct Input {
  ex::Sequence sequence;
  std::optional<affine_orb::PinholeCamera> camera;
  bool rotation = false;  // a camera and ground-truth poses: rotations are checked
  int count = 0;
};

Input read_input(const Settings& settings) {
  Input in;
  if (!settings.poses.empty()) {
    if (settings.format != "kitti" && settings.format != "auto") {
      throw std::invalid_argument("--poses is for the KITTI layout");
    }
    in.sequence = ex::read_kitti(settings.dir, settings.poses);
  } else {
    in.sequence = ex::read_sequence(settings.dir, settings.format);
  }
  std::vector<ex::SequenceFrame>& frames = in.sequence.frames;
  if (settings.frame_limit > 0 && static_cast<std::size_t>(settings.frame_limit) < frames.size()) {
    frames.resize(static_cast<std::size_t>(settings.frame_limit));
  }
  in.camera = settings.calib.empty() ? in.sequence.camera
                                     : std::optional<affine_orb::PinholeCamera>(ex::read_calibration(settings.calib));
  const bool has_poses =
      std::any_of(frames.begin(), frames.end(), [](const ex::SequenceFrame& f) { return f.pose.has_value(); });
  in.rotation = in.camera.has_value() && has_poses;
  in.count = static_cast<int>(frames.size());
  return in;
}

/// --plot: K = 1..5 with plain features (max tilt 1), then with the affine ones; each frame is
/// extracted once per tilt.
std::array<std::vector<Summary>, 2> plot_runs(const Settings& settings, const Input& in) {
  std::array<std::vector<Summary>, 2> summaries;  // plain, affine
  for (const double tilt : {1.0, settings.extractor.views.max_tilt}) {
    affine_orb::ExtractorOptions o = settings.extractor;
    o.views.max_tilt = tilt;
    affine_orb::Extractor<affine_orb::Rbrief> extractor(o);
    const double first = warm_up(extractor, in.sequence);
    std::vector<Extracted> cache;
    for (const ex::SequenceFrame& frame : in.sequence.frames) cache.push_back(extract(extractor, frame));
    for (int k = 1; k <= 5; ++k) {
      Run run = track(in.sequence, kept_indices(in.count, k), k, tilt, settings.tracker, in.camera,
                      [&](int i) { return cache[static_cast<std::size_t>(i)]; });
      run.summary.views = static_cast<int>(extractor.views().size());
      run.summary.ms_first_extract = first;
      summaries[tilt == 1.0 ? 0 : 1].push_back(run.summary);
    }
  }
  return summaries;
}

void print_plot_json(const Settings& settings, const Input& in, const std::array<std::vector<Summary>, 2>& summaries) {
  std::printf(
      "{\"sequence\": %s, \"format\": %s, \"frames\": %d, \"features\": %d, \"threads\": %d, "
      "\"plot\": %s, \"runs\": [",
      json_string(settings.dir).c_str(), json_string(in.sequence.format).c_str(), in.count, settings.extractor.features,
      settings.extractor.threads, json_string(settings.plot).c_str());
  bool first = true;
  for (const std::vector<Summary>& set : summaries) {
    for (const Summary& s : set) {
      std::printf("%s%s", first ? "" : ", ", summary_json(s, in.rotation).c_str());
      first = false;
    }
  }
  std::printf("]}\n");
}

void print_plot_table(const Settings& settings, const Input& in, const std::array<std::vector<Summary>, 2>& summaries) {
  std::printf("%s: %s, %d frames, %d features, %d thread(s)\n", settings.dir.c_str(), in.sequence.format.c_str(),
              in.count, settings.extractor.features, settings.extractor.threads);
  std::printf(
      "| features | K | frames | lost | loss rate | keyframes | rot. err. median / mean (deg) | "
      "rotations recovered | ms/frame (extract) |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const std::vector<Summary>& set : summaries) {
    for (const Summary& s : set) {
      char tilt[64];
      std::snprintf(tilt, sizeof(tilt), "affine (tilt %.2f, %d views)", s.max_tilt, s.views);
      if (s.max_tilt == 1.0) std::snprintf(tilt, sizeof(tilt), "plain");
      char error[64] = "n/a";
      if (in.rotation && s.compared > 0) {
        std::snprintf(error, sizeof(error), "%.3f / %.3f", s.rotation_error_median, s.rotation_error_mean);
      }
      std::printf("| %s | %d | %d | %d | %.1f %% | %d | %s | %d / %d | %.1f |\n", tilt, s.step, s.frames, s.lost,
                  100.0 * s.loss_rate, s.keyframes, error, s.compared, s.truth_pairs, s.ms_extract_mean);
    }
  }
  std::printf("plot: %s\n", settings.plot.c_str());
}

/// --plot: runs, draws and prints.
void plot(const Settings& settings, const Input& in) {
  const std::array<std::vector<Summary>, 2> summaries = plot_runs(settings, in);
  draw_plot(settings.plot,
            settings.dir + " (" + std::to_string(in.count) + " frames, " + std::to_string(settings.extractor.features) +
                " features)",
            summaries[0], summaries[1]);
  if (settings.json) {
    print_plot_json(settings, in, summaries);
  } else {
    print_plot_table(settings, in, summaries);
  }
}

void print_run_text(const Settings& settings, const Input& in, const Run& run, std::size_t views) {
  const bool rotation = in.rotation;
  std::printf("%s: %s, %d frames, step %d -> %zu frames; max tilt %.2f (%zu views), %d features, %d thread(s)%s\n",
              settings.dir.c_str(), in.sequence.format.c_str(), in.count, settings.step, run.frames.size(),
              settings.extractor.views.max_tilt, views, settings.extractor.features, settings.extractor.threads,
              rotation ? "" : (in.camera ? "; no poses: no rotation check" : "; no intrinsics: no rotation check"));
  std::printf("%6s %10s %5s %6s %5s %-11s %5s %6s %-16s %8s %8s %8s %7s %7s\n", "frame", "time", "feat", "match", "inl",
              "model", "R_H", "ratio", "state", "prev_inl", "rot_gt", "rot_err", "ms_ext", "ms_trk");
  for (const FrameRecord& r : run.frames) {
    const affine_orb::TrackedFrame& t = r.tracked;
    std::string state = t.lost ? "LOST" : "tracked";
    if (t.keyframe) state += t.initialised ? "+KF(init)" : "+KF";
    const std::string truth = r.truth_angle ? json_number(r.truth_angle, "%.3f") : "-";
    const std::string error = r.rotation_error ? json_number(r.rotation_error, "%.3f") : "-";
    std::printf("%6d %10.3f %5d %6d %5d %-11s %5.2f %6.3f %-16s %8d %8s %8s %7.1f %7.1f\n", r.sequence_index,
                r.timestamp, t.features, r.matches, t.inliers, affine_orb::model_name(t.model), t.homography_ratio,
                t.inlier_ratio, state.c_str(), t.previous_inliers, truth.c_str(), error.c_str(), r.ms_extract,
                r.ms_track);
  }
  print_summary_text(run.summary, rotation);
}

/// One run at --step, printed frame by frame.
void run_once(const Settings& settings, const Input& in) {
  affine_orb::Extractor<affine_orb::Rbrief> extractor(settings.extractor);
  const double first = warm_up(extractor, in.sequence);
  Run run = track(in.sequence, kept_indices(in.count, settings.step), settings.step, settings.extractor.views.max_tilt,
                  settings.tracker, in.camera,
                  [&](int i) { return extract(extractor, in.sequence.frames[static_cast<std::size_t>(i)]); });
  const std::size_t views = extractor.views().size();
  run.summary.views = static_cast<int>(views);
  run.summary.ms_first_extract = first;
  if (!settings.json) {
    print_run_text(settings, in, run, views);
    return;
  }
  std::printf(
      "{\"sequence\": %s, \"format\": %s, \"features\": %d, \"threads\": %d, \"views\": %zu, "
      "\"summary\": %s, \"frames\": [",
      json_string(settings.dir).c_str(), json_string(in.sequence.format).c_str(), settings.extractor.features,
      settings.extractor.threads, views, summary_json(run.summary, in.rotation).c_str());
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    std::printf("%s%s", i ? ", " : "", frame_json(run.frames[i]).c_str());
  }
  std::printf("]}\n");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    ex::Args args(argc, argv);
    if (args.flag("--help") || args.flag("-h")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    const Settings settings = parse_settings(args);
    const Input in = read_input(settings);
    if (settings.plot.empty()) {
      run_once(settings, in);
    } else {
      plot(settings, in);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "affine_orb_sequence: %s\n%s", e.what(), kUsage);
    return 2;
  }
}
