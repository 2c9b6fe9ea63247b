// Ranks, P, swept as threads are (issue 43 item 4): the parameter and the launcher in a config,
// their errors at the key path, the expansion (P multiplies only the engines that use it), the
// launcher's words before psim's, the environment and the cost model of a run of P ranks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "config/expansion.hpp"
#include "config/launcher.hpp"
#include "config/shard.hpp"
#include "declaration_fixture.hpp"
#include "run/command.hpp"
#include "sweep/plan.hpp"

using namespace psweep;

namespace {

const std::string kBase =
    R"("base": {"engine": "mpi", "N": 200, "L": 2000, "r": 1, "S": 10})";

Config config_of(const std::string& extra) {
  return parse_config("{" + kBase + extra + "}", "c.json");
}

std::string error_of(const std::string& extra) {
  try {
    expand(config_of(extra), fixture::declared());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Ranks, PDefaultsToOneAndTheLauncherToMpirun) {
  const Config c = config_of("");
  EXPECT_EQ(c.base.P, 1);
  EXPECT_EQ(c.launcher, default_launcher(geteuid() == 0));
  EXPECT_EQ(c.launcher.front(), "mpirun");
  // Ranks bound to their cores, more ranks than cores allowed; root needs OpenMPI's permission.
  for (const char* word : {"--bind-to", "--oversubscribe", "-np", "{P}", "slot:PE={rank_cores}",
                           "mpi_yield_when_idle"})
    EXPECT_NE(std::find(c.launcher.begin(), c.launcher.end(), word), c.launcher.end()) << word;
  const auto root = default_launcher(true), user = default_launcher(false);
  EXPECT_NE(std::find(root.begin(), root.end(), "--allow-run-as-root"), root.end());
  EXPECT_EQ(std::find(user.begin(), user.end(), "--allow-run-as-root"), user.end());
}

TEST(Ranks, BadValuesOfPNameTheKey) {
  EXPECT_EQ(error_of(R"(, "sweep": {"P": [1, 0]})"),
            "c.json: sweep.P[1]: expected a positive integer, got 0");
  EXPECT_EQ(error_of(R"(, "sweep": {"P": [2.5]})"),
            "c.json: sweep.P[0]: expected a positive integer, got 2.5");
  EXPECT_EQ(error_of(R"(, "sweep": {"P": ["2"]})"),
            "c.json: sweep.P[0]: expected a positive integer, got \"2\"");
  EXPECT_EQ(error_of(R"(, "sweep": {"P": []})"),
            "c.json: sweep.P: expected a non-empty array of values");
  EXPECT_EQ(error_of(R"(, "sweep": {"P": [4097]})"),
            "c.json: sweep.P[0]: expected at most 4096 ranks, got 4097");
  try {
    parse_config(R"({"base": {"engine": "mpi", "N": 2, "L": 20, "r": 1, "S": 1, "P": -1}})",
                 "c.json");
    ADD_FAILURE() << "base.P = -1 accepted";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "c.json: base.P: expected a positive integer, got -1");
  }
}

TEST(Ranks, BadLaunchersNameTheKey) {
  EXPECT_EQ(error_of(R"(, "launcher": "mpirun -np {P}")"),
            "c.json: launcher: expected a non-empty list of strings, the launcher and its "
            "arguments before psim's, e.g. [\"srun\", \"-n\", \"{P}\"] (no shell)");
  EXPECT_EQ(error_of(R"(, "launcher": [])"),
            "c.json: launcher: expected a non-empty list of strings, the launcher and its "
            "arguments before psim's, e.g. [\"srun\", \"-n\", \"{P}\"] (no shell)");
  EXPECT_EQ(error_of(R"(, "launcher": ["srun", 4])"), "c.json: launcher[1]: expected a string, got 4");
  EXPECT_EQ(error_of(R"(, "launcher": ["", "-n", "{P}"])"),
            "c.json: launcher[0]: expected the launcher's path or name, got \"\"");
  EXPECT_EQ(error_of(R"(, "launcher": ["srun", "-n", "{N}"])"),
            "c.json: launcher[2]: unknown placeholder {N} (expected {P}, {T} or {rank_cores}; {{ "
            "and }} for literal braces)");
  EXPECT_EQ(error_of(R"(, "launcher": ["srun", "-c", "{T}"])"),
            "c.json: launcher: names no {P}: the launcher must start the run's P ranks (mpirun "
            "-np {P}, srun -n {P})");
  EXPECT_NE(error_of(R"(, "launcher": ["srun", "-n", "{P"])").find("c.json: launcher[2]: "),
            std::string::npos);
}

// P multiplies the runs of the engines that use it (mpi) and no other: brute's runs collapse into
// one per T, with an empty P, and keep the config ids they had before P existed.
TEST(Ranks, POnlyMultipliesTheEnginesThatUseIt) {
  const Config c = parse_config(
      R"({"base": {"engine": "mpi", "N": 200, "L": 2000, "r": 1, "S": 10},
          "sweep": {"engine": ["brute", "mpi"], "P": [1, 2, 4], "T": [1, 2]}})",
      "c.json");
  const auto runs = expand(c, fixture::declared());
  ASSERT_EQ(runs.size(), 2u + 6u);
  EXPECT_EQ(count_configurations(c, fixture::declared()), runs.size());
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(runs[i].params.engine, "brute");
    EXPECT_FALSE(runs[i].params.P);
  }
  EXPECT_EQ(runs[2].params.engine, "mpi");
  EXPECT_EQ(runs[2].params.P, 1);
  EXPECT_EQ(runs[7].params.P, 4);
  EXPECT_EQ(runs[7].params.T, 2);
  // brute's id is the one of a config that never named P
  const auto plain = expand(parse_config(
      R"({"base": {"engine": "brute", "N": 200, "L": 2000, "r": 1, "S": 10, "T": 1}})", "c.json"),
                            fixture::declared());
  EXPECT_EQ(runs[0].id, plain[0].id);
  // every mpi configuration has its own id, and P is in its description
  std::vector<std::string> ids;
  for (const auto& r : runs) ids.push_back(r.id);
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(std::unique(ids.begin(), ids.end()), ids.end());
  EXPECT_NE(describe(runs[7]).find(" P=4"), std::string::npos);
}

