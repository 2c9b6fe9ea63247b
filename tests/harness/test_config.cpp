// Config errors name the file and the key's path; valid configs get their defaults.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "particle/describe.hpp"

using namespace psweep;

namespace {

std::string error_of(const std::string& text) {
  try {
    parse_config(text, "c.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

const char* minimal =
    R"({"name": "t", "base": {"engine": "brute", "N": 100, "L": 1000, "r": 1, "S": 10}})";

}  // namespace

TEST(Config, MinimalGetsDefaults) {
  Config c = parse_config(minimal, "c.json");
  EXPECT_EQ(c.name, "t");
  EXPECT_EQ(c.base.engine, "brute");
  EXPECT_EQ(c.base.N, 100);
  EXPECT_DOUBLE_EQ(c.base.L, 1000);
  EXPECT_EQ(c.base.slow_factor, 1);
  EXPECT_EQ(c.base.T, 1);
  EXPECT_EQ(c.base.seed, 3210u);
  EXPECT_FALSE(c.base.G);
  EXPECT_EQ(c.combine, Combine::product);
  EXPECT_EQ(c.pin, Pin::none);
  EXPECT_EQ(c.repetitions, 1);
  EXPECT_EQ(c.warmup, 0);
}

TEST(Config, NameDefaultsToFileStem) {
  Config c = parse_config(R"({"base": {"engine": "brute", "N": 1, "L": 10, "r": 1, "S": 1}})",
                          "dir/my.sweep.json");
  EXPECT_EQ(c.name, "my.sweep");
}

TEST(Config, FullConfigParses) {
  Config c = parse_config(R"({
      "name": "threads", "description": "x",
      "base": {"N": 1000, "L": 20000, "r": 1, "S": 1000, "slow_factor": 4, "seed": 7, "engine": "brute", "T": 1, "G": 8,
               "speed_min": 1.5, "speed_max": 3},
      "sweep": {"N": [250, 500], "T": [1, 2, 4]},
      "combine": "one-at-a-time", "repetitions": 5, "warmup": 1, "pin": "spread", "timeout_s": 2.5,
      "analysis": {"scenes": [{"name": "a"}]}})",
                          "c.json");
  ASSERT_EQ(c.sweep.size(), 2u);
  EXPECT_EQ(c.sweep[0].key, "N");  // file order kept
  EXPECT_EQ(c.sweep[1].values.size(), 3u);
  EXPECT_EQ(c.combine, Combine::one_at_a_time);
  EXPECT_EQ(c.pin, Pin::spread);
  EXPECT_EQ(c.repetitions, 5);
  EXPECT_EQ(c.warmup, 1);
  EXPECT_DOUBLE_EQ(c.timeout_s, 2.5);
  EXPECT_EQ(c.base.slow_factor, 4);
  EXPECT_EQ(c.base.G, 8);
  EXPECT_DOUBLE_EQ(*c.base.speed_min, 1.5);
  EXPECT_EQ(c.raw["analysis"]["scenes"][0]["name"], "a");  // kept, unread, for meta.json
}

TEST(Config, InvalidJsonNamesLineAndColumn) {
  std::string e = error_of("{\n  \"name\": \"x\",\n  \"base\": {,}\n}");
  EXPECT_EQ(e.rfind("c.json: line 3, column 12: invalid JSON:", 0), 0u) << e;
  EXPECT_NE(error_of("").find("c.json: line 1, column 1: invalid JSON"), std::string::npos);
}

TEST(Config, ErrorsNameTheKeyPath) {
  auto with = [](const std::string& extra) {
    return error_of(R"({"base": {"engine": "brute", "N": 100, "L": 1000, "r": 1, "S": 10})" +
                    extra + "}");
  };
  EXPECT_EQ(with(R"(, "sweep": {"T": [1, 2, 0]})"),
            "c.json: sweep.T[2]: expected a positive integer, got 0");
  EXPECT_EQ(with(R"(, "sweep": {"T": [1, 2.5]})"),
            "c.json: sweep.T[1]: expected a positive integer, got 2.5");
  EXPECT_EQ(with(R"(, "sweep": {"N": ["9"]})"),
            "c.json: sweep.N[0]: expected a positive integer, got \"9\"");
  EXPECT_EQ(with(R"(, "sweep": {"slow_factor": [1, 3]})"),
            "c.json: sweep.slow_factor[1]: expected a power of two (1, 2, 4, ...), got 3");
  EXPECT_EQ(with(R"(, "sweep": {"r": [-1]})"),
            "c.json: sweep.r[0]: expected a positive number, got -1");
  EXPECT_EQ(with(R"(, "sweep": {"T": []})"),
            "c.json: sweep.T: expected a non-empty array of values");
  EXPECT_EQ(with(R"(, "sweep": {"T": 4})"),
            "c.json: sweep.T: expected a non-empty array of values");
  EXPECT_NE(with(R"(, "sweep": {"Q": [1]})").find("c.json: sweep.Q: unknown parameter"),
            std::string::npos);
  EXPECT_NE(with(R"(, "bogus": 1)").find("c.json: bogus: unknown key"), std::string::npos);
  EXPECT_EQ(with(R"(, "analysis": [1])"),
            "c.json: analysis: expected an object (read by the analysis through meta.json)");
  EXPECT_EQ(with(R"(, "pin": "tight")"),
            "c.json: pin: expected one of \"close\", \"spread\", \"none\", got \"tight\"");
  EXPECT_NE(with(R"(, "combine": "all")").find("c.json: combine: expected one of"),
            std::string::npos);
  EXPECT_EQ(with(R"(, "repetitions": 0)"),
            "c.json: repetitions: expected a positive integer, got 0");
  EXPECT_EQ(with(R"(, "warmup": -1)"), "c.json: warmup: expected a non-negative integer, got -1");
  EXPECT_EQ(with(R"(, "timeout_s": 0)"), "c.json: timeout_s: expected a positive number, got 0");
  EXPECT_NE(with(R"(, "name": "../x")").find("c.json: name: expected a name"), std::string::npos);
  EXPECT_NE(error_of(R"({"base": {"engine": "brute", "N": 1, "L": 1, "r": 1, "S": 1, "X": 2}})")
                .find("c.json: base.X: unknown parameter"),
            std::string::npos);
  // a number beyond a double has no position in nlohmann's message: its key path instead
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute", "N": 1, "L": 1e400, "r": 1, "S": 1}})"),
            "c.json: base.L: number overflow parsing '1e400' (beyond the range of a double)");
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute"}, "sweep": {"L": [10, 1e999]}})"),
            "c.json: sweep.L[1]: number overflow parsing '1e999' (beyond the range of a double)");
  EXPECT_EQ(error_of("[1]"), "c.json: (top level): expected a JSON object");
}

