#pragma once
// Image sequence readers for the examples (not part of the library): the KITTI odometry layout,
// the TUM RGB-D layout and a plain folder of images. Errors (missing or malformed files) throw
// std::runtime_error naming the file and line.
//
// Poses are camera-to-world: a point X_c in camera coordinates is X_w = R X_c + p in the world.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "affine_orb/geometry/relative_pose.hpp"

namespace affine_orb::examples {

/// Camera-to-world pose: X_world = rotation · X_camera + position.
struct CameraPose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// One frame: its image file, time stamp (seconds) and ground-truth pose when known.
struct SequenceFrame {
  std::string image;
  double timestamp = 0.0;
  std::optional<CameraPose> pose;
};

/// A sequence in time order.
struct Sequence {
  std::string format;  ///< "kitti", "tum" or "folder"
  std::vector<SequenceFrame> frames;
  std::optional<PinholeCamera> camera;  ///< intrinsics when the layout has them (KITTI calib.txt)
};

/// Rotation R of X_to = R X_from + t between the camera frames of two camera-to-world poses:
/// R = R_toᵀ R_from.
inline Eigen::Matrix3d relative_rotation(const CameraPose& from, const CameraPose& to) {
  return to.rotation.transpose() * from.rotation;
}

namespace detail {

/// The whole content of a text file.
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Lines of a text without comments ('#' to the end of the line) and blank lines, each with its
/// 1-based line number.
inline std::vector<std::pair<int, std::string>> content_lines(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

/// Exactly `count` numbers from `line`, else an error naming the file (`name`) and line.
inline std::vector<double> numbers(const std::string& line, std::size_t count, const std::string& name, int number) {
  std::istringstream in(line);
  std::vector<double> out;
  double x = 0.0;
  while (in >> x) out.push_back(x);
  if (!in.eof() || out.size() != count) {
    throw std::runtime_error(name + ":" + std::to_string(number) + ": expected " + std::to_string(count) + " numbers");
  }
  return out;
}

inline bool is_image_file(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* known : {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff"}) {
    if (ext == known) return true;
  }
  return false;
}

/// Name order with runs of digits compared as numbers ("frame2" before "frame10"); equal values
/// with different zero padding, and otherwise equal names, fall back to plain string order.
inline bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::size_t ia = i, jb = j;
      while (ia + 1 < ie && a[ia] == '0') ++ia;
      while (jb + 1 < je && b[jb] == '0') ++jb;
      if (ie - ia != je - jb) return ie - ia < je - jb;
      const int c = a.compare(ia, ie - ia, b, jb, je - jb);
      if (c != 0) return c < 0;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if (i < a.size() || j < b.size()) return j < b.size() && i >= a.size();
  return a < b;
}

/// Image files of a directory in natural name order.
inline std::vector<std::string> image_files(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw std::runtime_error("not a directory: " + dir.string());
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && is_image_file(entry.path())) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end(), natural_less);
  std::vector<std::string> paths;
  for (const std::string& n : names) paths.push_back((dir / n).string());
  return paths;
}

}  // namespace detail

/// Reads intrinsics from a calibration file in any of three forms (comments after '#'):
/// - KITTI odometry's calib.txt: a line "P0: p00 p01 … p23" (3x4 projection, row-major):
///   fx = p00, cx = p02, fy = p11, cy = p12;
/// - "key=value" tokens fx=…, fy=…, cx=…, cy=… (other keys ignored);
/// - one line of four numbers "fx fy cx cy".
/// `text` is the file's content, `name` names it in errors.
inline PinholeCamera parse_calibration(const std::string& text, const std::string& name) {
  const auto lines = detail::content_lines(text);
  const auto valid = [&name](const PinholeCamera& c) {
    if (!(std::isfinite(c.fx) && c.fx > 0.0 && std::isfinite(c.fy) && c.fy > 0.0 && std::isfinite(c.cx) &&
          std::isfinite(c.cy))) {
      throw std::runtime_error(name + ": the focal lengths must be positive and all values finite");
    }
    return c;
  };
  PinholeCamera camera;
  int found = 0;
  for (const auto& [number, line] : lines) {
    std::istringstream tokens(line);
    std::string first;
    tokens >> first;
    if (first == "P0:") {
      const std::vector<double> p = detail::numbers(line.substr(line.find(':') + 1), 12, name, number);
      return valid({p[0], p[5], p[2], p[6]});
    }
    if (line.find('=') != std::string::npos) {
      std::istringstream all(line);
      std::string token;
      while (all >> token) {
        const std::size_t eq = token.find('=');
        if (eq == std::string::npos) continue;
        const std::string key = token.substr(0, eq);
        double* target = key == "fx"   ? &camera.fx
                         : key == "fy" ? &camera.fy
                         : key == "cx" ? &camera.cx
                         : key == "cy" ? &camera.cy
                                       : nullptr;
        if (!target) continue;
        try {
          std::size_t used = 0;
          *target = std::stod(token.substr(eq + 1), &used);
          if (used != token.size() - eq - 1) throw std::invalid_argument(token);
        } catch (const std::exception&) {
          throw std::runtime_error(name + ":" + std::to_string(number) + ": bad value in " + token);
        }
        ++found;
      }
      continue;
    }
    std::istringstream in(line);
    std::vector<double> v;
    double x = 0.0;
    while (in >> x) v.push_back(x);
    if (in.eof() && v.size() == 4) return valid({v[0], v[1], v[2], v[3]});
  }
  if (found < 4) {
    throw std::runtime_error(name +
                             ": no intrinsics found (expected \"P0: ...\", fx=/fy=/cx=/cy= or "
                             "\"fx fy cx cy\")");
  }
  return valid(camera);
}

