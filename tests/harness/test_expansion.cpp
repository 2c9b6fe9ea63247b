// Expansion (left-out axes, duplicate collapse, one-at-a-time, zip), schedule and psim command
// lines.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "config/expansion.hpp"
#include "declaration_fixture.hpp"
#include "run/command.hpp"
#include "sweep/schedule.hpp"

using namespace psweep;

namespace {

const Declaration& declared() {
  static const Declaration d = fixture::with_event();
  return d;
}

std::vector<RunSpec> expand_text(const std::string& sweep, const std::string& extra = "",
                                 const std::string& engine = "brute") {
  return expand(
      parse_config(R"({"base": {"engine": ")" + engine +
                       R"(", "N": 1000, "L": 20000, "r": 1, "S": 100, "T": 1, "G": 8}, "sweep": )" +
                       sweep + extra + "}",
                   "c.json"),
      declared());
}

std::string error_of(const std::string& text) {
  try {
    expand(parse_config(text, "c.json"), declared());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Expansion, ProductInOdometerOrder) {
  auto runs = expand_text(R"({"N": [250, 500, 1000], "T": [1, 2]})");
  ASSERT_EQ(runs.size(), 6u);
  EXPECT_EQ(runs[0].params.N, 250);
  EXPECT_EQ(runs[0].params.T, 1);
  EXPECT_EQ(runs[1].params.N, 250);
  EXPECT_EQ(runs[1].params.T, 2);
  EXPECT_EQ(runs[5].params.N, 1000);
  EXPECT_EQ(runs[5].params.T, 2);
}

TEST(Expansion, GridAxisLeftOutForOtherEngines) {
  auto brute = expand_text(R"({"G": [4, 8, 16], "T": [1, 2]})");
  EXPECT_EQ(brute.size(), 2u);
  for (const auto& run : brute) EXPECT_FALSE(run.params.G);
  auto grid = expand_text(R"({"G": [4, 8, 16], "T": [1, 2]})", "", "grid");
  EXPECT_EQ(grid.size(), 6u);
  for (const auto& run : grid) EXPECT_TRUE(run.params.G);
}

TEST(Expansion, EventIgnoresThreadsGridAndSlowFactor) {
  auto runs = expand_text(R"({"T": [1, 2, 4], "slow_factor": [1, 2], "G": [2, 4], "N": [10, 20]})",
                          "", "event");
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_FALSE(runs[0].params.T);
  EXPECT_FALSE(runs[0].params.slow_factor);
  EXPECT_FALSE(runs[0].params.G);
}

TEST(Expansion, MixedEnginesCountOnlyWhatEachUses) {
  auto runs = expand_text(R"({"engine": ["brute", "grid", "event"], "T": [1, 2], "G": [4, 8]})");
  std::map<std::string, int> per_engine;
  for (const auto& run : runs) ++per_engine[run.params.engine];
  EXPECT_EQ(per_engine["brute"], 2);
  EXPECT_EQ(per_engine["grid"], 4);
  EXPECT_EQ(per_engine["event"], 1);
  EXPECT_EQ(runs.size(), 7u);
}

TEST(Expansion, DuplicatesCollapseKeepingFirst) {
  auto runs = expand_text(R"({"N": [100, 200, 100], "T": [2, 2]})");
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].params.N, 100);
  EXPECT_EQ(runs[1].params.N, 200);
}

TEST(Expansion, OneAtATimeVariesEachAxisAroundBase) {
  auto runs = expand_text(R"({"N": [500, 1000], "T": [1, 2], "S": [50]})",
                          R"(, "combine": "one-at-a-time")");
  // N=500; N=1000 (= base); T=1 (= base, collapses); T=2; S=50
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0].params.N, 500);
  EXPECT_EQ(runs[0].params.T, 1);
  EXPECT_EQ(runs[1].params.N, 1000);
  EXPECT_EQ(runs[2].params.T, 2);
  EXPECT_EQ(runs[2].params.N, 1000);
  EXPECT_EQ(runs[3].params.S, 50);
  EXPECT_EQ(runs[3].params.T, 1);
}

