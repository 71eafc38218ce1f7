#pragma once
/// \file
/// The 0.1 path of affine_orb/descriptors/brisk.hpp: warns and includes it (deprecated, removed in 0.3).

#include "affine_orb/core/detail/deprecated_path.hpp"
AFFINE_ORB_DEPRECATED_PATH("affine_orb/brisk.hpp is deprecated: include affine_orb/descriptors/brisk.hpp")
#include "affine_orb/descriptors/brisk.hpp"
