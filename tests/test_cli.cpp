// The examples' command-line helpers (support/cli.hpp): numeric values parsed whole, errors that
// name the flag and the value, and the plot title fitted before the legend.
#include <doctest/doctest.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cli.hpp"

namespace {

affine_orb::examples::Args make_args(std::vector<std::string> words) {
  static std::vector<std::string> storage;
  storage = std::move(words);
  storage.insert(storage.begin(), "program");
  static std::vector<char*> argv;
  argv.clear();
  for (std::string& w : storage) argv.push_back(w.data());
  return affine_orb::examples::Args(static_cast<int>(argv.size()), argv.data());
}

std::string message(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("integers and numbers are parsed whole, with the flag and the value in every error") {
  auto args = make_args({"--features", "1500", "--max-tilt", "2.5", "--threads", "-3", "--ratio", "1e-2"});
  CHECK(args.integer("--features", 7) == 1500);
  CHECK(args.real("--max-tilt", 0.0) == 2.5);
  CHECK(args.integer("--threads", 1) == -3);  // range checks belong to the caller
  CHECK(args.real("--ratio", 0.0) == 0.01);
  CHECK(args.integer("--absent", 42) == 42);
  for (const std::string bad : {"abc", "9000x", "", " 12", "1.5", "99999999999", "0x10", "12 "}) {
    CAPTURE(bad);
    if (bad.empty()) continue;  // an empty value means "absent" to value()
    CHECK(message([&] { affine_orb::examples::Args::parse_integer("--features", bad); }) ==
          "--features: expected an integer, got \"" + bad + "\"");
  }
  for (const std::string bad : {"abc", "2.5.1", "nan", "inf", "1e999", "2,5", " 1"}) {
    CAPTURE(bad);
    CHECK(message([&] { affine_orb::examples::Args::parse_real("--max-tilt", bad); }) ==
          "--max-tilt: expected a number, got \"" + bad + "\"");
  }
  CHECK(affine_orb::examples::Args::parse_real("--x", "-0.25") == -0.25);
  auto missing = make_args({"--features"});
  CHECK(message([&] { missing.integer("--features", 1); }) == "--features needs a value");
}

TEST_CASE("a long plot title is cut from the front to end before the legend") {
  const std::string path = "/very/long/path/to/a/sequence/directory/that/goes/on/and/on/kitti/sequences/06/image_0";
  const std::string fitted = affine_orb::examples::fit_text(path, 610, cv::FONT_HERSHEY_SIMPLEX, 0.5);
  int baseline = 0;
  CHECK(cv::getTextSize(fitted, cv::FONT_HERSHEY_SIMPLEX, 0.5, 1, &baseline).width <= 610);
  CHECK(fitted.rfind("...", 0) == 0);
  CHECK(path.size() > fitted.size());
  CHECK(path.substr(path.size() - (fitted.size() - 3)) == fitted.substr(3));  // the tail is kept
  CHECK(affine_orb::examples::fit_text("kitti06", 610, cv::FONT_HERSHEY_SIMPLEX, 0.5) == "kitti06");
}
