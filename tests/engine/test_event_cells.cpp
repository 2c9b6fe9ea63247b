// The event engine's cell grid (event/cells.hpp): cells never narrower than the contact distance
// whatever the cost model asks, the sizes the model picks on the scenes it was measured on, and
// a cell holding more particles than a prediction's first guess of room (the gather's growth).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "event/cells.hpp"
#include "helpers.hpp"

namespace particle {
namespace {

using detail::CellGrid;

double cells_per_particle(const CellGrid& g, std::size_t n) {
  return static_cast<double>(g.cells_per_axis()) * g.cells_per_axis() / static_cast<double>(n);
}

TEST(EventCells, NeverNarrowerThanTheContactDistance) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> log10(-3, 6);
  for (int k = 0; k < 2000; ++k) {
    const double L = std::pow(10.0, log10(rng)), s = L * std::pow(10.0, -std::abs(log10(rng)));
    const auto n = static_cast<std::size_t>(1 + rng() % 200000);
    const CellGrid g(L, s, n);
    ASSERT_GE(g.cells_per_axis(), 1u);
    ASSERT_TRUE(g.cells_per_axis() == 1 || L / g.cells_per_axis() >= s)
        << L << " " << s << " " << n;
    // at most 4 per particle, rounded up per axis: memory stays O(N)
    const double most = std::sqrt(4.0 * static_cast<double>(n)) + 1;
    ASSERT_LE(g.cells_per_axis(), most) << L << " " << s << " " << n;
  }
}

// The scenes whose times the model was fitted to and checked on (README, "The exact engine").
TEST(EventCells, TheCostModelPicksTheMeasuredBest) {
  // dense: the contact limit (cells of side s)
  EXPECT_EQ(CellGrid(std::sqrt(100000 * M_PI / 0.3), 2, 100000).cells_per_axis(), 511u);
  // the default scene: nearly every event a crossing, about half a cell per particle
  EXPECT_NEAR(cells_per_particle(CellGrid(20000, 2, 1000), 1000), 0.5, 0.05);
  // packing fraction 0.2 at N = 1000: the contact limit again (3.84 per particle)
  EXPECT_EQ(CellGrid(20000, 320, 1000).cells_per_axis(), 62u);
}

// 36 disks in a 6 x 6 lattice inside one cell of a dilute box (a cell of side 400), jostling
// slowly: every prediction among them sees 35 neighbours in its own cell, beyond the gather's
// first room of 10. A discrete engine at K = 1024 takes the same collisions on this short horizon.
TEST(EventCells, ACrowdedCellAgreesWithAFineDiscreteEngine) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> speed(-1.5, 1.5);
  std::string text = "40\n2000\n1\n2\nperf\n";
  int i = 0;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b, ++i)
      text += std::to_string(i) + " " + std::to_string(1010 + 3 * a) + " " +
              std::to_string(1010 + 3 * b) + " " + std::to_string(speed(rng)) + " " +
              std::to_string(speed(rng)) + "\n";
  for (; i < 40; ++i)
    text += std::to_string(i) + " " + std::to_string(100 + 400 * (i - 36)) + " 1900 3 -2\n";
  Scene exact = testing::scene_from_text(text);
  Scene discrete = exact;
  const RunReport e = testing::run(exact, "event");
  const RunReport d = testing::run(discrete, "cells", 1, 1024);
  EXPECT_GT(e.counters.pair_collisions, 10u);
  EXPECT_EQ(e.counters.pair_collisions, d.counters.pair_collisions);
  EXPECT_EQ(e.counters.wall_collisions, d.counters.wall_collisions);
  for (std::size_t k = 0; k < exact.size(); ++k) {
    EXPECT_NEAR(exact.particles.x[k], discrete.particles.x[k], 1e-6) << k;
    EXPECT_NEAR(exact.particles.y[k], discrete.particles.y[k], 1e-6) << k;
  }
}

}  // namespace
}  // namespace particle
