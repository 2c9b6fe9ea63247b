// The sweep's stages alone: plan (shard selection, --dry-run output, the max_runs guard, the
// folder), resume (rows read back, a cut line, foreign rows, set-aside, meta continued), the run
// loop with a stand-in for psim (rows and summary kept current, warm-ups unrecorded, an
// interrupted child stops it) and finish (the session's cost, the exit status).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "declaration_fixture.hpp"
#include "results/csv.hpp"
#include "results/folder.hpp"
#include "results/results.hpp"
#include "run/command.hpp"
#include "sweep/finish.hpp"
#include "sweep/plan.hpp"
#include "sweep/resume.hpp"
#include "sweep/run_loop.hpp"

using namespace psweep;
namespace fs = std::filesystem;

namespace {

using fixture::declared;

Config config(const std::string& extra = "") {
  return parse_config(
      R"({"name": "st", "base": {"engine": "brute", "N": 100, "L": 2000, "r": 1, "S": 10, "T": 1},
          "sweep": {"engine": ["brute", "sweep"], "N": [50, 100, 200], "T": [1, 2]},
          "repetitions": 2)" +
          extra + "}",
      "st.json");
}

// A folder per test: ctest runs the tests of this file in parallel.
fs::path folder() {
  const fs::path dir = fs::path(::testing::TempDir()) /
                       (std::string("psweep_stages_") +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string slurp(const fs::path& path) { return read_file(path.string()); }

std::string dry_run(const Plan& plan, bool count) {
  char* buffer = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  print_dry_run(plan, count, out);
  std::fclose(out);
  std::string text(buffer, size);
  std::free(buffer);
  return text;
}

std::size_t lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

}  // namespace

TEST(Plan, ShardsSplitTheConfigurationsAndTheirSize) {
  const Plan whole = make_plan(config(), declared(), std::nullopt);
  EXPECT_EQ(whole.what, "the sweep");
  EXPECT_EQ(whole.size.total.configurations, 12u);
  std::size_t together = 0;
  std::vector<std::string> ids;
  for (int i = 1; i <= 3; ++i) {
    const Plan part = make_plan(config(), declared(), ShardSpec{i, 3});
    EXPECT_EQ(part.what, "shard " + std::to_string(i) + "/3");
    const auto runs = planned_runs(part, false);
    EXPECT_EQ(runs.size(), part.size.total.configurations);
    together += runs.size();
    for (const auto& r : runs) ids.push_back(r.id);
  }
  EXPECT_EQ(together, 12u);
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(std::unique(ids.begin(), ids.end()), ids.end());
}

TEST(Plan, DryRunListsTheShardOrCountsIt) {
  const Plan plan = make_plan(config(), declared(), ShardSpec{2, 3});
  const std::string listing = dry_run(plan, false);
  EXPECT_EQ(lines(listing), plan.size.total.configurations + 1);
  for (const auto& run : planned_runs(plan, false))
    EXPECT_NE(listing.find(run.id + " engine="), std::string::npos) << listing;
  EXPECT_NE(
      listing.find(fmt::format("{} configurations x 2 repetitions = {} runs (+ 0 warm-up "
                               "runs), pin none, timeout 600 s\n",
                               plan.size.total.configurations, 2 * plan.size.total.configurations)),
      std::string::npos)
      << listing;
  const std::string counted = dry_run(plan, true);
  EXPECT_EQ(counted.rfind("shard 2/3 of st.json\n", 0), 0u) << counted;
  const std::size_t n = plan.size.total.configurations;
  EXPECT_NE(counted.find(fmt::format("\n{:<14} {:>14} {:>16} ", "total", n, 2 * n)),
            std::string::npos)
      << counted;
  const std::string whole = dry_run(make_plan(config(), declared(), std::nullopt), true);
  EXPECT_EQ(whole.find("shard"), std::string::npos) << whole;
  EXPECT_NE(whole.find("\nlargest T: 2\n"), std::string::npos) << whole;
}

// The size's estimate is this machine's (T = 2 on one CPU costs what T = 1 does), the split is not:
// every Slurm task and the merge must compute the same one wherever they run.
TEST(Plan, TheCpusChangeTheEstimateButNotTheSplit) {
  EXPECT_EQ(make_plan(config(), declared(), ShardSpec{1, 3}, 1).shard_of,
            make_plan(config(), declared(), ShardSpec{1, 3}, 0).shard_of);
  const Plan one = make_plan(config(), declared(), std::nullopt, 1);
  const Plan ideal = make_plan(config(), declared(), std::nullopt, 0);
  EXPECT_GT(one.size.total.seconds, ideal.size.total.seconds);
  EXPECT_NE(dry_run(one, true).find("on this machine's 1 CPU (more threads take turns)"),
            std::string::npos)
      << dry_run(one, true);
  EXPECT_NE(dry_run(ideal, true).find("with ideal speed-up"), std::string::npos);
}

TEST(Plan, MaxRunsStopsABigSweepUnlessConfirmed) {
  const Plan plan = make_plan(config(R"(, "max_runs": 10)"), declared(), std::nullopt);
  try {
    planned_runs(plan, false);
    ADD_FAILURE() << "24 runs passed max_runs = 10";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("the sweep has 24 runs"), std::string::npos) << e.what();
  }
  EXPECT_EQ(planned_runs(plan, true).size(), 12u);
}