TEST(Expansion, ZipPairsAxesElementByElement) {
  // Weak scaling: N grows with T, engine and L zipped along.
  auto runs = expand_text(
      R"({"engine": ["brute", "brute", "cells", "cells"], "N": [1000, 1414, 4000, 8000],)"
      R"( "L": [20000, 20000, 20000, 28284], "T": [1, 2, 1, 2]})",
      R"(, "combine": "zip")");
  ASSERT_EQ(runs.size(), 4u);  // not the 4 x 4 x 2 x 2 of a product
  EXPECT_EQ(runs[0].params.engine, "brute");
  EXPECT_EQ(runs[0].params.N, 1000);
  EXPECT_EQ(runs[0].params.T, 1);
  EXPECT_EQ(runs[1].params.N, 1414);
  EXPECT_EQ(runs[1].params.T, 2);
  EXPECT_EQ(runs[3].params.engine, "cells");
  EXPECT_EQ(runs[3].params.N, 8000);
  EXPECT_EQ(runs[3].params.L, 28284);
  EXPECT_EQ(runs[3].params.T, 2);
}

TEST(Expansion, ZipRejectsAxesOfUnequalLength) {
  EXPECT_EQ(
      error_of(
          R"({"base": {"engine": "brute", "N": 1, "L": 10, "r": 1, "S": 1}, "sweep": {"N": [1, 2, 4], "T": [1, 2]}, "combine": "zip"})"),
      "c.json: sweep.T: 2 values, but sweep.N has 3 (combine \"zip\" pairs the axes element by "
      "element, so all must have the same length)");
}

TEST(Expansion, NoSweepIsJustBase) {
  auto runs = expand(
      parse_config(R"({"base": {"engine": "brute", "N": 5, "L": 100, "r": 1, "S": 2}})", "c.json"),
      declared());
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].params.N, 5);
}

TEST(Expansion, ConfigIdIsStableAndDistinguishes) {
  auto a = expand_text(R"({"T": [1, 2]})");
  auto b = expand_text(R"({"T": [2, 1], "N": [1000]})");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].id, b[1].id);  // same parameters, same id, whatever the file order
  EXPECT_EQ(a[1].id, b[0].id);
  EXPECT_NE(a[0].id, a[1].id);
  EXPECT_EQ(a[0].id.size(), 12u);
  EXPECT_EQ(a[0].id.find_first_not_of("0123456789abcdef"), std::string::npos);
  auto pinned = expand_text(R"({"T": [1, 2]})", R"(, "pin": "close")");
  EXPECT_NE(pinned[0].id, a[0].id);  // the pin policy is part of the configuration
  auto noisy = expand_text(R"({"T": [1], "neighbour": ["none", "busy"]})");
  ASSERT_EQ(noisy.size(), 2u);
  EXPECT_EQ(noisy[0].id, a[0].id);  // a quiet run keeps the id it had before the axis existed
  EXPECT_NE(noisy[1].id, a[0].id);
}

TEST(Expansion, CrossParameterErrors) {
  EXPECT_EQ(error_of(R"({"base": {"engine": "grid", "N": 5, "L": 100, "r": 1, "S": 2}})"),
            "c.json: base.G: required when engine \"grid\" runs (or sweep G)");
  EXPECT_EQ(
      error_of(
          R"({"base": {"engine": "brute", "N": 5, "L": 100, "r": 1, "S": 2, "speed_min": 1}})"),
      "c.json: base.speed_max: required together with speed_min");
  EXPECT_NE(
      error_of(
          R"({"base": {"engine": "brute", "N": 5, "L": 100, "r": 1, "S": 2, "speed_min": 3, "speed_max": 1}})")
          .find("speed_min: 3 exceeds speed_max 1"),
      std::string::npos);
  EXPECT_NE(error_of(R"({"base": {"engine": "brute", "N": 5, "L": 1, "r": 1, "S": 2}})")
                .find("c.json: L: 1 is less than 2r"),
            std::string::npos);
}

