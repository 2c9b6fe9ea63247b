// Every discrete engine at every thread count gives the bit-identical final state of brute at
// one thread (docs/model.md, "Determinism"), and the run conserves energy.
#include <gtest/gtest.h>
#include <sched.h>

#include <cmath>
#include <utility>
#include <vector>

#include "helpers.hpp"
#include "parallel/private_state.hpp"
#include "particle/wait_policy.hpp"

namespace particle {
namespace {

using testing::expect_same;
using testing::Outcome;
using testing::outcome;
using testing::random_scene;
using testing::run;

constexpr int kThreadCounts[] = {1, 2, 3, 4, 8, 16};

// Every engine gives the same state for every thread count (more threads than cores included),
// and every exact engine gives brute's.
void expect_deterministic(const Scene& scene, int slow_factor = 1,
                          WallStop wall_stop = WallStop::per_coordinate,
                          Overlap overlap = Overlap::approaching) {
  const Outcome reference = outcome(scene, "brute", 1, slow_factor, 8, wall_stop, overlap);
  for (const std::string& engine : runnable_engines()) {
    const Outcome own = is_exact(engine)
                            ? reference
                            : outcome(scene, engine, 1, slow_factor, 8, wall_stop, overlap);
    for (int threads : kThreadCounts) {
      SCOPED_TRACE(engine + " T=" + std::to_string(threads));
      expect_same(outcome(scene, engine, threads, slow_factor, 8, wall_stop, overlap), own);
    }
  }
}

TEST(Determinism, SameHashForEveryThreadCountAndEngine) {
  // Dense enough that many collisions and drops happen in 60 steps. Below kPrivateStateBelow:
  // every thread evolves its own copy of the state (one barrier per sub-step).
  const Scene scene = random_scene(500, 300, 2, 60, 42);
  const Outcome reference = outcome(scene, "brute", 1);
  ASSERT_GT(reference.report.counters.pair_collisions, 100u);
  ASSERT_GT(reference.report.counters.dropped, 0u);
  expect_deterministic(scene);
}

// The 2019 authors' reading of "stops just next to the wall" (docs/model.md, "Readings"): another
// state, the same in every engine at every T.
TEST(Determinism, TheWholeMotionReadingIsDeterministicToo) {
  const Scene scene = random_scene(500, 300, 2, 60, 42);
  const Outcome per_coordinate = outcome(scene, "brute", 1);
  const Outcome whole = outcome(scene, "brute", 1, 1, 8, WallStop::whole_motion);
  ASSERT_NE(whole.hash, per_coordinate.hash);  // the scene tells the readings apart
  expect_deterministic(scene, 1, WallStop::whole_motion);
  expect_deterministic(scene, 4, WallStop::whole_motion);
}

// The handout's overlap sentence read literally (docs/model.md, "Readings"): pairs left overlapping
// by the one-collision rule collide at once even while they recede. Another state, the same in
// every engine at every T; the counters say where the readings part.
TEST(Determinism, TheAlwaysOverlapReadingIsDeterministicToo) {
  const Scene scene = random_scene(500, 300, 2, 60, 42);
  const Outcome approaching = outcome(scene, "brute", 1);
  const Outcome always =
      outcome(scene, "brute", 1, 1, 8, WallStop::per_coordinate, Overlap::always);
  ASSERT_GT(approaching.report.counters.receding_overlaps, 0u);
  ASSERT_GT(approaching.report.counters.wall_stops, 0u);
  ASSERT_NE(always.hash, approaching.hash);
  expect_deterministic(scene, 1, WallStop::per_coordinate, Overlap::always);
  expect_deterministic(scene, 2, WallStop::whole_motion, Overlap::always);
}

// Where nothing happens on which the readings part (no receding overlap, no collision cut short
// by a wall line), every reading gives the same state: psim check shares one reference run
// between its readings on that ground (check/reference_run.hpp).
TEST(Determinism, ReadingsThatNeverPartGiveOneState) {
  const Scene scene = random_scene(200, 500, 1, 30, 7, SpeedRange{0.5, 1});
  const Outcome base = outcome(scene, "brute", 1);
  ASSERT_GT(base.report.counters.pair_collisions + base.report.counters.wall_collisions, 0u);
  ASSERT_EQ(base.report.counters.receding_overlaps, 0u);
  ASSERT_EQ(base.report.counters.wall_stops, 0u);
  for (const WallStop wall_stop : kWallStops)
    for (const Overlap overlap : kOverlaps)
      EXPECT_EQ(outcome(scene, "brute", 1, 1, 8, wall_stop, overlap).hash, base.hash);
}

TEST(Determinism, SameHashWithTheSharedState) {
  // kPrivateStateBelow particles and more share one state (two barriers per sub-step): slow and
  // dense, so every sub-step has collisions and drops, and few steps (brute is the reference).
  const Scene scene =
      random_scene(static_cast<int>(detail::kPrivateStateBelow), 600, 1, 3, 5, SpeedRange{0.5, 4});
  const Outcome reference = outcome(scene, "brute", 1);
  ASSERT_GT(reference.report.counters.pair_collisions, 1000u);
  ASSERT_GT(reference.report.counters.dropped, 0u);
  expect_deterministic(scene);
}

TEST(Determinism, MillionParticleSceneShapeIsDeterministic) {
  // The million-particle scene's shape (slow speeds 0.05-0.2, r = 1, one particle per 16 units of
  // area) at the smallest N that shares one state, where cells and auto run in cell order
  // (broad_phase/cell_order.hpp) and cells takes its short-span kernel: brute's hash at every
  // thread count, and print mode's states at every time unit in id order.
  const int n = static_cast<int>(detail::kPrivateStateBelow);
  const Scene scene = random_scene(n, 4 * std::sqrt(n), 1, 10, 21, SpeedRange{0.05, 0.2});
  const auto states = [&](const std::string& engine, int threads) {
    Scene s = scene;
    RunOptions options;
    options.engine = engine;
    options.threads = threads;
    std::vector<std::uint64_t> hashes;
    const RunReport report = simulate(
        s, options, [&](std::int64_t, const Particles& p) { hashes.push_back(state_hash(p)); });
    hashes.push_back(state_hash(s.particles));
    return std::pair{hashes, report};
  };
  const auto [reference, brute] = states("brute", 2);
  ASSERT_GT(brute.counters.pair_collisions, 1000u);
  ASSERT_GT(brute.counters.dropped, 0u);
  for (const std::string engine : {"cells", "auto"})
    for (int threads : kThreadCounts) {
      SCOPED_TRACE(engine + " T=" + std::to_string(threads));
      const auto [hashes, own] = states(engine, threads);
      EXPECT_EQ(hashes, reference);
      expect_same({hashes.back(), own}, {reference.back(), brute});
    }
}

TEST(Determinism, TheRelayGivesTheSameStatesAtEveryTimeUnit) {
  // Below kPrivateStateBelow particles with more threads than the process has cores, the relay
  // runs (parallel/relay.hpp; on this count of cores whatever the machine, and again on one core):
  // every time unit's state, with two sub-steps each, is brute's at one thread, for every discrete
  // engine.
  const Scene scene = random_scene(500, 300, 2, 12, 7);
  const auto states = [&](const std::string& engine, int threads) {
    Scene s = scene;
    RunOptions options;
    options.engine = engine;
    options.threads = threads;
    options.slow_factor = 2;
    std::vector<std::uint64_t> hashes;
    simulate(s, options,
             [&](std::int64_t, const Particles& p) { hashes.push_back(state_hash(p)); });
    hashes.push_back(state_hash(s.particles));
    return hashes;
  };
  const std::vector<std::uint64_t> reference = states("brute", 1);
  ASSERT_EQ(reference.size(), 12u);
  const auto expect_reference = [&] {
    const int cpus = available_cpus();
    for (const std::string& engine : runnable_engines()) {
      if (!is_exact(engine) || engine == "event") continue;
      for (int threads : {cpus + 1, 2 * cpus + 3}) {
        SCOPED_TRACE(engine + " T=" + std::to_string(threads) + " on " + std::to_string(cpus) +
                     " cpus");
        EXPECT_EQ(states(engine, threads), reference);
      }
    }
  };
  expect_reference();  // one closer per core, and threads that only search
  // On one CPU (this thread's mask, which available_cpus() reads): a single closer.
  cpu_set_t all;
  ASSERT_EQ(sched_getaffinity(0, sizeof all, &all), 0);
  if (CPU_COUNT(&all) == 1) return;
  const cpu_set_t one = testing::first_cpu_of(all);
  ASSERT_EQ(sched_setaffinity(0, sizeof one, &one), 0);
  expect_reference();
  ASSERT_EQ(sched_setaffinity(0, sizeof all, &all), 0);
}

TEST(Determinism, SlowFactorRunsAreDeterministicToo) {
  const Scene scene = random_scene(300, 200, 1, 20, 9);
  expect_deterministic(scene, 4);
}

TEST(Determinism, DifferentSeedsGiveDifferentStates) {
  EXPECT_NE(outcome(random_scene(100, 300, 1, 10, 1), "brute", 1).hash,
            outcome(random_scene(100, 300, 1, 10, 2), "brute", 1).hash);
}

TEST(Conservation, EnergyIsConservedToRounding) {
  Scene scene = random_scene(400, 400, 2, 200, 3);
  const double before = kinetic_energy(scene.particles);
  const RunReport report = run(scene, "brute", 2);
  ASSERT_GT(report.counters.pair_collisions, 200u);
  EXPECT_NEAR(kinetic_energy(scene.particles), before, 1e-12 * before * 1e3);
}

TEST(Conservation, PositionsStayInTheBox) {
  Scene scene = random_scene(400, 200, 2, 100, 4);
  run(scene, "brute", 2, 2);
  for (std::size_t i = 0; i < scene.size(); ++i) {
    ASSERT_GE(scene.particles.x[i], scene.r);
    ASSERT_LE(scene.particles.x[i], scene.L - scene.r);
    ASSERT_GE(scene.particles.y[i], scene.r);
    ASSERT_LE(scene.particles.y[i], scene.L - scene.r);
  }
}

}  // namespace
}  // namespace particle
