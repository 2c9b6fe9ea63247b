// psim check against programs it must judge (tests/CMakeLists.txt builds them from
// plain_allpairs.c): the reference as it is is exact, with other floating-point contraction it is
// never accused, and each broken rule is named at the step and particle where a scene hits it.
#include <gtest/gtest.h>

#include "helpers.hpp"

namespace {

using particle::check::Report;
using particle::check::Verdict;

const std::string kPrograms = CHECK_PROGRAMS;
const std::string kScenes = SCENES_DIR;
const std::string kRandom = std::string(CHECK_SCENES) + "/random200.in";

TEST(CheckPrograms, PlainReferenceIsExactOnEveryScene) {
  for (const char* scene :
       {"head_on", "cradle", "corner", "wall_beats_pair", "overlap_approaching", "three_at_once",
        "three_in_row_tie", "four_at_centre", "diagonal", "crossing"}) {
    const std::string path = kScenes + "/" + scene + ".in";
    const Report r = check_test::check(path, check_test::run_program(PLAIN_PATH, path));
    EXPECT_EQ(r.verdict, Verdict::exact) << scene << "\n" << particle::check::to_text(r);
  }
  const Report r = check_test::check(kRandom, check_test::run_program(PLAIN_PATH, kRandom));
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r);
  EXPECT_EQ(r.exact_steps, 51);
}

TEST(CheckPrograms, PlainReferenceIsExactAtSlowFactor4) {
  const Report r = check_test::check(kRandom, check_test::run_program(PLAIN_PATH, kRandom, 4), 4);
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r);
}

// A program that counts its own sub-steps (every one printed, numbered to S x K, velocities per
// sub-step), as the 2019 authors' parallel-2 does: exact when said, malformed when not.
TEST(CheckPrograms, AnOutputThatNumbersSubStepsIsJudgedAsTheSceneItSimulates) {
  const std::string out = check_test::run_program(kPrograms + "/sub_steps", kRandom, 4);
  particle::check::CheckRequest request{kRandom, out, 4};
  request.sub_steps_numbered = true;
  const Report r = particle::check::run_check(request);
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r);
  EXPECT_EQ(r.exact_steps, 4 * 50 + 1);
  EXPECT_NE(particle::check::to_text(r).find("note: sub-steps numbered: "), std::string::npos);
  const Report unsaid = check_test::check(kRandom, out, 4);
  EXPECT_EQ(unsaid.verdict, Verdict::malformed) << particle::check::to_text(unsaid);
  EXPECT_NE(unsaid.malformed.find(
                "(read as an output that numbers sub-steps, it is exact: --sub-steps-numbered)"),
            std::string::npos)
      << unsaid.malformed;
  // Numbered by time unit, it is not read as sub-steps.
  request.output = check_test::run_program(PLAIN_PATH, kRandom, 4);
  EXPECT_NE(particle::check::run_check(request).verdict, Verdict::exact);
}

// The 2019 authors' reading of "stops just next to the wall" (whole motion) is a reading of the
// specification, not a violation: judged by it, named, and exact where the arithmetic is the
// model's; required to follow the other one, it is 107 violations on random200 (as Aussiroth's
// student program was, with its other differences patched out).
TEST(CheckPrograms, TheWholeMotionReadingIsAcceptedAndNamed) {
  const std::string whole = check_test::run_program(kPrograms + "/whole_motion", kRandom);
  const Report r = check_test::check(kRandom, whole);
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r);
  EXPECT_EQ(r.reading, "whole-motion");
  EXPECT_FALSE(r.reading_required);
  EXPECT_NE(particle::check::to_text(r).find("verdict: exact, whole-motion reading, overlap "),
            std::string::npos);
  const Report plain = check_test::check(kRandom, check_test::run_program(PLAIN_PATH, kRandom));
  EXPECT_EQ(plain.reading, "per-coordinate");
  const Report required = check_test::check(kRandom, whole, 1, particle::WallStop::per_coordinate);
  EXPECT_EQ(required.verdict, Verdict::violations);
  EXPECT_EQ(required.violation_count, 107);
  EXPECT_GE(required.kinds.at("wall hit resolved differently"), 100);  // the rest: counted kinds
  EXPECT_TRUE(required.reading_required);
  EXPECT_NE(particle::check::to_text(required).find("per-coordinate reading (required)"),
            std::string::npos);
  // A scene whose collisions never end at a wall line does not tell them apart.
  const std::string head_on = kScenes + "/head_on.in";
  EXPECT_EQ(check_test::check(head_on, check_test::run_program(PLAIN_PATH, head_on)).reading,
            "either");
}

