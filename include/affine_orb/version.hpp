#pragma once
/// \file
/// The library's version, the one place it is defined: CMakeLists.txt reads the three macros below
/// for project(VERSION), and with it the CMake package version, the pkg-config file, the Debian
/// packages and the Python module's __version__. Before 1.0 a MINOR step may change the API, so the
/// CMake package accepts only a request for the same MAJOR.MINOR (find_package(affine_orb 0.2)).

/// Major version.
#define AFFINE_ORB_VERSION_MAJOR 0
/// Minor version: a new one for a release that adds to or changes the API.
#define AFFINE_ORB_VERSION_MINOR 2
/// Patch version: a new one for a release of fixes that leave the API as it is.
#define AFFINE_ORB_VERSION_PATCH 0

// Internal: the decimal text of a macro's value.
#define AFFINE_ORB_DETAIL_STRINGIFY_(x) #x
#define AFFINE_ORB_DETAIL_STRINGIFY(x) AFFINE_ORB_DETAIL_STRINGIFY_(x)

/// "MAJOR.MINOR.PATCH", e.g. "0.2.0".
#define AFFINE_ORB_VERSION_STRING                       \
  AFFINE_ORB_DETAIL_STRINGIFY(AFFINE_ORB_VERSION_MAJOR) \
  "." AFFINE_ORB_DETAIL_STRINGIFY(AFFINE_ORB_VERSION_MINOR) "." AFFINE_ORB_DETAIL_STRINGIFY(AFFINE_ORB_VERSION_PATCH)

namespace affine_orb {

/// The version of the headers this translation unit was compiled with, "MAJOR.MINOR.PATCH"
/// (AFFINE_ORB_VERSION_STRING).
constexpr const char* version() { return AFFINE_ORB_VERSION_STRING; }

}  // namespace affine_orb
