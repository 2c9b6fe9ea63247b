#include <gtest/gtest.h>

#include "step/stages.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

using testing::WorldFixture;

// Wall candidates in a box of 10 with r = 1: wall lines at 1 and 9.
std::vector<Candidate> walls(const std::vector<testing::Body>& bodies) {
  WorldFixture f(10, 1, bodies);
  ThreadScratch s;
  find_wall_candidates(f.w, s);
  return s.candidates;
}

TEST(Walls, EarlierAxisWins) {
  const auto c = walls({{8, 5, 2, 1}});  // x at t = 0.5, y at t = 4
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].t, 0.5);
  EXPECT_EQ(c[0].j, kWallX);
  const auto d = walls({{5, 2, 0.5, -2}});  // y at t = 0.5
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].j, kWallY);
}

TEST(Walls, EqualTimesAreACorner) {
  const auto c = walls({{8, 2, 2, -2}});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].t, 0.5);
  EXPECT_EQ(c[0].j, kWallCorner);
}

TEST(Walls, TouchingAtOneCountsAndBeyondDoesNot) {
  EXPECT_EQ(walls({{7, 5, 2, 0}}).size(), 1u);
  EXPECT_TRUE(walls({{6.9, 5, 2, 0}}).empty());
}

TEST(Walls, OnOrPastTheLineMovingOutHitsNow) {
  const auto c = walls({{9, 5, 1, 0}, {1, 5, -3, 0}});
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].t, 0.0);
  EXPECT_EQ(c[1].t, 0.0);
}

TEST(Walls, RestingOrSlidingOnTheWallIsNoCandidate) {
  // At rest in a corner, sliding along the wall line, and leaving the wall: never 0/0, no hit.
  EXPECT_TRUE(walls({{1, 1, 0, 0}, {9, 5, 0, 1}, {9, 5, -1, 0.5}}).empty());
}

TEST(Walls, ResolveFlipsAndStopsAtTheLine) {
  WorldFixture f(10, 1, {{8, 2, 2, -2}, {5, 5, 30, 0}});
  ThreadScratch s;
  find_wall_candidates(f.w, s);
  ASSERT_EQ(s.candidates.size(), 2u);
  resolve_collisions(f.w, s.candidates);
  // Corner at t = 0.5: both flip, half a step back.
  EXPECT_EQ(f.x[0], 8);
  EXPECT_EQ(f.y[0], 2);
  EXPECT_EQ(f.ux[0], -2);
  EXPECT_EQ(f.uy[0], 2);
  EXPECT_EQ(f.wall_collisions[0], 1u);
  // Bounces off x = 9 and would cross x = 1 in the same sub-step: stops on the line.
  EXPECT_EQ(f.x[1], 1);
  EXPECT_EQ(f.ux[1], -30);
}

TEST(Walls, AdvanceClampsToTheWallLines) {
  WorldFixture f(10, 1, {{8.75, 5, 0.5, 0}, {3, 3, 1, 1}});
  std::vector<std::uint8_t> taken(2, 0);
  advance_free(f.w, taken);
  EXPECT_EQ(f.x[0], 9);
  EXPECT_EQ(f.x[1], 4);
  EXPECT_EQ(f.y[1], 4);
}

// Past eight particles the advance goes eight lanes at a time (with AVX-512): each lane clamps to
// either line on either axis, or moves freely, and a taken particle is neither read nor moved.
TEST(Walls, AdvanceClampsInEveryLane) {
  std::vector<testing::Body> bodies;
  for (int i = 0; i < 19; ++i) {
    const double past = i % 2 ? 0.5 : -0.5;  // past x = 9 or x = 1 by a quarter
    bodies.push_back({i % 2 ? 8.75 : 1.25, i % 3 == 0 ? 5.0 : (i % 3 == 1 ? 8.8 : 1.2), past,
                      i % 3 == 0 ? 0.25 : (i % 3 == 1 ? 0.5 : -0.5)});
  }
  WorldFixture f(10, 1, bodies);
  std::vector<std::uint8_t> taken(bodies.size(), 0);
  for (std::size_t i = 0; i < bodies.size(); i += 5) taken[i] = 1;
  advance_free(f.w, taken);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    SCOPED_TRACE(i);
    if (taken[i]) {
      EXPECT_EQ(f.x[i], bodies[i].x);
      EXPECT_EQ(f.y[i], bodies[i].y);
    } else {
      EXPECT_EQ(f.x[i], i % 2 ? 9 : 1);
      EXPECT_EQ(f.y[i], i % 3 == 0 ? 5.25 : (i % 3 == 1 ? 9 : 1));
    }
  }
}

}  // namespace
}  // namespace particle::detail
