// The output reader and psim check's command line: every malformed output is a verdict naming
// its line, never a crash or an unbounded read; usage errors exit 2.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "helpers.hpp"
#include "particle/io.hpp"
#include "particle/output_text.hpp"

namespace {

using particle::parse_fixed8;
using particle::check::Report;
using particle::check::Verdict;

const std::string kHeadOn = std::string(SCENES_DIR) + "/head_on.in";

TEST(ParseFixed8, ReadsWhatPrintfWrites) {
  double v = 0;
  ASSERT_TRUE(parse_fixed8("12.50000000", v));
  EXPECT_EQ(v, 12.5);
  ASSERT_TRUE(parse_fixed8("-0.00000001", v));
  EXPECT_EQ(v, -1e-8);
  ASSERT_TRUE(parse_fixed8("7008.46365981", v));
  EXPECT_EQ(v, 7008.46365981);  // correctly rounded, as strtod
  ASSERT_TRUE(parse_fixed8("123456789012.12345678", v));
  EXPECT_EQ(v, 123456789012.12345678);
  ASSERT_TRUE(parse_fixed8("-nan", v));
  EXPECT_TRUE(std::isnan(v));
  ASSERT_TRUE(parse_fixed8("inf", v));
  EXPECT_EQ(v, INFINITY);
  for (const char* bad : {"1.5", "1", "1.123456789", ".12345678", "1e3", "+1.00000000",
                          "1.0000000x", "abc", "", "-", "1,00000000", "0x1.00000000"})
    EXPECT_FALSE(parse_fixed8(bad, v)) << bad;
  // Every width before the point, 1 to 7 digits read as one word and more through from_chars,
  // each as strtod reads it, and refused with a non-digit at any place before the point.
  for (int digits = 1; digits <= 12; ++digits) {
    const std::string whole = std::string("9876543210987").substr(0, digits);
    for (const std::string& text : {whole + ".00390625", "-" + whole + ".12345678"}) {
      ASSERT_TRUE(parse_fixed8(text, v)) << text;
      EXPECT_EQ(v, std::strtod(text.c_str(), nullptr)) << text;
      for (std::size_t at = text[0] == '-'; at < text.find('.'); ++at)
        for (const char c : {'/', ':', ' ', '+', '-', '.'}) {
          std::string broken = text;
          broken[at] = c;
          if (at > 0 || c != '-') EXPECT_FALSE(parse_fixed8(broken, v)) << broken;  // a sign
        }
    }
  }
}

// head_on.in: N = 2, S = 4, print mode: 10 lines; its first two.
std::string head_on_output() {
  return "0 0 40.00000000 50.00000000 5.00000000 0.00000000\n"
         "0 1 60.00000000 50.00000000 -5.00000000 0.00000000\n";
}

Report check_text(const std::string& text) {
  return check_test::check(kHeadOn, check_test::write_file("output.txt", text));
}

TEST(OutputReader, MalformedOutputsNameTheirLine) {
  struct Case {
    std::string text;
    std::int64_t line;
    const char* says;
  };
  const std::string start = head_on_output();
  const Case cases[] = {
      {"", 0, "the output ends after 0 lines; expected 10 lines"},
      {start.substr(0, start.size() / 2), 1, "the output ends after 1 lines"},
      {"0 0 40.00000000 50.00000000 5.00000000 0.00000000\n0 2 60.00000000 50.00000000 "
       "-5.00000000 0.00000000\n",
       2, "i: expected particle 1 (lines in index order)"},
      {"1 0 40.00000000 50.00000000 5.00000000 0.00000000\n", 1, "time: expected 0"},
      {"0 0 40.0 50.00000000 5.00000000 0.00000000\n0 1 60.00000000 50.00000000 -5.00000000 "
       "0.00000000\n",
       1, "x: expected a number as %.8f prints it"},
      {"0 0 40.00000000 50.00000000 5.00000000 0.00000000 7\n", 1, "expected 6 fields"},
      {std::string(5000, '7') + "\n", 1, "longer than 4096 bytes"},
  };
  for (const Case& c : cases) {
    const Report r = check_text(c.text);
    EXPECT_EQ(r.verdict, Verdict::malformed) << c.says;
    EXPECT_EQ(r.malformed_line, c.line) << r.malformed;
    EXPECT_NE(r.malformed.find(c.says), std::string::npos) << r.malformed;
  }
}

// One set of line rules with the scene reader (io/scene_text.hpp): CRLF line ends, leading and
// trailing blanks, tabs between fields and a '+' before a whole number read as they do in a scene.
TEST(OutputReader, LinesFollowTheSceneReadersRules) {
  const std::string out = check_test::run_program(PLAIN_PATH, kHeadOn);
  std::ifstream in(out);
  std::string text, line;
  for (int k = 0; std::getline(in, line); ++k)
    text += (k % 2 ? "\t+" : "  ") + line + (k % 3 ? " \r\n" : "\t\n");
  const Report r = check_text(text);
  EXPECT_EQ(r.verdict, Verdict::exact) << r.malformed << r.summary;
  EXPECT_EQ(check_text(text + "\n\r\n").verdict, Verdict::exact);  // blank lines at the end
}

// A program that prints without end: the read stops at the first line beyond the output's end.
TEST(OutputReader, EndlessOutputStopsAtTheFirstExtraLine) {
  const std::string out = check_test::run_program(PLAIN_PATH, kHeadOn);
  const std::string command = fmt::format(
      "{{ cat '{}'; yes '5 0 1.00000000 1.00000000 1.00000000 1.00000000'; }} | '{}' "
      "check '{}' -",
      out, PSIM_PATH, kHeadOn);
  std::FILE* p = popen(command.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char buffer[4096];
  std::string text;
  while (std::fgets(buffer, sizeof buffer, p)) text += buffer;
  EXPECT_EQ(WEXITSTATUS(pclose(p)), 2);
  EXPECT_NE(text.find(":11: expected the end of the output after 10 lines"), std::string::npos)
      << text;
}

int run_psim(const std::string& args) {
  const int status =
      std::system(fmt::format("'{}' check {} >/dev/null 2>&1", PSIM_PATH, args).c_str());
  return WEXITSTATUS(status);
}

TEST(CheckCommand, ExitStatusAndJson) {
  const std::string out = check_test::run_program(PLAIN_PATH, kHeadOn);
  const std::string json = (check_test::temp_dir() / "report.json").string();
  EXPECT_EQ(run_psim(fmt::format("'{}' '{}' --json '{}'", kHeadOn, out, json)), 0);
  std::ifstream in(json);
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["verdict"], "exact");
  EXPECT_EQ(report["exact_steps"], 5);
  const std::string broken =
      check_test::run_program(std::string(CHECK_PROGRAMS) + "/overlap",
                              std::string(SCENES_DIR) + "/overlap_approaching.in");
  EXPECT_EQ(run_psim(fmt::format("'{}/overlap_approaching.in' '{}'", SCENES_DIR, broken)), 1);
  EXPECT_EQ(run_psim(fmt::format("'{}' '{}'", kHeadOn, check_test::write_file("bad", "x\n"))), 2);
  EXPECT_EQ(run_psim(""), 2);
  EXPECT_EQ(run_psim(fmt::format("'{}' '{}' --slow-factor 3", kHeadOn, out)), 2);
  EXPECT_EQ(run_psim(fmt::format("'{}' '{}' --bogus", kHeadOn, out)), 2);
  EXPECT_EQ(run_psim(fmt::format("/no/such/scene '{}'", out)), 2);
  EXPECT_EQ(run_psim(fmt::format("'{}' /no/such/output", kHeadOn)), 2);
}

TEST(CheckCommand, PerfModeIsJudgedOnInvariantsOnly) {
  const std::string scene =
      check_test::write_file("perf.in", "2\n100\n1\n4\nperf\n0 40 50 5 0\n1 60 50 -5 0\n");
  const Report exact = check_test::check(scene, check_test::run_program(PLAIN_PATH, scene));
  EXPECT_EQ(exact.verdict, Verdict::exact) << particle::check::to_text(exact);
  EXPECT_TRUE(exact.notes.empty()) << particle::check::to_text(exact);
  // Other final states of the same two-particle run: particle 0 ends at x0, particle 1 with
  // `pairs1` pair collisions (the first two lines are the scene's state).
  const auto final_state = [&](const std::string& name, const char* x0, int pairs1) {
    return check_test::check(
        scene, check_test::write_file(
                   name, fmt::format("0 0 40.00000000 50.00000000 5.00000000 0.00000000\n"
                                     "0 1 60.00000000 50.00000000 -5.00000000 0.00000000\n"
                                     "4 0 {} 50.00000000 -5.00000000 0.00000000 1 0\n"
                                     "4 1 70.00000000 50.00000000 5.00000000 0.00000000 {} 0\n",
                                     x0, pairs1)));
  };
  // Another final state that keeps every invariant: consistent, and said to be invariants only.
  const Report other = final_state("perf.out", "30.00000000", 1);
  EXPECT_EQ(other.verdict, Verdict::consistent) << particle::check::to_text(other);
  EXPECT_NE(other.summary.find("invariants only"), std::string::npos);
  const Report odd = final_state("perf_odd.out", "30.00000000", 0);
  EXPECT_EQ(odd.verdict, Verdict::violations);
  EXPECT_EQ(odd.kinds.at("collision counts"), 1);
  // The final state's invariants are checked in perf mode too: a particle far outside the box.
  const Report outside = final_state("perf_outside.out", "300.00000000", 1);
  EXPECT_EQ(outside.verdict, Verdict::violations) << particle::check::to_text(outside);
}

// The handout leaves open whether a perf-mode output starts with step 0: the final state alone
// is accepted, judged as the two-block layout is, and said; only in perf mode.
TEST(CheckCommand, PerfModeAcceptsTheFinalStateAlone) {
  const std::string scene =
      check_test::write_file("alone.in", "2\n100\n1\n4\nperf\n0 40 50 5 0\n1 60 50 -5 0\n");
  const auto final_only = [&](const std::string& name, const char* x0) {
    return check_test::check(
        scene, check_test::write_file(
                   name, fmt::format("4 0 {} 50.00000000 -5.00000000 0.00000000 1 0\n"
                                     "4 1 70.00000000 50.00000000 5.00000000 0.00000000 1 0\n",
                                     x0)));
  };
  // The correct program's output without its step-0 block.
  std::ifstream in(check_test::run_program(PLAIN_PATH, scene));
  std::string line, tail;
  for (int k = 0; std::getline(in, line); ++k)
    if (k >= 2) tail += line + "\n";
  const Report exact = check_test::check(scene, check_test::write_file("alone.out", tail));
  EXPECT_EQ(exact.verdict, Verdict::exact) << particle::check::to_text(exact);
  EXPECT_TRUE(exact.final_only);
  ASSERT_EQ(exact.notes.size(), 1u);
  EXPECT_NE(exact.notes[0].find("the final state alone"), std::string::npos);
  EXPECT_NE(particle::check::to_json(exact).find("\"layout\": \"final state alone\""),
            std::string::npos);
  const Report other = final_only("alone_other.out", "31.00000000");
  EXPECT_EQ(other.verdict, Verdict::consistent) << particle::check::to_text(other);
  const Report outside = final_only("alone_outside.out", "300.00000000");
  EXPECT_EQ(outside.verdict, Verdict::violations) << particle::check::to_text(outside);
  // A final block at the wrong time, or half of one, is no layout of the format.
  const Report wrong_time = check_test::check(
      scene, check_test::write_file("alone_t.out",
                                    "3 0 30.00000000 50.00000000 -5.00000000 0.00000000 1 0\n"
                                    "3 1 70.00000000 50.00000000 5.00000000 0.00000000 1 0\n"));
  EXPECT_EQ(wrong_time.verdict, Verdict::malformed);
  const Report half = check_test::check(
      scene, check_test::write_file("alone_half.out",
                                    "4 0 30.00000000 50.00000000 -5.00000000 0.00000000 1 0\n"));
  EXPECT_EQ(half.verdict, Verdict::malformed);
  // Print mode prints every time unit: its final state alone is malformed.
  const std::string print_scene =
      check_test::write_file("alone_print.in", "2\n100\n1\n4\nprint\n0 40 50 5 0\n1 60 50 -5 0\n");
  const Report print = check_test::check(
      print_scene,
      check_test::write_file("alone_print.out",
                             "4 0 30.00000000 50.00000000 -5.00000000 0.00000000 1 0\n"
                             "4 1 70.00000000 50.00000000 5.00000000 0.00000000 1 0\n"));
  EXPECT_EQ(print.verdict, Verdict::malformed);
}

// The handout's print mode prints "after each step" and "at the end" the final state with its
// counts: a program may print the last time unit twice, as bannified/cs3210-ass1 does. Accepted
// and said where both hold the same values; not where they differ, nor with the counts missing.
TEST(CheckCommand, PrintModeAcceptsTheLastTimeUnitPrintedTwice) {
  const std::string scene =
      check_test::write_file("twice.in", "2\n100\n1\n2\nprint\n0 40 50 5 0\n1 60 50 -5 0\n");
  const std::string once = check_test::read_file(check_test::run_program(PLAIN_PATH, scene));
  // Its last two lines, the final state, printed again first without the counts.
  const auto cut = once.rfind("\n2 0 ");
  ASSERT_NE(cut, std::string::npos) << once;
  const std::string final_lines = once.substr(cut + 1);
  std::string again;
  for (std::size_t at = 0, end; (end = final_lines.find('\n', at)) != std::string::npos;
       at = end + 1) {
    const std::string line = final_lines.substr(at, end - at);
    again += line.substr(0, line.rfind(' ', line.rfind(' ') - 1)) + "\n";
  }
  const std::string twice = once.substr(0, cut + 1) + again + final_lines;
  const Report r = check_test::check(scene, check_test::write_file("twice.out", twice));
  EXPECT_EQ(r.verdict, Verdict::exact) << particle::check::to_text(r) << twice;
  EXPECT_TRUE(r.final_repeated);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("prints its last time unit twice"), std::string::npos);
  EXPECT_NE(particle::check::to_json(r).find(
                "\"layout\": \"every time unit, then the final state again with its counts\""),
            std::string::npos);
  const Report plain = check_test::check(scene, check_test::write_file("once.out", once));
  EXPECT_FALSE(plain.final_repeated);
  EXPECT_TRUE(plain.notes.empty());
  // The two printings disagree: malformed, naming the value.
  std::string differ = twice;
  differ.replace(differ.find(again), again.find(' ', 4), "2 0 47.00000000");
  const Report bad = check_test::check(scene, check_test::write_file("twice_bad.out", differ));
  EXPECT_EQ(bad.verdict, Verdict::malformed) << differ;
  EXPECT_NE(bad.malformed.find("printed twice"), std::string::npos) << bad.malformed;
  EXPECT_NE(bad.malformed.find("particle 0's x is \"47.00000000\""), std::string::npos)
      << bad.malformed;
  // The repeat without the final state after it: the counts are missing.
  const Report cut_short = check_test::check(
      scene, check_test::write_file("twice_short.out", once.substr(0, cut + 1) + again));
  EXPECT_EQ(cut_short.verdict, Verdict::malformed);
  EXPECT_NE(cut_short.malformed.find("pair_collisions wall_collisions"), std::string::npos)
      << cut_short.malformed;
}

}  // namespace

