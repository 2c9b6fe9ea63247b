#include <gtest/gtest.h>

#include <utility>

#include "helpers.hpp"
#include "particle/overlaps.hpp"

namespace particle {
namespace {

// Every pair against every other: the count and the first pair in (i, j) order.
Overlaps all_pairs(const Scene& s) {
  const Particles& p = s.particles;
  const double s2 = s.contact_distance() * s.contact_distance();
  Overlaps o;
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      const double dx = p.x[i] - p.x[j], dy = p.y[i] - p.y[j];
      if (dx * dx + dy * dy < s2 && o.pairs++ == 0)
        std::tie(o.first_i, o.first_j) = std::pair(i, j);
    }
  return o;
}

// Centres drawn anywhere in the box without rejection, so pairs
// overlap across cell borders, in corners and along the walls; from dilute to every disk touching
// several.
TEST(Overlaps, SameCountAndFirstPairAsEveryPairAgainstEveryOther) {
  for (const double r : {0.5, 2.0, 6.0, 30.0}) {
    Scene s = testing::random_scene(1500, 400, 0.1, 1, 11);
    s.r = r;
    Random rng(5);
    for (std::size_t i = 0; i < s.size(); ++i) {
      s.particles.x[i] = r + rng.uniform() * (s.L - 2 * r);
      s.particles.y[i] = r + rng.uniform() * (s.L - 2 * r);
    }
    const Overlaps want = all_pairs(s), got = find_overlaps(s);
    ASSERT_GT(want.pairs, 0u) << r;
    EXPECT_EQ(got.pairs, want.pairs) << r;
    EXPECT_EQ(got.first_i, want.first_i) << r;
    EXPECT_EQ(got.first_j, want.first_j) << r;
  }
}

// 6000 disks: 78 x 78 cells, so the radix sort by cell takes two passes of 7 bits; the first
// pair is not the first overlap met in cell order; on one to three threads.
TEST(Overlaps, ManyCellsSortedInTwoPasses) {
  Scene s = testing::random_scene(6000, 2000, 0.1, 1, 11);
  s.r = 4;
  Random rng(7);
  for (std::size_t i = 0; i < s.size(); ++i) {
    s.particles.x[i] = s.r + rng.uniform() * (s.L - 2 * s.r);
    s.particles.y[i] = s.r + rng.uniform() * (s.L - 2 * s.r);
  }
  const Overlaps want = all_pairs(s);
  ASSERT_GT(want.pairs, 10u);
  for (const int threads : {1, 2, 3}) {  // 12 ranges of the sorted disks at 3 threads
    const Overlaps got = find_overlaps(s, threads);
    EXPECT_EQ(got.pairs, want.pairs) << threads;
    EXPECT_EQ(got.first_i, want.first_i) << threads;
    EXPECT_EQ(got.first_j, want.first_j) << threads;
  }
}

}  // namespace
}  // namespace particle
