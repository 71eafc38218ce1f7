// libFuzzer target: the text readers of the examples (support/homography_io.hpp,
// support/sequence_io.hpp). The first byte picks the reader, the rest is the file's text. A
// reader must either throw std::runtime_error or return what its documentation promises; any other
// exception, a crash or a sanitizer report is a finding.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "homography_io.hpp"
#include "sequence_io.hpp"

namespace {

using affine_orb::fuzz::require;

namespace ex = affine_orb::examples;

/// Lines of `text` that content_lines() must keep: not blank once the comment is cut.
std::size_t content_line_count(const std::string& text) {
  std::size_t count = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") != std::string::npos) ++count;
    if (end == text.size()) break;
    start = end + 1;
  }
  return count;
}

bool finite_pose(const ex::CameraPose& p) { return p.rotation.allFinite() && p.position.allFinite(); }

void check(std::uint8_t reader, const std::string& text) {
  switch (reader % 6) {
    case 0: {
      const cv::Matx33d h = ex::parse_homography(text, "fuzz");
      for (double v : h.val) require(std::isfinite(v));
      require(cv::determinant(h) != 0.0);
      break;
    }
    case 1: {
      const affine_orb::PinholeCamera c = ex::parse_calibration(text, "fuzz");
      require(std::isfinite(c.fx) && c.fx > 0.0 && std::isfinite(c.fy) && c.fy > 0.0);
      require(std::isfinite(c.cx) && std::isfinite(c.cy));
      break;
    }
    case 2: {
      const std::vector<double> times = ex::parse_times(text, "fuzz");
      require(times.size() == content_line_count(text));
      for (double t : times) require(std::isfinite(t));
      break;
    }
    case 3: {
      const std::vector<ex::CameraPose> poses = ex::parse_kitti_poses(text, "fuzz");
      require(poses.size() == content_line_count(text));
      for (const ex::CameraPose& p : poses) require(finite_pose(p));
      break;
    }
    case 4: {
      const auto list = ex::parse_tum_list(text, "fuzz");
      require(!list.empty() && list.size() == content_line_count(text));
      for (std::size_t i = 0; i < list.size(); ++i) {
        require(std::isfinite(list[i].first) && !list[i].second.empty());
        require(list[i].second.find_first_of(" \t\r\n#") == std::string::npos);
        if (i > 0) require(list[i - 1].first <= list[i].first);
      }
      break;
    }
    default: {
      const auto poses = ex::parse_tum_groundtruth(text, "fuzz");
      require(poses.size() == content_line_count(text));
      for (std::size_t i = 0; i < poses.size(); ++i) {
        const ex::CameraPose& p = poses[i].second;
        require(std::isfinite(poses[i].first) && finite_pose(p));
        // A rotation: orthonormal with determinant +1.
        require((p.rotation.transpose() * p.rotation - Eigen::Matrix3d::Identity()).norm() < 1e-9);
        require(std::abs(p.rotation.determinant() - 1.0) < 1e-9);
        if (i > 0) require(poses[i - 1].first <= poses[i].first);
      }
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    check(data[0], text);
  } catch (const std::runtime_error&) {
    // A documented rejection.
  }
  return 0;
}
