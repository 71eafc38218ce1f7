#pragma once
/// \file
/// The 0.2 path of affine_orb/extraction/view_session.hpp: warns and includes it (deprecated,
/// removed in 0.4). ViewCursor is gone: Extractor::extract_image() returns a ViewSession.

#include "affine_orb/core/detail/deprecated_path.hpp"
AFFINE_ORB_DEPRECATED_PATH(
    "affine_orb/extraction/view_cursor.hpp is deprecated: include affine_orb/extraction/view_session.hpp")
#include "affine_orb/extraction/view_session.hpp"
