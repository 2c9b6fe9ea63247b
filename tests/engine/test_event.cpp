// The event engine against outcomes computed by hand (exact continuous-time physics), against a
// discrete engine at a fine slow factor, and against conservation and determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "event/simulation.hpp"
#include "helpers.hpp"
#include "world_fixture.hpp"

namespace particle {
namespace {

using testing::Body;
using testing::run;
using testing::scene_from_file;
using testing::scene_from_text;
using testing::WorldFixture;

struct Expected {
  double x, y, vx, vy;
  std::uint64_t pair_collisions, wall_collisions;
};

void expect_state(const Particles& p, const std::vector<Expected>& expected, double tol = 1e-9) {
  ASSERT_EQ(p.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE("particle " + std::to_string(i));
    EXPECT_NEAR(p.x[i], expected[i].x, tol);
    EXPECT_NEAR(p.y[i], expected[i].y, tol);
    EXPECT_NEAR(p.vx[i], expected[i].vx, tol);
    EXPECT_NEAR(p.vy[i], expected[i].vy, tol);
    EXPECT_EQ(p.pair_collisions[i], expected[i].pair_collisions);
    EXPECT_EQ(p.wall_collisions[i], expected[i].wall_collisions);
  }
}

// Gap 20 - s = 18 closing at 10: contact at exactly t = 396 / (200 + sqrt(400)) = 1.8 (the
// nearest double), at 49 and 51; not one ulp before.
TEST(Event, HeadOnExchangesAtTheExactTime) {
  WorldFixture f(100, 1, {{40, 50, 5, 0}, {60, 50, -5, 0}});
  detail::EventSimulation sim(f.w, 1);
  sim.run_until(std::nextafter(1.8, 0.0));
  EXPECT_EQ(sim.counters().pair_collisions, 0u);
  sim.run_until(1.8);
  EXPECT_EQ(sim.counters().pair_collisions, 1u);
  sim.write_state(1.8);
  EXPECT_NEAR(f.x[0], 49, 1e-12);
  EXPECT_NEAR(f.x[1], 51, 1e-12);
  EXPECT_EQ(f.ux[0], -5);
  EXPECT_EQ(f.ux[1], 5);
  Scene s = scene_from_file("head_on.in");
  run(s, "event");
  expect_state(s.particles, {{38, 50, -5, 0, 1, 0}, {62, 50, 5, 0, 1, 0}});
}

// Speed 42 in a box of 10 (centre span D = 8): the unfolded path x0 - r + v t folded into [0, D]
// is a triangle wave, and the wall hits up to t are the k >= 0 with (9 - x0) + k D <= v t.
TEST(Event, FasterThanTheBoxIsATriangleWave) {
  const double v = 42, x0 = 5, r = 1, D = 8;
  Scene s = scene_from_text("1\n10\n1\n3\nprint\n0 5 5 42 0\n");
  std::vector<std::pair<double, double>> seen;  // (x, vx) at t = 1, 2
  RunOptions options;
  options.engine = "event";
  simulate(s, options, [&](std::int64_t, const Particles& p) {
    seen.push_back({p.x[0], p.vx[0]});
  });
  seen.push_back({s.particles.x[0], s.particles.vx[0]});
  ASSERT_EQ(seen.size(), 3u);
  for (int t = 1; t <= 3; ++t) {
    const double unfolded = std::fmod(x0 - r + v * t, 2 * D);
    const bool outbound = unfolded < D;
    EXPECT_NEAR(seen[t - 1].first, r + (outbound ? unfolded : 2 * D - unfolded), 1e-9) << t;
    EXPECT_EQ(seen[t - 1].second, outbound ? v : -v) << t;
  }
  const auto hits = static_cast<std::uint64_t>(std::floor((v * 3 - (9 - x0)) / D)) + 1;
  EXPECT_EQ(hits, 16u);
  EXPECT_EQ(s.particles.wall_collisions[0], hits);
  EXPECT_EQ(s.particles.y[0], 5);
}

// Each wall hit gives the wall 2 |v_normal|: 16 hits at speed 42 by t = 3 (the triangle wave
// above), and a corner hit at (4, 4) gives both components.
TEST(Event, WallImpulseSumsTwiceTheNormalSpeed) {
  WorldFixture f(10, 1, {{5, 5, 42, 0}});
  detail::EventSimulation sim(f.w, 1);
  sim.run_until(3);
  EXPECT_EQ(sim.counters().wall_collisions, 16u);
  EXPECT_DOUBLE_EQ(sim.wall_impulse(), 16 * 2 * 42.0);
  WorldFixture corner(10, 1, {{5, 5, 4, 4}});
  detail::EventSimulation at_corner(corner.w, 1);
  at_corner.run_until(1);
  EXPECT_EQ(at_corner.counters().wall_collisions, 1u);
  EXPECT_DOUBLE_EQ(at_corner.wall_impulse(), 2 * 4 + 2 * 4.0);
}

// Neighbours touch when a sqrt(2) = s, at t = (10 - sqrt(2)) / 5: 0 meets 2, then in a zero-time
// cascade 0-3, 3-1, 1-2, and every disk leaves along its own axis: at t = 2, a = 2 sqrt(2).
// (The discrete model takes one collision per disk per step and deflects them instead.)
TEST(Event, FourDisksMeetingAtTheCentreAllReverse) {
  Scene s = scene_from_file("four_at_centre.in");
  run(s, "event");
  const double a = 2 * std::sqrt(2.0);
  expect_state(s.particles, {{50 - a, 50, -5, 0, 2, 0},
                             {50 + a, 50, 5, 0, 2, 0},
                             {50, 50 - a, 0, -5, 2, 0},
                             {50, 50 + a, 0, 5, 2, 0}});
  Scene discrete = scene_from_file("four_at_centre.in");
  run(discrete, "brute");
  EXPECT_NEAR(discrete.particles.vy[0], 5, 1e-9);  // one collision per step: deflected upwards
}

// 0 reaches the row at t = 2; the motion passes through 1 and 2 at once and 3 runs on to 42.
TEST(Event, CradlePassesTheMotionToTheLastDiskOnly) {
  Scene s = scene_from_file("cradle.in");
  run(s, "event");
  expect_state(
      s.particles,
      {{28, 50, 0, 0, 1, 0}, {30, 50, 0, 0, 2, 0}, {32, 50, 0, 0, 2, 0}, {42, 50, 4, 0, 1, 0}});
}

// Overlapping and approaching: collide at t = 0 and part. Overlapping and receding: no event.
TEST(Event, OverlapRules) {
  Scene approaching = scene_from_file("overlap_approaching.in");
  run(approaching, "event");
  expect_state(approaching.particles, {{49, 50, -1, 0, 1, 0}, {52, 50, 1, 0, 1, 0}});
  Scene receding = scene_from_file("overlap_receding.in");
  run(receding, "event");
  expect_state(receding.particles, {{49, 50, -1, 0, 0, 0}, {52, 50, 1, 0, 0, 0}});
  // Centres 1 apart, s = 2: half of s deep.
  WorldFixture f(100, 1, {{50, 50, -1, 0}, {51, 50, 1, 0}});
  detail::EventSimulation sim(f.w, 1);
  sim.run_until(1);
  EXPECT_DOUBLE_EQ(sim.max_overlap(), 0.5);
}

// A tight cluster of overlapping disks, all moving inwards: a zero-time cascade that must end.
TEST(Event, OverlappingClusterCascadeEnds) {
  std::vector<Body> bodies;
  for (int k = 0; k < 7; ++k) {
    const double angle = 2 * M_PI * k / 7;
    bodies.push_back({50 + 1.2 * std::cos(angle), 50 + 1.2 * std::sin(angle), -3 * std::cos(angle),
                      -3 * std::sin(angle)});
  }
  WorldFixture f(100, 1, bodies);
  detail::EventSimulation sim(f.w, 1);
  sim.run_until(1);
  EXPECT_GT(sim.counters().pair_collisions, 0u);
  EXPECT_LT(sim.counters().pair_collisions, 1000u);
}

// Dilute scene, short horizon: a discrete engine at K = 1024 takes every collision at its exact
// time (no particle meets two others within 1/1024 of a time unit), so both take the same
// collisions and end in the same state up to rounding, amplified by each collision (below 1e-4
// here; see the README's chaos horizon).
TEST(Event, AgreesWithAFineDiscreteEngineOnADiluteScene) {
  Scene exact = testing::random_scene(200, 400, 1, 2, 7);
  Scene discrete = exact;
  const RunReport e = run(exact, "event");
  const RunReport d = run(discrete, "cells", 1, 1024);
  EXPECT_GT(e.counters.pair_collisions, 20u);
  EXPECT_EQ(e.counters.pair_collisions, d.counters.pair_collisions);
  EXPECT_EQ(e.counters.wall_collisions, d.counters.wall_collisions);
  double deviation = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    deviation = std::max(deviation, std::abs(exact.particles.x[i] - discrete.particles.x[i]));
    deviation = std::max(deviation, std::abs(exact.particles.y[i] - discrete.particles.y[i]));
    deviation = std::max(deviation, std::abs(exact.particles.vx[i] - discrete.particles.vx[i]));
    deviation = std::max(deviation, std::abs(exact.particles.vy[i] - discrete.particles.vy[i]));
  }
  EXPECT_LT(deviation, 1e-3);
}

TEST(Event, ConservesEnergy) {
  Scene s = testing::random_scene(2000, 200, 1, 5, 11);
  const double before = kinetic_energy(s.particles);
  const RunReport report = run(s, "event");
  EXPECT_GT(report.counters.pair_collisions, 10000u);
  EXPECT_NEAR(kinetic_energy(s.particles) / before, 1, 1e-12);
}

// Same input, same bits: twice, and print mode against perf mode.
TEST(Event, IsDeterministic) {
  Scene a = testing::random_scene(1000, 300, 1, 4, 5);
  Scene b = a;
  Scene c = a;
  c.mode = OutputMode::print;
  run(a, "event");
  run(b, "event", 2, 8);
  RunOptions options;
  options.engine = "event";
  int calls = 0;
  simulate(c, options, [&](std::int64_t, const Particles&) { ++calls; });
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(state_hash(a.particles), state_hash(b.particles));
  EXPECT_EQ(state_hash(a.particles), state_hash(c.particles));
}

// event is exact physics but a different model from brute's: not bit-identical, and not unsafe.
TEST(Event, IsDeclaredNeitherBitIdenticalNorUnsafe) {
  EXPECT_FALSE(is_exact("event"));
  EXPECT_FALSE(drops_collisions("event"));
  EXPECT_TRUE(drops_collisions("grid-unsafe"));
  EXPECT_FALSE(drops_collisions("brute"));
}

}  // namespace
}  // namespace particle