/// read_calibration() of a file.
inline PinholeCamera read_calibration(const std::filesystem::path& path) {
  return parse_calibration(detail::read_text(path), path.string());
}

/// KITTI times.txt: one time stamp (seconds) per line.
inline std::vector<double> parse_times(const std::string& text, const std::string& name) {
  std::vector<double> times;
  for (const auto& [number, line] : detail::content_lines(text))
    times.push_back(detail::numbers(line, 1, name, number)[0]);
  return times;
}

/// KITTI poses: one line per frame of 12 numbers, the 3x4 camera-to-world [R | t], row-major.
inline std::vector<CameraPose> parse_kitti_poses(const std::string& text, const std::string& name) {
  std::vector<CameraPose> poses;
  for (const auto& [number, line] : detail::content_lines(text)) {
    const std::vector<double> p = detail::numbers(line, 12, name, number);
    CameraPose pose;
    pose.rotation << p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10];
    pose.position << p[3], p[7], p[11];
    poses.push_back(pose);
  }
  return poses;
}

/// TUM rgb.txt: "timestamp path" per line (path relative to the sequence folder), at least one,
/// time stamps increasing.
inline std::vector<std::pair<double, std::string>> parse_tum_list(const std::string& text, const std::string& name) {
  std::vector<std::pair<double, std::string>> list;
  for (const auto& [number, line] : detail::content_lines(text)) {
    std::istringstream in(line);
    double timestamp = 0.0;
    std::string path, extra;
    if (!(in >> timestamp >> path) || (in >> extra)) {
      throw std::runtime_error(name + ":" + std::to_string(number) + ": expected \"timestamp path\"");
    }
    list.emplace_back(timestamp, path);
  }
  if (list.empty()) throw std::runtime_error("no images listed in " + name);
  if (!std::is_sorted(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.first < b.first; })) {
    throw std::runtime_error(name + ": time stamps are not in increasing order");
  }
  return list;
}

/// TUM groundtruth.txt: "timestamp tx ty tz qx qy qz qw" per line (camera-to-world position and
/// unit quaternion, |q| within 1e-3 of 1), returned in time order.
inline std::vector<std::pair<double, CameraPose>> parse_tum_groundtruth(const std::string& text,
                                                                        const std::string& name) {
  std::vector<std::pair<double, CameraPose>> poses;
  for (const auto& [number, line] : detail::content_lines(text)) {
    const std::vector<double> v = detail::numbers(line, 8, name, number);
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (!(std::abs(q.norm() - 1.0) < 1e-3)) {
      throw std::runtime_error(name + ":" + std::to_string(number) + ": the quaternion is not unit length");
    }
    CameraPose pose;
    pose.rotation = q.normalized().toRotationMatrix();
    pose.position << v[1], v[2], v[3];
    poses.emplace_back(v[0], pose);
  }
  std::stable_sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return poses;
}

/// KITTI odometry layout: DIR/image_0/*.png (natural name order), DIR/times.txt (one time stamp
/// per image; without it the time stamps are the frame numbers), DIR/poses.txt or `poses_file`
/// (optional; one line per image, 12 numbers: the 3x4 camera-to-world [R | t], row-major; the
/// official layout keeps it as poses/NN.txt beside sequences/), DIR/calib.txt (optional, see
/// read_calibration()). Line counts must equal the image count.
inline Sequence read_kitti(const std::filesystem::path& dir, const std::filesystem::path& poses_file = {}) {
  Sequence s;
  s.format = "kitti";
  const std::vector<std::string> images = detail::image_files(dir / "image_0");
  if (images.empty()) throw std::runtime_error("no images in " + (dir / "image_0").string());
  for (std::size_t i = 0; i < images.size(); ++i) s.frames.push_back({images[i], static_cast<double>(i), std::nullopt});
  const auto count_error = [&](const std::filesystem::path& path, std::size_t lines) {
    return std::runtime_error(path.string() + " has " + std::to_string(lines) + " lines but image_0 has " +
                              std::to_string(images.size()) + " images");
  };
  const std::filesystem::path times = dir / "times.txt";
  if (std::filesystem::exists(times)) {
    const std::vector<double> stamps = parse_times(detail::read_text(times), times.string());
    if (stamps.size() != images.size()) throw count_error(times, stamps.size());
    for (std::size_t i = 0; i < stamps.size(); ++i) s.frames[i].timestamp = stamps[i];
  }
  const std::filesystem::path poses = poses_file.empty() ? dir / "poses.txt" : poses_file;
  if (!poses_file.empty() || std::filesystem::exists(poses)) {
    const std::vector<CameraPose> read = parse_kitti_poses(detail::read_text(poses), poses.string());
    if (read.size() != images.size()) throw count_error(poses, read.size());
    for (std::size_t i = 0; i < read.size(); ++i) s.frames[i].pose = read[i];
  }
  const std::filesystem::path calib = dir / "calib.txt";
  if (std::filesystem::exists(calib)) s.camera = read_calibration(calib);
  return s;
}

