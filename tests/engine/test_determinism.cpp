// Every discrete engine at every thread count gives the bit-identical final state of brute at
// one thread (DESIGN.md section 1, "Determinism"), and the run conserves energy.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"
#include "private_state.hpp"

namespace particle {
namespace {

using testing::random_scene;
using testing::run;

struct Outcome {
  std::uint64_t hash;
  Counters counters;
};

Outcome outcome(Scene scene, const std::string& engine, int threads, int slow_factor = 1) {
  const RunReport report = run(scene, engine, threads, slow_factor);
  return {state_hash(scene.particles), report.counters};
}

void expect_same(const Outcome& a, const Outcome& b) {
  EXPECT_EQ(a.hash, b.hash);
  EXPECT_EQ(a.counters.candidates, b.counters.candidates);
  EXPECT_EQ(a.counters.pair_collisions, b.counters.pair_collisions);
  EXPECT_EQ(a.counters.wall_collisions, b.counters.wall_collisions);
  EXPECT_EQ(a.counters.dropped, b.counters.dropped);
  EXPECT_EQ(a.counters.overlaps, b.counters.overlaps);
}

constexpr int kThreadCounts[] = {1, 2, 3, 4, 8, 16};

// Every engine gives the same state for every thread count (more threads than cores included),
// and every exact engine gives brute's.
void expect_deterministic(const Scene& scene, int slow_factor = 1) {
  const Outcome reference = outcome(scene, "brute", 1, slow_factor);
  for (const std::string& engine : engine_names()) {
    const Outcome own = is_exact(engine) ? reference : outcome(scene, engine, 1, slow_factor);
    for (int threads : kThreadCounts) {
      SCOPED_TRACE(engine + " T=" + std::to_string(threads));
      expect_same(outcome(scene, engine, threads, slow_factor), own);
    }
  }
}

TEST(Determinism, SameHashForEveryThreadCountAndEngine) {
  // Dense enough that many collisions and drops happen in 60 steps. Below kPrivateStateBelow:
  // every thread evolves its own copy of the state (one barrier per sub-step).
  const Scene scene = random_scene(500, 300, 2, 60, 42);
  const Outcome reference = outcome(scene, "brute", 1);
  ASSERT_GT(reference.counters.pair_collisions, 100u);
  ASSERT_GT(reference.counters.dropped, 0u);
  expect_deterministic(scene);
}

TEST(Determinism, SameHashWithTheSharedState) {
  // kPrivateStateBelow particles and more share one state (two barriers per sub-step): slow and
  // dense, so every sub-step has collisions and drops, and few steps (brute is the reference).
  const Scene scene = random_scene(static_cast<int>(detail::kPrivateStateBelow), 600, 1, 3, 5,
                                   SpeedRange{0.5, 4});
  const Outcome reference = outcome(scene, "brute", 1);
  ASSERT_GT(reference.counters.pair_collisions, 1000u);
  ASSERT_GT(reference.counters.dropped, 0u);
  expect_deterministic(scene);
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
