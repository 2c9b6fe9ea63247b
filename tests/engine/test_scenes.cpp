// Hand-made scenes with outcomes computed by hand from the model (docs/model.md, "The model"); the
// derivations are in the comments. Tolerance 1e-9 covers rounding of non-dyadic times.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"

namespace particle {
namespace {

using testing::run;
using testing::scene_from_file;

struct Expected {
  double x, y, vx, vy;
  std::uint64_t pair_collisions, wall_collisions;
};

void expect_state(const Particles& p, const std::vector<Expected>& expected) {
  ASSERT_EQ(p.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE("particle " + std::to_string(i));
    EXPECT_NEAR(p.x[i], expected[i].x, 1e-9);
    EXPECT_NEAR(p.y[i], expected[i].y, 1e-9);
    EXPECT_NEAR(p.vx[i], expected[i].vx, 1e-9);
    EXPECT_NEAR(p.vy[i], expected[i].vy, 1e-9);
    EXPECT_EQ(p.pair_collisions[i], expected[i].pair_collisions);
    EXPECT_EQ(p.wall_collisions[i], expected[i].wall_collisions);
  }
}

// Gap 20, closing 10 per step: step 1 t = 96/120 > 1; step 2 t = 0.8, meet at 49 and 51, swap,
// then 0.2 of a step apart: 48 and 52; two more steps: 38 and 62.
TEST(Scenes, HeadOn) {
  Scene s = scene_from_file("head_on.in");
  run(s);
  expect_state(s.particles, {{38, 50, -5, 0, 1, 0}, {62, 50, 5, 0, 1, 0}});
}

// Both axes reach the wall line 9 at t = 1 (touching at t = 1 counts): one corner collision,
// both components flip. Step 2 moves back to (5,5); step 3 reaches the corner (1,1).
TEST(Scenes, CornerFlipsBothAndCountsOnce) {
  Scene s = scene_from_file("corner.in");
  run(s);
  expect_state(s.particles, {{1, 1, 4, 4, 0, 2}});
}

// vx = 4 + 5e-15 from x = 5 reaches the wall line 9 at t = 4 / vx, 1.25e-15 before the end of
// time unit 1: that unit's hit (a wall test that asks the move to end 1e-14 beyond the line misses
// it; the 2019 authors' x + vx > L - r - 1e-14 takes it). The
// same again at x = 1 in time unit 3.
TEST(Scenes, AWallHitJustBeforeTheStepsEndIsThatSteps) {
  Scene s = scene_from_file("wall_before_end.in");
  Scene one = s;
  one.steps = 1;
  run(one);
  expect_state(one.particles, {{9, 5, -4, 0, 0, 1}});
  run(s);
  expect_state(s.particles, {{1, 5, 4, 0, 0, 2}});
}

// Particle 0 reaches the wall at t = 0.5 and particle 1 at the same t: (2,-4)/(−4,4) gives
// b = -24, c = 16, disc = 64, t = 16/32. Wall first: 0 bounces to 17; the pair is dropped and
// 1 slides up the wall line to (19,10).
TEST(Scenes, WallBeatsPairAtEqualTime) {
  Scene s = scene_from_file("wall_beats_pair.in");
  const RunReport report = run(s);
  expect_state(s.particles, {{17, 10, -4, 0, 0, 1}, {19, 10, 0, 4, 0, 0}});
  EXPECT_EQ(report.counters.candidates, 2u);
  EXPECT_EQ(report.counters.pair_candidates, 1u);  // the other is 0's wall hit
  EXPECT_EQ(report.counters.dropped, 1u);
}

// Step 2: (0,1) and (1,2) both at t = 21/35 = 0.6; the lower indices win, (1,2) and (0,2)
// (t = 0.8) are dropped, so 2 overlaps 1 after the step. Step 3: (1,2) recedes; (0,2) touch
// (c = 0) and approach: they collide at t = 0. Final 13, 27, 20.
TEST(Scenes, ThreeInARowTieGoesToLowestIndices) {
  Scene s = scene_from_file("three_in_row_tie.in");
  run(s);
  expect_state(s.particles, {{13, 50, -5, 0, 2, 0}, {27, 50, 5, 0, 1, 0}, {20, 50, 0, 0, 1, 0}});
}

// Overlapping (distance 1 < 2) and approaching: collide at t = 0, swap, move apart a full step.
TEST(Scenes, OverlapApproachingCollidesNow) {
  Scene s = scene_from_file("overlap_approaching.in");
  const RunReport report = run(s);
  expect_state(s.particles, {{49, 50, -1, 0, 1, 0}, {52, 50, 1, 0, 1, 0}});
  EXPECT_EQ(report.counters.overlaps, 1u);
}

TEST(Scenes, OverlapRecedingPassesOn) {
  Scene s = scene_from_file("overlap_receding.in");
  const RunReport report = run(s);
  expect_state(s.particles, {{49, 50, -1, 0, 0, 0}, {52, 50, 1, 0, 0, 0}});
  EXPECT_EQ(report.counters.overlaps, 1u);
  EXPECT_EQ(report.counters.receding_overlaps, 1u);
}

// The overlap reading `always`: the receding pair collides at t = 0 all the same, so its
// velocities swap and each moves back over the other (still overlapping, now approaching).
TEST(Scenes, OverlapRecedingCollidesUnderTheAlwaysReading) {
  for (const std::string engine : {"brute", "sweep", "bands", "cells", "grid", "auto"}) {
    SCOPED_TRACE(engine);
    Scene s = scene_from_file("overlap_receding.in");
    const RunReport report =
        run(s, engine, 1, 1, 8, WallStop::per_coordinate, Overlap::always);
    expect_state(s.particles, {{51, 50, 1, 0, 1, 0}, {50, 50, -1, 0, 1, 0}});
    EXPECT_EQ(report.counters.receding_overlaps, 1u);
    EXPECT_EQ(report.counters.pair_collisions, 1u);
  }
}

// An approaching overlapping pair collides under either reading: the same state.
TEST(Scenes, OverlapApproachingIsTheSameUnderEitherReading) {
  Scene approaching = scene_from_file("overlap_approaching.in");
  Scene always = approaching;
  run(approaching);
  run(always, "brute", 1, 1, 8, WallStop::per_coordinate, Overlap::always);
  EXPECT_EQ(state_hash(always.particles), state_hash(approaching.particles));
}

// Speed 30 in a box of 10: wall at t = 4/30, the rest of the step would cross the far wall, so
// it stops on the line x = 1. Step 2: on the line moving out, t = 0: flips and stops at x = 9.
TEST(Scenes, FasterThanTheBoxStopsAtTheWall) {
  Scene s = scene_from_file("faster_than_box.in");
  run(s);
  expect_state(s.particles, {{9, 5, 30, 0, 0, 2}});
}

// Paths cross at (50,50) at times 3 and 6; the closest approach is sqrt(360) > 2.
TEST(Scenes, CrossingDiagonalsNeverMeet) {
  Scene s = scene_from_file("crossing.in");
  run(s);
  expect_state(s.particles, {{70, 70, 10, 10, 0, 0}, {55, 45, -5, 5, 0, 0}});
}

// Along the diagonal, contact after tau = (10 sqrt2 - 2) / (3 sqrt2) steps; each collision passes
// the whole velocity on: 0 stops at 10 + 3 tau, 1 at 20 + 3 tau, 2 moves from 2 tau to 8.
TEST(Scenes, DiagonalLinePassesMomentumAlong) {
  Scene s = scene_from_file("diagonal.in");
  run(s);
  const double tau = (10 * std::sqrt(2.0) - 2) / (3 * std::sqrt(2.0));
  const double x0 = 10 + 3 * tau, x1 = 20 + 3 * tau, x2 = 30 + 3 * (8 - 2 * tau);
  expect_state(s.particles, {{x0, x0, 0, 0, 1, 0}, {x1, x1, 0, 0, 2, 0}, {x2, x2, 3, 3, 1, 0}});
}

// Neighbours on the diagonals touch at t = 1 - 2/(5 sqrt2) of step 2, before the head-on pairs
// (t = 0.8). All four diagonal pairs tie; (0,2) and (1,3) win by index. Each pair turns by 90
// degrees: 0 up, 2 right, 1 down, 3 left, then moves 5 (1 - t) = sqrt2.
TEST(Scenes, FourMeetingAtTheCentre) {
  Scene s = scene_from_file("four_at_centre.in");
  const RunReport report = run(s);
  const double a = 50 - std::sqrt(2.0), b = 50 + std::sqrt(2.0);
  expect_state(s.particles,
               {{a, b, 0, 5, 1, 0}, {b, a, 0, -5, 1, 0}, {b, a, 5, 0, 1, 0}, {a, b, -5, 0, 1, 0}});
  EXPECT_EQ(report.counters.candidates, 6u);
  EXPECT_EQ(report.counters.pair_candidates, 6u);  // every pair of the four, no wall
  EXPECT_EQ(report.counters.dropped, 4u);
}

// Three converging: (0,2) and (1,2) tie, (0,2) wins; 1 is left without a collision and runs on
// to the centre.
TEST(Scenes, ThreeMeetingAtOnce) {
  Scene s = scene_from_file("three_at_once.in");
  run(s);
  const double a = 50 - std::sqrt(2.0), b = 50 + std::sqrt(2.0);
  expect_state(s.particles, {{a, b, 0, 5, 1, 0}, {50, 50, -5, 0, 0, 0}, {b, a, 5, 0, 1, 0}});
}

// K = 1: 0 touches 1 at t = 1 of step 2; 1 passes it to 2 at t = 0 of step 3, and 2 moves 4
// through 3 (both at rest at the step's start: no candidate), so 3 never moves.
TEST(Scenes, CradleAtSlowFactorOneSkipsTheLastBall) {
  Scene s = scene_from_file("cradle.in");
  run(s);
  expect_state(
      s.particles,
      {{28, 50, 0, 0, 1, 0}, {30, 50, 0, 0, 2, 0}, {40, 50, 4, 0, 1, 0}, {34, 50, 0, 0, 0, 0}});
}

// K = 4 (u = 1 per sub-step): contact at the end of sub-step 8; 1 -> 2 at t = 0 of sub-step 9;
// 2 moves to 33, overlaps 3 and passes it on in sub-step 10; 3 then moves 7 sub-steps to 41.
TEST(Scenes, CradleAtSlowFactorFourReachesTheLastBall) {
  Scene s = scene_from_file("cradle.in");
  run(s, "brute", 1, 4);
  expect_state(
      s.particles,
      {{28, 50, 0, 0, 1, 0}, {30, 50, 0, 0, 2, 0}, {33, 50, 0, 0, 2, 0}, {41, 50, 4, 0, 1, 0}});
}

// Closing 80 per step from 60 apart: contact at t = 58/80 in step 1, at 39 and 41, then back
// 40 * 22/80 = 11 each: 28 and 52. grid-unsafe (the 2019 pruning, speeds assumed <= L/4 = 25)
// reaches only s + 2 * 25 = 52 (34 cells of 1.5625 at G = 64) and the pair is 38 cells apart: it
// misses the collision and both run on to 50 and 30.
TEST(Scenes, FastPairIsMissedOnlyByTheUnsafeGrid) {
  Scene exact = scene_from_file("too_fast_for_2019_grid.in");
  run(exact, "grid", 1, 1, 64);
  expect_state(exact.particles, {{28, 50, -40, 0, 1, 0}, {52, 50, 40, 0, 1, 0}});
  Scene unsafe = scene_from_file("too_fast_for_2019_grid.in");
  run(unsafe, "grid-unsafe", 1, 1, 64);
  expect_state(unsafe.particles, {{50, 50, 40, 0, 0, 0}, {30, 50, -40, 0, 0, 0}});
  EXPECT_FALSE(is_exact("grid-unsafe"));
  EXPECT_TRUE(is_exact("grid"));
}

}  // namespace
}  // namespace particle
