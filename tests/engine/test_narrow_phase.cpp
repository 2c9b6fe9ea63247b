#include <gtest/gtest.h>

#include <random>

#include "narrow_phase.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

using testing::WorldFixture;

// Pair candidates of two bodies in a large box (no walls involved), r = 1, s = 2.
std::vector<Candidate> pair_candidates(testing::Body a, testing::Body b,
                                       ThreadScratch* out = nullptr) {
  WorldFixture f(1000, 1, {a, b});
  ThreadScratch local;
  ThreadScratch& s = out ? *out : local;
  test_row(f.w, 0, 1, 2, s);
  return s.candidates;
}

TEST(NarrowPhase, ApproachingPairCollidesAtTheSmallerRoot) {
  // d = 10, closing 10 per sub-step: contact at distance 2 after t = 0.8.
  const auto c = pair_candidates({100, 100, 5, 0}, {110, 100, -5, 0});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c[0].t, 0.8);
  EXPECT_EQ(c[0].i, 0u);
  EXPECT_EQ(c[0].j, 1u);
}

TEST(NarrowPhase, RecedingPairIsNoCandidate) {
  EXPECT_TRUE(pair_candidates({100, 100, -5, 0}, {103, 100, 5, 0}).empty());
}

TEST(NarrowPhase, EqualVelocitiesAreNoCandidate) {
  EXPECT_TRUE(pair_candidates({100, 100, 3, 4}, {103, 100, 3, 4}).empty());
}

TEST(NarrowPhase, ExactGrazeIsNoCandidate) {
  // Closest approach is exactly s = 2: disc = 25 * 4 - (0 - 2 * -5)^2 = 0.
  EXPECT_TRUE(pair_candidates({100, 100, 0, 0}, {110, 102, -5, 0}).empty());
  // A hair closer does collide.
  EXPECT_EQ(pair_candidates({100, 100, 0, 0}, {104, 101.999, -5, 0}).size(), 1u);
}

TEST(NarrowPhase, OverlappingApproachingCollidesAtZero) {
  ThreadScratch s;
  const auto c = pair_candidates({100, 100, 1, 0}, {101, 100, -1, 0}, &s);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].t, 0.0);
  EXPECT_EQ(s.overlaps, 1u);
}

TEST(NarrowPhase, OverlappingRecedingIsCountedButNoCandidate) {
  ThreadScratch s;
  EXPECT_TRUE(pair_candidates({100, 100, -1, 0}, {101, 100, 1, 0}, &s).empty());
  EXPECT_EQ(s.overlaps, 1u);
}

TEST(NarrowPhase, TouchAtExactlyOneCountsAndJustAfterDoesNot) {
  // Gap 8 closed at speed 8: touching at t = 1 exactly.
  const auto at_one = pair_candidates({100, 100, 8, 0}, {110, 100, 0, 0});
  ASSERT_EQ(at_one.size(), 1u);
  EXPECT_EQ(at_one[0].t, 1.0);
  EXPECT_TRUE(pair_candidates({100, 100, 8, 0}, {110.5, 100, 0, 0}).empty());
}

TEST(NarrowPhase, OrderOfThePairDoesNotChangeTheResult) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> pos(0, 20), vel(-6, 6);
  for (int k = 0; k < 2000; ++k) {
    const testing::Body a{pos(rng), pos(rng), vel(rng), vel(rng)};
    const testing::Body b{pos(rng), pos(rng), vel(rng), vel(rng)};
    const auto ab = pair_candidates(a, b), ba = pair_candidates(b, a);
    ASSERT_EQ(ab.size(), ba.size());
    if (!ab.empty()) {
      EXPECT_EQ(ab[0].t, ba[0].t);  // bit-identical, not just close
    }
  }
}

// The vectorized row must report exactly the pairs the scalar test accepts, on rows long enough
// to exercise whole blocks, remainders and rescans.
TEST(NarrowPhase, RowKernelMatchesThePairByPairTest) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(1, 99), vel(-8, 8);
  std::vector<testing::Body> bodies;
  for (int k = 0; k < 300; ++k) bodies.push_back({pos(rng), pos(rng), vel(rng), vel(rng)});
  WorldFixture f(100, 1, bodies);
  for (std::uint32_t i = 0; i < 300; ++i) {
    ThreadScratch row, single;
    test_row(f.w, i, i + 1, 300, row);
    for (std::uint32_t j = i + 1; j < 300; ++j) test_pair(f.w, i, j, single);
    ASSERT_EQ(row.candidates.size(), single.candidates.size()) << "row " << i;
    for (std::size_t k = 0; k < row.candidates.size(); ++k) {
      EXPECT_EQ(row.candidates[k].j, single.candidates[k].j);
      EXPECT_EQ(row.candidates[k].t, single.candidates[k].t);
    }
    EXPECT_EQ(row.overlaps, single.overlaps);
    EXPECT_EQ(row.pair_tests, 299u - i);
  }
}

}  // namespace
}  // namespace particle::detail