TEST(Plan, ResultsFolder) {
  EXPECT_EQ(results_folder(make_plan(config(), declared(), std::nullopt), std::nullopt),
            fs::path("results/st"));
  EXPECT_EQ(results_folder(make_plan(config(), declared(), ShardSpec{2, 3}), std::nullopt),
            fs::path("results/st/shard-2"));
  EXPECT_EQ(results_folder(make_plan(config(), declared(), ShardSpec{2, 3}), "x"), fs::path("x"));
}

TEST(Resume, ReadsTheRowsAndCutsAPartialLine) {
  const fs::path out = folder();
  const auto runs = expand(config(), declared());
  const auto columns = runs_columns(declared());
  std::vector<std::string> row(columns.size());
  auto set = [&](const char* name, const std::string& value) {
    row[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) -
                                 columns.begin())] = value;
  };
  set("status", "ok");
  set("wall_s", "0.5");
  std::string text = csv_line(columns);
  for (const auto& [id, rep] : {std::pair{runs[0].id, 0},
                                {runs[0].id, 1},
                                {runs[3].id, 0},
                                {std::string("0123456789ab"), 0}}) {
    set("config_id", id);
    set("rep", std::to_string(rep));
    text += csv_line(row);
  }
  const std::size_t complete = text.size();
  std::ofstream(out / "runs.csv") << text << runs[4].id << ",br";  // a write cut short
  const Resumed r = resume_or_set_aside(out, true, runs, columns);
  EXPECT_EQ(r.recorded.size(), 4u);
  EXPECT_EQ(r.foreign, 1u);
  EXPECT_TRUE(r.done.count({runs[0].id, 1}));
  EXPECT_TRUE(r.done.count({runs[3].id, 0}));
  EXPECT_FALSE(r.done.count({runs[3].id, 1}));
  EXPECT_EQ(fs::file_size(out / "runs.csv"), complete);

  auto other = columns;
  other.pop_back();
  EXPECT_THROW(resume_or_set_aside(out, true, runs, other), ResultsError);
}

TEST(Resume, WithoutResumeTheEarlierFilesMoveAside) {
  const fs::path out = folder();
  std::ofstream(out / "runs.csv") << "a\n1\n";
  std::ofstream(out / "meta.json") << "{}\n";
  const Resumed r = resume_or_set_aside(out, false, {}, {"a"});
  EXPECT_TRUE(r.recorded.empty());
  EXPECT_FALSE(fs::exists(out / "runs.csv"));
  EXPECT_EQ(slurp(out / "previous" / "runs.csv"), "a\n1\n");
  EXPECT_TRUE(fs::exists(out / "previous" / "meta.json"));
  // --resume of a folder without runs.csv starts afresh the same way
  EXPECT_TRUE(resume_or_set_aside(out, true, {}, {"a"}).recorded.empty());
  // ... and no earlier sweep is overwritten: the next ones go to previous-2, previous-3
  for (const char* text : {"b\n", "c\n"}) {
    std::ofstream(out / "summary.csv") << text;
    set_aside_previous(out);
  }
  EXPECT_EQ(slurp(out / "previous" / "runs.csv"), "a\n1\n");
  EXPECT_EQ(slurp(out / "previous-2" / "summary.csv"), "b\n");
  EXPECT_EQ(slurp(out / "previous-3" / "summary.csv"), "c\n");
  EXPECT_FALSE(holds_results(out));
  set_aside_previous(out);  // nothing to set aside: no empty previous-4
  EXPECT_FALSE(fs::exists(out / "previous-4"));
}

