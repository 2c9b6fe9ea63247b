// Shards: the --shard argument, the cost model and the partition (deterministic, complete,
// disjoint, balanced on a skewed sweep).
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "config/expansion.hpp"
#include "config/shard.hpp"
#include "declaration_fixture.hpp"

using namespace psweep;

namespace {

using fixture::declared;

std::string shard_error(const std::string& text) {
  try {
    parse_shard(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::vector<double> loads(const std::vector<double>& costs, const std::vector<int>& shard_of,
                          int shards) {
  std::vector<double> load(static_cast<std::size_t>(shards), 0.0);
  for (std::size_t i = 0; i < costs.size(); ++i)
    load[static_cast<std::size_t>(shard_of[i])] += costs[i];
  return load;
}

// The 2019 report's kind of sweep, skewed on purpose: brute's N^2 next to the O(N) engines, sizes
// over a factor 16, thread counts over a factor 8.
Config skewed_config() {
  return parse_config(
      R"({"base": {"engine": "brute", "N": 1000, "L": 20000, "r": 1, "S": 100, "T": 1},
          "sweep": {"engine": ["brute", "auto", "sweep"], "N": [250, 500, 1000, 2000, 4000],
                    "T": [1, 2, 4, 8], "seed": [1, 2, 3]},
          "repetitions": 5, "warmup": 1})",
      "skewed.json");
}

}  // namespace

TEST(Shard, ParsesIOfN) {
  auto s = parse_shard("2/8");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 8);
  EXPECT_EQ(to_string(s), "2/8");
  EXPECT_EQ(parse_shard("1/1").count, 1);
}

TEST(Shard, RejectsBadArguments) {
  EXPECT_NE(shard_error("0/4").find("I must be between 1 and N"), std::string::npos);
  EXPECT_NE(shard_error("5/4").find("I must be between 1 and N"), std::string::npos);
  EXPECT_NE(shard_error("1/0").find("N must be at least 1"), std::string::npos);
  EXPECT_NE(shard_error("3").find("no '/'"), std::string::npos);
  EXPECT_NE(shard_error("a/4").find("not two integers"), std::string::npos);
  EXPECT_NE(shard_error("1/4x").find("not two integers"), std::string::npos);
  EXPECT_NE(shard_error("/4").find("--shard /4"), std::string::npos);
}

// The facts of an engine whose work grows as N^growth at cost_ns (0: the model's default).
EngineFacts facts(int growth, double cost_ns = 0) {
  EngineFacts f;
  f.growth = growth;
  f.cost_ns = cost_ns;
  return f;
}

TEST(Shard, CostModelScalesByTheDeclaredGrowthAndCost) {
  Params p;
  p.engine = "brute";
  p.N = 1000;
  p.S = 100;
  p.T = 1;
  p.slow_factor = 1;
  const CostModel m{1.0, 1.0, 0.0};
  const EngineFacts pairs = facts(2), particles = facts(1);
  EXPECT_DOUBLE_EQ(estimate_run_s(p, pairs, m), 1e6 * 100);
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, m), 1e3 * 100);
  // A declared cost_ns replaces the default of its growth.
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts(2, 2e9), m), 2 * 1e6 * 100);
  p.slow_factor = 4;
  p.T = 8;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, m), 1e3 * 100 * 4 / 8);
  p.slow_factor.reset();  // an engine that ignores K and T counts them as 1
  p.T.reset();
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, m), 1e3 * 100);
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, CostModel{1.0, 1.0, 0.5}), 1e3 * 100 + 0.5);
}

// A program is costed as the plain C reference, not as brute: brute's figure was 9x too low for
// a straightforward one.
TEST(Shard, AProgramIsCostedAsAStraightforwardOne) {
  Params p;
  p.N = 1000;
  p.S = 1000;
  p.T = 1;
  EngineFacts program = facts(2);
  program.program = true;
  const CostModel m;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, program, m), m.process_s + 1.2e-9 * 1e6 * 1000);
  EXPECT_DOUBLE_EQ(estimate_run_s(p, facts(2), m), m.process_s + 0.35e-9 * 1e6 * 1000);
}

