// The bounds psim check judges by (docs/check.md), each pinned from both sides: the reference's
// output moved just inside a bound must be accepted, moved just beyond it must be a violation.
// A bound made looser by a small factor (a tolerance doubled, a slack one larger) fails here,
// where the programs of test_programs.cpp are far beyond every bound or well inside it.
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "helpers.hpp"
#include "step_check.hpp"

namespace {

using particle::check::Report;
using particle::check::to_text;
using particle::check::Verdict;

// Two particles that meet neither each other nor a wall in S = 4 time units, with values that are
// sums of binary fractions (at K = 2 too): the reference prints the model's values exactly, so a
// moved field is the whole difference from the model.
std::string free_flight(const char* mode) {
  return check_test::write_file(
      fmt::format("free_flight_{}.in", mode),
      fmt::format("2\n100\n1\n4\n{}\n0 10 10 2 1\n1 50 80 -3 0.5\n", mode));
}
constexpr std::int64_t kSteps = 4;

std::string reference(const std::string& scene, int k = 1) {
  return check_test::read_file(check_test::run_program(PLAIN_PATH, scene, k));
}

// The fields of an output line `t i x y vx vy [pair_collisions wall_collisions]`.
enum Field { kX = 2, kVx = 4, kWalls = 7 };

// `text` with particle i's field at time unit t moved by `by`: a value printed again as `%.8f`, a
// count as a whole number.
std::string moved(const std::string& text, std::int64_t t, std::size_t i, Field field, double by) {
  std::istringstream in(text);
  std::string out, line;
  bool found = false;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::vector<std::string> f{std::istream_iterator<std::string>(fields), {}};
    if (f.size() > static_cast<std::size_t>(field) && f[0] == std::to_string(t) &&
        f[1] == std::to_string(i)) {
      f[field] = field == kWalls ? std::to_string(std::stoll(f[field]) + std::llround(by))
                                 : fmt::format("{:.8f}", std::stod(f[field]) + by);
      line = fmt::format("{}", fmt::join(f, " "));
      found = true;
    }
    out += line + '\n';
  }
  // A change that misses its line would leave the reference's output, which every bound accepts.
  if (!found) throw std::runtime_error(fmt::format("no line for time {}, particle {}", t, i));
  return out;
}

Report check_text(const std::string& scene, const std::string& text, int k = 1) {
  return check_test::check(scene, check_test::write_file("moved.out", text), k);
}

// The tolerance of a free particle (docs/check.md, "The tolerance") is out + 2 in + arith: from a
// printed start (time unit 2) 5e-9 + 2 x 5e-9 + 2^-44 L, about 1.5e-8; one unit in the 8th
// decimal lies inside it.
TEST(CheckBounds, PositionWithinTheToleranceIsConsistent) {
  const std::string scene = free_flight("print");
  const Report r = check_text(scene, moved(reference(scene), 2, 0, kX, 1e-8));
  EXPECT_EQ(r.verdict, Verdict::consistent) << to_text(r);
}

// Particle 0's x at time unit t moved by `by` is a violation there that rounding cannot explain.
void expect_position_violation(std::int64_t t, double by) {
  const std::string scene = free_flight("print");
  const Report r = check_text(scene, moved(reference(scene), t, 0, kX, by));
  const std::string text = to_text(r);
  ASSERT_EQ(r.verdict, Verdict::violations) << text;
  EXPECT_EQ(r.violations.front().step, t) << text;
  EXPECT_EQ(r.violations.front().particles, std::vector<std::uint32_t>{0}) << text;
  EXPECT_EQ(r.violations.front().kind, "free motion differs") << text;
  EXPECT_TRUE(r.ambiguous.empty()) << text;
}

// Twice the tolerance (3e-8 against 1.5e-8), far below a looser one; a start within the print
// rounding moves the model's x by at most 1e-8 (x and vx 5e-9 each): not enough to explain it.
TEST(CheckBounds, PositionTwiceTheToleranceIsAViolation) { expect_position_violation(2, 3e-8); }

// Time unit 1 starts from the scene's own values: in = 0, a tolerance of about 5e-9, so one unit in
// the 8th decimal is twice it.
TEST(CheckBounds, PositionOneUnitOffInTimeUnit1IsAViolation) { expect_position_violation(1, 1e-8); }

// Print mode: the final counts are the sum of the model's over the time units; a time unit beyond
// the tolerance (ambiguous or broken) allows 2K per particle. Here the final time unit of
// particle 0 is broken (x off by 1e-3, itself a violation) at K = 2: a slack of 4.
constexpr int kK = 2;
std::string broken_final_step(const std::string& scene) {
  return moved(reference(scene, kK), kSteps, 0, kX, 1e-3);
}

TEST(CheckBounds, CountsOffByTheSlackAreAccepted) {
  const std::string scene = free_flight("print");
  const Report r =
      check_text(scene, moved(broken_final_step(scene), kSteps, 0, kWalls, 2 * kK), kK);
  ASSERT_EQ(r.verdict, Verdict::violations) << to_text(r);
  EXPECT_FALSE(r.kinds.contains("collision counts")) << to_text(r);
}

// Every time unit follows the model: no slack, and one count off is the only violation.
TEST(CheckBounds, CountsOffByOneWithoutSlackAreAViolation) {
  const std::string scene = free_flight("print");
  const Report r = check_text(scene, moved(reference(scene, kK), kSteps, 0, kWalls, 1), kK);
  ASSERT_EQ(r.violation_count, 1) << to_text(r);
  EXPECT_EQ(r.violations.front().kind, "collision counts") << to_text(r);
  EXPECT_EQ(r.violations.front().particles, std::vector<std::uint32_t>{0});
}

