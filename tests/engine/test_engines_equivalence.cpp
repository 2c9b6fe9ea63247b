// The fast engines (grid, cells, sweep, bands, auto) give brute's bit-identical final state and
// counters (all but pair_tests) on many kinds of scene and at thread counts 1, 2, 3 (issue 5).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "broad_phase/cells.hpp"
#include "helpers.hpp"

namespace particle {
namespace {

using testing::Outcome;
using testing::outcome;
using testing::random_scene;
using testing::speeds;

// expect_same, and pruning never tests a pair twice.
void expect_same_pruned(const Outcome& got, const Outcome& want) {
  testing::expect_same(got, want);
  EXPECT_LE(got.report.counters.pair_tests, want.report.counters.pair_tests);
}

// Every fast engine at T = 1, 2, 3 against brute at T = 1.
void expect_all_engines_match(const Scene& scene, int slow_factor = 1) {
  const Outcome reference = outcome(scene, "brute", 1, slow_factor);
  for (const std::string engine : {"grid", "cells", "sweep", "bands", "auto"})
    for (int threads : {1, 2, 3}) {
      SCOPED_TRACE(engine + " T=" + std::to_string(threads));
      expect_same_pruned(outcome(scene, engine, threads, slow_factor), reference);
    }
}

// Speeds from `slow` to `fast` per time unit, uniform (the random scene's range).

TEST(EnginesMatchBrute, DefaultRandomScene) {
  // The 2019 kind: speeds L/(8r) to L/4 per step, a quarter of the box.
  const Scene scene = random_scene(400, 4000, 1, 60, 11);
  expect_all_engines_match(scene);
}

TEST(EnginesMatchBrute, DenseScene) {
  const Scene scene = random_scene(600, 300, 2, 60, 42);
  const Outcome brute = outcome(scene, "brute", 1);
  ASSERT_GT(brute.report.counters.dropped, 0u);
  ASSERT_GT(brute.report.counters.overlaps, 0u);
  expect_all_engines_match(scene);
}

TEST(EnginesMatchBrute, SlowCrowd) {
  expect_all_engines_match(random_scene(3000, 400, 1, 30, 5, speeds(0.5, 1)));
}

TEST(EnginesMatchBrute, FasterThanTheBox) {
  expect_all_engines_match(random_scene(200, 500, 1, 40, 6, speeds(400, 1200)));
}

TEST(EnginesMatchBrute, AFewVeryFastAmongSlow) {
  Scene scene = random_scene(2000, 500, 1, 40, 8, speeds(0.2, 0.6));
  for (std::size_t i = 0; i < scene.size(); i += 400) {  // 5 bullets crossing the box
    scene.particles.vx[i] = 150.0 + static_cast<double>(i) / 10;
    scene.particles.vy[i] = -90.0;
  }
  expect_all_engines_match(scene);
}

TEST(EnginesMatchBrute, SweepSpansLongerThanItsGroupStream) {
  // Faster than the box: most spans hold thousands of partners, more than FloatGroups holds
  // (512 groups of 16), so they are tested in pieces.
  const Scene scene = random_scene(9000, 20000, 1, 2, 14, speeds(20000, 40000));
  const Outcome reference = outcome(scene, "brute", 1);
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE("sweep T=" + std::to_string(threads));
    expect_same_pruned(outcome(scene, "sweep", threads), reference);
  }
}

TEST(EnginesMatchBrute, AtRest) {
  expect_all_engines_match(random_scene(500, 200, 1, 5, 2, speeds(0, 0)));
}

TEST(EnginesMatchBrute, HugeBoxWithDefaultSpeeds) {
  expect_all_engines_match(random_scene(300, 1e9, 1e5, 40, 12));
}

// 800 particles in a square of 120 whose far corner lies `from_wall` from the walls at L: every
// engine against brute, which sees collisions there.
void expect_far_cluster_matches(double L, double from_wall, std::uint64_t seed, SpeedRange v) {
  Scene scene = random_scene(800, 120, 1, 40, seed, v);
  const double offset = L - 120 - from_wall;
  scene.L = L;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    scene.particles.x[i] += offset;
    scene.particles.y[i] += offset;
  }
  const Outcome brute = outcome(scene, "brute", 1);
  ASSERT_GT(brute.report.counters.pair_collisions, 0u);
  expect_all_engines_match(scene);
}