// Threads beyond the machine's CPUs take turns: on 2 CPUs, T = 8 costs what T = 2 does.
TEST(Shard, ThreadsBeyondTheCpusDoNotSpeedUp) {
  Params p;
  p.N = 1000;
  p.S = 100;
  p.T = 8;
  const EngineFacts particles = facts(1);
  const CostModel ideal{.pair_step_s = 1, .particle_step_s = 1, .process_s = 0};
  CostModel two = ideal;
  two.cpus = 2;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, two), 1e3 * 100 / 2);
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, ideal), 1e3 * 100 / 8);
  p.T = 1;
  EXPECT_DOUBLE_EQ(estimate_run_s(p, particles, two), 1e3 * 100);
}

// The growth and the cost come from psim's declaration, not from engine names: the engine library
// declares brute N^2 and the others N, each with its cost, and a declaration saying otherwise
// changes the estimate.
TEST(Shard, GrowthAndCostAreTheDeclarationsNotAName) {
  const Config c = parse_config(
      R"({"base": {"engine": "brute", "N": 1000, "L": 20000, "r": 1, "S": 100, "T": 1},
          "repetitions": 3, "warmup": 1})",
      "c.json");
  Params brute = c.base, sweep = c.base;
  sweep.engine = "sweep";
  const EngineFacts& brute_facts = *declared().engine("brute");
  const EngineFacts& sweep_facts = *declared().engine("sweep");
  EXPECT_DOUBLE_EQ(configuration_s(c, declared(), brute), 4 * estimate_run_s(brute, brute_facts));
  EXPECT_DOUBLE_EQ(configuration_s(c, declared(), sweep), 4 * estimate_run_s(sweep, sweep_facts));
  Json json = Json::parse(particle::describe_json());
  for (auto& e : json["engines"]) {
    const bool is_brute = e["name"] == "brute";
    e["growth"] = is_brute ? "N" : "N^2";
    e["cost_ns"] = is_brute ? 7.0 : 0.5;
  }
  const Declaration swapped = parse_declaration(json.dump());
  EXPECT_DOUBLE_EQ(configuration_s(c, swapped, brute), 4 * estimate_run_s(brute, facts(1, 7)));
  EXPECT_DOUBLE_EQ(configuration_s(c, swapped, sweep), 4 * estimate_run_s(sweep, facts(2, 0.5)));
  // An engine psim does not declare (a dry run without psim) counts as N at the default.
  EXPECT_DOUBLE_EQ(configuration_s(c, Declaration{}, brute), 4 * estimate_run_s(brute, {}));
}

// A program (not psim's engine: no declared cost) costs its confinement on top of every run, and
// grows as its `growth` says: N^2 unless it says N, costed as the plain C reference. On a
// perf-mode scene it also has its judging run: 3 repetitions + 1 warm-up + 1 judging run.
TEST(Shard, AProgramAddsItsConfinementToEveryRun) {
  const auto config = [](const std::string& growth) {
    return parse_config(
        R"({"base": {"engine": "mine", "N": 10, "L": 100, "r": 1, "S": 3, "T": 1},
            "programs": {"mine": {"command": ["./x"])" +
            growth + R"(}}, "repetitions": 3, "warmup": 1})",
        "p.json");
  };
  const CostModel m;
  const Config pairs = config(""), linear = config(R"(, "growth": "N")");
  EngineFacts program = facts(2, 0);
  program.program = true;
  EXPECT_DOUBLE_EQ(configuration_s(pairs, declared(), pairs.base, m),
                   5 * (m.program_s + estimate_run_s(pairs.base, program, m)));
  EXPECT_DOUBLE_EQ(configuration_s(linear, declared(), linear.base, m),
                   5 * (m.program_s + estimate_run_s(linear.base, facts(1, 0), m)));
}

TEST(Shard, TheDeclarationRejectsAnUnknownGrowthAndANegativeCost) {
  auto error = [](const char* key, const Json& value) {
    Json json = Json::parse(particle::describe_json());
    json["engines"][0][key] = value;
    try {
      parse_declaration(json.dump());
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error("growth", "N^3").find("growth: unknown growth \"N^3\""), std::string::npos);
  EXPECT_NE(error("cost_ns", -1).find("cost_ns: expected a number of nanoseconds >= 0, got -1"),
            std::string::npos);
  EXPECT_NE(error("cost_ns", "fast").find("cost_ns: expected a number"), std::string::npos);
}

// The declared costs against what ran (issue 31: the estimate once ranked auto slower than brute):
// configs/quick.json on the 2-core VM took brute 3-4x auto's time in all, auto cheaper at every
// N. One figure per particle cannot follow auto's cost per particle over N (see engines.cpp), so
// at N = 250, where both take little more than the process's start, the estimate ranks brute
// first; from N = 500, where the time is, it must rank auto first.
TEST(Shard, DeclaredCostsRankAutoBelowBruteOnTheQuickSweep) {
  const Config quick = parse_config(
      R"({"base": {"engine": "brute", "N": 1000, "L": 20000, "r": 1, "S": 3000, "T": 1},
          "sweep": {"engine": ["brute", "auto"], "N": [250, 500, 1000, 2000], "T": [1, 2]},
          "repetitions": 5, "warmup": 1})",
      "quick.json");
  const CostModel two_cpus{.cpus = 2};
  double brute_total = 0, auto_total = 0;
  for (std::int64_t n : {500, 1000, 2000}) {
    Params brute = quick.base, automatic = quick.base;
    brute.N = automatic.N = n;
    automatic.engine = "auto";
    const double b = configuration_s(quick, declared(), brute, two_cpus);
    const double a = configuration_s(quick, declared(), automatic, two_cpus);
    EXPECT_LT(a, b) << "N = " << n;
    brute_total += b;
    auto_total += a;
  }
  EXPECT_GT(brute_total, 2 * auto_total);
  EXPECT_LT(brute_total, 6 * auto_total);
}