// Contraction into FMAs changes the bits (checked here, or the test would prove nothing) but not
// the model: never a violation.
TEST(CheckPrograms, FmaContractionChangesBitsButIsNeverAViolation) {
  const std::string fma = check_test::run_program(kPrograms + "/fma", kRandom);
  EXPECT_NE(check_test::read_file(fma),
            check_test::read_file(check_test::run_program(PLAIN_PATH, kRandom)));
  const Report r = check_test::check(kRandom, fma);
  EXPECT_TRUE(r.verdict == Verdict::consistent || r.verdict == Verdict::ambiguous)
      << particle::check::to_text(r);
}

// -ffast-math with -O3 -march=native reassociates and contracts: other bits, same model.
TEST(CheckPrograms, FastMathChangesBitsButIsNeverAViolation) {
  const std::string fast = check_test::run_program(kPrograms + "/fast_math", kRandom);
  EXPECT_NE(check_test::read_file(fast),
            check_test::read_file(check_test::run_program(PLAIN_PATH, kRandom)));
  const Report r = check_test::check(kRandom, fast);
  EXPECT_TRUE(r.verdict == Verdict::consistent || r.verdict == Verdict::ambiguous)
      << particle::check::to_text(r);
}

struct Broken {
  const char* program;
  std::string scene;
  std::int64_t step;
  std::vector<std::uint32_t> particles;
  const char* kind;
  // ctest lists each case by its program rather than by the raw bytes of this struct.
  friend void PrintTo(const Broken& b, std::ostream* os) { *os << b.program; }
};

class BrokenRule : public testing::TestWithParam<Broken> {};

TEST_P(BrokenRule, IsNamedAtItsStepAndParticle) {
  const Broken& b = GetParam();
  const Report r =
      check_test::check(b.scene, check_test::run_program(kPrograms + "/" + b.program, b.scene));
  const std::string text = particle::check::to_text(r);
  ASSERT_EQ(r.verdict, Verdict::violations) << text;
  ASSERT_FALSE(r.violations.empty());
  const auto& first = r.violations.front();
  EXPECT_EQ(first.step, b.step) << text;
  EXPECT_EQ(first.particles, b.particles) << text;
  EXPECT_EQ(first.kind, b.kind) << text;
}

INSTANTIATE_TEST_SUITE_P(
    CheckPrograms, BrokenRule,
    testing::Values(
        // wall_before_end.in reaches its wall line 1.25e-15 of a step before the end of time
        // unit 1, where a hit that must end 1e-14 beyond the line is none.
        Broken{"wall_tolerance", kScenes + "/wall_before_end.in", 1, {0}, "wall hit missed"},
        // wall_beats_pair.in: particle 0's wall hit and pair 0-1 both at t = 0.5.
        Broken{"pair_before_wall",
               kScenes + "/wall_beats_pair.in",
               1,
               {0, 1},
               "pair before wall on a tie"},
        // wall_beats_pair_high.in: the same tie with the wall on the higher index, where a tie
        // broken by index alone (the 2019 authors' rule) takes the pair.
        Broken{"index_order",
               kScenes + "/wall_beats_pair_high.in",
               1,
               {0, 1},
               "pair before wall on a tie"},
        Broken{"two_collisions",
               kScenes + "/wall_beats_pair.in",
               1,
               {0, 1},
               "two collisions for one particle in a step"},
        Broken{"overlap",
               kScenes + "/overlap_approaching.in",
               1,
               {0, 1},
               "overlapping approaching pair not resolved"},
        // Single precision cannot even print the scene's own values.
        Broken{"float", kRandom, 0, {0}, "initial state differs from the scene"},
        Broken{"nan", kRandom, 1, {0}, "not finite"}),
    [](const auto& info) { return std::string(info.param.program); });

