#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "step/float_pretest.hpp"
#include "step/narrow_phase.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

using testing::WorldFixture;

// Pair candidates of two bodies in a large box (no walls involved), r = 1, s = 2.
std::vector<Candidate> pair_candidates(testing::Body a, testing::Body b,
                                       ThreadScratch* out = nullptr) {
  WorldFixture f(1000, 1, {a, b});
  ThreadScratch local;
  ThreadScratch& s = out ? *out : local;
  test_row(f.w, 0, 1, 2, s);
  return s.candidates;
}

TEST(NarrowPhase, ApproachingPairCollidesAtTheSmallerRoot) {
  // d = 10, closing 10 per sub-step: contact at distance 2 after t = 0.8.
  const auto c = pair_candidates({100, 100, 5, 0}, {110, 100, -5, 0});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c[0].t, 0.8);
  EXPECT_EQ(c[0].i, 0u);
  EXPECT_EQ(c[0].j, 1u);
}

TEST(NarrowPhase, RecedingPairIsNoCandidate) {
  EXPECT_TRUE(pair_candidates({100, 100, -5, 0}, {103, 100, 5, 0}).empty());
}

TEST(NarrowPhase, EqualVelocitiesAreNoCandidate) {
  EXPECT_TRUE(pair_candidates({100, 100, 3, 4}, {103, 100, 3, 4}).empty());
}

TEST(NarrowPhase, ExactGrazeIsNoCandidate) {
  // Closest approach is exactly s = 2: disc = 25 * 4 - (0 - 2 * -5)^2 = 0.
  EXPECT_TRUE(pair_candidates({100, 100, 0, 0}, {110, 102, -5, 0}).empty());
  // A hair closer does collide.
  EXPECT_EQ(pair_candidates({100, 100, 0, 0}, {104, 101.999, -5, 0}).size(), 1u);
}

TEST(NarrowPhase, OverlappingApproachingCollidesAtZero) {
  ThreadScratch s;
  const auto c = pair_candidates({100, 100, 1, 0}, {101, 100, -1, 0}, &s);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].t, 0.0);
  EXPECT_EQ(s.overlaps, 1u);
}

TEST(NarrowPhase, OverlappingRecedingIsCountedButNoCandidate) {
  ThreadScratch s;
  EXPECT_TRUE(pair_candidates({100, 100, -1, 0}, {101, 100, 1, 0}, &s).empty());
  EXPECT_EQ(s.overlaps, 1u);
}

TEST(NarrowPhase, TouchAtExactlyOneCountsAndJustAfterDoesNot) {
  // Gap 8 closed at speed 8: touching at t = 1 exactly.
  const auto at_one = pair_candidates({100, 100, 8, 0}, {110, 100, 0, 0});
  ASSERT_EQ(at_one.size(), 1u);
  EXPECT_EQ(at_one[0].t, 1.0);
  EXPECT_TRUE(pair_candidates({100, 100, 8, 0}, {110.5, 100, 0, 0}).empty());
}

TEST(NarrowPhase, OrderOfThePairDoesNotChangeTheResult) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> pos(0, 20), vel(-6, 6);
  for (int k = 0; k < 2000; ++k) {
    const testing::Body a{pos(rng), pos(rng), vel(rng), vel(rng)};
    const testing::Body b{pos(rng), pos(rng), vel(rng), vel(rng)};
    const auto ab = pair_candidates(a, b), ba = pair_candidates(b, a);
    ASSERT_EQ(ab.size(), ba.size());
    if (!ab.empty()) {
      EXPECT_EQ(ab[0].t, ba[0].t);  // bit-identical, not just close
    }
  }
}