TEST(Shard, PartitionIsDeterministicCompleteAndDisjoint) {
  const Config config = skewed_config();
  const auto runs = expand(config, declared());
  const auto a = assign_shards(config, declared(), 7);
  const auto b = assign_shards(config, declared(), 7);
  EXPECT_EQ(a, b);
  // One shard per configuration (so disjoint, all repetitions together), every shard used.
  ASSERT_EQ(a.size(), runs.size());
  std::vector<int> per_shard(7, 0);
  for (int s : a) {
    ASSERT_GE(s, 0);
    ASSERT_LT(s, 7);
    ++per_shard[static_cast<std::size_t>(s)];
  }
  EXPECT_EQ(std::accumulate(per_shard.begin(), per_shard.end(), 0), static_cast<int>(runs.size()));
  for (int n : per_shard) EXPECT_GT(n, 0);
}

TEST(Shard, PartitionBalancesASkewedSweepWithinTenPercent) {
  const Config config = skewed_config();
  const auto runs = expand(config, declared());
  std::vector<double> costs;
  for (const auto& run : runs) costs.push_back(configuration_s(config, declared(), run.params));
  const double largest = *std::max_element(costs.begin(), costs.end());
  const double total = std::accumulate(costs.begin(), costs.end(), 0.0);
  for (int shards : {2, 3, 4, 8, 16}) {
    const auto load = loads(costs, assign_shards(config, declared(), shards), shards);
    const double mean = total / shards;
    const double most = *std::max_element(load.begin(), load.end());
    // Where no configuration is larger than a tenth of a shard's share, within 10% of the mean.
    if (largest < mean / 10) {
      EXPECT_LE(most, 1.10 * mean) << shards << " shards";
    }
    EXPECT_LE(most, mean + largest) << shards << " shards";  // Graham's bound, always
  }
}

TEST(Shard, LargestFirstBeatsOrderOfAppearance) {
  // An odometer order puts the largest N last. Greedy in order of appearance ends at 8 and 4 on
  // these two shards; largest first ends at 6 and 6.
  const std::vector<double> costs = {1, 1, 1, 1, 2, 2, 4};
  const auto load = loads(costs, partition(costs, 2), 2);
  EXPECT_DOUBLE_EQ(load[0], 6);
  EXPECT_DOUBLE_EQ(load[1], 6);
}

TEST(Shard, MoreShardsThanConfigurationsLeavesSomeEmpty) {
  const auto shard_of = partition({3, 2, 1}, 5);
  EXPECT_EQ(shard_of, (std::vector<int>{0, 1, 2}));
}