// The index rule and a pair-first rule are told apart where both break the same tie, and only the
// tie with the wall on the higher index catches the index rule at all.
TEST(CheckPrograms, ATieBrokenByIndexIsToldFromAPairFirstRule) {
  const std::string low = kScenes + "/wall_beats_pair.in";
  const std::string high = kScenes + "/wall_beats_pair_high.in";
  EXPECT_EQ(
      check_test::check(low, check_test::run_program(kPrograms + "/index_order", low)).verdict,
      Verdict::exact);
  const Report index =
      check_test::check(high, check_test::run_program(kPrograms + "/index_order", high));
  ASSERT_EQ(index.verdict, Verdict::violations);
  EXPECT_NE(index.violations.front().detail.find("a tie broken by the lower index alone"),
            std::string::npos)
      << particle::check::to_text(index);
  const Report pairs =
      check_test::check(low, check_test::run_program(kPrograms + "/pair_before_wall", low));
  ASSERT_EQ(pairs.verdict, Verdict::violations);
  EXPECT_EQ(pairs.violations.front().detail.find("lower index alone"), std::string::npos);
}

// A corner hit that flips one component: a violation from the scene's own values (time unit 1
// of corner.in reaches both wall lines exactly); from a printed state it is ambiguous only because
// a start within the print rounding reaches one line first, and the report says so.
TEST(CheckPrograms, ACornerFlippingOneComponentIsNamedAndItsAmbiguitySaid) {
  const std::string corner = kScenes + "/corner.in";
  const Report r =
      check_test::check(corner, check_test::run_program(kPrograms + "/corner_one_flip", corner));
  const std::string text = particle::check::to_text(r);
  ASSERT_EQ(r.verdict, Verdict::violations) << text;
  EXPECT_EQ(r.violations.front().step, 1);
  EXPECT_EQ(r.violations.front().kind, "corner hit resolved as a one-wall hit");
  EXPECT_NE(r.violations.front().detail.find("the program flips only vx"), std::string::npos);
  ASSERT_EQ(r.ambiguous.size(), 1u) << text;
  EXPECT_EQ(r.ambiguous.front().step, 3);
  EXPECT_NE(r.ambiguous.front().detail.find("a corner: both wall lines at the same time"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("0 of a step apart"), std::string::npos) << text;
}

// Every rule named with the particles on both sides: an overlapping pair the model leaves alone
// (moving apart), collided by the program, names both.
// The handout's overlap sentence read literally (docs/model.md, "Readings"): a program that
// collides an overlapping pair whatever its motion follows the reading `always`, named; required
// to follow `approaching`, it breaks the rule at both particles.
TEST(CheckPrograms, ARecedingOverlapResolvedIsTheAlwaysReading) {
  const std::string scene = kScenes + "/overlap_receding.in";
  const std::string output = check_test::run_program(kPrograms + "/overlap_receding", scene);
  const Report r = check_test::check(scene, output);
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r);
  EXPECT_EQ(r.overlap, "always");
  EXPECT_EQ(r.reading, "either");
  EXPECT_NE(particle::check::to_text(r).find("either reading, overlap always: identical"),
            std::string::npos);
  const Report required =
      check_test::check(scene, output, 1, std::nullopt, particle::Overlap::approaching);
  ASSERT_EQ(required.verdict, Verdict::violations) << particle::check::to_text(required);
  EXPECT_TRUE(required.overlap_required);
  EXPECT_EQ(required.violation_count, 1);
  EXPECT_EQ(required.violations.front().particles, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(required.violations.front().kind, "overlapping receding pair resolved");
  // psim's own output follows `approaching`, and `always` required finds the pair left alone.
  const std::string plain = check_test::run_program(PLAIN_PATH, scene);
  EXPECT_EQ(check_test::check(scene, plain).overlap, "approaching");
  EXPECT_EQ(check_test::check(scene, plain, 1, std::nullopt, particle::Overlap::always).verdict,
            Verdict::violations);
}

// Random print scenes at K = 1: a program that takes every pair before any wall hit is named by
// its collision order, not by what happens to one particle.
TEST(CheckPrograms, PairsFirstIsACollisionOrderOnRandomScenes) {
  for (int seed : {1, 2, 3, 4}) {
    const std::string scene =
        (check_test::temp_dir() / ("pairs-first-" + std::to_string(seed) + ".in")).string();
    const std::string make =
        fmt::format("printf '200\\n2000\\n1\\n30\\nprint\\n' | '{}' --write-scene '{}' --seed {}",
                    PSIM_PATH, scene, seed);
    ASSERT_EQ(std::system(make.c_str()), 0) << make;
    const Report r =
        check_test::check(scene, check_test::run_program(kPrograms + "/pairs_first", scene));
    ASSERT_EQ(r.verdict, Verdict::violations) << seed;
    EXPECT_EQ(r.violations.front().kind, "collision order") << seed << "\n"
                                                            << particle::check::to_text(r);
    EXPECT_EQ(r.violations.front().particles.size(), 2u) << seed;
  }
}

// Every violation of that program is named by its collision order, not only those of the first
// time units the diagnosis details: beyond them the rule was not tried, and each particle got the
// kind the model's counts say, "wall hit resolved differently", alone (6 to 32 of 29 to 54
// violations on these five scenes; now 26 to 38, each naming the pair and the wall hit).
TEST(CheckPrograms, PairsFirstIsACollisionOrderInEveryTimeUnit) {
  for (int seed : {1, 2, 3, 4, 5}) {
    const std::string scene =
        (check_test::temp_dir() / ("pairs-first-long-" + std::to_string(seed) + ".in")).string();
    const std::string make =
        fmt::format("printf '200\\n2000\\n1\\n120\\nprint\\n' | '{}' --write-scene '{}' --seed {}",
                    PSIM_PATH, scene, seed);
    ASSERT_EQ(std::system(make.c_str()), 0) << make;
    const Report r =
        check_test::check(scene, check_test::run_program(kPrograms + "/pairs_first", scene));
    ASSERT_EQ(r.verdict, Verdict::violations) << seed;
    EXPECT_EQ(r.kinds,
              (std::map<std::string, std::int64_t>{{"collision order", r.violation_count}}))
        << seed << "\n"
        << particle::check::to_text(r);
  }
}

TEST(CheckPrograms, FloatBreaksFreeMotionToo) {
  const Report r =
      check_test::check(kRandom, check_test::run_program(kPrograms + "/float", kRandom));
  EXPECT_GT(r.kinds.at("free motion differs"), 0) << particle::check::to_text(r);
}

TEST(CheckPrograms, DroppedLastLineIsMalformedAtItsLine) {
  const Report r =
      check_test::check(kRandom, check_test::run_program(kPrograms + "/drop_last", kRandom));
  EXPECT_EQ(r.verdict, Verdict::malformed);
  EXPECT_EQ(r.malformed_line, 200 * 51 - 1);
  EXPECT_NE(r.malformed.find("next `50 199 x y vx vy pair_collisions wall_collisions`"),
            std::string::npos)
      << r.malformed;
}

// A hit at exactly t = 1 taken at the start of the next step, as the wrong-way tolerance test and
// both public student programs take it (the 2019 authors' in this step): the specification's "at
// any time during a step" leaves the step's end to either step (docs/model.md), so corner.in's two
// such hits (time units 1 and 3) are ambiguous, not violations, with the model's hit named.
TEST(CheckPrograms, AHitAtTheStepsEndTakenInTheNextStepIsAmbiguous) {
  const std::string scene = kScenes + "/corner.in";
  const Report r =
      check_test::check(scene, check_test::run_program(kPrograms + "/wall_tolerance", scene));
  const std::string text = particle::check::to_text(r);
  ASSERT_EQ(r.verdict, Verdict::ambiguous) << text;
  EXPECT_EQ(r.violation_count, 0) << text;
  ASSERT_EQ(r.ambiguous.size(), 2u) << text;
  EXPECT_EQ(r.ambiguous[0].step, 1);
  EXPECT_EQ(r.ambiguous[1].step, 3);
  EXPECT_EQ(r.ambiguous[0].detail,
            "the model takes the wall hit of particle 0 at t = 1 of the step (vx and vy flip) in "
            "this step; the program takes it at the start of the next: a contact at exactly the "
            "step's end, which the specification leaves to either step (docs/model.md)");
}

// Deferred is not dropped: a program that parks the particle on the wall lines at time unit 1
// and never takes the hit is a violation at time unit 2, where the model, run from the printed
// state, takes it at t = 0.
TEST(CheckPrograms, AHitAtTheStepsEndNeverTakenIsAViolationInTheNextStep) {
  const std::string scene = kScenes + "/corner.in";
  const std::string output =
      check_test::write_file("corner_never_hit.out",
                             "0 0 5.00000000 5.00000000 4.00000000 4.00000000\n"
                             "1 0 9.00000000 9.00000000 4.00000000 4.00000000\n"
                             "2 0 9.00000000 9.00000000 4.00000000 4.00000000\n"
                             "3 0 9.00000000 9.00000000 4.00000000 4.00000000 0 0\n");
  const Report r = check_test::check(scene, output);
  const std::string text = particle::check::to_text(r);
  ASSERT_EQ(r.verdict, Verdict::violations) << text;
  EXPECT_EQ(r.violations.front().step, 2) << text;
  ASSERT_EQ(r.ambiguous.size(), 1u) << text;
  EXPECT_EQ(r.ambiguous[0].step, 1);
}

}  // namespace