TEST(CheckBounds, CountsOnePastTheSlackAreAViolation) {
  const std::string scene = free_flight("print");
  const Report r =
      check_text(scene, moved(broken_final_step(scene), kSteps, 0, kWalls, 2 * kK + 1), kK);
  EXPECT_TRUE(r.kinds.contains("collision counts")) << to_text(r);
}

// Perf mode judges a final state by what any run satisfies: at most one collision per sub-step,
// S K = 8 at K = 2.
TEST(CheckBounds, PerfCountsOfOnePerSubStepAreConsistent) {
  const std::string scene = free_flight("perf");
  const Report r =
      check_text(scene, moved(reference(scene, kK), kSteps, 0, kWalls, kSteps * kK), kK);
  EXPECT_EQ(r.verdict, Verdict::consistent) << to_text(r);
}

TEST(CheckBounds, PerfCountsBeyondOnePerSubStepAreAViolation) {
  const std::string scene = free_flight("perf");
  const Report r =
      check_text(scene, moved(reference(scene, kK), kSteps, 0, kWalls, kSteps * kK + 1), kK);
  ASSERT_EQ(r.violation_count, 1) << to_text(r);
  EXPECT_EQ(r.violations.front().kind, "collision counts") << to_text(r);
  EXPECT_EQ(r.violations.front().particles, std::vector<std::uint32_t>{0});
}

// The energy of a printed state may differ from the initial one by the print rounding of its
// velocities, sum (|vx| + |vy|) 5e-9 = 6.5 x 5e-9 = 3.25e-8 here, plus 2^-46 of the energy (1e-13;
// more after pair collisions, none here). Particle 1's vx of -3 moved by one unit in the 8th
// decimal changes the energy by 3e-8, by two units 6e-8; in perf mode nothing else judged changes.
TEST(CheckBounds, EnergyWithinThePrintRoundingIsConsistent) {
  const std::string scene = free_flight("perf");
  const Report r = check_text(scene, moved(reference(scene), kSteps, 1, kVx, -1e-8));
  EXPECT_EQ(r.verdict, Verdict::consistent) << to_text(r);
}

TEST(CheckBounds, EnergyBeyondThePrintRoundingIsAViolation) {
  const std::string scene = free_flight("perf");
  const Report r = check_text(scene, moved(reference(scene), kSteps, 1, kVx, -2e-8));
  ASSERT_EQ(r.violation_count, 1) << to_text(r);
  EXPECT_EQ(r.violations.front().kind, "energy not conserved") << to_text(r);
  EXPECT_EQ(r.violations.front().step, kSteps);
}

// The whole-motion reading's stop (docs/check.md, "The tolerance"): a particle that hits the left
// wall, then meets the top wall line in the rest of the time unit at a shallow angle (|vx / vy|
// about 20), stops where its path meets the line; the print rounding of its y and vy (3.7e-9
// each here) moves that point along the line by some 20 times as much: 1.3e-7, nine times the
// bound of a free particle (1.5e-8, what the check allowed before). A program that followed the
// model exactly from its unrounded state must be within the bound outright, not accused (as a
// whole-motion student program was, 30 times, on the 2019 timing scene) nor merely ambiguous; moved
// 1e-6 further along the line it is a violation.
particle::Particles rounded(const particle::Particles& p) {
  particle::Particles out = p;
  for (auto* field : {&out.x, &out.y, &out.vx, &out.vy})
    for (double& v : *field) v = std::stod(fmt::format("{:.8f}", v));
  return out;
}

particle::check::StepResult shallow_stop(particle::WallStop reading, double moved_x) {
  particle::Scene scene;
  scene.L = 100;
  scene.r = 1;
  scene.steps = 3;
  scene.mode = particle::OutputMode::print;
  particle::Particles state(1);  // the program's state at time unit 1, as it holds it
  state.x[0] = 5.376543211;
  state.y[0] = 98.3000000037;
  state.vx[0] = -20.123456789;
  state.vy[0] = 1.0000000037;
  const particle::StepRules rules{1, reading};
  particle::Particles printed = rounded(particle::step_time_unit(scene, state, rules));
  printed.x[0] += moved_x;
  const particle::Particles start = rounded(state);
  return particle::check::check_step(scene, rules, 2, start, false, printed,
                                     particle::step_time_unit(scene, start, rules));
}

TEST(CheckBounds, AWholeMotionStopAtAShallowAngleIsWithinTheBound) {
  for (const particle::WallStop reading : particle::kWallStops) {
    const particle::check::StepResult r = shallow_stop(reading, 0);
    EXPECT_TRUE(r.explained.empty() && r.unexplained.empty())
        << particle::wall_stop_name(reading) << ": " << r.largest_difference << " beyond "
        << r.largest_tolerance;
  }
  // The case in point: the model stopped it on the top line after its wall hit.
  const particle::check::StepResult whole = shallow_stop(particle::WallStop::whole_motion, 0);
  EXPECT_EQ(whole.model.y[0], 99);
  EXPECT_EQ(whole.model.wall_collisions[0], 1u);
}

TEST(CheckBounds, AWholeMotionStopMovedBeyondTheBoundIsAViolation) {
  const particle::check::StepResult r = shallow_stop(particle::WallStop::whole_motion, 1e-6);
  EXPECT_EQ(r.unexplained, std::vector<std::uint32_t>{0}) << r.largest_tolerance;
}

}  // namespace