TEST(EnginesMatchBrute, SlowClusterFarFromTheOriginOfAHugeBox) {
  // Coordinates near 1e12, where an ulp is 1.2e-4: the padding of every reach must cover it.
  expect_far_cluster_matches(1e12, 80, 13, speeds(0.3, 1));
}

TEST(EnginesMatchBrute, SlowClusterFarFromTheOriginOfAMillionBox) {
  // Coordinates near 10^6, where float's spacing is 1/16 (s = 2), against the walls: the cells'
  // listed pairs take the float pre-test there (step/float_pretest.hpp), whose margins must
  // cover it.
  expect_far_cluster_matches(1e6, 5, 15, speeds(0.05, 0.3));
}

TEST(EnginesMatchBrute, CellsStreamingTheirRecordsMatchSweep) {
  // Past kStreamedRecords particles the cells' pair list stores its float records past the
  // caches: at the million-particle scene's density and speeds, against sweep (itself tested
  // against brute above; brute at this N takes minutes).
  const int n = static_cast<int>(detail::kStreamedRecords) + 20000;
  const Scene scene = random_scene(n, 4 * std::sqrt(n), 1, 4, 16, speeds(0.05, 0.2));
  const Outcome reference = outcome(scene, "sweep", 2);
  ASSERT_GT(reference.report.counters.pair_collisions, 10000u);
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE("cells T=" + std::to_string(threads));
    const Outcome cells = outcome(scene, "cells", threads);
    EXPECT_EQ(cells.hash, reference.hash);
    EXPECT_EQ(cells.report.counters.pair_collisions, reference.report.counters.pair_collisions);
  }
}

TEST(EnginesMatchBrute, SlowFactor) {
  expect_all_engines_match(random_scene(400, 3000, 1, 20, 14), 4);
}

TEST(EnginesMatchBrute, GridForEveryGFrom1To64) {
  const Scene fast = random_scene(250, 2500, 1, 12, 15);
  const Scene slow = random_scene(800, 200, 1, 12, 16, speeds(0.5, 3));
  for (const Scene* scene : {&fast, &slow}) {
    const Outcome reference = outcome(*scene, "brute", 1);
    for (int g = 1; g <= 64; ++g) {
      const int threads = 1 + g % 3;
      SCOPED_TRACE("G=" + std::to_string(g) + " T=" + std::to_string(threads));
      expect_same_pruned(outcome(*scene, "grid", threads, 1, g), reference);
    }
  }
}

TEST(AutoEngine, ReportsItsChoice) {
  // Fast particles in a large box: sweep; the slow crowd: cells.
  EXPECT_EQ(outcome(random_scene(1000, 20000, 1, 3), "auto", 2).report.engine, "auto:sweep");
  EXPECT_EQ(outcome(random_scene(20000, 2000, 1, 2, 1, speeds(0.5, 1)), "auto", 2).report.engine,
            "auto:cells");
  EXPECT_EQ(outcome(random_scene(5000, 1000, 1, 3, 1, speeds(0.5, 1)), "cells", 1).report.engine,
            "cells");
}

// Each scene of the cost model's measurements (docs/performance.md, "bands") gets the engine the
// model picks for it: cells for a slow crowd, sweep for the default scene and a dense one, bands
// for the default scene's kind at N = 4000 and once the fast share of a mixed scene has spread
// its speed, brute where paths are longer than the box.
TEST(AutoEngine, EachSceneGetsTheModelsEngine) {
  const auto engine = [](const Scene& scene, int steps = 2) {
    Scene run = scene;
    run.steps = steps;
    return outcome(run, "auto", 1).report.engine;
  };
  EXPECT_EQ(engine(random_scene(20000, 2000, 1, 2, 1, speeds(0.5, 1))), "auto:cells");
  EXPECT_EQ(engine(random_scene(1000, 20000, 1, 2)), "auto:sweep");
  EXPECT_EQ(engine(random_scene(4000, 40000, 1, 2)), "auto:bands");
  EXPECT_EQ(engine(random_scene(300, 500, 1, 2, 1, speeds(600, 2000))), "auto:brute");
  EXPECT_EQ(engine(random_scene(600, 300, 2, 2)), "auto:sweep");
  Scene mixed = random_scene(3000, 3000, 1, 2, 5, speeds(0.2, 1));
  for (std::size_t i = 0; i < mixed.size(); i += 10) {  // a tenth at 300 to 600 per time unit
    mixed.particles.vx[i] = 300 + static_cast<double>(i % 300);
    mixed.particles.vy[i] = (i % 20 == 0 ? -1 : 1) * 250.0;
  }
  EXPECT_EQ(engine(mixed, 40), "auto:sweep+bands");
}