// test_row (the 8-lane kernel over the World's own arrays, its last group ending at the row's end,
// or pair by pair in a World of fewer than 8) against test_pair on every pair of the same bodies.
// Returns how many candidates and overlaps they found.
std::size_t expect_rows_match_pairs(const std::vector<testing::Body>& bodies, double L, double r) {
  WorldFixture f(L, r, bodies);
  const auto n = static_cast<std::uint32_t>(bodies.size());
  std::size_t found = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    ThreadScratch row, single;
    test_row(f.w, i, i + 1, n, row);
    for (std::uint32_t j = i + 1; j < n; ++j) test_pair(f.w, i, j, single);
    EXPECT_EQ(row.candidates.size(), single.candidates.size()) << "row " << i;
    if (row.candidates.size() != single.candidates.size()) continue;
    for (std::size_t k = 0; k < row.candidates.size(); ++k) {
      EXPECT_EQ(row.candidates[k].j, single.candidates[k].j);
      EXPECT_EQ(row.candidates[k].t, single.candidates[k].t);
    }
    EXPECT_EQ(row.overlaps, single.overlaps);
    EXPECT_EQ(row.pair_tests, n - 1 - i);
    found += row.candidates.size() + row.overlaps;
  }
  return found;
}

// The vectorized row must report exactly the pairs the scalar test accepts, on rows of every
// length (whole groups, remainders, a World too small for one group).
TEST(NarrowPhase, RowKernelMatchesThePairByPairTest) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(1, 99), vel(-8, 8);
  std::vector<testing::Body> bodies;
  for (int k = 0; k < 300; ++k) bodies.push_back({pos(rng), pos(rng), vel(rng), vel(rng)});
  EXPECT_GT(expect_rows_match_pairs(bodies, 100, 1), 100u);
  for (std::size_t n = 2; n < 12; ++n)
    expect_rows_match_pairs({bodies.begin(), bodies.begin() + static_cast<long>(n)}, 100, 1);
}

// test_span over a copy (padded for its vector reads) against test_pair on the same bodies, for
// every span length from 1 to 80: the short 4- and 8-lane groups with their reach bound, the
// masked blocks and whole blocks. Returns how many candidates they found.
std::size_t expect_span_matches_pairs(const std::vector<testing::Body>& bodies, double r) {
  std::vector<testing::Body> padded = bodies;
  padded.resize(bodies.size() + kSpanPadding, testing::Body{1e9, 1e9, 0, 0});
  WorldFixture f(1e10, r, padded);
  std::vector<std::uint32_t> ids(padded.size());
  for (std::uint32_t k = 0; k < ids.size(); ++k) ids[k] = k;
  const SpanArrays a{f.w.x, f.w.y, f.w.ux, f.w.uy, ids.data()};
  const auto n = static_cast<std::uint32_t>(bodies.size());
  std::size_t found = 0;
  for (std::uint32_t i = 0; i + 1 < n; ++i) {
    const std::uint32_t end = std::min(n, i + 2 + (i % 80));
    ThreadScratch span, single;
    test_span({f.w.x[i], f.w.y[i], f.w.ux[i], f.w.uy[i], i}, a, i + 1, end, f.w.s2, span);
    for (std::uint32_t j = i + 1; j < end; ++j) test_pair(f.w, i, j, single);
    EXPECT_EQ(span.candidates.size(), single.candidates.size()) << "span from " << i;
    if (span.candidates.size() != single.candidates.size()) continue;
    for (std::size_t k = 0; k < span.candidates.size(); ++k) {
      EXPECT_EQ(span.candidates[k].j, single.candidates[k].j);
      EXPECT_EQ(span.candidates[k].t, single.candidates[k].t);
    }
    EXPECT_EQ(span.overlaps, single.overlaps);
    found += span.candidates.size();
  }
  return found;
}

TEST(NarrowPhase, SpanKernelMatchesThePairByPairTest) {
  // Slow and crowded (the cells' regime, where the reach bound drops most flagged pairs) and
  // fast (where it drops none).
  for (const double speed : {0.3, 2.0, 8.0}) {
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> pos(0, 12), vel(-speed, speed);
    std::vector<testing::Body> bodies;
    for (int k = 0; k < 2000; ++k) bodies.push_back({pos(rng), pos(rng), vel(rng), vel(rng)});
    SCOPED_TRACE(speed);
    EXPECT_GT(expect_span_matches_pairs(bodies, 1), 100u);
  }
}