// psim's own limits (particle::run_limit_breach), checked for every configuration at expansion,
// at the key path that set the offending value.
TEST(Expansion, RunsPsimWouldRefuseNameTheKeyPath) {
  auto base = [](const std::string& extra) {
    return R"({"base": {"engine": "brute", "N": 100, "L": 1000, "r": 1, "S": 10)" + extra + "}";
  };
  EXPECT_EQ(error_of(base("}, \"sweep\": {\"N\": [5, 100000001]}")),
            "c.json: sweep.N[1]: must be between 1 and 100000000, got 100000001 (psim's limit)");
  EXPECT_EQ(error_of(R"({"base": {"engine": "grid", "N": 100, "L": 1000, "r": 1, "S": 10, "G": 100000}})"),
            "c.json: base.G: G must be between 1 and 4096, got 100000 (psim's limit)");
  EXPECT_EQ(
      error_of(base(R"(, "slow_factor": 1073741824})")).rfind("c.json: base.slow_factor: ", 0), 0u);
  EXPECT_NE(error_of(base(R"(}, "sweep": {"T": [1, 5000]})")).find("c.json: sweep.T[1]: must be"),
            std::string::npos);
  // zip and one-at-a-time name the index too
  EXPECT_EQ(error_of(base(R"(}, "sweep": {"T": [1, 2], "N": [5, 200000000]}, "combine": "zip")"))
                .rfind("c.json: sweep.N[1]: must be between 1 and 100000000", 0),
            0u);
  EXPECT_EQ(
      error_of(base(R"(}, "sweep": {"T": [1], "N": [5, 200000000]}, "combine": "one-at-a-time")"))
          .rfind("c.json: sweep.N[1]: must be between 1 and 100000000", 0),
      0u);
  // 2000 disks of radius 1 in a box of 40: at most 455 fit (Oler's packing bound)
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute", "N": 2000, "L": 40, "r": 1, "S": 1}})")
                .rfind("c.json: base.N: scene too dense for random placement", 0),
            0u);
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute", "N": 2, "L": 1e300, "r": 1e-300, "S": 1}})")
                .rfind("c.json: base.r: the box is L/(2r) = ", 0),
            0u);
  // psim's own placement from the seed: 249 disks of radius 1 fit in a box of 40 from seed 3210,
  // the 250th does not (a psim test runs both); Oler's bound alone would allow 455
  const auto dense = [](int n) {
    return fmt::format(R"({{"base": {{"engine": "brute", "N": {}, "L": 40, "r": 1, "S": 1}}}})", n);
  };
  EXPECT_EQ(error_of(dense(249)), "(no error)");
  EXPECT_EQ(error_of(dense(250)),
            "c.json: base.N: scene too dense for random placement: placed 249 of 250 particles of "
            "radius 1 in a box of 40 (give fewer or smaller particles, or a larger box) (psim's "
            "limit)");
  // a speed range no draw can hold, at its key
  EXPECT_EQ(error_of(base(R"(, "speed_min": 1e300, "speed_max": 1e300})"))
                .rfind("c.json: base.speed_max: the particles can reach a speed of 1e+301 per time "
                       "unit",
                       0),
            0u);
  // one the range leaves open (speeds from 0): decided by drawing the scene as psim would
  EXPECT_EQ(
      error_of(base(R"(, "speed_min": 0, "speed_max": 1}, "sweep": {"speed_max": [1, 1e300]})"))
          .rfind("c.json: sweep.speed_max[1]: the particles can reach", 0),
      0u);
  // the event engine's limit on box crossings (2 disks at 1e15 or more cross a box of 998 at
  // least 1.4e12 times, beyond 2^40), for its runs only
  const auto fast = [](const char* engines) {
    return fmt::format(R"({{"base": {{"engine": "brute", "N": 2, "L": 1000, "r": 1, "S": 1,
        "speed_min": 1e15, "speed_max": 1.2e15}}, "sweep": {{"engine": {}}}}})",
                       engines);
  };
  EXPECT_EQ(error_of(fast(R"(["brute", "event"])"))
                .rfind("c.json: base.speed_max: with the event engine the fastest particle could "
                       "cross the box 1.4e+12 times",
                       0),
            0u);
  EXPECT_EQ(error_of(fast(R"(["brute", "auto"])")), "(no error)");
  // the default speeds L/(8r) to L/4 at L = 1e-200, r = 1e-201 (7.5e200 contact distances per
  // sub-step), at r's key
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute", "N": 2, "L": 1e-200, "r": 1e-201, "S": 1}})")
                .rfind("c.json: base.r: with the default speeds L/(8r) to L/4, the particles", 0),
            0u);
}

