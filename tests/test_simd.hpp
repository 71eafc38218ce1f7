#pragma once
// What the SIMD tests could check on the CPU running them: the AVX2 kernels are compared with
// their references only where the CPU has AVX2, so each such test says which it was.
#include <string>

#include "affine_orb/core/detail/simd.hpp"

namespace affine_orb::test {

/// "AVX2 paths checked", or why they were not, for doctest's MESSAGE.
inline std::string avx2_paths_message() {
  return affine_orb::detail::cpu_has_avx2() ? "AVX2 paths checked" : "AVX2 paths not checked: no AVX2 on this CPU";
}

}  // namespace affine_orb::test