TEST(NarrowPhase, ReachBoundKeepsTouchesAtTheEndOfTheSubStep) {
  // Head-on at |w| = s, touching at t = 1 exactly (d = s + |w|), in random directions and
  // scales, each followed by bodies that keep it in a short group.
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> angle(0, 6.283185307179586), scale(-30, 30);
  std::size_t found = 0;
  for (int k = 0; k < 400; ++k) {
    const double r = std::ldexp(1.0, static_cast<int>(scale(rng))), s = 2 * r;
    const double a = angle(rng), c = std::cos(a), sn = std::sin(a);
    found += expect_span_matches_pairs({{0, 0, s * c, s * sn},  // |w| = s, straight at the other
                                        {2 * s * c, 2 * s * sn, 0, 0}},  // |d| = 2 s
                                       r);
  }
  EXPECT_GT(found, 100u);  // rounding puts some touches just past t = 1
}

// may_touch_within_substep's two tests of time: a pair that touches at t = 1 (|d + w| = s, its
// first root at 1 or, where the paths cross the contact circle obliquely, its root before 1) or
// passes through contact within the sub-step (both roots inside it) is kept, whatever the
// direction, the angle of approach and the scale; one whose contact comes later is dropped.
TEST(NarrowPhase, TimeBoundKeepsEveryContactWithinTheSubStep) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0, 1), scale(-30, 30);
  const double e[] = {-0x1p-30, -0x1p-52, 0, 0x1p-52, 0x1p-44};
  std::size_t found = 0;
  for (int k = 0; k < 300; ++k) {
    const double r = std::ldexp(1.0, static_cast<int>(scale(rng))), s = 2 * r;
    const double a = 6.283185307179586 * unit(rng), b = 6.283185307179586 * unit(rng);
    const double speed = s * std::ldexp(1.0, static_cast<int>(unit(rng) * 12) - 8);
    const double wx = speed * std::cos(a), wy = speed * std::sin(a);
    // At t = 1 the second body is s (1 + e) from the first, at angle b: d = s n - w.
    std::vector<testing::Body> bodies{{0, 0, 0, 0}};
    for (const double ek : e)
      bodies.push_back({s * (1 + ek) * std::cos(b) - wx, s * (1 + ek) * std::sin(b) - wy, wx, wy});
    // Straight through the first body's centre, the contact at 0.3 and 0.3 + 2 s / |w|.
    const double tx = -std::cos(a), ty = -std::sin(a);
    bodies.push_back({(s + 0.3 * speed) * tx, (s + 0.3 * speed) * ty, wx, wy});
    found += expect_span_matches_pairs(bodies, r);
  }
  EXPECT_GT(found, 150u);  // about half the touches at t = 1 come from inside the circle
  // Head-on at closing speed 1 from d = 3.02 (s = 2): contact at t = 1.02, which the line test
  // flags and the time bound drops; from d = 2.98 at t = 0.98, which both keep.
  EXPECT_TRUE(needs_exact_test(3.02, 0.0, -1.0, 0.0, 4.0));
  EXPECT_FALSE(may_touch_within_substep(3.02 * 3.02, -3.02, 1.0, 4.0));
  EXPECT_TRUE(may_touch_within_substep(2.98 * 2.98, -2.98, 1.0, 4.0));
  // Grazing: 1.999 across, 0.5 ahead, closing 1 along: contact near t = 0.44.
  EXPECT_TRUE(may_touch_within_substep(0.25 + 1.999 * 1.999, -0.5, 1.0, 4.0));
}