// Particles on a jittered grid moving along y only: oblique collisions turn y motion into x
// motion, and the speed statistics that auto's cost model reads change with it.
Scene vertical_movers() {
  constexpr int n = 2000, side = 45;  // side^2 >= n
  Scene scene;
  scene.L = 190;
  scene.r = 1;
  scene.steps = 60;
  scene.particles = Particles(n);
  Particles& p = scene.particles;
  const double step = scene.L / side, jitter = step / 2 - 1.05;  // neighbours stay > 2r apart
  Random rng(1);
  for (int i = 0; i < n; ++i) {
    p.x[i] = (i % side + 0.5) * step + (2 * rng.uniform() - 1) * jitter;
    p.y[i] = (i / side + 0.5) * step;
    p.vy[i] = (1 + rng.uniform()) * (rng.uniform() < 0.5 ? -1 : 1);
  }
  return scene;
}

TEST(AutoEngine, SwitchesAsSpeedsChange) {
  const Scene scene = vertical_movers();
  const Outcome reference = outcome(scene, "brute", 1);
  for (int threads : {1, 2}) {
    const Outcome got = outcome(scene, "auto", threads);
    expect_same_pruned(got, reference);
    // The name lists the engines auto ran in order of first use: more than one means a switch.
    EXPECT_NE(got.report.engine.find('+'), std::string::npos) << got.report.engine;
  }
}

TEST(AutoEngine, BulletsInASlowCrowdMatchBrute) {
  // A slow crowd hit by a few bullets: they stay fast and rare, so cells with outliers is cheaper
  // than any re-plan; the run must still match brute whatever auto picks.
  Scene scene = random_scene(3000, 600, 1, 70, 17, speeds(0.3, 0.8));
  for (std::size_t i = 0; i < 40; ++i) scene.particles.vx[i] = 200;
  const Outcome reference = outcome(scene, "brute", 1);
  for (int threads : {1, 2}) expect_same_pruned(outcome(scene, "auto", threads), reference);
}

// broad_phase_builds: none for brute and event, one a sub-step for the broad phases that build
// afresh each, fewer for cells on a slow scene (it keeps its cells) and mpi (its ranks keep
// theirs), auto's those of what it ran; the same at every T.
TEST(BroadPhaseBuilds, CountedPerEngine) {
  const Scene scene = random_scene(3000, 400, 1, 30, 5, speeds(0.05, 0.2));
  const int slow_factor = 2;
  const std::uint64_t substeps = 30 * slow_factor;
  const auto builds = [&](const std::string& engine, int threads) {
    return outcome(scene, engine, threads, slow_factor).report.counters.broad_phase_builds;
  };
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE("T=" + std::to_string(threads));
    EXPECT_EQ(builds("brute", threads), 0u);
    for (const std::string engine : {"grid", "sweep", "bands"})
      EXPECT_EQ(builds(engine, threads), substeps) << engine;
    const std::uint64_t cells = builds("cells", threads);
    EXPECT_GE(cells, 1u);
    EXPECT_LT(cells, substeps / 4);
    EXPECT_EQ(cells, builds("cells", 1));
    const RunReport automatic = outcome(scene, "auto", threads, slow_factor).report;
    ASSERT_EQ(automatic.engine, "auto:cells");
    EXPECT_EQ(automatic.counters.broad_phase_builds, cells);
    // A job of one rank keeps its own particles' cells as cells does (mpi/pair_search.hpp).
    if (engine_unavailable("mpi").empty()) EXPECT_EQ(builds("mpi", threads), cells);
  }
  EXPECT_EQ(outcome(scene, "event", 1).report.counters.broad_phase_builds, 0u);
}

}  // namespace
}  // namespace particle
