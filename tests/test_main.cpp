// The doctest main of every test program. A test case that reads the evaluation data
// (AFFINE_ORB_DATA_DIR: Oxford sequences, KITTI 06 frames; docs/data.md) is in doctest's test suite
// "data". tests/CMakeLists.txt registers each program twice: without that suite, and as
// <program>_data, labelled "data", which passes --needs-data. A run given --needs-data first checks
// that the data is there; when it is not, it names what is missing and exits with
// affine_orb::test::kSkipReturnCode, which ctest reports as a skip (SKIP_RETURN_CODE).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstring>
#include <iostream>
#include <vector>

#include "test_data.hpp"

int main(int argc, char** argv) {
  std::vector<char*> args;
  bool needs_data = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--needs-data") == 0) {
      needs_data = true;
    } else {
      args.push_back(argv[i]);
    }
  }
  if (needs_data) {
    const std::string missing = affine_orb::test::missing_data();
    if (!missing.empty()) {
      std::cout << "SKIPPED: the evaluation data is missing: " << missing
                << " (configure with -DAFFINE_ORB_DATA_DIR=<dir>; docs/data.md says where it comes from)\n";
      return affine_orb::test::kSkipReturnCode;
    }
  }
  doctest::Context context(static_cast<int>(args.size()), args.data());
  return context.run();
}