// Bodies at distance s (1 + e) from the first, e from -2^-20 to 2^-19 (around s, where the
// kernel's fl(dx^2) <= s2 finds touches and overlaps), along the x axis (where that is tight) and
// in random directions, moving straight at it, away, across (grazing at about s) or not at all, at
// speeds from s/64 to 4 s; r from 2^-30 to 2^30. The rows and spans over them must keep every
// touch, overlap and graze that the pair-by-pair test keeps.
TEST(NarrowPhase, KernelsKeepNearContactsAndGrazes) {
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> angle(0, 6.283185307179586), scale(-30, 30);
  const double offsets[] = {-0x1p-20, -0x1p-40, -0x1p-52, 0, 0x1p-52, 0x1p-40, 0x1p-21, 0x1p-19};
  std::size_t found = 0;
  for (int scene = 0; scene < 60; ++scene) {
    const double r = std::ldexp(1.0, static_cast<int>(scale(rng))), s = 2 * r;
    const double cx = 1000 * s, cy = 1000 * s;
    std::vector<testing::Body> bodies{{cx, cy, 0, 0}};
    for (int k = 0; k < 64; ++k) {
      const double a = k / 8 % 2 == 0 ? (k % 2 == 0 ? 0 : 3.141592653589793) : angle(rng);
      const double nx = std::cos(a), ny = std::sin(a);
      const double d = s * (1 + offsets[k % 8]);
      const double speed = std::ldexp(s, k % 9 - 6);
      const int motion = (k / 16 + scene) % 4;  // towards, away, across, still
      const double vx = motion == 0 ? -nx : motion == 1 ? nx : motion == 2 ? -ny : 0;
      const double vy = motion == 0 ? -ny : motion == 1 ? ny : motion == 2 ? nx : 0;
      bodies.push_back({cx + d * nx, cy + d * ny, speed * vx, speed * vy});
    }
    found += expect_rows_match_pairs(bodies, 1e6 * s, r);
    found += expect_span_matches_pairs(bodies, r);
  }
  EXPECT_GT(found, 1000u);
}

#ifdef PARTICLE_FLOAT_PRETEST
// The float pre-test (step/float_pretest.hpp) flags every pair the exact test accepts or finds
// overlapping, where float rounding matters most: coordinates near L = 2^20 (float's spacing
// there is 1/16, s = 2), pairs whose paths pass within s (1 - 10^-3) of each other, overlaps, and
// equal velocities. Without its margins (line = s^2, spread = 0) thousands are missed.
TEST(NarrowPhase, FloatPretestFlagsEveryPairTheExactTestTakes) {
  const double L = 0x1p20, s = 2, s2 = s * s, V = 5000;
  const FloatPretest t(s, L, V);
  std::mt19937_64 rng(53);
  std::uniform_real_distribution<double> pos(L / 2, L - 1), vel(-V, V), unit(0, 1);
  std::vector<double> x(32), y(32), ux(32), uy(32);
  std::vector<float> xf(32), yf(32), uxf(32), uyf(32);
  int taken = 0, missed = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    // Particle 0, and particle 1 placed so that they meet (or overlap) within the sub-step.
    x[0] = pos(rng), y[0] = pos(rng), ux[0] = vel(rng), uy[0] = vel(rng);
    ux[1] = trial % 7 == 0 ? ux[0] : vel(rng);
    uy[1] = trial % 7 == 0 ? uy[0] : vel(rng);
    const double wx = ux[1] - ux[0], wy = uy[1] - uy[0], wn = std::hypot(wx, wy);
    const double miss = s * (1 - 1e-3 * unit(rng)), when = unit(rng);
    const double nx = wn > 0 ? -wy / wn : 1, ny = wn > 0 ? wx / wn : 0;
    const double gap = trial % 5 == 0 ? s * unit(rng) : miss;  // some overlap now
    x[1] = x[0] + gap * nx - wx * (trial % 5 == 0 ? 0 : when);
    y[1] = y[0] + gap * ny - wy * (trial % 5 == 0 ? 0 : when);
    for (std::size_t k = 0; k < 32; ++k) {
      xf[k] = static_cast<float>(x[k]), yf[k] = static_cast<float>(y[k]);
      uxf[k] = static_cast<float>(ux[k]), uyf[k] = static_cast<float>(uy[k]);
    }
    const PairTerms p = pair_terms(x[1] - x[0], y[1] - y[0], ux[1] - ux[0], uy[1] - uy[0], s2);
    double when_exact;
    if (!pair_time(p, when_exact) && p.c >= 0) continue;
    ++taken;
    const SpanFloats af{xf.data(), yf.data(), uxf.data(), uyf.data()};
    const unsigned flags = flag_floats({xf[0], yf[0], uxf[0], uyf[0]}, af, 1, t);
    missed += (flags & 1u) == 0;
  }
  EXPECT_GT(taken, 100000);
  EXPECT_EQ(missed, 0);
}

