#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "step/narrow_phase.hpp"
#include "step/stages.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

using testing::WorldFixture;

// Oblique collisions at random angles: energy and momentum before and after agree to 1e-12
// relative, and the particles end the sub-step separating.
TEST(Resolve, PairConservesEnergyAndMomentum) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> pos(40, 60), vel(-10, 10);
  int collided = 0;
  while (collided < 500) {
    WorldFixture f(
        1000, 1,
        {{pos(rng), pos(rng), vel(rng), vel(rng)}, {pos(rng), pos(rng), vel(rng), vel(rng)}});
    ThreadScratch s;
    test_pair(f.w, 0, 1, s);
    if (s.candidates.empty()) continue;
    ++collided;
    const double px = f.ux[0] + f.ux[1], py = f.uy[0] + f.uy[1];
    const double e = f.ux[0] * f.ux[0] + f.uy[0] * f.uy[0] + f.ux[1] * f.ux[1] + f.uy[1] * f.uy[1];
    resolve_collisions(f.w, s.candidates);
    const double scale = std::sqrt(e) + 1e-300;
    EXPECT_NEAR(f.ux[0] + f.ux[1], px, 1e-12 * scale);
    EXPECT_NEAR(f.uy[0] + f.uy[1], py, 1e-12 * scale);
    EXPECT_NEAR(f.ux[0] * f.ux[0] + f.uy[0] * f.uy[0] + f.ux[1] * f.ux[1] + f.uy[1] * f.uy[1], e,
                1e-12 * e);
    EXPECT_EQ(f.pair_collisions[0], 1u);
    EXPECT_EQ(f.pair_collisions[1], 1u);
    const double dx = f.x[1] - f.x[0], dy = f.y[1] - f.y[0];
    EXPECT_GE(dx * (f.ux[1] - f.ux[0]) + dy * (f.uy[1] - f.uy[0]), -1e-9 * e);
  }
}

// A pair resolves to the same state bit for bit whichever particle the candidate names first:
// split_contested leaves the uncontested pairs in the narrow phase's slot order rather than
// orienting them by id, which a cell-ordered run would otherwise resolve differently from brute.
// Oblique meetings near the walls too (move_rest's line times), and two centres on one point
// (exchange_along_normal's head-on fallback).
TEST(Resolve, EitherOrderOfAPairGivesTheSameStateBitForBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(1.5, 6), vel(-3, 3), when(0, 1);
  const auto bits = [](const WorldFixture& f) {
    std::vector<std::uint64_t> v;
    for (const auto* a : {&f.x, &f.y, &f.ux, &f.uy})
      for (const double d : *a) v.push_back(std::bit_cast<std::uint64_t>(d));
    for (const std::uint64_t c : f.pair_collisions) v.push_back(c);
    return v;
  };
  for (int k = 0; k < 2000; ++k) {
    const double x = pos(rng), y = pos(rng);
    const bool same_point = k % 100 == 0;
    const std::vector<testing::Body> bodies = {
        {x, y, vel(rng), vel(rng)},
        {same_point ? x : pos(rng), same_point ? y : pos(rng), vel(rng), vel(rng)}};
    WorldFixture ij(8, 1, bodies), ji(8, 1, bodies);
    const double t = when(rng);
    const unsigned a = resolve_collision(ij.w, {t, 0, 1});
    const unsigned b = resolve_collision(ji.w, {t, 1, 0});
    ASSERT_EQ(bits(ij), bits(ji)) << "pair " << k;
    EXPECT_EQ(stopped_count(a), stopped_count(b));
  }
}

// Head-on along x at t = 0.5: velocities swap exactly and each moves back half a sub-step.
TEST(Resolve, HeadOnSwapsVelocities) {
  WorldFixture f(1000, 1, {{100, 100, 2, 0}, {104, 100, -2, 0}});
  resolve_collisions(f.w, {{0.5, 0, 1}});
  EXPECT_EQ(f.ux[0], -2);
  EXPECT_EQ(f.ux[1], 2);
  EXPECT_EQ(f.x[0], 100);
  EXPECT_EQ(f.x[1], 104);
  EXPECT_EQ(f.uy[0], 0);
}

}  // namespace
}  // namespace particle::detail