// C's %.8f prints -0.0 (and -1e-9) as "-0.00000000": the same number as the scene's 0.
TEST(CheckCommand, MinusZeroIsZero) {
  const std::string output = (check_test::temp_dir() / "minus0.out").string();
  ASSERT_EQ(std::system(fmt::format("'{}' '{}' | sed 's/ 0\\.00000000/ -0.00000000/g' > '{}'",
                                    PSIM_PATH, kHeadOn, output)
                            .c_str()),
            0);
  std::ifstream in(output);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_NE(text.find(" -0.00000000"), std::string::npos);  // vy of both particles, each step
  const auto report = check_test::check(kHeadOn, output);
  EXPECT_EQ(report.verdict, particle::check::Verdict::exact) << particle::check::to_text(report);
}

// An output on stdin is judged as the same output in a file, under every reading: a pipe cannot
// be read twice, and each reading reads the output (a whole-motion program was `exact` from a
// file and 197 violations under the per-coordinate reading alone from stdin). The three programs
// are exact under one reading each and broken under both (pairs_first).
TEST(CheckCommand, StdinIsJudgedAsAFileIs) {
  const std::string scene = std::string(CHECK_SCENES) + "/random200.in";
  for (const std::string program :
       {PLAIN_PATH, CHECK_PROGRAMS "/whole_motion", CHECK_PROGRAMS "/pairs_first"}) {
    const std::string output = check_test::run_program(program, scene);
    const std::string text = (check_test::temp_dir() / "stdin_judged.txt").string();
    const auto judged = [&](const std::string& command) {
      const int raw = std::system((command + " > '" + text + "'").c_str());
      return std::pair(WEXITSTATUS(raw), check_test::read_file(text));
    };
    const auto from_file = judged(fmt::format("'{}' check '{}' '{}'", PSIM_PATH, scene, output));
    const auto from_pipe =
        judged(fmt::format("cat '{}' | '{}' check '{}' -", output, PSIM_PATH, scene));
    EXPECT_EQ(from_pipe, from_file) << program;
    EXPECT_EQ(from_file.second.find("verdict: malformed"), std::string::npos) << from_file.second;
  }
}