// A scene file's particles meet psim's limits before anything runs: the speed per sub-step at the
// slow factor's key (a larger K lifts it), the event engine's box crossings at scene_file's.
// (The config is re-read for each case: the file is read when the config is parsed.)
TEST(Expansion, SceneFileSpeedsCheckedAgainstPsimsLimits) {
  const std::string path = ::testing::TempDir() + "psweep_fast.in";
  // sqrt(2) 1e153 per time unit, s = 2: 7.1e152 contact distances per time unit, the limit
  // 2^506 = 2.1e152 per sub-step: K = 4 holds it, K = 2 does not
  { std::ofstream(path) << "2\n1000\n1\n20\nperf\n0 100 500 1e153 0\n1 300 500 -1e153 0\n"; }
  const auto config = [&](const std::string& base, const std::string& sweep) {
    return R"({"scene_file": ")" + path + R"(", "base": {"engine": "brute")" + base +
           R"(}, "sweep": {)" + sweep + "}}";
  };
  EXPECT_EQ(error_of(config("", R"("slow_factor": [4, 2])"))
                .rfind("c.json: sweep.slow_factor[1]: the particles can reach a speed of 1.4e+153 "
                       "per time unit",
                       0),
            0u);
  EXPECT_EQ(error_of(config(R"(, "slow_factor": 4)", R"("engine": ["brute", "auto"])")),
            "(no error)");
  // 1e150: within the limits at K = 1, but 2.8e148 crossings of the box for the event engine
  { std::ofstream(path) << "2\n1000\n1\n20\nperf\n0 100 500 1e150 0\n1 300 500 -1e150 1e149\n"; }
  EXPECT_EQ(error_of(config("", R"("engine": ["brute", "event"])")),
            "c.json: scene_file: with the event engine the fastest particle could cross the box "
            "2.8e+148 times in S time units (speed bound sqrt(sum v^2) x S / (L - 2r)), beyond the "
            "limit 2^40 (about 1.1e12) events it can count; use a discrete engine (psim's limit)");
  EXPECT_EQ(error_of(config("", R"("engine": ["brute", "auto"])")), "(no error)");
  std::remove(path.c_str());
}

TEST(Schedule, EveryRepetitionOnceWarmupsFirstRoundsInterleaved) {
  const std::size_t runs = 7;
  const int reps = 4;
  auto jobs = make_schedule(runs, reps, 2, schedule_seed, [](std::size_t, int) { return false; });
  ASSERT_EQ(jobs.size(), runs * (reps + 2));
  for (std::size_t i = 0; i < 2 * runs; ++i) EXPECT_TRUE(jobs[i].warmup);
  std::set<std::pair<std::size_t, int>> seen;
  for (std::size_t i = 2 * runs; i < jobs.size(); ++i) {
    EXPECT_FALSE(jobs[i].warmup);
    EXPECT_EQ(jobs[i].rep, static_cast<int>((i - 2 * runs) / runs));  // round k = repetition k
    EXPECT_TRUE(seen.insert({jobs[i].run, jobs[i].rep}).second);
  }
  EXPECT_EQ(seen.size(), runs * reps);
  // rounds are shuffled (not all in index order, and not all the same order)
  std::vector<std::size_t> r0, r1;
  for (std::size_t i = 0; i < runs; ++i) {
    r0.push_back(jobs[2 * runs + i].run);
    r1.push_back(jobs[3 * runs + i].run);
  }
  EXPECT_FALSE(std::is_sorted(r0.begin(), r0.end()) && std::is_sorted(r1.begin(), r1.end()));
  EXPECT_NE(r0, r1);
  // deterministic
  auto again = make_schedule(runs, reps, 2, schedule_seed, [](std::size_t, int) { return false; });
  for (std::size_t i = 0; i < jobs.size(); ++i) EXPECT_EQ(jobs[i].run, again[i].run);
}