TEST(Config, RequiredKeys) {
  EXPECT_EQ(error_of(R"({"base": {"N": 1, "L": 10, "r": 1, "S": 1}})"),
            "c.json: base.engine: missing (set it in base or sweep it)");
  // product: an axis may replace the base value ...
  EXPECT_NO_THROW(parse_config(
      R"({"base": {"engine": "brute", "L": 10, "r": 1, "S": 1}, "sweep": {"N": [1, 2]}})",
      "c.json"));
  // ... zip too (each run takes one value of every axis) ...
  EXPECT_EQ(
      parse_config(
          R"({"base": {"engine": "brute", "L": 10, "r": 1, "S": 1}, "sweep": {"N": [1, 2]}, "combine": "zip"})",
          "c.json")
          .combine,
      Combine::zip);
  // ... one-at-a-time varies around base, so base needs it.
  EXPECT_EQ(
      error_of(
          R"({"base": {"engine": "brute", "L": 10, "r": 1, "S": 1}, "sweep": {"N": [1, 2]}, "combine": "one-at-a-time"})"),
      "c.json: base.N: missing (one-at-a-time varies axes around base)");
  EXPECT_EQ(error_of(R"({"name": "x"})"),
            "c.json: base: missing (the parameters every run starts from)");
}

TEST(Config, SceneFileFixesTheScene) {
  const std::string path = ::testing::TempDir() + "psweep_scene.in";
  { std::ofstream(path) << "3\n100.5\n1\n20\nperf\n0 10 10 1 1\n1 20 20 1 1\n2 30 30 1 1\n"; }
  Config c =
      parse_config(R"({"base": {"engine": "brute"}, "scene_file": ")" + path + "\"}", "c.json");
  EXPECT_EQ(c.base.N, 3);
  EXPECT_DOUBLE_EQ(c.base.L, 100.5);
  EXPECT_EQ(c.base.S, 20);
  EXPECT_FALSE(c.base.seed);
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute", "N": 5}, "scene_file": ")" + path + "\"}"),
            "c.json: base.N: not allowed with scene_file (the scene file fixes the scene)");
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute"}, "sweep": {"seed": [1]}, "scene_file": ")" +
                     path + "\"}"),
            "c.json: sweep.seed: not allowed with scene_file (the scene file fixes the scene)");
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute"}, "scene_file": "/nonexistent/x.in"})"),
            "c.json: scene_file: cannot open \"/nonexistent/x.in\"");
  // its particle lines too, with psim's messages, before anything runs
  { std::ofstream(path) << "2\n100\n1\n20\nperf\n0 10 10 1 1\n0 20 20 1 1\n"; }
  EXPECT_EQ(error_of(R"({"base": {"engine": "brute"}, "scene_file": ")" + path + "\"}"),
            "c.json: scene_file: " + path + ":7: i: duplicate index 0");
  std::remove(path.c_str());
}