// Stdin's copy that cannot be made is a usage error naming it, exit 2, before anything is judged.
TEST(CheckCommand, StdinsCopyThatCannotBeMadeExitsTwo) {
  const std::string output = check_test::run_program(PLAIN_PATH, kHeadOn);
  const std::string err = (check_test::temp_dir() / "stdin_copy.err").string();
  const int raw = std::system(fmt::format("TMPDIR=/nonexistent '{}' check '{}' - < '{}' 2> '{}'",
                                          PSIM_PATH, kHeadOn, output, err)
                                  .c_str());
  EXPECT_EQ(WEXITSTATUS(raw), 2);
  EXPECT_NE(check_test::read_file(err).find(
                "psim check: <stdin>: its copy for the readings after the first (in TMPDIR, else "
                "/tmp): cannot create /nonexistent/psim-check-stdin-"),
            std::string::npos)
      << check_test::read_file(err);
}

// The summary names the step, the particles and the kind: "particle 52" for one.
TEST(CheckCommand, TheSummaryNamesTheParticles) {
  EXPECT_EQ(particle::check::particles_phrase({52}), "particle 52");
  EXPECT_EQ(particle::check::particles_phrase({3, 9}), "particles 3, 9");
  EXPECT_EQ(particle::check::particles_phrase({}), "the whole state");
  const std::string scene = std::string(SCENES_DIR) + "/wall_before_end.in";
  const std::string broken =
      check_test::run_program(std::string(CHECK_PROGRAMS) + "/wall_tolerance", scene);
  const auto report = check_test::check(scene, broken);
  EXPECT_EQ(report.summary.substr(0, report.summary.find(": ") + 1),
            "1 violation; the first at time unit 1, particle 0:")
      << report.summary;
}

