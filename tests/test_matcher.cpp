// Hamming matcher (SPEC §4) against a naive reference written here: bit-by-bit distances over the
// descriptor bytes, every distance of a query computed and fully sorted, the tests of
// MatcherOptions applied to the sorted lists.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "affine_orb/core/features.hpp"
#include "affine_orb/matching/matcher.hpp"
#include "test_simd.hpp"

namespace {

using affine_orb::BinaryDescriptor;
using affine_orb::KnnMatch;
using affine_orb::Match;
using affine_orb::MatcherOptions;

template <int Bits>
using Descriptors = std::vector<BinaryDescriptor<Bits>>;

// Bit by bit over the bytes of the two descriptors.
template <int Bits>
int naive_distance(const BinaryDescriptor<Bits>& a, const BinaryDescriptor<Bits>& b) {
  unsigned char bytes_a[Bits / 8];
  unsigned char bytes_b[Bits / 8];
  std::memcpy(bytes_a, a.data(), sizeof(bytes_a));
  std::memcpy(bytes_b, b.data(), sizeof(bytes_b));
  int distance = 0;
  for (int k = 0; k < Bits / 8; ++k) {
    for (int bit = 0; bit < 8; ++bit) distance += ((bytes_a[k] >> bit) & 1) != ((bytes_b[k] >> bit) & 1);
  }
  return distance;
}

int naive_popcount(std::uint64_t x) {
  int count = 0;
  for (int bit = 0; bit < 64; ++bit) count += static_cast<int>((x >> bit) & 1);
  return count;
}

// All (distance, index) pairs from `from` to every element of `to`, sorted.
template <int Bits>
std::vector<std::pair<int, int>> sorted_distances(const BinaryDescriptor<Bits>& from, const Descriptors<Bits>& to) {
  std::vector<std::pair<int, int>> all;
  for (std::size_t j = 0; j < to.size(); ++j) all.emplace_back(naive_distance<Bits>(from, to[j]), static_cast<int>(j));
  std::sort(all.begin(), all.end());
  return all;
}

template <int Bits>
void check_knn_equals_naive(const std::vector<KnnMatch>& knn, const Descriptors<Bits>& query,
                            const Descriptors<Bits>& train) {
  REQUIRE(knn.size() == query.size());
  for (std::size_t i = 0; i < query.size(); ++i) {
    const auto all = sorted_distances<Bits>(query[i], train);
    CAPTURE(i);
    CHECK(knn[i].query == static_cast<int>(i));
    REQUIRE(knn[i].count == static_cast<int>(std::min<std::size_t>(2, train.size())));
    if (!all.empty()) {
      CHECK(knn[i].best.distance == all[0].first);
      CHECK(knn[i].best.train == all[0].second);
    }
    if (all.size() >= 2) {
      CHECK(knn[i].second.distance == all[1].first);
      CHECK(knn[i].second.train == all[1].second);
    } else {
      CHECK(knn[i].second.distance == std::numeric_limits<int>::max());
    }
  }
}

template <int Bits>
std::vector<Match> naive_match(const Descriptors<Bits>& query, const Descriptors<Bits>& train,
                               const MatcherOptions& options) {
  std::vector<Match> matches;
  if (train.empty()) return matches;
  for (std::size_t i = 0; i < query.size(); ++i) {
    const auto all = sorted_distances<Bits>(query[i], train);
    const int d1 = all[0].first;
    const int j1 = all[0].second;
    if (d1 > options.max_distance) continue;
    if (all.size() >= 2 && !(static_cast<double>(d1) < static_cast<double>(options.ratio) * all[1].first)) continue;
    if (options.cross_check &&
        sorted_distances<Bits>(train[static_cast<std::size_t>(j1)], query)[0].second != static_cast<int>(i)) {
      continue;
    }
    matches.push_back({static_cast<int>(i), j1, d1});
  }
  return matches;
}

void check_same_matches(const std::vector<Match>& got, const std::vector<Match>& expected) {
  REQUIRE(got.size() == expected.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    CAPTURE(k);
    CHECK(got[k].query == expected[k].query);
    CHECK(got[k].train == expected[k].train);
    CHECK(got[k].distance == expected[k].distance);
  }
}

template <int Bits>
Descriptors<Bits> uniform_descriptors(std::size_t n, std::mt19937_64& rng) {
  Descriptors<Bits> d(n);
  for (auto& descriptor : d) {
    for (auto& word : descriptor) word = rng();
  }
  return d;
}

// Few bits set, among a handful of positions, and some exact copies: distances repeat a lot.
template <int Bits>
Descriptors<Bits> tied_descriptors(std::size_t n, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> count(0, 4);
  std::uniform_int_distribution<int> position(0, 11);
  std::uniform_int_distribution<int> copy(0, 9);
  Descriptors<Bits> d(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && copy(rng) == 0) {
      d[i] = d[std::uniform_int_distribution<std::size_t>(0, i - 1)(rng)];
      continue;
    }
    d[i].fill(0);
    for (int k = count(rng); k > 0; --k) {
      const int bit = position(rng) * (Bits / 12);  // spread over all the words
      d[i][static_cast<std::size_t>(bit / 64)] |= std::uint64_t{1} << (bit % 64);
    }
  }
  return d;
}

