// Each broad phase, run alone on random states, finds exactly brute's candidates (a broad phase
// may test more pairs, never fewer, and never one pair twice), at several thread counts; plus the
// pure planning functions of cells and auto.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <tuple>
#include <vector>

#include "broad_phase/auto.hpp"
#include "broad_phase/bands.hpp"
#include "broad_phase/brute.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/grid.hpp"
#include "broad_phase/sweep.hpp"
#include "helpers.hpp"
#include "pair_search.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

using testing::Body;
using testing::WorldFixture;

using testing::find;
using testing::Found;

// A random state: positions from the random scene, velocities per sub-step drawn from a mix of
// slow particles and a share of fast ones; some overlapping pairs are planted.
WorldFixture random_state(std::size_t n, double L, double r, double slow, double fast,
                          double fast_share, std::uint64_t seed) {
  Scene scene =
      particle::testing::random_scene(static_cast<int>(n), L, r, 1, seed, SpeedRange{0, slow});
  Random rng(seed * 7 + 1);
  std::vector<Body> bodies;
  for (std::size_t i = 0; i < n; ++i) {
    double ux = scene.particles.vx[i], uy = scene.particles.vy[i];
    if (rng.uniform() < fast_share) {
      ux = (2 * rng.uniform() - 1) * fast;
      uy = (2 * rng.uniform() - 1) * fast;
    }
    bodies.push_back({scene.particles.x[i], scene.particles.y[i], ux, uy});
  }
  for (std::size_t i = 0; i + 1 < n && i < 20; i += 2) {  // overlapping, both ways
    bodies[i + 1].x = std::min(L - r, bodies[i].x + r * 0.5);
    bodies[i + 1].y = bodies[i].y;
  }
  return WorldFixture(L, r, bodies);
}

void expect_same_candidates(const Found& got, const Found& brute) {
  EXPECT_EQ(got.candidates, brute.candidates);
  EXPECT_EQ(got.overlaps, brute.overlaps);
  EXPECT_LE(got.pair_tests, brute.pair_tests);
}

struct StateCase {
  std::size_t n;
  double L, r, slow, fast, fast_share;
};

class BroadPhasePairs : public ::testing::TestWithParam<StateCase> {};

TEST_P(BroadPhasePairs, FindBrutesCandidates) {
  const StateCase c = GetParam();
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    WorldFixture f = random_state(c.n, c.L, c.r, c.slow, c.fast, c.fast_share, seed);
    BruteBroadPhase brute;
    const Found reference = find(brute, f.w, 1, 1);
    ASSERT_FALSE(reference.candidates.empty());
    for (int threads : {1, 2, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " T=" + std::to_string(threads));
      for (int g : {1, 2, 7, 32}) {
        GridBroadPhase grid(g);
        expect_same_candidates(find(grid, f.w, threads), reference);
      }
      CellsBroadPhase cells;
      expect_same_candidates(find(cells, f.w, threads), reference);
      SweepBroadPhase sweep;
      expect_same_candidates(find(sweep, f.w, threads), reference);
      for (std::uint32_t b : {0u, 1u, 5u, 40u}) {
        BandsBroadPhase bands(b);
        expect_same_candidates(find(bands, f.w, threads), reference);
      }
      AutoBroadPhase automatic;
      expect_same_candidates(find(automatic, f.w, threads), reference);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    States, BroadPhasePairs,
    ::testing::Values(StateCase{1500, 300, 1, 1.5, 0, 0},          // slow and dense
                      StateCase{1500, 300, 1, 1.0, 60, 0.004},     // a few fast outliers
                      StateCase{1500, 300, 1, 1.0, 40, 0.3},       // many fast ones
                      StateCase{400, 2000, 1, 500, 0, 0},          // fast everywhere
                      StateCase{600, 1e6, 300, 2e4, 3e5, 0.01}));  // large box, large disks

// ordered_bits (broad_phase/common.hpp) orders finite doubles as they order, both signs, zeros,
// subnormals and extremes, and gives each back: sweep's smallest start and every engine's largest
// speed (the float pre-test's bound) are taken on it.
TEST(OrderedBits, OrderAsTheDoublesAndComeBack) {
  const std::vector<double> values = {-1.7976931348623157e308,
                                      -1e6,
                                      -2.5,
                                      -1.0,
                                      -0x1p-1074,
                                      -0.0,
                                      0.0,
                                      0x1p-1074,
                                      0x1p-1022,
                                      1e-300,
                                      0.5,
                                      1.0,
                                      2.5,
                                      20000.0,
                                      1.7976931348623157e308};
  for (std::size_t a = 0; a < values.size(); ++a) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(from_ordered_bits(ordered_bits(values[a]))),
              std::bit_cast<std::uint64_t>(values[a]));
    for (std::size_t b = 0; b < values.size(); ++b)
      if (values[a] < values[b])
        EXPECT_LT(ordered_bits(values[a]), ordered_bits(values[b]))
            << values[a] << " " << values[b];
  }
  EXPECT_LT(ordered_bits(-0.0), ordered_bits(0.0));  // apart, in the order of their bits
}