// The reader's memory follows what it has read, not S: a print scene of S = 10^18 and an output
// of four lines is malformed at once, under a 200 MB address-space limit.
TEST(CheckCommand, MemoryFollowsTheOutputNotS) {
  const std::string scene = check_test::write_file(
      "huge_s.in", "2\n100\n1\n1000000000000000000\nprint\n0 40 50 5 0\n1 60 50 -5 0\n");
  const std::string output =
      check_test::write_file("huge_s.out",
                             "0 0 40.00000000 50.00000000 5.00000000 0.00000000\n"
                             "0 1 60.00000000 50.00000000 -5.00000000 0.00000000\n"
                             "1 0 45.00000000 50.00000000 5.00000000 0.00000000\n"
                             "1 1 55.00000000 50.00000000 -5.00000000 0.00000000\n");
  const std::string verdict = (check_test::temp_dir() / "huge_s.txt").string();
  const int raw = std::system(fmt::format("ulimit -v 200000; timeout 20 '{}' check '{}' '{}' "
                                          ">'{}' 2>&1",
                                          PSIM_PATH, scene, output, verdict)
                                  .c_str());
  EXPECT_EQ(WEXITSTATUS(raw), 2);
  std::ifstream in(verdict);
  std::string first;
  std::getline(in, first);  // not "psim check: std::bad_alloc", nor nothing after a timeout
  EXPECT_EQ(first.rfind("verdict: malformed: line 4", 0), 0u) << first;
  const auto report = check_test::check(scene, output);
  EXPECT_EQ(report.verdict, particle::check::Verdict::malformed);
  EXPECT_NE(report.malformed.find("expected 2000000000000000002 lines"), std::string::npos)
      << report.malformed;
}

