#pragma once
/// \file
/// The 0.1 path of affine_orb/geometry/fundamental.hpp: warns and includes it (deprecated, removed in 0.3).

#include "affine_orb/core/detail/deprecated_path.hpp"
AFFINE_ORB_DEPRECATED_PATH("affine_orb/fundamental.hpp is deprecated: include affine_orb/geometry/fundamental.hpp")
#include "affine_orb/geometry/fundamental.hpp"