TEST(CellsPlan, FewOutliersKeepSmallCells) {
  SpeedStats stats;
  stats.probe = 2.0;
  stats.max = 50;
  stats.above = 3;
  const CellsPlan plan = plan_cells(250000, 1000, 2, stats);  // density side 2 < 2 + 2 * 2
  EXPECT_GE(plan.cut, 2.0);
  EXPECT_LT(plan.cut, 2.1);
  EXPECT_GE(1000.0 / plan.n, padded(2 + 2 * plan.cut, 1000));
}

TEST(CellsPlan, DensityBoundCellsRaiseTheCutForFree) {
  SpeedStats stats;
  stats.probe = 2.0;
  stats.max = 50;
  stats.above = 3;
  const CellsPlan plan = plan_cells(10000, 1000, 2, stats);  // cells of 10 allow a cut of 4
  EXPECT_NEAR(plan.cut, 4.0, 1e-4);                          // less the padding
  EXPECT_GE(1000.0 / plan.n, padded(2 + 2 * plan.cut, 1000));
}

TEST(CellsPlan, ManyOutliersRaiseTheCut) {
  SpeedStats stats;
  stats.probe = 2.0;
  stats.max = 50;
  stats.above = 2000;
  const CellsPlan plan = plan_cells(10000, 1000, 2, stats);
  EXPECT_GT(plan.cut, 50.0);
  EXPECT_GE(1000.0 / plan.n, padded(2 + 2 * plan.cut, 1000));
}

TEST(CellsPlan, CellsHoldAboutOneParticleAtLeast) {
  SpeedStats stats;
  stats.probe = 0;
  stats.max = 0;
  EXPECT_EQ(plan_cells(100, 1000, 2, stats).n, 10);
  EXPECT_EQ(plan_cells(1, 1000, 2, stats).n, 1);
}

TEST(AutoCosts, PicksByScene) {
  SpeedStats fast;  // the default scene: N=1000, L=20000, |u| up to L/4
  fast.count = 1000;
  fast.max = 5000;
  fast.sum = 1000 * 3400.0;
  fast.sum_abs_ux = fast.sum_abs_uy = 1000 * 2400.0;
  fast.probe = 6800;
  EXPECT_EQ(cheapest(estimate_costs(1000, 20000, 1, fast)), AutoChoice::sweep);

  SpeedStats more = fast;  // the same kind at N = 4000 in a box of 40000: bands
  more.count = 4000;
  more.sum = 4000 * 3400.0;
  more.sum_abs_ux = more.sum_abs_uy = 4000 * 2400.0;
  EXPECT_EQ(cheapest(estimate_costs(4000, 40000, 1, more)), AutoChoice::bands);

  SpeedStats slow;  // a slow crowd
  slow.count = 20000;
  slow.max = 1;
  slow.sum = 20000 * 0.7;
  slow.sum_abs_ux = 20000 * 0.5;
  slow.probe = 1.4;
  EXPECT_EQ(cheapest(estimate_costs(20000, 2000, 1, slow)), AutoChoice::cells);
}

}  // namespace
}  // namespace particle::detail