TEST(Folder, OneLockHolderAtATime) {
  const fs::path out = folder() / "new";
  {
    const FolderLock lock(out);  // creates the folder
    try {
      const FolderLock second(out);
      ADD_FAILURE() << "a second lock on one folder";
    } catch (const FolderBusy& e) {
      EXPECT_NE(std::string(e.what()).find(fmt::format("(PID {}, lock", getpid())),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(FolderLock{out});  // released with its holder
}

TEST(Resume, ARunOfOtherConfigurationsIsRefusedNamingTheKey) {
  const Config now = config();
  const Json old_meta = {{"config", now.raw}};
  EXPECT_NO_THROW(check_same_expansion(old_meta, now, declared(), "m.json"));
  Json renamed = now.raw;
  renamed["name"] = "other";  // the same configurations
  EXPECT_NO_THROW(check_same_expansion({{"config", renamed}}, now, declared(), "m.json"));
  Json other = now.raw;
  other["sweep"]["T"][1] = 3;
  try {
    check_same_expansion({{"config", other}}, now, declared(), "m.json");
    ADD_FAILURE() << "another config resumed";
  } catch (const ResultsError& e) {
    EXPECT_NE(std::string(e.what()).find("sweep.T[1]: expands to other configurations"),
              std::string::npos)
        << e.what();
  }
  other = now.raw;
  other["sweep"]["N"].push_back(400);
  EXPECT_THROW(check_same_expansion({{"config", other}}, now, declared(), "m.json"), ResultsError);
}

TEST(Resume, MetaContinuesTheSameShardOnly) {
  const Json fresh = {
      {"date", "d2"},     {"git", {{"commit", "c2"}}},   {"command_line", {"psweep"}},
      {"slurm", nullptr}, {"config", {{"name", "new"}}}, {"shard", {{"index", 1}, {"count", 2}}}};
  EXPECT_EQ(continued_meta(fresh, std::nullopt, "dir"), fresh);
  Json old = fresh;
  old["date"] = "d1";
  old["config"] = {{"name", "old"}};
  const Json meta = continued_meta(fresh, old, "dir");
  EXPECT_EQ(meta["date"], "d1");  // the sweep's start
  ASSERT_EQ(meta["resumed"].size(), 1u);
  EXPECT_EQ(meta["resumed"][0]["date"], "d2");
  EXPECT_EQ(meta["resumed"][0]["note"], "the config changed since the sweep started");
  old["shard"]["index"] = 2;
  try {
    continued_meta(fresh, old, "dir");
    ADD_FAILURE() << "shard 2's folder resumed as shard 1";
  } catch (const ResultsError& e) {
    EXPECT_NE(std::string(e.what()).find("dir holds shard 2/2, not shard 1/2"), std::string::npos)
        << e.what();
  }
  old.erase("shard");
  EXPECT_THROW(continued_meta(fresh, old, "dir"), ResultsError);  // a whole sweep's folder

  const fs::path dir = folder();
  EXPECT_FALSE(earlier_meta((dir / "meta.json").string()));
  std::ofstream(dir / "meta.json") << "{\"date\": ";  // cut short
  EXPECT_FALSE(earlier_meta((dir / "meta.json").string()));
  std::ofstream(dir / "meta.json") << old.dump();
  EXPECT_EQ(earlier_meta((dir / "meta.json").string()), old);
}

namespace {

// A stand-in for psim: each call writes metrics with wall_s = its call number (from 1) and exits
// 0, until call `interrupt_at`, which reports an interrupted child.
struct FakePsim {
  int calls = 0;
  int interrupt_at = 0;
  std::vector<std::string> inputs;
  Launch launch() {
    return [this](const RunSpec& run, const RunFiles& files) {
      const std::string& metrics = files.metrics;
      ChildResult child;
      child.process_s = 0.25;
      inputs.push_back(files.input);
      if (++calls == interrupt_at) {
        child.outcome = Outcome::interrupted;
        std::ofstream(metrics) << "{}";  // a partial file the loop must not keep
        return child;
      }
      std::ofstream(metrics) << fmt::format(
          R"({{"engine": "{}", "wall_s": {}, "state_hash": "00000000000000{:02d}"}})",
          run.params.engine, calls, calls);
      return child;
    };
  }
};

}  // namespace

TEST(RunLoop, RecordsEachRepetitionAsItEndsAndSkipsWarmups) {
  const fs::path out = folder();
  const Config c = config(R"(, "warmup": 1)");
  const auto runs = expand(c, declared());
  const auto jobs = make_schedule(runs.size(), c.repetitions, c.warmup, schedule_seed,
                                  [](std::size_t, int) { return false; });
  const LoopSetup setup{&c, &declared(), &runs, write_inputs(runs, out), out, 8, "", {}, {}, {}};
  EXPECT_EQ(slurp(setup.inputs[0]), random_scene_input(runs[0].params));
  FakePsim psim;
  std::vector<RecordedRun> recorded;
  const LoopTotals totals = run_loop(setup, jobs, psim.launch(), recorded);
  EXPECT_EQ(totals.finished, 36u);  // 12 warm-ups and 24 repetitions
  EXPECT_EQ(totals.not_ok, 0u);
  EXPECT_DOUBLE_EQ(totals.children_s, 36 * 0.25);
  EXPECT_EQ(recorded.size(), 24u);
  const RunsFile file = read_runs((out / "runs.csv").string(), false);
  EXPECT_EQ(file.header, runs_columns(declared()));
  ASSERT_EQ(file.rows.size(), 24u);
  const std::size_t wall = column(file, "wall_s", "runs.csv");
  EXPECT_EQ(file.rows[0][wall], "13");  // the first row is the first job after 12 warm-ups
  for (std::size_t i = 0; i < 36; ++i) EXPECT_EQ(psim.inputs[i], setup.inputs[jobs[i].run]);
  const auto summary = parse_csv(slurp(out / "summary.csv"));
  EXPECT_EQ(summary.size(), 13u);  // header and one row per configuration
  EXPECT_FALSE(fs::exists(out / "tmp"));
}

TEST(RunLoop, AnInterruptedChildStopsTheLoopAndLeavesNoRow) {
  const fs::path out = folder();
  const Config c = config();
  const auto runs = expand(c, declared());
  const auto jobs = make_schedule(runs.size(), c.repetitions, 0, schedule_seed,
                                  [](std::size_t, int) { return false; });
  const LoopSetup setup{&c, &declared(), &runs, write_inputs(runs, out), out, 8, "", {}, {}, {}};
  FakePsim psim;
  psim.interrupt_at = 4;
  std::vector<RecordedRun> recorded;
  const LoopTotals totals = run_loop(setup, jobs, psim.launch(), recorded);
  EXPECT_EQ(psim.calls, 4);
  EXPECT_EQ(totals.finished, 3u);
  EXPECT_EQ(read_runs((out / "runs.csv").string(), false).rows.size(), 3u);
  EXPECT_FALSE(fs::exists(out / "tmp"));  // the interrupted run's metrics file is gone too
}

TEST(Finish, RecordsTheSessionAndTheExitStatus) {
  LoopTotals t;
  t.finished = 5;
  t.children_s = 10;
  t.wall_s = 10.5;
  Json entry = session_entry(t, 0.25, "now");
  EXPECT_EQ(entry["jobs"], 5);
  EXPECT_DOUBLE_EQ(entry["overhead"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(entry["harness_cpu_s"].get<double>(), 0.25);
  EXPECT_EQ(session_entry(LoopTotals{}, 0, "now")["overhead"], 0.0);  // nothing ran

  const fs::path out = folder();
  const std::string meta_json = (out / "meta.json").string();
  Json meta = {{"sessions", Json::array()}};
  EXPECT_EQ(finish_sweep(meta, meta_json, t, 0, "psweep c --out o --resume", out), 0);
  EXPECT_EQ(finish_sweep(meta, meta_json, t, 15, "psweep c --out o --resume", out), 128 + 15);
  EXPECT_EQ(Json::parse(slurp(meta_json))["sessions"].size(), 2u);

  EXPECT_EQ(resume_command("c.json", std::nullopt, "results/c"),
            "psweep c.json --out results/c --resume");
  EXPECT_EQ(resume_command("c.json", ShardSpec{2, 4}, "r/shard-2"),
            "psweep c.json --shard 2/4 --out r/shard-2 --resume");  // the same shard, not the sweep
}