// An output with CRLF line ends: the same values, read line by line at every time unit, where
// the LF output's lines that are the reference's text are taken without being read (judge.hpp,
// Judge::expects).
std::string crlf(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
  return out;
}

// The report as JSON, without the output's name.
std::string unnamed_json(particle::check::Report report) {
  report.output.clear();
  return particle::check::to_json(report);
}

// Taken as the reference's text or read line by line, an output gets the same report, to the
// last violation and note: programs that leave the reference at a line inside a time unit (the
// lines before it taken as expected, the time unit before it read again for the model), that
// print NaN, that follow another reading or no reading at all.
TEST(OutputReader, LinesTakenAsExpectedGiveTheReportOfLinesReadOneByOne) {
  const std::string crowded = (check_test::temp_dir() / "taken_or_read.in").string();  // pairs
  const std::string make = fmt::format(  // leave it after a few time units (test_programs.cpp)
      "printf '200\\n2000\\n1\\n30\\nprint\\n' | '{}' --write-scene '{}' --seed 1", PSIM_PATH,
      crowded);
  ASSERT_EQ(std::system(make.c_str()), 0) << make;
  for (const std::string& scene : {std::string(CHECK_SCENES) + "/random200.in", crowded})
    for (const std::string program :
         {"float", "two_collisions", "nan", "whole_motion", "pairs_first", "fma", "fast_math"}) {
      const std::string lf = check_test::read_file(
          check_test::run_program(std::string(CHECK_PROGRAMS) + "/" + program, scene));
      const Report taken = check_test::check(scene, check_test::write_file("taken.out", lf));
      const Report read = check_test::check(scene, check_test::write_file("read.out", crlf(lf)));
      EXPECT_EQ(unnamed_json(taken), unnamed_json(read)) << program << " on " << scene;
      EXPECT_TRUE(taken.verdict != Verdict::exact || taken.reading != "per-coordinate")
          << program << " on " << scene << ": not a program that leaves the reference";
    }
}

