#pragma once
/// \file
/// Corner and the FAST circle (Rosten & Drummond, "Machine learning for high-speed corner
/// detection", ECCV 2006): what detection/fast.hpp detects and the geometry it tests.

#include <array>

namespace affine_orb {

/// Radius of the FAST circle in pixels: a pixel closer than this to the image border has no score.
inline constexpr int kFastRadius = 3;

/// The 16 circle offsets (dx, dy), clockwise from the top, as in Rosten & Drummond (2006), fig. 1.
inline constexpr std::array<std::array<int, 2>, 16> kFastCircle = {{{0, -3},
                                                                    {1, -3},
                                                                    {2, -2},
                                                                    {3, -1},
                                                                    {3, 0},
                                                                    {3, 1},
                                                                    {2, 2},
                                                                    {1, 3},
                                                                    {0, 3},
                                                                    {-1, 3},
                                                                    {-2, 2},
                                                                    {-3, 1},
                                                                    {-3, 0},
                                                                    {-3, -1},
                                                                    {-2, -2},
                                                                    {-1, -3}}};

/// A detected corner: integer pixel position in the image it was detected in, and its FAST score.
struct Corner {
  int x = 0;
  int y = 0;
  int score = 0;
};

}  // namespace affine_orb