// The launcher's words come before psim's, with {P}, {T} and {rank_cores} filled; a run without
// P gets none.
TEST(Ranks, TheLauncherStartsPsimOnPRanks) {
  const Config c = config_of(
      R"(, "launcher": ["srun", "-n", "{P}", "-c{rank_cores}", "--hint={T}x{{literal}}"],
           "sweep": {"engine": ["mpi", "brute"], "P": [3], "T": [4]})");
  const auto runs = expand(c, fixture::declared());
  ASSERT_EQ(runs.size(), 2u);
  const auto words = launcher_arguments(c.launcher, runs[0].params, 2);
  ASSERT_EQ(words.size(), 5u);
  EXPECT_NE(words[0].find("srun"), std::string::npos);  // found on PATH, or as written
  EXPECT_EQ(std::vector<std::string>(words.begin() + 1, words.end()),
            (std::vector<std::string>{"-n", "3", "-c2", "--hint=4x{literal}"}));
  EXPECT_EQ(launcher_arguments(c.launcher, runs[0].params, 8)[3], "-c4");
  EXPECT_TRUE(launcher_arguments(c.launcher, runs[1].params, 2).empty());
  // psim's own arguments do not change: the ranks are the launcher's
  const auto psim = psim_arguments(runs[0], "psim", "in", "m");
  EXPECT_EQ(std::find(psim.begin(), psim.end(), "3"), psim.end());
  // the default launcher finds mpirun on PATH
  const auto mpirun = launcher_arguments(default_launcher(false), runs[0].params, 2);
  EXPECT_EQ(mpirun.back(), "3");
  EXPECT_EQ(mpirun[mpirun.size() - 2], "-np");
}

// Ranks whose threads together exceed the CPUs wait passively; a single rank's psim decides.
TEST(Ranks, OversubscribedRanksWaitPassively) {
  const auto runs = expand(config_of(R"(, "sweep": {"P": [1, 4096]})"), fixture::declared());
  ASSERT_EQ(runs.size(), 2u);
  const auto passive = [](const std::vector<std::string>& env) {
    return std::find(env.begin(), env.end(), "OMP_WAIT_POLICY=passive") != env.end();
  };
  EXPECT_FALSE(passive(child_environment(runs[0], {})));
  EXPECT_TRUE(passive(child_environment(runs[1], {})));
}

// A run of P ranks costs its launcher's start and each sub-step's messages, and its ranks share
// the work as threads do, up to the CPUs; --dry-run --count's estimate follows P.
TEST(Ranks, TheCostModelCountsRanks) {
  Params p;
  p.N = 1000;
  p.S = 100;
  p.T = 1;
  EngineFacts facts;
  facts.growth = 1;
  facts.cost_ns = 1e9;  // a second per particle and sub-step
  CostModel m;
  m.process_s = 0;
  m.cpus = 4;
  const double work = 1e3 * 100;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts, m), work);
  p.P = 1;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts, m), m.launch_s + m.rank_step_s * 100 + work);
  p.P = 2;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts, m), m.launch_s + m.rank_step_s * 100 + work / 2);
  p.T = 2;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts, m), m.launch_s + m.rank_step_s * 100 + work / 4);
  p.P = 8;  // 16 threads on 4 CPUs take turns
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts, m), m.launch_s + m.rank_step_s * 100 + work / 4);

  const Config c = config_of(R"(, "sweep": {"P": [1, 2]})");
  const auto runs = expand(c, fixture::declared());
  ASSERT_EQ(runs.size(), 2u);
  CostModel two;
  two.cpus = 2;
  EXPECT_GT(configuration_s(c, fixture::declared(), runs[0].params, two),
            configuration_s(c, fixture::declared(), runs[1].params, two));
}

// A launcher that cannot be executed is the config's error before anything runs, where a run of
// P ranks needs it, and nobody's business where none does.
TEST(Ranks, ALauncherThatCannotRunIsRefusedBeforeTheSweep) {
  const std::string launcher = R"(, "launcher": ["/nonexistent/mpirun", "-np", "{P}"])";
  try {
    make_plan(config_of(launcher), fixture::declared(), std::nullopt);
    ADD_FAILURE() << "an unexecutable launcher accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(
                  "c.json: launcher[0]: cannot execute \"/nonexistent/mpirun\": ", 0),
              0u)
        << e.what();
  }
  EXPECT_NO_THROW(make_plan(config_of(launcher + R"(, "sweep": {"engine": ["brute"]})"),
                            fixture::declared(), std::nullopt));
  const Plan plan = make_plan(config_of(R"(, "sweep": {"P": [1, 3]})"), fixture::declared(), std::nullopt);
  EXPECT_EQ(plan.size.largest_P, 3);
  EXPECT_NE(size_report(plan.config, plan.size).find("largest P: 3\n"), std::string::npos);
}