/// TUM RGB-D layout: DIR/rgb.txt ("timestamp path" per line, path relative to DIR, comments
/// after '#'), DIR/groundtruth.txt (optional: "timestamp tx ty tz qx qy qz qw", camera-to-world
/// position and unit quaternion). Each image gets the ground-truth pose with the nearest time
/// stamp when it is within `max_time_difference` seconds (0.02 s: the default of the benchmark's
/// associate.py), none otherwise. TUM ships no intrinsics in these files.
inline Sequence read_tum(const std::filesystem::path& dir, double max_time_difference = 0.02) {
  Sequence s;
  s.format = "tum";
  const std::filesystem::path rgb = dir / "rgb.txt";
  for (const auto& [timestamp, name] : parse_tum_list(detail::read_text(rgb), rgb.string())) {
    s.frames.push_back({(dir / name).string(), timestamp, std::nullopt});
  }
  const std::filesystem::path truth = dir / "groundtruth.txt";
  if (!std::filesystem::exists(truth)) return s;
  const std::vector<std::pair<double, CameraPose>> poses =
      parse_tum_groundtruth(detail::read_text(truth), truth.string());
  for (SequenceFrame& frame : s.frames) {
    const auto it = std::lower_bound(poses.begin(), poses.end(), frame.timestamp,
                                     [](const auto& p, double t) { return p.first < t; });
    const std::pair<double, CameraPose>* best = nullptr;
    if (it != poses.end()) best = &*it;
    if (it != poses.begin() && (!best || frame.timestamp - std::prev(it)->first <= best->first - frame.timestamp)) {
      best = &*std::prev(it);
    }
    if (best && std::abs(best->first - frame.timestamp) <= max_time_difference) frame.pose = best->second;
  }
  return s;
}

/// A folder of images (png, jpg, jpeg, pgm, ppm, bmp, tif, tiff) in natural name order; time
/// stamps are the frame numbers; no poses, no intrinsics.
inline Sequence read_folder(const std::filesystem::path& dir) {
  Sequence s;
  s.format = "folder";
  const std::vector<std::string> images = detail::image_files(dir);
  if (images.empty()) throw std::runtime_error("no images in " + dir.string());
  for (std::size_t i = 0; i < images.size(); ++i) s.frames.push_back({images[i], static_cast<double>(i), std::nullopt});
  return s;
}

/// Reads DIR as `format` ("kitti", "tum", "folder"), or, for "auto", as KITTI when DIR/image_0
/// exists, TUM when DIR/rgb.txt exists, a folder otherwise.
inline Sequence read_sequence(const std::filesystem::path& dir, const std::string& format = "auto") {
  if (!std::filesystem::is_directory(dir)) throw std::runtime_error("not a directory: " + dir.string());
  if (format == "kitti" || (format == "auto" && std::filesystem::is_directory(dir / "image_0"))) return read_kitti(dir);
  if (format == "tum" || (format == "auto" && std::filesystem::exists(dir / "rgb.txt"))) return read_tum(dir);
  if (format == "folder" || format == "auto") return read_folder(dir);
  throw std::runtime_error("unknown sequence format \"" + format + "\" (kitti, tum, folder or auto)");
}

/// Every `step`-th frame (0, step, 2·step, …): the same path at `step` times the speed.
inline Sequence subsample(const Sequence& s, int step) {
  if (step < 1) throw std::runtime_error("the step must be >= 1, got " + std::to_string(step));
  Sequence out = s;
  out.frames.clear();
  for (std::size_t i = 0; i < s.frames.size(); i += static_cast<std::size_t>(step)) out.frames.push_back(s.frames[i]);
  return out;
}

/// The frame's image as CV_8UC1 (colour images are converted); throws when it cannot be read.
inline cv::Mat load_frame(const SequenceFrame& frame) {
  cv::Mat image = cv::imread(frame.image, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error("cannot read image " + frame.image);
  return image;
}

}  // namespace affine_orb::examples
