#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "stages.hpp"

namespace particle::detail {
namespace {

TEST(Order, TimeThenWallBeforePairThenIndices) {
  std::vector<Candidate> c = {{0.5, 3, 7}, {0.5, 9, kWallX}, {0.25, 8, 9},
                              {0.5, 2, 9}, {0.5, 2, 8},      {0.5, 4, kWallCorner}};
  order_candidates(c);
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> expected = {
      {8, 9}, {4, kWallCorner}, {9, kWallX}, {2, 8}, {2, 9}, {3, 7}};
  ASSERT_EQ(c.size(), expected.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    EXPECT_EQ(c[k].i, expected[k].first) << k;
    EXPECT_EQ(c[k].j, expected[k].second) << k;
  }
}

TEST(Order, ResultDoesNotDependOnInputOrder) {
  std::mt19937_64 rng(3);
  std::vector<Candidate> c;
  for (std::uint32_t k = 0; k < 200; ++k)
    c.push_back({static_cast<double>(rng() % 4) / 4, k % 13, k % 3 ? 13 + k : kWallY});
  std::vector<Candidate> shuffled = c;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  order_candidates(c);
  order_candidates(shuffled);
  for (std::size_t k = 0; k < c.size(); ++k) {
    EXPECT_EQ(c[k].i, shuffled[k].i);
    EXPECT_EQ(c[k].j, shuffled[k].j);
  }
}

TEST(Filter, GreedyOneCollisionPerParticle) {
  const std::vector<Candidate> ordered = {{0.1, 1, kWallX}, {0.2, 0, 1}, {0.3, 0, 2},
                                          {0.4, 2, kWallY}, {0.5, 3, 4}, {0.6, 4, kWallX}};
  std::vector<std::uint8_t> taken(5, 0);
  std::vector<Candidate> accepted;
  filter_candidates(ordered, taken, accepted);
  ASSERT_EQ(accepted.size(), 3u);
  EXPECT_EQ(accepted[0].j, kWallX);  // 1 at the wall
  EXPECT_EQ(accepted[1].j, 2u);      // (0,1) dropped: 1 taken; (0,2) accepted
  EXPECT_EQ(accepted[2].i, 3u);      // 2's wall dropped; (3,4) accepted; 4's wall dropped
  EXPECT_EQ(std::count(taken.begin(), taken.end(), 1), 5);
}

}  // namespace
}  // namespace particle::detail
