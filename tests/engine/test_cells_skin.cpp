// The cells engine keeps its cells across sub-steps, sets apart the particles that drift out of
// reach of them and bins afresh when too many do (broad_phase/cells.hpp, keep()). Scenes built to
// break that skin, each run to brute's bits at T = 1, 2, 3, 8 (final state, counters, and the
// state at every time unit), and each shown to break it and, but for one, to keep the cells in
// some sub-steps, so every path ran. Scenes of kPrivateStateBelow particles or more run in cell
// order and may have the World re-sorted mid-run (resort()); those here are shown to.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "broad_phase/cell_order.hpp"
#include "broad_phase/cells.hpp"
#include "helpers.hpp"
#include "step/pipeline.hpp"
#include "world_fixture.hpp"

namespace particle {
namespace {

using testing::Outcome;
using testing::outcome;
using testing::random_scene;
using testing::speeds;

struct Skin {
  std::uint64_t builds, drifted, resorts;  // CellsBroadPhase::builds(), drifted(), resorts()
};

// How often the run binned afresh, set particles apart and re-sorted the World: the cells broad
// phase alone over the pipeline, in cell order where the engine runs in it (unless
// `in_cell_order` is false: then in id order, never re-sorted).
Skin skin_of(const Scene& scene, int slow_factor, bool in_cell_order = true) {
  std::vector<testing::Body> bodies;
  for (std::size_t i = 0; i < scene.size(); ++i)
    bodies.push_back({scene.particles.x[i], scene.particles.y[i],
                      scene.particles.vx[i] / slow_factor, scene.particles.vy[i] / slow_factor});
  testing::WorldFixture state(scene.L, scene.r, bodies);
  detail::CellsBroadPhase broad;
  detail::PipelineParams params;
  params.steps = scene.steps;
  params.slow_factor = slow_factor;
  if (in_cell_order)
    detail::run_in_cell_order(broad, state.w, params);
  else
    detail::run_pipeline(broad, state.w, params);
  return {broad.builds(), broad.drifted(), broad.resorts()};
}

// cells at T = 1, 2, 3, 8 gives brute's final state and counters, and its state at every time
// unit; and the scene breaks the skin (a particle drifts out of reach of its cell, or the cells
// are binned afresh) and, where `kept`, keeps the cells in some sub-steps.
void expect_skin_holds(const Scene& scene, int slow_factor = 1, bool kept = true) {
  const Outcome reference = outcome(scene, "brute", 1, slow_factor);
  const std::vector<std::uint64_t> units = testing::unit_hashes(scene, "brute", slow_factor);
  for (int threads : {1, 2, 3, 8}) {
    SCOPED_TRACE("cells T=" + std::to_string(threads));
    testing::expect_same(outcome(scene, "cells", threads, slow_factor), reference);
    EXPECT_EQ(testing::unit_hashes(scene, "cells", slow_factor, simulate, threads), units);
  }
  const Skin skin = skin_of(scene, slow_factor);
  const auto substeps = static_cast<std::uint64_t>(scene.steps * slow_factor);
  EXPECT_TRUE(skin.builds > 1 || skin.drifted > 0) << "the skin never broke";
  if (kept) {
    EXPECT_LT(skin.builds, substeps) << "the cells were never kept";
  }
}

// A crowd at speeds 0.05 to 0.2 in cells of side about 4.5 (s = 2, a cut of about 1.25) with one
// particle at each of `fast` (per axis; a third of it on the other).
Scene fast_among_slow(std::initializer_list<double> fast) {
  Scene scene = random_scene(2000, 200, 1, 40, 21, speeds(0.05, 0.2));
  std::size_t i = 0;
  for (double u : fast) {
    scene.particles.vx[i] = u;
    scene.particles.vy[i] = -u / 3;
    i += 300;
  }
  return scene;
}

TEST(CellsSkin, OneFastParticleAmongSlowOnes) {
  // Binned, it breaks the skin in two or three sub-steps.
  expect_skin_holds(fast_among_slow({0.9}));
}

TEST(CellsSkin, FastOutliersAmongSlowOnes) {
  // Outliers, tested apart; every particle they hit leaves faster than the cut, and the cells are
  // binned afresh in nearly every sub-step.
  expect_skin_holds(fast_among_slow({2.5, 6}), 1, false);
}

TEST(CellsSkin, AParticleBecomesTheFastestAfterACollision) {
  // Rows of particles at rest, one cell side apart on the axis of motion, each row hit head-on by
  // a fast particle: every collision hands the whole speed to a particle that had no drift at
  // all, in a crowd that barely moves (cells of side about 7.7: the fastest break the skin in two
  // sub-steps).
  Scene scene = random_scene(1500, 300, 1, 60, 22, speeds(0, 0.05));
  const double speed[] = {1.2, 0.8};
  std::size_t i = 0;
  for (int row = 0; row < 2; ++row) {
    const double y = 40 + 120 * row;
    for (int k = 0; k < 12; ++k, ++i) {
      scene.particles.x[i] = 20 + 4.4 * k + (k == 0 ? -6 : 0);
      scene.particles.y[i] = y;
      scene.particles.vx[i] = k == 0 ? speed[row] : 0;
      scene.particles.vy[i] = 0;
    }
  }
  // Keep the random crowd off the rows (a draw near one is moved up by half the box).
  for (std::size_t k = i + 12; k < scene.size(); ++k)
    for (int row = 0; row < 2; ++row)
      if (std::fabs(scene.particles.y[k] - (40 + 120 * row)) < 3) scene.particles.y[k] += 150;
  // Glancing pairs meeting at right angles: one leaves faster than either came.
  for (int k = 0; k < 6; ++k, ++i) {
    const double x0 = 40 + 40 * k, y0 = 260;
    scene.particles.x[i] = x0 - 8;
    scene.particles.y[i] = y0 + 0.7;
    scene.particles.vx[i] = 1;
    scene.particles.vy[i] = 0;
    ++i;
    scene.particles.x[i] = x0;
    scene.particles.y[i] = y0 - 8;
    scene.particles.vx[i] = 0;
    scene.particles.vy[i] = 1;
  }
  expect_skin_holds(scene);
}

// 256 particles at rest on a lattice of spacing 4 in a box of 64: cells of side 4 (one particle
// each) and s = 2, so a drift of 1 is allowed. In five rows, `per_row` pairs of particles start
// just over a cell side apart, in cells two apart, and close in at u each a sub-step. The lattice
// particle between each pair waits at a corner of the lattice away from the rows.
Scene closing_pairs(double u, int per_row) {
  Scene scene = random_scene(256, 64, 1, 12, 23, speeds(0, 0));
  for (std::size_t i = 0; i < 256; ++i) {
    scene.particles.x[i] = 2 + 4 * static_cast<double>(i % 16);
    scene.particles.y[i] = 2 + 4 * static_cast<double>(i / 16);
  }
  for (std::size_t row = 1; row < 16; row += 3)
    for (int k = 0; k < per_row; ++k) {
      const std::size_t a = row * 16 + 3 + 6 * k, b = a + 2;  // cells 3 and 5, then 9 and 11
      scene.particles.x[a] = 16 + 24 * k - 0x1p-40;
      scene.particles.x[b] = 20 + 24 * k + 0x1p-40;
      scene.particles.vx[a] = u;
      scene.particles.vx[b] = -u;
      scene.particles.x[a + 1] = 32 + 16 * k;  // between rows row + 1 and row + 2
      scene.particles.y[a + 1] = 4 * static_cast<double>(row + 2);
    }
  return scene;
}

TEST(CellsSkin, ParticlesCrossTheSkinExactly) {
  // At 0.25 the drifts reach the bound exactly (0.25 + 3 x 0.25 each) in the sub-step before the
  // pairs come within reach.
  expect_skin_holds(closing_pairs(0.25, 1));
}

TEST(CellsSkin, TheFirstSubStepPastTheSkin) {
  // At 0.3 the pairs come within reach (and collide) in the first sub-step past the bound
  // (3 x 0.3 + 0.3 each): ten particles drift out of reach there, each tested apart from then on.
  const Scene scene = closing_pairs(0.3, 1);
  expect_skin_holds(scene);
  EXPECT_EQ(skin_of(scene, 1).drifted, 10u);
}

TEST(CellsSkin, TooManyDriftersBinAfresh) {
  // Twenty drift out together, more than the 16 that may be tested apart: the cells are binned
  // afresh in that sub-step.
  const Scene scene = closing_pairs(0.3, 2);
  expect_skin_holds(scene);
  EXPECT_GT(skin_of(scene, 1).builds, 1u);
}

TEST(CellsSkin, TheBuildComesInTheSubStepTheDriftersPassTheCap) {
  // The twenty drift out at the fourth sub-step's check (4 x 0.3 > 1): a run of three keeps the
  // first build, a run of four builds again at its last sub-step, at every T (the report's
  // broad_phase_builds). A rebuild skipped once, or put off a sub-step, leaves the four at one.
  Scene scene = closing_pairs(0.3, 2);
  for (const int steps : {3, 4}) {
    scene.steps = steps;
    const std::uint64_t want = steps == 4 ? 2 : 1;
    EXPECT_EQ(skin_of(scene, 1).builds, want) << "S = " << steps;
    for (int threads : {1, 2, 3})
      EXPECT_EQ(outcome(scene, "cells", threads).report.counters.broad_phase_builds, want)
          << "S = " << steps << ", T = " << threads;
  }
}

TEST(CellsSkin, ACrowdCompressesAgainstAWall) {
  // Everyone drifts right at about 0.3, into the wall at x = L - r: the crowd piles up, packs
  // and bounces back through itself, with overlaps and many dropped collisions.
  Scene scene = random_scene(1200, 150, 1, 150, 24, speeds(0, 0.08));
  for (std::size_t i = 0; i < scene.size(); ++i) scene.particles.vx[i] += 0.3;
  const Outcome brute = outcome(scene, "brute", 1);
  ASSERT_GT(brute.report.counters.dropped, 0u);
  expect_skin_holds(scene);
}

TEST(CellsSkin, ALongRunWhereEveryParticleLeavesItsCellManyTimes) {
  // Speeds 0.05 to 0.15 for 600 time units: 30 to 90 units of path in cells of about 3.2.
  expect_skin_holds(random_scene(1000, 100, 1, 600, 25, speeds(0.05, 0.15)));
}

// A crowd of 16,384 at speeds 2 to 3 in cells of 5 (one particle each, the grid of the cell
// order set at the start; four sub-steps a time unit), with `fast` particles among them
// (outliers at every build): the particles cross the two rows of cells that make a break in a
// few time units, so the World's order decays and is re-sorted again and again.
Scene decaying_order(int steps, std::initializer_list<double> fast) {
  Scene scene = random_scene(16384, 640, 1, steps, 27, speeds(2, 3));
  std::size_t i = 0;
  for (double u : fast) {
    scene.particles.vx[i] = u;
    scene.particles.vy[i] = u / 2;
    i += 5001;
  }
  return scene;
}

TEST(CellsSkin, TheWorldIsReSortedWhenItsOrderDecays) {
  // Re-sorted mid-run, each time moving every array and the ids, with outliers at the end of
  // the order (the state at every time unit puts it back by id, and the next unit goes on in
  // the order of the moment).
  const Scene scene = decaying_order(10, {28, 36, 48});
  ASSERT_GE(detail::kPrivateStateBelow, 16384u);  // the scene runs in cell order
  expect_skin_holds(scene, 4);
  const Skin skin = skin_of(scene, 4);
  EXPECT_GE(skin.resorts, 2u) << skin.builds << " builds";
  EXPECT_LT(skin.resorts, skin.builds);
}

TEST(CellsSkin, AReSortMovesTheDriftsOriginsWithTheParticles) {
  // A particle's drift is measured from where the last build saw it: once a re-sort has moved
  // the particles to other slots, those origins must follow them, so the particles set apart and
  // the builds are those of the same run in id order, which never re-sorts.
  const Scene scene = decaying_order(10, {28, 36, 48});
  const Skin sorted = skin_of(scene, 4), unsorted = skin_of(scene, 4, false);
  ASSERT_GE(sorted.resorts, 2u);
  ASSERT_EQ(unsorted.resorts, 0u);
  EXPECT_GT(sorted.drifted, 0u);
  EXPECT_EQ(sorted.drifted, unsorted.drifted);
  EXPECT_EQ(sorted.builds, unsorted.builds);
}

TEST(CellsSkin, AnOrderThatHoldsIsNotReSorted) {
  // Two time units at a tenth of the speed: few particles change cell, none by two rows, and the
  // order set at the start holds.
  Scene scene = decaying_order(2, {});
  for (std::size_t i = 0; i < scene.size(); ++i) {
    scene.particles.vx[i] /= 10;
    scene.particles.vy[i] /= 10;
  }
  EXPECT_EQ(skin_of(scene, 1).resorts, 0u);
}

TEST(CellsSkin, SubStepsOfAQuarter) {
  expect_skin_holds(random_scene(1500, 150, 1, 40, 26, speeds(0.4, 1.6)), 4);
}

}  // namespace
}  // namespace particle