TEST(Schedule, ResumeSkipsDoneAndKeepsOrder) {
  auto all = make_schedule(5, 3, 1, schedule_seed, [](std::size_t, int) { return false; });
  // run 2 is complete; run 0 has rep 0 done
  auto done = [](std::size_t run, int rep) { return run == 2 || (run == 0 && rep == 0); };
  auto rest = make_schedule(5, 3, 1, schedule_seed, done);
  std::vector<Job> expected;
  for (const auto& j : all)
    if (j.warmup ? j.run != 2 : !done(j.run, j.rep)) expected.push_back(j);
  ASSERT_EQ(rest.size(), expected.size());
  for (std::size_t i = 0; i < rest.size(); ++i) {
    EXPECT_EQ(rest[i].run, expected[i].run);
    EXPECT_EQ(rest[i].rep, expected[i].rep);
    EXPECT_EQ(rest[i].warmup, expected[i].warmup);
  }
}

TEST(Command, ArgumentsFollowTheEngine) {
  auto runs = expand_text(R"({"engine": ["brute", "grid", "event"]})");
  ASSERT_EQ(runs.size(), 3u);
  auto brute = psim_arguments(runs[0], "/b/psim", "in.txt", "m.json");
  EXPECT_EQ(brute, (std::vector<std::string>{"/b/psim", "--engine", "brute", "--threads", "1",
                                             "--slow-factor", "1", "--seed", "3210", "--metrics",
                                             "m.json", "in.txt"}));
  auto grid = psim_arguments(runs[1], "psim", "in", "m");
  EXPECT_NE(std::find(grid.begin(), grid.end(), "--grid"), grid.end());
  auto event = psim_arguments(runs[2], "psim", "in", "m");
  EXPECT_EQ(std::find(event.begin(), event.end(), "--threads"), event.end());
  EXPECT_EQ(std::find(event.begin(), event.end(), "--slow-factor"), event.end());
  EXPECT_EQ(random_scene_input(runs[0].params), "1000\n20000\n1\n100\nperf\n");
  auto speeds = expand(
      parse_config(
          R"({"base": {"engine": "brute", "N": 5, "L": 100, "r": 1, "S": 2, "speed_min": 0.5, "speed_max": 2}})",
          "c.json"),
      declared());
  auto args = psim_arguments(speeds[0], "psim", "in", "m");
  EXPECT_NE(std::find(args.begin(), args.end(), "0.5,2"), args.end());
}

TEST(Command, EnvironmentPinsThreads) {
  const std::vector<std::string> parent = {"PATH=/bin", "OMP_NUM_THREADS=64", "OMP_PLACES=threads",
                                           "HOME=/root"};
  auto has = [](const std::vector<std::string>& env, const std::string& var) {
    return std::find(env.begin(), env.end(), var) != env.end();
  };
  auto count_omp = [](const std::vector<std::string>& env) {
    return std::count_if(env.begin(), env.end(),
                         [](const std::string& v) { return v.rfind("OMP_", 0) == 0; });
  };
  auto close = expand_text(R"({"T": [2]})", R"(, "pin": "close")");
  auto env = child_environment(close[0], parent);
  EXPECT_TRUE(has(env, "PATH=/bin"));
  EXPECT_TRUE(has(env, "OMP_NUM_THREADS=2"));
  EXPECT_TRUE(has(env, "OMP_PROC_BIND=close"));
  EXPECT_TRUE(has(env, "OMP_PLACES=cores"));
  EXPECT_EQ(count_omp(env), 3);
  auto spread = child_environment(expand_text(R"({"T": [3]})", R"(, "pin": "spread")")[0], parent);
  EXPECT_TRUE(has(spread, "OMP_PROC_BIND=spread"));
  EXPECT_TRUE(has(spread, "OMP_NUM_THREADS=3"));
  auto none = child_environment(expand_text(R"({"T": [3]})", R"(, "pin": "none")")[0], parent);
  EXPECT_TRUE(has(none, "OMP_PROC_BIND=false"));
  EXPECT_EQ(count_omp(none), 2);  // no OMP_PLACES
  auto event = child_environment(expand_text(R"({"T": [3]})", "", "event")[0], parent);
  EXPECT_EQ(count_omp(event), 0);
}

