// The physics metrics of the declaration (particle/describe.hpp) on scenes computed by hand, the
// same for every discrete engine and thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "helpers.hpp"
#include "particle/describe.hpp"

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
  for (const EngineInfo& e : engines())
    if (e.uses_param(Param::slow_factor)) names.emplace_back(e.name);
  return names;
}

// Centres 1 apart, s = 2: depth (2 - 1)/2 = 0.5 at the first sub-step's start (c = 1 - 4 = -3,
// 1 - sqrt(1 - 3/4) = 0.5 exactly), approaching or receding alike. After that they separate.
TEST(PhysicsMetrics, MaxOverlapIsTheDeepestRelativeOverlap) {
  for (const char* file : {"overlap_approaching.in", "overlap_receding.in"})
    for (const std::string& engine : discrete_engines())
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

}  // namespace
}  // namespace particle