namespace particle {
namespace {

// Kinetic theory for hard disks: Enskog's collision rate per particle nu = 2 n s g(s)
// sqrt(pi <v^2> / 2) with Henderson's contact value g(s) = (1 - 7 eta / 16) / (1 - eta)^2, and
// Henderson's equation of state Z = (1 + eta^2 / 8) / (1 - eta)^2, against the event engine on a
// moderately dense scene (eta = 0.2). After one time unit of relaxation (about 17 collisions per
// particle: the uniform speed law becomes Maxwellian), blocks of half a time unit give the mean
// and its standard error. Tolerance: 4 standard errors plus s/L, the order of the walls' effect
// (theory is for an infinite system; here the centres live in (L - s)^2 and the layer of width s
// at the walls has a different contact density). Measured at s/L = 0.56%: rate +0.6%, Z +0.8%.
TEST(EventKineticTheory, CollisionRateAndPressureMatchEnskogHenderson) {
  const int n = 8000, blocks = 10;
  const double eta = 0.2, r = 1, s = 2 * r;
  const double L = std::sqrt(n * M_PI * r * r / eta);
  Scene scene = testing::random_scene(n, L, r, 1, 3210);
  Particles& p = scene.particles;
  std::vector<double> ux = p.vx, uy = p.vy, impulse(n);
  const detail::World w =
      detail::make_world(L, r, n, p.x.data(), p.y.data(), ux.data(), uy.data(),
                         p.pair_collisions.data(), p.wall_collisions.data(), impulse.data());
  detail::EventSimulation sim(w, 1);
  sim.run_until(1);
  std::vector<double> rate, z;
  const double v2 = 2 * kinetic_energy(p) / n;  // <v^2>, conserved
  for (int b = 0; b < blocks; ++b) {
    const std::uint64_t pairs = sim.counters().pair_collisions;
    const double impulse = sim.wall_impulse();
    sim.run_until(1 + 0.5 * (b + 1));
    rate.push_back(static_cast<double>(sim.counters().pair_collisions - pairs) / 0.5);
    const double pressure = (sim.wall_impulse() - impulse) / (4 * L * 0.5);
    z.push_back(pressure * L * L / (n * v2 / 2));
  }
  const auto mean_and_error = [](const std::vector<double>& v) {
    double m = 0, ss = 0;
    for (double x : v) m += x;
    m /= v.size();
    for (double x : v) ss += (x - m) * (x - m);
    return std::pair{m, std::sqrt(ss / (v.size() - 1) / v.size())};
  };
  const double density = n / (L * L);
  const double g = (1 - 7 * eta / 16) / ((1 - eta) * (1 - eta));
  const double enskog = n * (2 * density * s * g * std::sqrt(M_PI * v2 / 2)) / 2;
  const double henderson = (1 + eta * eta / 8) / ((1 - eta) * (1 - eta));
  const auto [rate_mean, rate_error] = mean_and_error(rate);
  const auto [z_mean, z_error] = mean_and_error(z);
  EXPECT_NEAR(rate_mean, enskog, 4 * rate_error + enskog * s / L);
  EXPECT_NEAR(z_mean, henderson, 4 * z_error + henderson * s / L);
}

}  // namespace
}  // namespace particle
