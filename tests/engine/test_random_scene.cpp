#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "helpers.hpp"
#include "particle/limits.hpp"
#include "particle/random_scene.hpp"

namespace particle {
namespace {

using testing::random_scene;

TEST(RandomScene, InTheBoxWithoutOverlapAndSpeedsInRange) {
  const Scene s = random_scene(2000, 400, 2, 1, 77);
  const Particles& p = s.particles;
  const double lo = std::min(s.L / (8 * s.r), s.L / 4), hi = std::max(s.L / (8 * s.r), s.L / 4);
  for (std::size_t i = 0; i < s.size(); ++i) {
    ASSERT_GE(p.x[i], s.r);
    ASSERT_LE(p.x[i], s.L - s.r);
    ASSERT_GE(p.y[i], s.r);
    ASSERT_LE(p.y[i], s.L - s.r);
    const double speed = std::hypot(p.vx[i], p.vy[i]);
    ASSERT_GE(speed, lo * (1 - 1e-12));
    ASSERT_LE(speed, hi * (1 + 1e-12));
  }
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      const double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i];
      ASSERT_GE(dx * dx + dy * dy, 4 * s.r * s.r) << i << " " << j;
    }
}

TEST(RandomScene, SameSeedSameSceneOtherSeedOtherScene) {
  EXPECT_EQ(state_hash(random_scene(500, 1000, 1, 1, 5).particles),
            state_hash(random_scene(500, 1000, 1, 1, 5).particles));
  EXPECT_NE(state_hash(random_scene(500, 1000, 1, 1, 5).particles),
            state_hash(random_scene(500, 1000, 1, 1, 6).particles));
}

// Pins the generator to SplitMix64 and the first placement to values computed by an independent
// Python implementation: a change here changes every random scene users have measured.
TEST(RandomScene, GeneratorIsPinned) {
  Random rng(3210);
  EXPECT_EQ(rng.next(), 0x59b45a7586707d3full);
  const Scene s = random_scene(3, 100, 1, 1, 3210);
  EXPECT_DOUBLE_EQ(s.particles.x[0], 35.34000593364822);
  EXPECT_DOUBLE_EQ(s.particles.y[0], 30.177403931214805);
}

// The placement rule written plainly: one draw at a time (its position from the generator's draws
// 2k and 2k + 1), tested against every particle placed, at most kMaxPlacementAttempts draws a
// particle; then the speeds from the draws after the last position tested (draw_speeds).
// Returns the error's count ("placed i of"), or "" with the scene in `p`.
std::string place_plainly(Particles& p, double L, double r, std::uint64_t seed) {
  Random rng(seed);
  const double span = L - 2 * r;
  std::uint64_t taken = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int attempt = 1;; ++attempt) {
      if (attempt > kMaxPlacementAttempts) return "placed " + std::to_string(i) + " of";
      const double x = std::min(r + rng.uniform() * span, L - r);
      const double y = std::min(r + rng.uniform() * span, L - r);
      ++taken;
      bool refused = false;
      for (std::size_t j = 0; j < i && !refused; ++j)
        refused = (p.x[j] - x) * (p.x[j] - x) + (p.y[j] - y) * (p.y[j] - y) < 4 * r * r;
      if (refused) continue;
      p.x[i] = x;
      p.y[i] = y;
      break;
    }
  }
  draw_speeds(p, seed, taken, default_speed_range(L, r));
  return "";
}

