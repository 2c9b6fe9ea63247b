// External programs in a config: the `programs` key's errors at their key paths, their runs in the
// expansion, their command lines, the bound on their output, their records and the check columns.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "config/expansion.hpp"
#include "config/program.hpp"
#include "declaration_fixture.hpp"
#include "run/judge.hpp"
#include "run/record.hpp"

using namespace psweep;
using psweep::fixture::declared;

namespace {

std::string config_text(const std::string& programs, const std::string& extra = "") {
  return R"({"name": "p", "base": {"engine": "brute", "N": 10, "L": 100, "r": 1, "S": 3},
             "sweep": {"engine": ["brute", "mine"], "T": [1, 2]}, "programs": )" +
         programs + extra + "}";
}

std::string error_of(const std::string& text) {
  try {
    const Config c = parse_config(text, "p.json");
    check_engines(c, declared().engine_names());
    expand(c, declared());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Programs, ParseWithDefaults) {
  const Config c = parse_config(
      config_text(R"({"mine": {"command": ["./my_sim", "{T}", "{N}"], "uses": ["T"]}})"), "p.json");
  ASSERT_EQ(c.programs.size(), 1u);
  const Program& p = c.programs[0];
  EXPECT_EQ(c.program("mine"), &p);
  EXPECT_EQ(c.program("brute"), nullptr);
  EXPECT_EQ(p.command, (std::vector<std::string>{"./my_sim", "{T}", "{N}"}));
  EXPECT_FALSE(p.input_file);
  EXPECT_TRUE(p.facts.uses_param("T"));
  EXPECT_FALSE(p.takes_slow_factor);
  // Described as an engine is: K always reaches it (its check), all pairs unless it says.
  EXPECT_TRUE(p.facts.uses_param("slow_factor"));
  EXPECT_FALSE(p.facts.uses_param("G"));
  EXPECT_EQ(p.facts.growth, 2);
  EXPECT_TRUE(p.facts.program);
  EXPECT_EQ(p.slow_factor, 1);
  EXPECT_FALSE(c.judge_steps);  // a program's judging run: print mode, the scene's whole S
  const std::string mine = R"({"mine": {"command": ["./x"]}})";
  EXPECT_EQ(parse_config(config_text(mine, R"(, "judge_steps": 7)"), "p.json").judge_steps, 7);
  EXPECT_EQ(error_of(config_text(mine, R"(, "judge_steps": 0)")),
            "p.json: judge_steps: expected a positive integer, got 0");
}

TEST(Programs, ErrorsNameTheKeyPath) {
  const auto has = [](const std::string& text, const std::string& expected) {
    const std::string error = error_of(text);
    EXPECT_NE(error.find(expected), std::string::npos) << error;
  };
  has(config_text(R"({"mine": {"command": ["./x", "{Q}"]}})"),
      "p.json: programs.mine.command[1]: unknown placeholder {Q}");
  has(config_text(R"({"mine": {"command": ["./x", "{T"]}})"),
      "programs.mine.command[1]: unmatched \"{\"");
  has(config_text(R"({"mine": {"command": "./x {T}"}})"),
      "programs.mine.command: expected a non-empty list of strings");
  has(config_text(R"({"mine": {"command": ["./x", 3]}})"),
      "programs.mine.command[1]: expected a string, got 3");
  has(config_text(R"({"mine": {"command": []}})"), "programs.mine.command: expected a non-empty");
  has(config_text(R"({"mine": {"command": ["./x"], "threads": 2}})"),
      "programs.mine.threads: unknown key (expected one of command, input, uses, slow_factor, "
      "growth, limits, env, numbers)");
  has(config_text(R"({"mine": {"command": ["./x"], "numbers": "steps"}})"),
      "p.json: programs.mine.numbers: expected \"time units\" (the 2019 format) or \"sub-steps\"");
  has(config_text(R"({"mine": {"command": ["./x"], "growth": "N^3"}})"),
      "p.json: programs.mine.growth: unknown growth \"N^3\" (expected N or N^2)");
  has(config_text(R"({"mine": {"command": ["./x"], "growth": 2}})"),
      "p.json: programs.mine.growth: expected \"N\" or \"N^2\", got 2");
  has(config_text(R"({"mine": {"command": ["./x", "{T}"]}})"),
      "programs.mine.command[1]: {T}: add \"T\" to the program's \"uses\"");
  has(config_text(R"({"mine": {"command": ["./x", "{scene}"]}})"),
      "programs.mine.command[1]: {scene}: only with \"input\": \"file\"");
  has(config_text(R"({"mine": {"command": ["./x"], "input": "file"}})"),
      "programs.mine.command: \"input\": \"file\" needs {scene}");
  has(config_text(R"({"mine": {"command": ["./x"], "input": "pipe"}})"),
      "programs.mine.input: expected \"stdin\" or \"file\"");
  has(config_text(R"({"mine": {"command": ["./x"], "uses": ["G"]}})"),
      "programs.mine.uses[0]: expected \"T\", \"P\" or \"slow_factor\", got \"G\"");
  has(config_text(R"({"mine": {"command": ["mpirun", "-np", "{P}", "./x"]}})"),
      "programs.mine.command[2]: {P}: add \"P\" to the program's \"uses\"");
  has(config_text(R"({"mine": {"command": ["mpirun", "./x"], "uses": ["P"]}})"),
      "programs.mine.command: names no {P}, but \"P\" is in \"uses\"");
  has(config_text(R"({"mine": {"command": ["./x", "{ranks}"]}})"),
      "programs.mine.command[1]: unknown placeholder {ranks} (expected {T}, {P}, {N}, {K} or "
      "{scene}");
  has(config_text(R"({"mine": {"command": ["./x"], "uses": ["slow_factor"], "slow_factor": 2}})"),
      "programs.mine.slow_factor: not with \"slow_factor\" in uses");
  has(config_text(R"({"mine": {"command": ["./x"], "slow_factor": 3}})"),
      "programs.mine.slow_factor: expected a power of two");
  has(config_text(R"({"mine": ["./x"]})"), "programs.mine: expected an object");
  has(config_text(R"([])"), "p.json: programs: expected an object");
  has(config_text(R"({"my sim": {"command": ["./x"]}})"),
      "programs.my sim: expected a program name");
  has(config_text(R"({"brute": {"command": ["./x"]}})"),
      "p.json: programs.brute: shadows psim's engine \"brute\"");
  has(config_text(R"({"other": {"command": ["./x"]}})"),
      "sweep.engine[1]: unknown engine \"mine\" (psim offers: ");
}

TEST(Programs, RunAsEnginesWithTheirOwnParameters) {
  // T multiplies a program's runs only when it uses T; K is always its run's (the check's K).
  const Config uses_t = parse_config(
      config_text(R"({"mine": {"command": ["./x", "{T}"], "uses": ["T"]}})"), "p.json");
  const auto runs = expand(uses_t, declared());
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[2].params.engine, "mine");
  EXPECT_EQ(runs[3].params.T, 2);
  EXPECT_EQ(runs[3].params.slow_factor, 1);
  const Config serial = parse_config(config_text(R"({"mine": {"command": ["./x"]}})"), "p.json");
  const auto serial_runs = expand(serial, declared());
  ASSERT_EQ(serial_runs.size(), 3u);
  EXPECT_FALSE(serial_runs[2].params.T);
}

TEST(Programs, AProgramOfRanksIsSweptOverPAndStartsThemItself) {
  // P multiplies only the runs of a program that uses it, and reaches its command as {P}.
  const Config c = parse_config(
      R"({"name": "p", "base": {"engine": "ranks", "N": 10, "L": 100, "r": 1, "S": 3},
          "sweep": {"engine": ["ranks", "serial"], "P": [1, 2, 4]},
          "programs": {"ranks": {"command": ["mpirun", "-np", "{P}", "./x"], "uses": ["P"]},
                       "serial": {"command": ["./y"]}}})",
      "p.json");
  const auto runs = expand(c, declared());
  ASSERT_EQ(runs.size(), 4u);
  std::vector<std::string> ranks;
  for (const RunSpec& run : runs)
    if (run.params.engine == "ranks")
      ranks.push_back(program_arguments(*c.program("ranks"), run.params, "scene.in")[2]);
    else
      EXPECT_FALSE(run.params.P);
  EXPECT_EQ(ranks, (std::vector<std::string>{"1", "2", "4"}));
}

