#pragma once
/// \file
/// What the k = 2 nearest-neighbour search (knn2() in matching/matcher.hpp) finds for one query
/// descriptor: its two nearest train descriptors by Hamming distance.

#include <limits>

namespace affine_orb {

/// One neighbour of a query descriptor: index into the train descriptors and distance in bits. The
/// defaults mark an entry that holds no neighbour (distance larger than any real one).
struct Neighbour {
  int train = 0;
  int distance = std::numeric_limits<int>::max();
};

/// The two nearest train descriptors of one query descriptor, ties broken by the smaller train
/// index. `count` = min(2, number of train descriptors) says how many of `best`, `second` are real;
/// the others keep Neighbour's defaults.
struct KnnMatch {
  int query = 0;
  int count = 0;
  Neighbour best;
  Neighbour second;
};

}  // namespace affine_orb
