#pragma once
/// \file
/// Umbrella header: the whole public API of affine_orb.

#include "affine_orb/brisk.hpp"
#include "affine_orb/descriptor.hpp"
#include "affine_orb/detector.hpp"
#include "affine_orb/distribution.hpp"
#include "affine_orb/extractor.hpp"
#include "affine_orb/fast.hpp"
#include "affine_orb/features.hpp"
#include "affine_orb/fundamental.hpp"
#include "affine_orb/harris.hpp"
#include "affine_orb/homography.hpp"
#include "affine_orb/image_correction.hpp"
#include "affine_orb/matcher.hpp"
#include "affine_orb/model_selection.hpp"
#include "affine_orb/orientation.hpp"
#include "affine_orb/pyramid.hpp"
#include "affine_orb/ransac.hpp"
#include "affine_orb/rbrief.hpp"