TEST(Programs, AProgramBuiltForOneKRefusesAnother) {
  const std::string text =
      R"({"name": "p", "base": {"engine": "mine", "N": 10, "L": 100, "r": 1, "S": 3},
          "sweep": {"slow_factor": [2, 4]},
          "programs": {"mine": {"command": ["./x"], "slow_factor": 2}}})";
  EXPECT_NE(error_of(text).find("p.json: sweep.slow_factor[1]: program \"mine\" was built for "
                                "slow_factor 2 (its \"slow_factor\"), this run asks 4"),
            std::string::npos)
      << error_of(text);
  const std::string takes_k =
      R"({"name": "p", "base": {"engine": "mine", "N": 10, "L": 100, "r": 1, "S": 3},
          "sweep": {"slow_factor": [2, 4]},
          "programs": {"mine": {"command": ["./x", "{K}"], "uses": ["slow_factor"]}}})";
  EXPECT_EQ(expand(parse_config(takes_k, "p.json"), declared()).size(), 2u);
}

TEST(Programs, CommandLineFillsPlaceholdersAndFindsThePath) {
  Program p;
  p.facts.name = "mine";
  p.command = {"sh", "-c", "echo {{{N}}} {T} {K}", "{scene}"};
  Params params;
  params.N = 12;
  params.T = 3;
  params.slow_factor = 4;
  const auto argv = program_arguments(p, params, "in/scene.in");
  EXPECT_TRUE(argv[0] == "/usr/bin/sh" || argv[0] == "/bin/sh") << argv[0];
  EXPECT_EQ(argv[2], "echo {12} 3 4");
  EXPECT_EQ(argv[3], "in/scene.in");
  EXPECT_EQ(resolve_executable("./my_sim"), "./my_sim");
  EXPECT_EQ(resolve_executable("no-such-program-here"), "no-such-program-here");
}