// A program that takes every pair collision before any wall hit, whatever their times, on random
// scenes: the first violation names the pair it took and the earlier wall hit it displaced, where
// the rule first acts; at K > 1, where it breaks the rule in several sub-steps of a time unit, as
// the rule applied in every sub-step.
TEST(CheckPrograms, PairsBeforeEarlierWallHitsAreNamedOnRandomScenes) {
  struct Case {
    int n, steps, seed, k;
    std::int64_t step;
    std::vector<std::uint32_t> particles;
    const char* wall;
    const char* pair;
  };
  for (const Case& c :
       {Case{200, 30, 1, 1, 2, {2, 173}, "the wall hit of particle 2", "the pair 2-173"},
        Case{200, 30, 3, 1, 3, {47, 107}, "the wall hit of particle 47", "the pair 47-107"},
        Case{300, 20, 5, 4, 1, {205, 239}, "the wall hit of particle 205", "the pair 205-239"}}) {
    const std::string scene =
        (check_test::temp_dir() / fmt::format("pairs_first_{}_{}.in", c.seed, c.k)).string();
    ASSERT_EQ(std::system(fmt::format("printf '{}\\n2000\\n1\\n{}\\nprint\\n' | '{}' "
                                      "--write-scene '{}' --seed {}",
                                      c.n, c.steps, PSIM_PATH, scene, c.seed)
                              .c_str()),
              0);
    const Report r = check_test::check(
        scene, check_test::run_program(kPrograms + "/pairs_first", scene, c.k), c.k);
    const std::string text = particle::check::to_text(r);
    ASSERT_EQ(r.verdict, Verdict::violations) << text;
    const auto& first = r.violations.front();
    EXPECT_EQ(first.step, c.step) << text;
    EXPECT_EQ(first.particles, c.particles) << text;
    EXPECT_EQ(first.kind, "collision order") << text;
    EXPECT_NE(first.detail.find(std::string("the model takes the ") + (c.wall + 4)),
              std::string::npos)
        << first.detail;
    EXPECT_NE(first.detail.find(std::string("the program takes the ") + (c.pair + 4)),
              std::string::npos)
        << first.detail;
  }
}
