#pragma once
// The ground-truth homography reader of the examples (not part of the library). Errors throw
// std::runtime_error naming the file.

#include <cmath>
#include <cstddef>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace affine_orb::examples {

namespace detail {

/// The text after the first `key` (an XML tag name or a YAML key, e.g. "rows") up to the end of
/// its value: for XML `<key>value</key>`, for YAML `key: value` to the end of the line or, for a
/// flow sequence, to its closing ']'. Empty when `key` does not occur.
inline std::string storage_value(const std::string& text, const std::string& key, bool xml) {
  if (xml) {
    const std::string open = "<" + key + ">";
    const std::size_t begin = text.find(open);
    if (begin == std::string::npos) return {};
    const std::size_t value = begin + open.size();
    const std::size_t end = text.find("</" + key + ">", value);
    if (end == std::string::npos) return {};
    return text.substr(value, end - value);
  }
  const std::size_t begin = text.find(key + ":");
  if (begin == std::string::npos) return {};
  std::size_t value = begin + key.size() + 1;
  while (value < text.size() && (text[value] == ' ' || text[value] == '\t')) ++value;
  if (value < text.size() && text[value] == '[') {
    const std::size_t end = text.find(']', value);
    if (end == std::string::npos) return {};
    return text.substr(value + 1, end - value - 1);
  }
  const std::size_t end = text.find('\n', value);
  return text.substr(value, end == std::string::npos ? std::string::npos : end - value);
}

}  // namespace detail

/// A 3x3 homography x2 ~ H x1 from the text of a file named `name`: OpenCV's matrix storage
/// (`type_id="opencv-matrix"` in XML or `!!opencv-matrix` in YAML, the first matrix of the file,
/// e.g. opencv-doc's H1to3p.xml) or at least 9 numbers, row-major (the Oxford files). Every entry
/// must be finite and H invertible. The storage is read here rather than with cv::FileStorage,
/// whose in-memory XML parser (OpenCV 4.6) dereferences null on truncated input.
inline cv::Matx33d parse_homography(const std::string& text, const std::string& name) {
  const bool xml = text.find("<?xml") != std::string::npos;
  const bool yaml = text.find("%YAML") != std::string::npos;
  std::string numbers_text = text;
  if (xml || yaml) {
    if (text.find("opencv-matrix") == std::string::npos) throw std::runtime_error("no 3x3 matrix in " + name);
    int rows = 0;
    int cols = 0;
    std::istringstream(detail::storage_value(text, "rows", xml)) >> rows;
    std::istringstream(detail::storage_value(text, "cols", xml)) >> cols;
    if (rows != 3 || cols != 3) throw std::runtime_error("no 3x3 matrix in " + name);
    numbers_text = detail::storage_value(text, "data", xml);
    if (yaml) {
      for (char& c : numbers_text) {
        if (c == ',') c = ' ';
      }
    }
  }
  cv::Matx33d h;
  std::istringstream numbers(numbers_text);
  for (int i = 0; i < 9; ++i) {
    if (!(numbers >> h.val[i])) throw std::runtime_error("expected 9 numbers in " + name);
  }
  for (double v : h.val) {
    if (!std::isfinite(v)) throw std::runtime_error("the homography in " + name + " is not finite");
  }
  const double det = cv::determinant(h);
  if (!std::isfinite(det) || det == 0.0) throw std::runtime_error("the homography in " + name + " is singular");
  return h;
}

/// parse_homography() of a file.
inline cv::Matx33d read_homography(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read homography " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return parse_homography(text.str(), path);
}

}  // namespace affine_orb::examples