// place_random decides the draws in batches sorted by cell, on any number of threads
// (scene/placement.cpp): the same scene, bit for bit, as the plain rule, and the same count where
// the box is too full. The cases: one particle; sparse boxes decided in one batch (20,000: a
// batch split over threads at every step); dense ones where each batch holds at most a draw a cell
// of the placement's grid, so that later batches are decided against the disks of earlier ones,
// some finishing and some refused; a box one disk wide (L = 2r: every centre on one point, found
// by make fuzz). (Units where s * s is exact: the plain rule's squares agree with DiskCells'
// scaled ones.)
TEST(RandomScene, TheBatchesPlaceWhatThePlainRulePlaces) {
  struct Case {
    std::size_t n;
    double L, r;
    std::uint64_t seed;
  };
  int refused = 0;
  for (const Case& c :
       {Case{1, 10, 1, 3}, Case{700, 3000, 1, 5}, Case{20000, 2000, 1, 8}, Case{2000, 400, 2, 77},
        Case{250, 40, 1, 3210}, Case{290, 40, 1, 7}, Case{330, 40, 1, 3210}, Case{5000, 200, 1, 12},
        Case{9000, 200, 1, 11}, Case{3000, 120, 1, 4}, Case{5, 4, 2, 1}}) {
    Particles plain(c.n);
    const std::string plain_error = place_plainly(plain, c.L, c.r, c.seed);
    refused += !plain_error.empty();
    for (const int threads : {1, 2, 3, 8}) {
      SCOPED_TRACE("N " + std::to_string(c.n) + " L " + std::to_string(c.L) + " T " +
                   std::to_string(threads));
      Scene scene;
      scene.L = c.L;
      scene.r = c.r;
      scene.particles = Particles(c.n);
      std::string error;
      try {
        place_random(scene, RandomInit{c.seed, std::nullopt}, threads);
      } catch (const InputError& e) {
        error = e.what();
      }
      if (!plain_error.empty()) {
        EXPECT_NE(error.find(plain_error), std::string::npos) << error;
        continue;
      }
      ASSERT_EQ(error, "");
      EXPECT_EQ(scene.particles.x, plain.x);
      EXPECT_EQ(scene.particles.y, plain.y);
      EXPECT_EQ(scene.particles.vx, plain.vx);
      EXPECT_EQ(scene.particles.vy, plain.vy);
    }
  }
  EXPECT_GT(refused, 0);
  EXPECT_LT(refused, 7);
}

TEST(RandomScene, SpeedRangeIsHonoured) {
  const Scene s = random_scene(1000, 4000, 1, 1, 8, SpeedRange{0.05, 0.2});
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double speed = std::hypot(s.particles.vx[i], s.particles.vy[i]);
    ASSERT_GE(speed, 0.05 * (1 - 1e-12));
    ASSERT_LE(speed, 0.2 * (1 + 1e-12));
  }
}

// Whether psim would run a random scene: its own path (read_scene places the particles from the
// seed, then check_representable), and what run_limit_breach, which psweep asks, predicts.
bool psim_accepts(std::int64_t n, double L, double r, std::uint64_t seed,
                  std::optional<SpeedRange> speed, int slow_factor) {
  try {
    const Scene s = testing::random_scene(static_cast<int>(n), L, r, 1, seed, speed);
    check_representable(s, slow_factor);
    return true;
  } catch (const InputError&) {
    return false;
  }
}

std::optional<LimitBreach> predicted(std::int64_t n, double L, double r, std::uint64_t seed,
                                     std::optional<SpeedRange> speed, int slow_factor) {
  RunRequest run;
  run.header = {n, L, r, 1, OutputMode::perf};
  run.options.engine = "brute";
  run.options.slow_factor = slow_factor;
  run.seed = seed;
  run.speed = speed;
  return run_limit_breach(run);
}