// Expansion follows the declaration, not engine names: an engine declared to use G needs G and
// keeps the G axis; the same name declared without G loses it.
TEST(Expansion, FollowsTheDeclarationNotNames) {
  Json json = Json::parse(particle::describe_json());
  json["engines"].push_back({{"name", "custom"}, {"uses", {"G"}}});
  const Declaration d = parse_declaration(json.dump());
  auto runs = expand(parse_config(R"({"base": {"engine": "custom", "N": 10, "L": 100, "r": 1,
      "S": 2, "G": 2}, "sweep": {"G": [2, 4], "T": [1, 2], "slow_factor": [1, 2]}})",
                                  "c.json"),
                     d);
  ASSERT_EQ(runs.size(), 2u);  // T and slow_factor ignored, G kept
  EXPECT_FALSE(runs[0].params.T);
  EXPECT_EQ(*runs[1].params.G, 4);
  // unknown to the declaration (a dry run without psim): nothing left out
  EXPECT_EQ(expand(parse_config(R"({"base": {"engine": "custom", "N": 10, "L": 100, "r": 1,
      "S": 2}, "sweep": {"T": [1, 2]}})",
                                "c.json"),
                   Declaration{})
                .size(),
            2u);
}

namespace {

// The definition the lazy walk must match: every combination in odometer order, ignored
// parameters cleared, each distinct configuration kept at its first occurrence.
std::vector<std::string> reference_product(const Config& c) {
  std::vector<std::string> texts;
  std::set<std::string> seen;
  std::vector<std::size_t> digit(c.sweep.size(), 0);
  for (;;) {
    Params p = c.base;
    for (std::size_t a = 0; a < c.sweep.size(); ++a)
      set_param(p, c.sweep[a].key, c.sweep[a].values[digit[a]], c.sweep[a].key);
    drop_ignored(p, declared(), c);
    auto text = canonical_text(p, "", c.pin);
    if (seen.insert(text).second) texts.push_back(text);
    std::size_t a = c.sweep.size();
    while (a > 0 && ++digit[a - 1] == c.sweep[a - 1].values.size()) digit[--a] = 0;
    if (a == 0) break;
  }
  return texts;
}

long max_rss_kb() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

}  // namespace

TEST(Expansion, LazyProductMatchesTheSetOfFirstOccurrences) {
  // Duplicate values (N 100 twice, engine brute twice), axes some engines ignore (G, T for event),
  // and the engine axis in the middle.
  const Config c = parse_config(
      R"({"base": {"engine": "brute", "N": 1000, "L": 20000, "r": 1, "S": 100, "T": 1, "G": 8},
          "sweep": {"N": [100, 200, 100], "engine": ["grid", "brute", "event", "brute"],
                    "G": [4, 8, 4, 16], "T": [1, 2, 1], "slow_factor": [1, 2]}})",
      "c.json");
  std::vector<std::string> lazy;
  for (const auto& run : expand(c, declared()))
    lazy.push_back(canonical_text(run.params, "", c.pin));
  EXPECT_EQ(lazy, reference_product(c));
  EXPECT_EQ(lazy.size(), 2u * (3 * 2 * 2 + 2 * 2 + 1));  // N x (grid: G T K; brute: T K; event)
}