TEST(Config, UnknownEngineNamesThePath) {
  Config c = parse_config(R"({"base": {"engine": "brute", "N": 1, "L": 10, "r": 1, "S": 1},
                               "sweep": {"engine": ["brute", "warp"]}})",
                          "c.json");
  EXPECT_NO_THROW(check_engines(c, {"brute", "warp"}));
  try {
    check_engines(c, {"brute", "grid"});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "c.json: sweep.engine[1]: unknown engine \"warp\" (psim offers: brute, grid)");
  }
  Config b =
      parse_config(R"({"base": {"engine": "nope", "N": 1, "L": 10, "r": 1, "S": 1}})", "c.json");
  EXPECT_THROW(check_engines(b, {"brute"}), ConfigError);
}

TEST(Config, AnEngineThisBuildCannotRunIsRefusedWithPsimsReason) {
  Config c = parse_config(R"({"base": {"engine": "brute", "N": 1, "L": 10, "r": 1, "S": 1},
                               "sweep": {"engine": ["brute", "gpu"]}})",
                          "c.json");
  EXPECT_NO_THROW(check_engines(c, {"brute", "gpu"}));
  try {
    check_engines(c, {"brute", "gpu"}, {{"gpu", "this build has no CUDA"}});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "c.json: sweep.engine[1]: engine \"gpu\" cannot run in this build of psim: this "
                 "build has no CUDA (psim --describe says which engines can)");
  }
}

TEST(Declaration, NamesTheEnginesPsimCannotRun) {
  Json json = Json::parse(particle::describe_json());
  for (auto& e : json["engines"]) e["unavailable"] = e["name"] == "gpu" ? "no CUDA here" : "";
  EXPECT_EQ(parse_declaration(json.dump()).unavailable,
            (std::map<std::string, std::string>{{"gpu", "no CUDA here"}}));
  for (auto& e : json["engines"]) e.erase("unavailable");  // an older psim: every engine runs
  EXPECT_TRUE(parse_declaration(json.dump()).unavailable.empty());
}

TEST(Config, NeighbourIsAnAxisOfNoneOrBusy) {
  Config c = parse_config(
      R"({"base": {"engine": "brute", "N": 10, "L": 100, "r": 1, "S": 1},
          "sweep": {"neighbour": ["none", "busy"]}})",
      "c.json");
  EXPECT_EQ(c.base.neighbour, "none");
  ASSERT_EQ(c.sweep.size(), 1u);
  EXPECT_EQ(c.sweep[0].values.size(), 2u);
  EXPECT_NE(error_of(R"({"base": {"engine": "brute", "N": 10, "L": 100, "r": 1, "S": 1,
                                  "neighbour": "loud"}})")
                .find("c.json: base.neighbour: "),
            std::string::npos);
}
