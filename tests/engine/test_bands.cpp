// The bands broad phase (broad_phase/bands.hpp) on the scenes where long paths meet: brute's
// final state and counters at T = 1, 2, 3, 8, at every time unit in print mode, and brute's
// candidates on hand-made sub-steps whose paths run past a wall line (issue 53).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

#include "broad_phase/bands.hpp"
#include "broad_phase/brute.hpp"
#include "helpers.hpp"
#include "pair_search.hpp"
#include "world_fixture.hpp"

namespace particle {
namespace {

using testing::Body;
using testing::Outcome;
using testing::outcome;
using testing::random_scene;
using testing::speeds;
using testing::WorldFixture;

// bands at T = 1, 2, 3, 8 gives brute's final state and counters, testing fewer pairs.
void expect_bands_match(const Scene& scene) {
  const Outcome reference = outcome(scene, "brute", 1);
  for (int threads : {1, 2, 3, 8}) {
    SCOPED_TRACE("T=" + std::to_string(threads));
    const Outcome got = outcome(scene, "bands", threads);
    testing::expect_same(got, reference);
    EXPECT_LE(got.report.counters.pair_tests, reference.report.counters.pair_tests);
  }
}

TEST(BandsMatchBrute, DefaultScene) {
  // The 2019 default scene (N = 1000, L = 20000, r = 1, speeds L/(8r) to L/4), 100 time units.
  const Scene scene = random_scene(1000, 20000, 1, 100);
  const Outcome bands = outcome(scene, "bands", 1);
  const Outcome sweep = outcome(scene, "sweep", 1);
  EXPECT_LT(bands.report.counters.pair_tests * 2, sweep.report.counters.pair_tests);
  expect_bands_match(scene);
}

TEST(BandsMatchBrute, FasterThanTheBox) {
  expect_bands_match(random_scene(300, 500, 1, 40, 6, speeds(600, 2000)));
}

TEST(BandsMatchBrute, FastAmongStill) {
  Scene scene = random_scene(1500, 3000, 1, 40, 9, speeds(300, 800));
  for (std::size_t i = 0; i < scene.size(); i += 2) {
    scene.particles.vx[i] = 0;
    scene.particles.vy[i] = 0;
  }
  expect_bands_match(scene);
}

TEST(BandsMatchBrute, DenseAndSlow) {
  const Scene scene = random_scene(600, 300, 2, 60, 42);
  ASSERT_GT(outcome(scene, "brute", 1).report.counters.overlaps, 0u);
  expect_bands_match(scene);
}

// The state hash after every time unit, as print mode writes it, and at the end.
std::vector<std::uint64_t> unit_hashes(Scene scene, const std::string& engine, int threads) {
  std::vector<std::uint64_t> hashes;
  RunOptions options;
  options.engine = engine;
  options.threads = threads;
  simulate(scene, options,
           [&](std::int64_t, const Particles& p) { hashes.push_back(state_hash(p)); });
  hashes.push_back(state_hash(scene.particles));
  return hashes;
}

TEST(BandsMatchBrute, PrintModeAtEveryTimeUnit) {
  Scene scene = random_scene(500, 8000, 1, 30, 21);
  scene.mode = OutputMode::print;
  const std::vector<std::uint64_t> reference = unit_hashes(scene, "brute", 1);
  ASSERT_GE(reference.size(), 30u);  // every time unit
  for (int threads : {1, 2, 3, 8}) EXPECT_EQ(unit_hashes(scene, "bands", threads), reference);
}

}  // namespace

namespace detail {
namespace {

using testing::find;
using testing::Found;


// bands, planned and with 1 to 64 bands, at T = 1, 2, 3, 8, finds brute's candidates (each once:
// a duplicate would differ from brute's list), overlaps and receding overlaps, each pair tested
// once at most; returns brute's.
Found expect_brutes_candidates(const std::vector<Body>& bodies, double L, double r) {
  WorldFixture f(L, r, bodies);
  BruteBroadPhase brute;
  const Found reference = find(brute, f.w, 1);
  for (std::uint32_t bands : {0u, 1u, 2u, 3u, 7u, 64u})
    for (int threads : {1, 2, 3, 8}) {
      SCOPED_TRACE("B=" + std::to_string(bands) + " T=" + std::to_string(threads));
      BandsBroadPhase broad(bands);
      const Found got = find(broad, f.w, threads);
      EXPECT_EQ(got.candidates, reference.candidates);
      EXPECT_EQ(got.overlaps, reference.overlaps);
      EXPECT_EQ(got.receding, reference.receding);
      EXPECT_LE(got.pair_tests, reference.pair_tests);
    }
  return reference;
}

// Two particles near the right wall, both moving right and towards each other in y: their
// straight paths meet past the wall line (each would bounce first), a candidate of the model that
// a broad phase of the paths cut at the wall would miss. Beside them, particles far away in
// every band, so the pair is not alone in its band.
TEST(BandsCandidates, PathsMeetPastAWallLine) {
  const double L = 1000, r = 1;
  std::vector<Body> bodies = {{990, 400, 40, 50}, {990, 500, 40, -50}};
  for (int k = 0; k < 40; ++k) bodies.push_back({20.0 + 20 * k, 25.0 * k + 3, 30, -20});
  const Found found = expect_brutes_candidates(bodies, L, r);
  ASSERT_FALSE(found.candidates.empty());
  EXPECT_EQ(std::get<0>(found.candidates.front()), 0u);
  EXPECT_EQ(std::get<1>(found.candidates.front()), 1u);
}

// The same at a corner: both paths cross both wall lines before they meet.
TEST(BandsCandidates, PathsMeetPastACorner) {
  const double L = 1000, r = 1;
  // The first reaches both wall lines at once (a corner bounce), the second one after the other;
  // cut at its first wall line, the second's path would not reach the first's box.
  std::vector<Body> bodies = {{980, 980, 60, 60}, {900, 990, 150, 50}, {10, 10, 0, 0}};
  for (int k = 0; k < 40; ++k) bodies.push_back({20.0 + 20 * k, 900.0 - 20 * k, -25, 30});
  const Found found = expect_brutes_candidates(bodies, L, r);
  ASSERT_FALSE(found.candidates.empty());
  EXPECT_EQ(std::get<0>(found.candidates.front()), 0u);
  EXPECT_EQ(std::get<1>(found.candidates.front()), 1u);
}

// Boxes that overlap on both axes but paths that never come near: a cross whose arms pass the
// middle at different times, and two parallel diagonals 10r apart.
TEST(BandsCandidates, BoxesOverlapPathsApart) {
  const std::vector<Body> bodies = {
      {100, 500, 400, 0},
      {500, 100, 0, 500},  // the second passes x = 500, y = 500 at t = 0.8
      {100, 100, 300, 300},
      {100, 114.14, 300, 300}};
  const Found found = expect_brutes_candidates(bodies, 1000, 1);
  EXPECT_TRUE(found.candidates.empty());
}

// Paths that pass at exactly 2r (disc = 0: no candidate) and a hair closer (a candidate).
TEST(BandsCandidates, PathsGrazeAtTwoR) {
  const std::vector<Body> bodies = {{100, 100, 200, 0},
                                    {300, 102, -200, 0},  // parallel lines 2r apart: they graze
                                    {100, 600, 200, 0},
                                    {300, 601.999, -200, 0}};
  const Found found = expect_brutes_candidates(bodies, 1000, 1);
  ASSERT_EQ(found.candidates.size(), 1u);
  EXPECT_EQ(std::get<0>(found.candidates.front()), 2u);
}

// Head-on pairs that meet at t = 1/4, 1/2 and 3/4, beside pairs that overlap at the start: one
// that stays together and one that recedes (both kept apart as receding, at t = 0), and one that
// approaches (a candidate at t = 0); each found once, each overlap counted once.
TEST(BandsCandidates, MeetingsAndOverlapsAtTheStart) {
  const std::vector<Body> bodies = {{100, 100, 2, 0},    {104, 100, -2, 0},   // t = 1/2
                                    {100, 300, 4, 0},    {104, 300, -4, 0},   // t = 1/4
                                    {100, 500, 4, 0},    {108, 500, -4, 0},   // t = 3/4
                                    {300, 300, 50, 50},  {301, 300.5, 50, 50},
                                    {600, 600, -30, 10}, {601.5, 600, 30, 10},
                                    {700, 700, 10, 0},   {701.5, 700, -10, 0}};  // t = 0
  const Found found = expect_brutes_candidates(bodies, 1000, 1);
  EXPECT_EQ(found.candidates.size(), 4u);
  EXPECT_EQ(found.receding.size(), 2u);
  EXPECT_EQ(found.overlaps, 3u);
}

// Displacements of several boxes per sub-step, beside still particles.
TEST(BandsCandidates, FasterThanTheBoxAmongStill) {
  std::vector<Body> bodies;
  for (int k = 0; k < 60; ++k) {
    const double a = 0.37 * k;
    bodies.push_back({5.0 + (k * 37) % 190, 5.0 + (k * 53) % 190, 0, 0});
    bodies.push_back(
        {5.0 + (k * 71) % 190, 5.0 + (k * 29) % 190, 900 * std::cos(a), 700 * std::sin(a)});
  }
  const Found found = expect_brutes_candidates(bodies, 200, 1);
  ASSERT_FALSE(found.candidates.empty());
}

// From kPrivateStateBelow particles on, one shared order is built by the team (the placing and
// the copies split over the threads): the same candidates at every T.
TEST(BandsCandidates, SharedOrderOfALargeScene) {
  const std::size_t n = kPrivateStateBelow + 1000;
  Scene scene =
      particle::testing::random_scene(static_cast<int>(n), 4000, 1, 1, 31, SpeedRange{20, 120});
  std::vector<Body> bodies;
  for (std::size_t i = 0; i < n; ++i)
    bodies.push_back(
        {scene.particles.x[i], scene.particles.y[i], scene.particles.vx[i], scene.particles.vy[i]});
  const Found found = expect_brutes_candidates(bodies, scene.L, scene.r);
  ASSERT_FALSE(found.candidates.empty());
}

TEST(BandsPlan, BandsPayOnlyForLongPaths) {
  PathSums fast;  // the default scene: boxes about 0.12 L on each axis
  fast.width = fast.height = 1000 * 0.12 * 20000;
  EXPECT_EQ(plan_bands(1000, 20000, fast), 6u);
  EXPECT_EQ(plan_bands(4000, 40000, fast), 12u);  // more particles: more bands pay
  PathSums flat;  // motion along y only: bands cost entries and keep every pair
  flat.width = 1000 * 2.0;
  flat.height = 1000 * 0.5 * 20000;
  EXPECT_EQ(plan_bands(1000, 20000, flat), 1u);
}

}  // namespace
}  // namespace detail
}  // namespace particle
