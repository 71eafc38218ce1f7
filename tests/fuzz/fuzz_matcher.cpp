// libFuzzer target: Hamming matching. The bytes give two descriptor sets of 256 bits
// (up to 40 query and 40 train descriptors, few distinct values so that ties are common), a ratio,
// a maximum distance and the cross-check flag; knn2() must equal a brute-force search (ties to the
// smaller train index) and match() must keep exactly the queries its documented tests accept.
//   clang++ -fsanitize=fuzzer,address,undefined ... (see tests/CMakeLists.txt, AFFINE_ORB_BUILD_FUZZERS)
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "affine_orb/matching/matcher.hpp"
#include "fuzz_input.hpp"

namespace {

using affine_orb::fuzz::require;

using Descriptor = std::array<std::uint64_t, 4>;

/// Best and second-best train index and distance by brute force (ties: the smaller index).
struct Naive {
  int best = -1, best_distance = 0, second = -1, second_distance = 0;
};

Naive naive(const Descriptor& q, const std::vector<Descriptor>& train) {
  Naive n;
  for (int j = 0; j < static_cast<int>(train.size()); ++j) {
    int d = 0;
    for (int w = 0; w < 4; ++w)
      d += __builtin_popcountll(q[static_cast<std::size_t>(w)] ^
                                train[static_cast<std::size_t>(j)][static_cast<std::size_t>(w)]);
    if (n.best < 0 || d < n.best_distance) {
      n.second = n.best;
      n.second_distance = n.best_distance;
      n.best = j;
      n.best_distance = d;
    } else if (n.second < 0 || d < n.second_distance) {
      n.second = j;
      n.second_distance = d;
    }
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  const std::size_t queries = data[0] % 41;
  const std::size_t trains = data[1] % 41;
  affine_orb::MatcherOptions options;
  options.ratio = static_cast<float>(data[2]) / 100.0f;  // 0 is invalid
  options.max_distance = data[3] == 255 ? -1 : data[3];  // -1 is invalid
  options.cross_check = (data[4] & 1) != 0;
  std::size_t next = 5;
  // Each descriptor: one byte picks a 64-bit pattern repeated with a per-word twist, so that equal
  // and nearly equal descriptors (ties) are frequent.
  auto make = [&](std::size_t count) {
    std::vector<Descriptor> set(count);
    for (Descriptor& d : set) {
      const std::uint8_t b = next < size ? data[next++] : 0;
      for (std::size_t w = 0; w < 4; ++w)
        d[w] = (0x9E3779B97F4A7C15ull * (b >> 2)) ^ (static_cast<std::uint64_t>(b & 3) << (w * 9));
    }
    return set;
  };
  const std::vector<Descriptor> query = make(queries);
  const std::vector<Descriptor> train = make(trains);

  const std::vector<affine_orb::KnnMatch> knn = affine_orb::knn2(query, train);
  require(knn.size() == query.size());
  for (std::size_t i = 0; i < query.size(); ++i) {
    const Naive n = naive(query[i], train);
    const affine_orb::KnnMatch& m = knn[i];
    require(m.query == static_cast<int>(i));
    require(m.count == static_cast<int>(std::min<std::size_t>(2, train.size())));
    if (m.count >= 1) require(m.best.train == n.best && m.best.distance == n.best_distance);
    if (m.count == 2) require(m.second.train == n.second && m.second.distance == n.second_distance);
  }

  std::vector<affine_orb::Match> matches;
  try {
    matches = affine_orb::match(query, train, options);
  } catch (const std::invalid_argument&) {
    require(!(options.ratio > 0.0f) || options.max_distance < 0);
    return 0;
  }
  const std::vector<affine_orb::KnnMatch> back = affine_orb::knn2(train, query);
  std::size_t k = 0;
  for (std::size_t i = 0; i < query.size() && !train.empty(); ++i) {
    const affine_orb::KnnMatch& m = knn[i];
    bool accept = m.best.distance <= options.max_distance && affine_orb::passes_ratio_test(m, options.ratio);
    // The ratio test by its definition, in double precision.
    const bool ratio_ok =
        m.count < 2 || static_cast<double>(m.best.distance) <
                           static_cast<double>(options.ratio) * static_cast<double>(m.second.distance);
    require(affine_orb::passes_ratio_test(m, options.ratio) == ratio_ok);
    if (options.cross_check)
      accept = accept && back[static_cast<std::size_t>(m.best.train)].best.train == static_cast<int>(i);
    if (!accept) continue;
    require(k < matches.size());
    require(matches[k].query == static_cast<int>(i) && matches[k].train == m.best.train &&
            matches[k].distance == m.best.distance);
    ++k;
  }
  require(k == matches.size());
  return 0;
}