// The listed pairs' float pre-test with its test of time (FloatSubStepPretest) flags every pair
// the exact test takes, near L = 2^20 again, at slow, mixed and fast speeds: pairs that come
// within s (1 - 10^-3) of each other at a time drawn in the sub-step, some at its very end
// (touching just before it ends), overlaps, and equal velocities. Its margins are what hold
// this: with near0 and near1 zero (the line test's kept) thousands are missed.
TEST(NarrowPhase, FloatSubStepPretestFlagsEveryPairTheExactTestTakes) {
  const double L = 0x1p20, s = 2, s2 = s * s;
  std::mt19937_64 rng(59);
  std::uniform_real_distribution<double> pos(L / 2, L - 1), unit(0, 1);
  for (const double V : {0.2, 5.0, 5000.0}) {
    SCOPED_TRACE(::testing::Message() << "V = " << V);
    const FloatSubStepPretest t(s, L, V);
    FloatSubStepPretest bare = t;
    bare.near0 = bare.near1 = 0;
    std::uniform_real_distribution<double> vel(-V, V);
    int taken = 0, missed = 0, missed_bare = 0, missed_bare8 = 0;
    for (int trial = 0; trial < 100000; ++trial) {
      const double x0 = pos(rng), y0 = pos(rng), ux0 = vel(rng), uy0 = vel(rng);
      const double ux1 = trial % 7 == 0 ? ux0 : vel(rng), uy1 = trial % 7 == 0 ? uy0 : vel(rng);
      const double wx = ux1 - ux0, wy = uy1 - uy0, wn = std::hypot(wx, wy);
      const double nx = wn > 0 ? -wy / wn : 1, ny = wn > 0 ? wx / wn : 0;
      const double when = trial % 3 == 0 ? 1 - 1e-9 * unit(rng) : unit(rng);
      const double gap = trial % 5 == 0 ? s * unit(rng) : s * (1 - 1e-3 * unit(rng));
      const double at = trial % 5 == 0 ? 0 : when;  // some overlap now
      const double x1 = x0 + gap * nx - wx * at, y1 = y0 + gap * ny - wy * at;
      const PairTerms p = pair_terms(x1 - x0, y1 - y0, wx, wy, s2);
      double when_exact;
      if (!pair_time(p, when_exact) && p.c >= 0) continue;
      ++taken;
      // The records' differences, as PairList::test_piece takes them.
      const auto f = [](double v) { return static_cast<float>(v); };
      const float dx = f(x1) - f(x0), dy = f(y1) - f(y0);
      const float dwx = f(ux1) - f(ux0), dwy = f(uy1) - f(uy0);
      // Each width this machine has: 16 lanes with AVX-512, 8 with AVX2.
#ifdef __AVX512F__
      const auto flag16 = [&](const FloatSubStepPretest& p) {
        return p.flag16(_mm512_set1_ps(dx), _mm512_set1_ps(dy), _mm512_set1_ps(dwx),
                        _mm512_set1_ps(dwy));
      };
      missed += (flag16(t) & 1u) == 0;
      missed_bare += (flag16(bare) & 1u) == 0;
#endif
#if defined(__AVX2__) && defined(__FMA__)
      const auto flag8 = [&](const FloatSubStepPretest& p) {
        return p.flag8(_mm256_set1_ps(dx), _mm256_set1_ps(dy), _mm256_set1_ps(dwx),
                       _mm256_set1_ps(dwy));
      };
      missed += (flag8(t) & 1u) == 0;
      missed_bare8 += (flag8(bare) & 1u) == 0;
#endif
    }
    EXPECT_GT(taken, 50000);
    EXPECT_EQ(missed, 0);
#ifdef __AVX512F__
    EXPECT_GT(missed_bare, 1000);
#endif
#if defined(__AVX2__) && defined(__FMA__)
    EXPECT_GT(missed_bare8, 1000);
#endif
  }
}
#endif

}  // namespace
}  // namespace particle::detail
