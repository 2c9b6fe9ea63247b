// The GPU engine on a device (ctest -L gpu): brute's state and counters, at K = 1 and 16, every
// printed time unit included, and cells' state on scenes too large for brute. Skipped, with the
// reason, where this process cannot run the engine (no CUDA in the build, or no device).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "helpers.hpp"
#include "particle/describe.hpp"

namespace particle {
namespace {

using testing::Outcome;
using testing::random_scene;
using testing::speeds;
using testing::unit_hashes;

class GpuDevice : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const std::string why = engine_unavailable("gpu"); !why.empty()) GTEST_SKIP() << why;
  }
};

void expect_matches(const Scene& scene, const std::string& reference, int slow_factor) {
  SCOPED_TRACE(reference + " K=" + std::to_string(slow_factor));
  const Outcome want = testing::outcome(scene, reference, 1, slow_factor);
  const Outcome got = testing::outcome(scene, "gpu", 1, slow_factor);
  testing::expect_same(got, want);
  EXPECT_EQ(got.report.physics.max_overlap, want.report.physics.max_overlap);
  EXPECT_EQ(got.report.physics.wall_impulse, want.report.physics.wall_impulse);
}

TEST_F(GpuDevice, MatchesBruteOnTheEquivalenceScenes) {
  Scene bullets = random_scene(2000, 500, 1, 40, 8, speeds(0.2, 0.6));
  for (std::size_t i = 0; i < bullets.size(); i += 400) {  // as in test_engines_equivalence.cpp
    bullets.particles.vx[i] = 150.0 + static_cast<double>(i) / 10;
    bullets.particles.vy[i] = -90.0;
  }
  const Scene scenes[] = {random_scene(400, 4000, 1, 60, 11),
                          random_scene(600, 300, 2, 60, 42),
                          random_scene(3000, 400, 1, 30, 5, speeds(0.5, 1)),
                          random_scene(200, 500, 1, 40, 6, speeds(400, 1200)),
                          random_scene(500, 200, 1, 5, 2, speeds(0, 0)),
                          bullets};
  for (const Scene& scene : scenes)
    for (int k : {1, 16}) expect_matches(scene, "brute", k);
}

TEST_F(GpuDevice, EveryPrintedTimeUnitMatchesBrute) {
  const Scene scene = random_scene(1000, 2000, 1, 20, 3, speeds(2, 20));
  for (int k : {1, 16})
    EXPECT_EQ(unit_hashes(scene, "gpu", k), unit_hashes(scene, "brute", k)) << "K=" << k;
}

TEST_F(GpuDevice, MatchesCellsOnAMillionParticleFamilyScene) {
  // Packing fraction about 0.2 (the million scene's family), speeds 0.05 to 0.2.
  const Scene scene = random_scene(200000, 1772, 1, 10, 4, speeds(0.05, 0.2));
  expect_matches(scene, "cells", 1);
}

}  // namespace
}  // namespace particle