// The count without the walk: equal to the walk's on products with duplicates, ignored axes and
// the engine axis anywhere, on zip and one-at-a-time, and at once on a product of 10^12.
TEST(Expansion, CountWithoutTheWalkEqualsTheWalk) {
  const std::string base =
      R"("base": {"engine": "brute", "N": 1000, "L": 20000, "r": 1, "S": 100, "T": 1, "G": 8})";
  for (const std::string sweep :
       {R"("sweep": {"N": [100, 200, 100], "engine": ["grid", "brute", "event", "brute"],
                     "G": [4, 8, 4, 16], "T": [1, 2, 1], "slow_factor": [1, 2]})",
        R"("sweep": {"engine": ["event", "grid"], "T": [1, 2, 3], "G": [4, 4, 8]})",
        R"("sweep": {"T": [2, 2], "N": [100, 200]})", R"("sweep": {})",
        R"("sweep": {"N": [100, 200], "T": [1, 2]}, "combine": "zip")",
        R"("sweep": {"N": [100, 200, 1000], "T": [1, 2]}, "combine": "one-at-a-time")"}) {
    const Config c = parse_config("{" + base + ", " + sweep + "}", "c.json");
    std::size_t walked = 0;
    for_each_configuration(c, declared(), [&](const Params&) { ++walked; });
    EXPECT_EQ(count_configurations(c, declared()), walked) << sweep;
  }
  std::string axis = "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]";
  std::string seeds = "[";
  for (int i = 1; i <= 10000; ++i) seeds += std::to_string(i) + (i < 10000 ? ", " : "]");
  const Config huge = parse_config(
      "{" + base + R"(, "sweep": {"engine": ["brute", "event"], "seed": )" + seeds + R"(, "T": )" +
          axis + R"(, "N": )" + axis + R"(, "S": )" + axis +
          R"(, "slow_factor": [1, 2, 4, 8, 16, 32, 64, 128, 256, 512], "r": )" + axis + "}}",
      "c.json");
  // brute: 10^4 seeds x 10^5 (T, N, S, K, r); event ignores T and K: 10^4 x 10^3
  EXPECT_EQ(count_configurations(huge, declared()), 1'000'000'000u + 10'000'000u);
}

TEST(Expansion, KeepSelectsByPositionInTheSequence) {
  const Config c = parse_config(
      R"({"base": {"engine": "brute", "N": 10, "L": 200, "r": 1, "S": 10},
          "sweep": {"N": [10, 20, 30, 40], "T": [1, 2]}})",
      "c.json");
  const auto all = expand(c, declared());
  const auto odd = expand(c, declared(), [](std::size_t i) { return i % 2 == 1; });
  ASSERT_EQ(odd.size(), 4u);
  for (std::size_t i = 0; i < odd.size(); ++i) EXPECT_EQ(odd[i].id, all[2 * i + 1].id);
}

TEST(Expansion, TenMillionConfigurationsCountedInConstantMemory) {
  // 10 x 10 x 10 x 10 x 10 x 10 x 10 = 10^7 distinct configurations.
  std::string axis = "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]";
  const Config c = parse_config(
      R"({"base": {"engine": "brute", "N": 10, "L": 2000, "r": 1, "S": 10},
          "sweep": {"N": )" +
          axis + R"(, "S": )" + axis + R"(, "T": )" + axis +
          R"(, "slow_factor": [1, 2, 4, 8, 16, 32, 64, 128, 256, 512], "seed": )" + axis +
          R"(, "L": [100, 200, 300, 400, 500, 600, 700, 800, 900, 1000], "r": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]}})",
      "big.json");
  const long before = max_rss_kb();
  std::size_t count = 0;
  std::int64_t n_sum = 0;
  for_each_configuration(c, declared(), [&](const Params& p) {
    ++count;
    n_sum += p.N;
  });
  EXPECT_EQ(count, 10'000'000u);
  EXPECT_EQ(n_sum, 55 * 1'000'000);
  // Holding the sequence would take gigabytes; the walk holds one combination.
  EXPECT_LT(max_rss_kb() - before, 16 * 1024);
}