// Time units larger than half the reader's buffer (1 MiB) are compared in pieces: a value changed
// at the first line of a time unit, in its middle beyond the buffer's first fill, or at its last
// line leaves the block read as without `expected`, the lines before it from `expected`'s text;
// unchanged, the block is taken as expected, and read_printed() reads it as the lines would be.
TEST(OutputReader, ATimeUnitLargerThanTheBufferIsTakenInPieces) {
  const std::size_t n = 20000;
  const std::string scene_path = check_test::write_file("n20000.in", "20000\n20000\n1\n3\nprint\n");
  const std::string out = (check_test::temp_dir() / "n20000.out").string();
  ASSERT_EQ(
      std::system(fmt::format("'{}' --threads 1 '{}' > '{}'", PSIM_PATH, scene_path, out).c_str()),
      0);
  std::ifstream scene_in(scene_path);
  const particle::Scene scene = particle::read_scene(scene_in, scene_path, particle::RandomInit{});
  const std::string lf = check_test::read_file(out);
  const auto line_start = [&](std::int64_t time, std::size_t i) {
    return i == 0 && time == 0 ? 0 : lf.find(fmt::format("\n{} {} ", time, i)) + 1;
  };
  const std::string block1 = lf.substr(line_start(1, 0), line_start(2, 0) - line_start(1, 0));
  ASSERT_GT(block1.size(), std::size_t{1} << 20);
  const auto same_block = [&](const particle::Block& a, const particle::Block& b) {
    EXPECT_FALSE(a.as_expected || b.as_expected);
    EXPECT_EQ(a.time, b.time);
    EXPECT_EQ(a.state.x, b.state.x);
    EXPECT_EQ(a.state.vy, b.state.vy);
    EXPECT_EQ(a.text, b.text);
  };
  for (const std::size_t i : {std::size_t{0}, std::size_t{15000}, n - 1, n}) {  // n: unchanged
    std::string changed = lf;
    if (i < n) {
      char& last =
          changed[changed.find(' ', line_start(1, i) + fmt::format("1 {} ", i).size()) - 1];
      last = last == '9' ? '8' : static_cast<char>(last + 1);  // x's last decimal
    }
    particle::OutputReader taken(check_test::write_file("taken.out", changed), scene);
    particle::OutputReader read(check_test::write_file("read.out", crlf(changed)), scene);
    particle::Block a, b;
    ASSERT_TRUE(taken.next(a) && read.next(b));
    ASSERT_TRUE(taken.next(a, block1) && read.next(b, block1));
    EXPECT_EQ(a.as_expected, i == n) << i;
    if (i == n) taken.read_printed(a, block1);
    same_block(a, b);
    ASSERT_TRUE(taken.next(a, block1) && read.next(b, block1));  // not time unit 2's text
    same_block(a, b);
  }
}
