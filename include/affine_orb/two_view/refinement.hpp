#pragma once
/// \file
/// The 0.2 path of affine_orb/two_view/alignment.hpp: warns and includes it (deprecated, removed in 0.4).

#include "affine_orb/core/detail/deprecated_path.hpp"
AFFINE_ORB_DEPRECATED_PATH(
    "affine_orb/two_view/refinement.hpp is deprecated: include affine_orb/two_view/alignment.hpp")
#include "affine_orb/two_view/alignment.hpp"