TEST(Programs, OutputLimitHoldsACorrectOutputAndLittleMore) {
  particle::Scene scene;
  scene.L = 20000;
  scene.r = 1;
  scene.steps = 10;
  scene.mode = particle::OutputMode::print;
  scene.particles = particle::Particles(2);
  scene.particles.vx = {3000, -4000};
  scene.particles.vy = {0, 0};
  // The longest correct line: all the energy in one particle, counts of 20 digits.
  const std::string longest =
      "10 1 19999.00000000 19999.00000000 -5000.00000000 -5000.00000000 "
      "18446744073709551615 18446744073709551615\n";
  const std::uint64_t limit = output_limit(scene);
  EXPECT_GE(limit, 11 * 2 * longest.size());
  EXPECT_LE(limit, 11 * 2 * 4 * longest.size());
  scene.mode = particle::OutputMode::perf;
  EXPECT_LT(output_limit(scene), limit / 5);
}

TEST(Programs, RecordsHaveNoEngineMetricsAndClearStatuses) {
  const Config c = parse_config(
      config_text(R"({"mine": {"command": ["./x", "{T}"], "uses": ["T"]}})"), "p.json");
  const auto runs = expand(c, declared());
  const RunSpec& run = runs[2];
  ChildResult child;
  child.process_s = 1.5;
  Record ok = make_program_record(run, 0, child, 100, 1000, 10, 2);
  EXPECT_EQ(ok.status, Status::ok);
  EXPECT_EQ(ok.wall_s(), 1.5);  // the whole process: a program has no timer of its own
  EXPECT_FALSE(ok.metrics);
  child.outcome = Outcome::signaled;
  child.signal = SIGXFSZ;
  Record flood = make_program_record(run, 0, child, 1000, 1000, 10, 2);
  EXPECT_EQ(flood.status, Status::too_much_output);
  EXPECT_FALSE(flood.wall_s());
  EXPECT_NE(flood.error.find("held 1000 bytes on disk (printed, or reserved with fallocate), where a "
                                "2019 output of this scene takes at most 1000"),
            std::string::npos);
  child.outcome = Outcome::timed_out;
  EXPECT_EQ(make_program_record(run, 0, child, 10, 1000, 10, 2).status, Status::timeout);
  child.outcome = Outcome::exited;
  child.exit_code = 127;
  child.stderr_tail = "psweep: cannot execute ./x: No such file or directory";
  Record missing = make_program_record(run, 0, child, 0, 1000, 10, 2);
  EXPECT_EQ(missing.status, Status::failed);
  EXPECT_EQ(missing.error, child.stderr_tail);
}

TEST(Programs, JudgementFromTheCheckReport) {
  ChildResult child;
  const Judgement exact =
      read_judgement(R"({"verdict": "exact", "summary": "identical", "violations": []})", child);
  EXPECT_EQ(exact.verdict, "exact");
  EXPECT_EQ(exact.first_step, "");
  EXPECT_EQ(exact.detail, "identical");
  const Judgement broken = read_judgement(
      R"({"verdict": "violations", "summary": "2 violations; the first at time unit 1: wall hit missed",
          "violations": [{"step": 1, "detail": "the model has a wall hit\nof particle 0"}]})",
      child);
  EXPECT_EQ(broken.first_step, "1");
  EXPECT_EQ(broken.detail,
            "2 violations; the first at time unit 1: wall hit missed: the model has a wall hit | "
            "of particle 0");
  const Judgement garbage = read_judgement(
      R"({"verdict": "malformed", "summary": "x", "malformed": {"line": 3, "message": "expected 6 fields"}})",
      child);
  EXPECT_EQ(garbage.detail, "line 3: expected 6 fields");
  child.exit_code = 2;
  child.stderr_tail = "psim check: scene.in: cannot open";
  const Judgement none = read_judgement("", child);
  EXPECT_EQ(none.verdict, "error");
  EXPECT_EQ(none.detail,
            "psim check: no report (exit status 2): psim check: scene.in: cannot open");
}