// Each word random with few bits (about 1 in 8), so distances land near 0 ... Bits/4: near the
// max_distance values under test, with ties.
template <int Bits>
Descriptors<Bits> sparse_descriptors(std::size_t n, std::mt19937_64& rng) {
  Descriptors<Bits> d(n);
  for (auto& descriptor : d) {
    for (auto& word : descriptor) word = rng() & rng() & rng();
  }
  return d;
}

// The (query size, train size) pairs every check runs on: empty, tiny, uneven, and sizes around the
// 64/128/256-lane blocks of the bit-sliced search.
const std::vector<std::pair<std::size_t, std::size_t>> kSizes = {
    {0, 0},   {0, 5},   {5, 0},   {1, 1},    {1, 2},    {2, 1},    {2, 2},   {3, 1},   {37, 53}, {53, 37},
    {20, 63}, {20, 64}, {20, 65}, {17, 127}, {17, 128}, {17, 129}, {9, 255}, {9, 256}, {9, 257}, {11, 300}};

template <int Bits>
std::vector<std::pair<Descriptors<Bits>, Descriptors<Bits>>> test_sets() {
  std::mt19937_64 rng(20240611 + Bits);
  std::vector<std::pair<Descriptors<Bits>, Descriptors<Bits>>> sets;
  for (const auto& [nq, nt] : kSizes) {
    // One statement per set: the order of the draws must not depend on argument evaluation order.
    for (const auto generate : {uniform_descriptors<Bits>, tied_descriptors<Bits>, sparse_descriptors<Bits>}) {
      Descriptors<Bits> query = generate(nq, rng);
      Descriptors<Bits> train = generate(nt, rng);
      sets.emplace_back(std::move(query), std::move(train));
    }
  }
  // Everything identical: every distance is 0, ties everywhere.
  sets.emplace_back(Descriptors<Bits>(7, BinaryDescriptor<Bits>{}), Descriptors<Bits>(131, BinaryDescriptor<Bits>{}));
  return sets;
}

template <int Bits>
void check_hamming_distance() {
  std::mt19937_64 rng(7 + Bits);
  const auto a = uniform_descriptors<Bits>(200, rng);
  const auto b = sparse_descriptors<Bits>(200, rng);
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(affine_orb::hamming_distance(a[i], b[i]) == naive_distance<Bits>(a[i], b[i]));
    CHECK(affine_orb::hamming_distance(a[i], a[i]) == 0);
    BinaryDescriptor<Bits> complement{};
    for (std::size_t w = 0; w < complement.size(); ++w) complement[w] = ~a[i][w];
    CHECK(affine_orb::hamming_distance(a[i], complement) == Bits);
  }
  // The row kernels: every compiled path against the bit-by-bit count, a row of mixed densities.
  BinaryDescriptor<Bits> query = a[0];
  Descriptors<Bits> row = a;
  row.insert(row.end(), b.begin(), b.end());
  std::vector<int> expected(row.size());
  for (std::size_t j = 0; j < row.size(); ++j) expected[j] = naive_distance<Bits>(query, row[j]);
  std::vector<int> out(row.size(), -1);
  affine_orb::detail::hamming_row(query, row.data(), row.size(), out.data());
  CHECK(out == expected);
  std::fill(out.begin(), out.end(), -1);
  affine_orb::detail::hamming_row_generic(query, row.data(), row.size(), out.data());
  CHECK(out == expected);
#if AFFINE_ORB_AVX2_RUNTIME
  if (affine_orb::detail::cpu_has_avx2()) {
    std::fill(out.begin(), out.end(), -1);
    affine_orb::detail::hamming_row_popcnt(query, row.data(), row.size(), out.data());
    CHECK(out == expected);
  }
#endif
}

