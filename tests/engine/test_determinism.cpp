// Every discrete engine at every thread count gives the bit-identical final state of brute at
// one thread (DESIGN.md section 1, "Determinism"), and the run conserves energy.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"

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

TEST(Determinism, SameHashForEveryThreadCountAndEngine) {
  // Dense enough that many collisions and drops happen in 60 steps.
  const Scene scene = random_scene(500, 300, 2, 60, 42);
  const Outcome reference = outcome(scene, "brute", 1);
  ASSERT_GT(reference.counters.pair_collisions, 100u);
  ASSERT_GT(reference.counters.dropped, 0u);
  for (const std::string& engine : engine_names())
    if (is_exact(engine))
      for (int threads : {1, 2, 3, 4, 8}) {
        SCOPED_TRACE(engine + " T=" + std::to_string(threads));
        expect_same(outcome(scene, engine, threads), reference);
      }
}

TEST(Determinism, SlowFactorRunsAreDeterministicToo) {
  const Scene scene = random_scene(300, 200, 1, 20, 9);
  const Outcome reference = outcome(scene, "brute", 1, 4);
  for (int threads : {2, 3}) expect_same(outcome(scene, "brute", threads, 4), reference);
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