// Around the count where psim's placement gives up (between the union bound, which accepts
// about 57 disks of radius 1 in a box of 40, and Oler's, which refuses beyond 455), and with
// speed ranges whose slowest draws fit the limits and fastest do not, the prediction is psim's
// verdict, seed by seed; both verdicts occur.
TEST(RandomScene, RunLimitBreachPredictsWhatPsimRuns) {
  int accepted = 0, refused = 0;
  const auto expect_same = [&](std::int64_t n, double L, double r, std::uint64_t seed,
                               std::optional<SpeedRange> speed, int k) {
    const std::optional<LimitBreach> breach = predicted(n, L, r, seed, speed, k);
    const bool accepts = psim_accepts(n, L, r, seed, speed, k);
    EXPECT_EQ(!breach, accepts) << "N " << n << " L " << L << " seed " << seed << ": "
                                << (breach ? breach->key + ": " + breach->problem : "no breach");
    (accepts ? accepted : refused) += 1;
  };
  for (std::int64_t n = 200; n <= 320; n += 6)
    for (std::uint64_t seed : {3210u, 7u}) expect_same(n, 40, 1, seed, std::nullopt, 1);
  // speed limit: sqrt(sum v^2) / K <= 2^506 s, about 5.2e152 at s = 2; 2 particles at up to
  // 1e153 may or may not reach it; energy: 3 particles at up to 1.4e154 carry up to 3e308
  for (std::uint64_t seed = 0; seed < 12; ++seed) {
    expect_same(2, 1000, 1, seed, SpeedRange{0, 1e153}, 1);
    expect_same(3, 1e200, 1e190, seed, SpeedRange{0, 1.4e154}, 1);
  }
  EXPECT_GT(accepted, 10);
  EXPECT_GT(refused, 10);
}

// Decided without drawing where the range decides: every draw breaks the limit, or none can.
TEST(RandomScene, RunLimitBreachNamesTheSpeedKey) {
  const auto given = predicted(10, 1000, 1, 3210, SpeedRange{1e160, 1e160}, 1);
  ASSERT_TRUE(given);
  EXPECT_EQ(given->key, "speed_max");
  EXPECT_NE(given->problem.find("contact distances per sub-step, beyond the limit"),
            std::string::npos);
  const auto energy = predicted(10, 1e300, 1e290, 3210, SpeedRange{1e300, 1e300}, 1);
  ASSERT_TRUE(energy);
  EXPECT_EQ(energy->key, "speed_max");
  EXPECT_NE(energy->problem.find("kinetic energy"), std::string::npos);
  // the default speeds L/(8r) to L/4 at L = 1e-200, r = 1e-201 (README's example)
  const auto tiny = predicted(10, 1e-200, 1e-201, 3210, std::nullopt, 1);
  ASSERT_TRUE(tiny);
  EXPECT_EQ(tiny->key, "r");
  EXPECT_EQ(tiny->problem.rfind("with the default speeds L/(8r) to L/4, the particles can", 0), 0u);
  EXPECT_FALSE(predicted(1000, 20000, 1, 3210, std::nullopt, 1));
}

// The event engine's limits, seed by seed where the speed range leaves them open (2 disks at up
// to 5e12 per time unit in a box of 1000 are resolved to up to 2^-51 x 7e12 / 2 = 1.6e-3 contact
// distances, the limit is 2^-10 = 9.8e-4): psweep's prediction is the verdict psim reaches from
// the drawn scene. The discrete engines have no such limit.
TEST(RandomScene, RunLimitBreachPredictsTheEventEnginesLimits) {
  int accepted = 0, refused = 0;
  for (std::uint64_t seed = 0; seed < 16; ++seed) {
    RunRequest run;
    run.header = {2, 1000, 1, 1, OutputMode::perf};
    run.options.engine = "event";
    run.seed = seed;
    run.speed = SpeedRange{0, 5e12};
    const std::optional<LimitBreach> breach = run_limit_breach(run);
    const Scene drawn = testing::random_scene(2, 1000, 1, 1, seed, run.speed);
    bool within = true;
    try {
      check_representable(drawn, 1, "drawn", "event");
    } catch (const InputError&) {
      within = false;
    }
    EXPECT_EQ(!breach, within) << "seed " << seed;
    if (breach) {
      EXPECT_EQ(breach->key, "speed_max");
      EXPECT_NE(breach->problem.find("with the event engine"), std::string::npos);
    }
    (within ? accepted : refused) += 1;
    run.options.engine = "brute";
    EXPECT_FALSE(run_limit_breach(run)) << "seed " << seed;
  }
  EXPECT_GT(accepted, 2);
  EXPECT_GT(refused, 2);
}

}  // namespace
}  // namespace particle