template <int Bits>
void check_knn2() {
  MESSAGE(affine_orb::test::avx2_paths_message());
  for (const auto& set : test_sets<Bits>()) {
    const Descriptors<Bits>& query = set.first;
    const Descriptors<Bits>& train = set.second;
    CAPTURE(query.size());
    CAPTURE(train.size());
    check_knn_equals_naive<Bits>(affine_orb::knn2(query, train), query, train);
    check_knn_equals_naive<Bits>(affine_orb::detail::bitsliced128::knn2_bitsliced<std::uint64_t>(query, train), query,
                                 train);
    check_knn_equals_naive<Bits>(
        affine_orb::detail::bitsliced128::knn2_bitsliced<affine_orb::detail::LaneVector128>(query, train), query,
        train);
#if AFFINE_ORB_KNN2_LANES256
    if (affine_orb::detail::cpu_has_avx2()) {
      check_knn_equals_naive<Bits>(
          affine_orb::detail::bitsliced256::knn2_bitsliced<affine_orb::detail::LaneVector256>(query, train), query,
          train);
    }
#endif
  }
}

template <int Bits>
void check_match_all_options() {
  int combinations = 0;
  for (const auto& set : test_sets<Bits>()) {
    const Descriptors<Bits>& query = set.first;
    const Descriptors<Bits>& train = set.second;
    for (const float ratio : {0.6f, 0.8f, 1.0f, 1.5f}) {
      for (const bool cross_check : {false, true}) {
        for (const int max_distance : {0, 40, 80, Bits}) {
          MatcherOptions options;
          options.ratio = ratio;
          options.cross_check = cross_check;
          options.max_distance = max_distance;
          CAPTURE(query.size());
          CAPTURE(train.size());
          CAPTURE(ratio);
          CAPTURE(cross_check);
          CAPTURE(max_distance);
          check_same_matches(affine_orb::match(query, train, options), naive_match<Bits>(query, train, options));
          ++combinations;
        }
      }
    }
  }
  CHECK(combinations == 32 * (3 * static_cast<int>(kSizes.size()) + 1));
}

}  // namespace

TEST_CASE("popcount64 and its portable fallback count bits") {
  std::mt19937_64 rng(3);
  std::vector<std::uint64_t> words = {0, ~std::uint64_t{0}, 1, std::uint64_t{1} << 63, 0x5555555555555555ULL};
  for (int k = 0; k < 1000; ++k) words.push_back(rng() & rng());
  for (int k = 0; k < 1000; ++k) words.push_back(rng());
  for (const std::uint64_t x : words) {
    CAPTURE(x);
    CHECK(affine_orb::detail::popcount64(x) == naive_popcount(x));
    CHECK(affine_orb::detail::popcount64_portable(x) == naive_popcount(x));
    if (x != 0) {
      int lowest = 0;
      while (((x >> lowest) & 1) == 0) ++lowest;
      CHECK(affine_orb::detail::lowest_set_bit(x) == lowest);
    }
  }
  static_assert(affine_orb::detail::popcount64_portable(0xffULL) == 8);
}

TEST_CASE("hamming_distance equals a bit-by-bit count, 256 and 512 bits") {
  check_hamming_distance<256>();
  check_hamming_distance<512>();
}

TEST_CASE("transpose_bits64 transposes a 64x64 bit matrix") {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    std::array<std::uint64_t, 64> m{};
    for (auto& row : m) row = rng();
    auto t = m;
    affine_orb::detail::transpose_bits64(t);
    for (int r = 0; r < 64; ++r) {
      for (int c = 0; c < 64; ++c) REQUIRE(((t[c] >> r) & 1) == ((m[r] >> c) & 1));
    }
  }
}

TEST_CASE("knn2 equals a naive sort of all distances, 256 bits, every search path") { check_knn2<256>(); }

TEST_CASE("knn2 equals a naive sort of all distances, 512 bits, every search path") { check_knn2<512>(); }

TEST_CASE("knn2 on other descriptor widths (64 and 192 bits)") {
  std::mt19937_64 rng(5);
  const auto q64 = sparse_descriptors<64>(30, rng);
  const auto t64 = sparse_descriptors<64>(140, rng);
  check_knn_equals_naive<64>(affine_orb::knn2(q64, t64), q64, t64);
  const auto q192 = tied_descriptors<192>(30, rng);
  const auto t192 = uniform_descriptors<192>(140, rng);
  check_knn_equals_naive<192>(affine_orb::knn2(q192, t192), q192, t192);
}

TEST_CASE("match equals the naive reference for every option combination, 256 bits") { check_match_all_options<256>(); }

TEST_CASE("match equals the naive reference for every option combination, 512 bits") { check_match_all_options<512>(); }

TEST_CASE("passes_ratio_test follows the documented definition") {
  KnnMatch m;
  CHECK_FALSE(affine_orb::passes_ratio_test(m, 0.8f));  // no neighbour
  m.count = 1;
  m.best = {3, 200};
  CHECK(affine_orb::passes_ratio_test(m, 0.01f));  // a single neighbour always passes
  m.count = 2;
  m.best = {3, 30};
  m.second = {4, 40};
  CHECK_FALSE(affine_orb::passes_ratio_test(m, 0.75f));  // 30 < 0.75 * 40 is false: strict
  CHECK(affine_orb::passes_ratio_test(m, 0.76f));
  m.second.distance = 30;
  CHECK_FALSE(affine_orb::passes_ratio_test(m, 1.0f));  // a tie is not strictly closer
  CHECK(affine_orb::passes_ratio_test(m, 1.5f));        // ratio > 1 accepts ties
  m.best.distance = 0;
  m.second.distance = 0;
  CHECK_FALSE(affine_orb::passes_ratio_test(m, 1.5f));  // 0 < 0 never holds
}

