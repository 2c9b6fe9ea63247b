// The physics metrics of the declaration (particle/describe.hpp) on scenes computed by hand, the
// same for every discrete engine and thread count; event's where it measures them too.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "helpers.hpp"
#include "parallel/private_state.hpp"
#include "particle/describe.hpp"
#include "particle/io.hpp"

namespace particle {
namespace {

using testing::run;
using testing::scene_from_file;

double metric(const RunReport& report, std::string_view key) {
  for (const MetricInfo& m : metrics())
    if (m.key == key) return m.value(report).real;
  ADD_FAILURE() << "no metric " << key;
  return -1;
}

// The discrete engines: they share the narrow phase that measures overlaps.
std::vector<std::string> discrete_engines() {
  std::vector<std::string> names;
  for (const std::string& name : runnable_engines())
    if (find_engine_info(name)->uses_param(Param::slow_factor)) names.push_back(name);
  return names;
}

// Centres 1 apart, s = 2: depth (2 - 1)/2 = 0.5 at the first sub-step's start (c = 1 - 4 = -3,
// 1 - sqrt(1 - 3/4) = 0.5 exactly), approaching or receding alike. After that they separate.
// event finds the same depth when it predicts the pair's first event at t = 0.
TEST(PhysicsMetrics, MaxOverlapIsTheDeepestRelativeOverlap) {
  std::vector<std::string> every = discrete_engines();
  every.emplace_back("event");
  for (const char* file : {"overlap_approaching.in", "overlap_receding.in"})
    for (const std::string& engine : every)
      for (int threads : {1, 2}) {
        SCOPED_TRACE(std::string(file) + " " + engine + " T=" + std::to_string(threads));
        Scene s = scene_from_file(file);
        EXPECT_EQ(metric(run(s, engine, threads), "max_overlap"), 0.5);
      }
}

// Head-on at speeds 5 and -5 meet exactly at contact (t = 0 of a sub-step, c = 0: touching is not
// overlapping) and swap velocities: no overlap, and the energy 2 * 12.5 is unchanged.
TEST(PhysicsMetrics, TouchingIsNoOverlapAndASwapConservesEnergy) {
  for (const std::string& engine : discrete_engines()) {
    SCOPED_TRACE(engine);
    Scene s = scene_from_file("head_on.in");
    const RunReport report = run(s, engine, 2);
    EXPECT_EQ(metric(report, "max_overlap"), 0.0);
    EXPECT_EQ(report.physics.energy_initial, 25.0);
    EXPECT_EQ(metric(report, "energy_drift"), 0.0);
  }
}

// The drift is relative to the initial energy (EnergyMeter, which simulate() reports through
// energy_drift), and zero for a scene at rest instead of 0/0.
TEST(PhysicsMetrics, EnergyDriftIsRelativeAndZeroWithoutEnergy) {
  Particles initial(1);
  initial.vx[0] = 2;  // E = 2
  const EnergyMeter meter(initial);
  EXPECT_EQ(meter.initial(), 2.0);
  Particles now(1);
  now.vx[0] = std::sqrt(6.0);  // E = 3
  EXPECT_NEAR(meter.drift(now), 0.5, 1e-15);
  now.vx[0] = std::sqrt(3.0);  // E = 1.5
  EXPECT_NEAR(meter.drift(now), -0.25, 1e-15);
  const Particles rest(2);
  EXPECT_EQ(EnergyMeter(rest).drift(rest), 0.0);
  RunReport report;
  report.physics.energy_drift = -0.25;
  EXPECT_EQ(metric(report, "energy_drift"), -0.25);
}

// Every engine (the discrete ones at T = 1, 2 and K = 1, 4; event), one particle, hand-computed.
// Along x at speed 3 between the wall lines 1 and 9 from x = 5: hits at t = 4/3, 4, 20/3, 28/3,
// so by S = 10 the walls received 4 x 2 x 3 = 24. From (5, 5) at (4, 4) the particle reaches the
// corner (9, 9) at t = 1 exactly: one wall collision giving both components, 2 x 4 + 2 x 4 = 16.
TEST(PhysicsMetrics, WallImpulseOfOneBouncingParticle) {
  struct Case {
    const char* text;
    std::uint64_t hits;
    double impulse;
  };
  const Case cases[] = {{"1\n10\n1\n10\nperf\n0 5 5 3 0\n", 4, 24},
                        {"1\n10\n1\n2\nperf\n0 5 5 4 4\n", 1, 16}};
  for (const Case& c : cases)
    for (const std::string& engine : runnable_engines())
      for (int threads : {1, 2})
        for (int k : {1, 4}) {
          SCOPED_TRACE(engine + " T=" + std::to_string(threads) + " K=" + std::to_string(k) + " " +
                       c.text);
          Scene s = testing::scene_from_text(c.text);
          const RunReport report = run(s, engine, threads, k);
          EXPECT_EQ(report.counters.wall_collisions, c.hits);
          EXPECT_EQ(metric(report, "wall_impulse"), c.impulse);
        }
}

// Many particles in a small box (a wall collision every few sub-steps each): every exact discrete
// engine at every thread count gives the same bits as brute at T = 1, in both the private-state
// (N < kPrivateStateBelow) and the shared-state regime. The per-particle sums and the final sum in
// index order make it so; a shared accumulator added to in resolve order would differ with T.
TEST(PhysicsMetrics, WallImpulseIsIdenticalAcrossEnginesAndThreads) {
  struct Case {
    int n;
    double L;
    int steps;
    std::vector<int> ks, threads;
  };
  const Case cases[] = {{2000, 400, 5, {1, 2}, {1, 2, 3}},
                        {static_cast<int>(detail::kPrivateStateBelow), 1000, 1, {1}, {1, 3}}};
  for (const Case& c : cases) {
    for (int k : c.ks) {
      SCOPED_TRACE("N=" + std::to_string(c.n) + " K=" + std::to_string(k));
      const bool large = c.n > 5000;  // brute's O(N^2) is left out; cells stands in at T = 1
      Scene reference_scene = testing::random_scene(c.n, c.L, 1, c.steps);
      const double reference =
          metric(run(reference_scene, large ? "cells" : "brute", 1, k), "wall_impulse");
      EXPECT_GT(reference, 0);
      for (const std::string& engine : discrete_engines()) {
        if (drops_collisions(engine)) continue;  // a different dynamics: its own figure
        if (engine == "brute" && large) continue;
        for (int threads : c.threads) {
          SCOPED_TRACE(engine + " T=" + std::to_string(threads));
          Scene s = testing::random_scene(c.n, c.L, 1, c.steps);
          EXPECT_EQ(metric(run(s, engine, threads, k), "wall_impulse"), reference);
        }
      }
    }
  }
}

// event's max_overlap is measured at its predictions: exact dynamics leaves only rounding at
// contact (the pair just exchanged sits at distance s within an ulp or so), where a discrete
// engine at K = 1 on the same dense scene finds pairs deep inside each other at sub-step starts.
TEST(PhysicsMetrics, EventMaxOverlapIsRoundingOnly) {
  Scene exact = testing::random_scene(2000, 160, 1, 2, 3210, SpeedRange{1, 4});
  const double event = metric(run(exact, "event"), "max_overlap");
  EXPECT_LT(event, 1e-12);
  Scene discrete = testing::random_scene(2000, 160, 1, 2, 3210, SpeedRange{1, 4});
  EXPECT_GT(metric(run(discrete, "auto"), "max_overlap"), 1e-3);
}

}  // namespace
}  // namespace particle