TEST_CASE("the cv::Mat overload equals the typed one and rejects bad matrices") {
  std::mt19937_64 rng(17);
  const auto q256 = tied_descriptors<256>(37, rng);
  const auto t256 = sparse_descriptors<256>(53, rng);
  const auto q512 = sparse_descriptors<512>(41, rng);
  const auto t512 = uniform_descriptors<512>(29, rng);
  MatcherOptions options;
  options.ratio = 1.5f;
  options.cross_check = true;
  const cv::Mat mq256 = affine_orb::descriptors_to_mat(q256);
  const cv::Mat mt256 = affine_orb::descriptors_to_mat(t256);
  const cv::Mat mq512 = affine_orb::descriptors_to_mat(q512);
  const cv::Mat mt512 = affine_orb::descriptors_to_mat(t512);
  check_same_matches(affine_orb::match(mq256, mt256, options), affine_orb::match(q256, t256, options));
  check_same_matches(affine_orb::match(mq512, mt512, options), affine_orb::match(q512, t512, options));
  CHECK_FALSE(affine_orb::match(q256, t256, options).empty());

  SUBCASE("rows that are not contiguous (a column range of a wider matrix)") {
    cv::Mat wide(mq256.rows, 40, CV_8U, cv::Scalar(0xa5));
    mq256.copyTo(wide.colRange(4, 36));
    const cv::Mat view = wide.colRange(4, 36);
    REQUIRE_FALSE(view.isContinuous());
    check_same_matches(affine_orb::match(view, mt256, options), affine_orb::match(q256, t256, options));
  }
  SUBCASE("zero rows give an empty result") {
    CHECK(affine_orb::match(cv::Mat(), mt256).empty());
    CHECK(affine_orb::match(mq256, cv::Mat()).empty());
    CHECK(affine_orb::match(cv::Mat(0, 32, CV_8U), cv::Mat(0, 32, CV_8U)).empty());
    CHECK(affine_orb::match(cv::Mat(0, 32, CV_8U), mt256).empty());
  }
  SUBCASE("bad matrices throw std::invalid_argument") {
    CHECK_THROWS_AS(affine_orb::match(mq256, mt512), std::invalid_argument);  // 32 vs 64 bytes
    CHECK_THROWS_AS(affine_orb::match(mq512, mt256), std::invalid_argument);
    cv::Mat as_float;
    mq256.convertTo(as_float, CV_32F);
    CHECK_THROWS_AS(affine_orb::match(as_float, as_float), std::invalid_argument);
    CHECK_THROWS_AS(affine_orb::match(mq256, as_float), std::invalid_argument);
    const cv::Mat colour(37, 32, CV_8UC3, cv::Scalar(1, 2, 3));
    CHECK_THROWS_AS(affine_orb::match(colour, colour), std::invalid_argument);
    const cv::Mat odd(37, 31, CV_8U, cv::Scalar(7));
    CHECK_THROWS_AS(affine_orb::match(odd, odd), std::invalid_argument);
    const cv::Mat too_wide(37, 72, CV_8U, cv::Scalar(7));
    CHECK_THROWS_AS(affine_orb::match(too_wide, too_wide), std::invalid_argument);
    MatcherOptions bad;
    bad.ratio = -1.0f;
    CHECK_THROWS_AS(affine_orb::match(mq256, mt256, bad), std::invalid_argument);
  }
}

TEST_CASE("MatcherOptions::check rejects nonsense") {
  CHECK_NOTHROW(MatcherOptions{}.check());
  for (const float ratio :
       {std::numeric_limits<float>::quiet_NaN(), -0.5f, 0.0f, std::numeric_limits<float>::infinity()}) {
    MatcherOptions options;
    options.ratio = ratio;
    CAPTURE(ratio);
    CHECK_THROWS_AS(options.check(), std::invalid_argument);
    const Descriptors<256> one(1, BinaryDescriptor<256>{});
    CHECK_THROWS_AS(affine_orb::match(one, one, options), std::invalid_argument);
  }
  MatcherOptions negative;
  negative.max_distance = -1;
  CHECK_THROWS_AS(negative.check(), std::invalid_argument);
  MatcherOptions zero;
  zero.max_distance = 0;
  CHECK_NOTHROW(zero.check());
}
