// Merge: shard folders of one sweep joined, refusals (not a shard, different config, commit or
// split), missing runs with the shard that owes them, duplicated runs kept once.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "declaration_fixture.hpp"
#include "results/csv.hpp"
#include "results/merge.hpp"
#include "results/results.hpp"

using namespace psweep;
namespace fs = std::filesystem;

namespace {

using fixture::declared;

const char* kConfig =
    R"({"name": "m", "base": {"engine": "brute", "N": 100, "L": 2000, "r": 1, "S": 10, "T": 1},
        "sweep": {"engine": ["brute", "auto"], "N": [50, 100, 200], "T": [1, 2]},
        "repetitions": 2})";

std::vector<std::string> row_of(const std::string& id, int rep, const std::string& node = "") {
  const auto cols = runs_columns(declared());
  std::vector<std::string> row(cols.size());
  auto col = [&](const char* name) {
    return static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin());
  };
  row[col("config_id")] = id;
  row[col("rep")] = std::to_string(rep);
  row[col("status")] = "ok";
  row[col("wall_s")] = "0.5";
  row[col("node")] = node;
  return row;
}

struct Sweep {
  Config config = parse_config(kConfig, "m.json");
  std::vector<RunSpec> runs = expand(config, declared());
  std::vector<int> shard_of = assign_shards(config, declared(), 3);
  // One folder per test: ctest runs the tests of this file in parallel.
  fs::path root = fs::path(::testing::TempDir()) /
                  (std::string("psweep_merge_") +
                   ::testing::UnitTest::GetInstance()->current_test_info()->name());

  Sweep() { fs::remove_all(root); }
  ~Sweep() { fs::remove_all(root); }

  // Writes shard `index` (1-based) of 3 as psweep --shard would: meta.json and all its runs.
  std::string write_shard(int index, const std::string& commit = "abc",
                          const char* config_text = kConfig, int count = 3,
                          const Json& declaration = declared().json) {
    const fs::path dir = root / ("shard-" + std::to_string(index));
    const std::string node = "node" + std::to_string(index);
    fs::create_directories(dir);
    Json meta = {{"config_file", "m.json"},
                 {"config", Json::parse(config_text)},
                 {"declaration", declaration},
                 {"git", {{"commit", commit}}},
                 {"machine", {{"hostname", node}}},
                 {"shard", {{"index", index}, {"count", count}}}};
    write_json((dir / "meta.json").string(), meta);
    std::string text = csv_line(runs_columns(declared()));
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (shard_of[i] == index - 1)
        for (int rep = 0; rep < config.repetitions; ++rep)
          text += csv_line(row_of(runs[i].id, rep, node));
    write_file_atomically((dir / "runs.csv").string(), text);
    return dir.string();
  }

  std::vector<ShardFolder> read(const std::vector<std::string>& dirs) {
    std::vector<ShardFolder> folders;
    for (const auto& d : dirs) folders.push_back(read_shard_folder(d));
    return folders;
  }
};

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const ResultsError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Merge, CompleteShardsGiveEveryRunOnceInExpansionOrder) {
  Sweep s;
  auto folders = s.read({s.write_shard(3), s.write_shard(1), s.write_shard(2)});
  check_same_sweep(folders);
  const Merged m = merge_rows(s.runs, s.shard_of, s.config.repetitions, folders);
  EXPECT_TRUE(m.missing.empty());
  EXPECT_TRUE(m.duplicated.empty());
  EXPECT_TRUE(m.unexpected.empty());
  ASSERT_EQ(m.runs.rows.size(), s.runs.size() * 2);
  for (std::size_t i = 0; i < s.runs.size(); ++i) {
    EXPECT_EQ(m.runs.rows[2 * i][0], s.runs[i].id);
    EXPECT_EQ(m.runs.rows[2 * i + 1][0], s.runs[i].id);
  }
}

TEST(Merge, MissingRunsNameTheShardThatOwesThem) {
  Sweep s;
  const auto d1 = s.write_shard(1), d3 = s.write_shard(3);
  // Shard 3 lost its last row (interrupted); shard 2 was not given at all.
  auto folders = s.read({d1, d3});
  const auto lost = folders[1].runs.rows.back();
  folders[1].runs.rows.pop_back();
  const Merged m = merge_rows(s.runs, s.shard_of, s.config.repetitions, folders);
  ASSERT_EQ(m.missing.size(), 2u);
  EXPECT_EQ(m.missing[0].shard, 2);
  EXPECT_EQ(m.missing[1].shard, 3);
  ASSERT_EQ(m.missing[1].runs.size(), 1u);
  EXPECT_EQ(m.missing[1].runs[0].first, lost[0]);
  std::size_t owed_by_2 = 0;
  for (std::size_t i = 0; i < s.runs.size(); ++i) owed_by_2 += s.shard_of[i] == 1 ? 2 : 0;
  EXPECT_EQ(m.missing[0].runs.size(), owed_by_2);
}

TEST(Merge, DuplicatedRunsAreKeptOnceAndReported) {
  Sweep s;
  const auto d1 = s.write_shard(1), d2 = s.write_shard(2), d3 = s.write_shard(3);
  auto folders = s.read({d1, d2, d3, d1});
  const Merged m = merge_rows(s.runs, s.shard_of, s.config.repetitions, folders);
  EXPECT_EQ(m.runs.rows.size(), s.runs.size() * 2);
  EXPECT_EQ(m.duplicated.size(), folders[0].runs.rows.size());
  EXPECT_TRUE(m.missing.empty());
  // Complete but for the duplicates, the merge still fails: a folder given twice is a mistake in
  // the job that a dependent Slurm job must not build on.
  const std::string out = (s.root / "merged").string();
  EXPECT_EQ(run_merge({out, {d1, d2, d3, d1}, {}}), 1);
  EXPECT_EQ(read_runs(out + "/runs.csv", false).rows.size(), s.runs.size() * 2);
  const Json meta = Json::parse(read_file(out + "/meta.json"));
  EXPECT_EQ(meta["merged"]["duplicated_runs"], folders[0].runs.rows.size());
  EXPECT_EQ(meta["merged"]["missing_runs"], 0);
}

TEST(Merge, RowsOfOtherConfigurationsAreLeftOut) {
  Sweep s;
  auto folders = s.read({s.write_shard(1), s.write_shard(2), s.write_shard(3)});
  folders[0].runs.rows.push_back(row_of("0123456789ab", 0));
  folders[0].runs.rows.push_back(row_of(s.runs[0].id, 7));  // a repetition the config does not have
  const Merged m = merge_rows(s.runs, s.shard_of, s.config.repetitions, folders);
  EXPECT_EQ(m.unexpected.size(), 2u);
  EXPECT_EQ(m.runs.rows.size(), s.runs.size() * 2);
}

TEST(Merge, RefusesShardsOfDifferentSweeps) {
  Sweep s;
  const auto d1 = s.write_shard(1);
  EXPECT_NE(refusal([&] {
              check_same_sweep(s.read({d1, s.write_shard(2, "def")}));
            }).find("commit"),
            std::string::npos);
  std::string other = kConfig;
  other.replace(other.find("\"S\": 10"), 7, "\"S\": 20");
  EXPECT_NE(refusal([&] {
              check_same_sweep(s.read({d1, s.write_shard(2, "abc", other.c_str())}));
            }).find("different configs"),
            std::string::npos);
  EXPECT_NE(refusal([&] {
              check_same_sweep(s.read({d1, s.write_shard(2, "abc", kConfig, 4)}));
            }).find("different splits"),
            std::string::npos);
  Json other_psim = declared().json;
  other_psim["metrics"].erase(other_psim["metrics"].size() - 1);
  EXPECT_NE(refusal([&] {
              check_same_sweep(s.read({d1, s.write_shard(2, "abc", kConfig, 3, other_psim)}));
            }).find("declare different engines or metrics"),
            std::string::npos);
}

TEST(Merge, RefusesFoldersThatAreNotShards) {
  Sweep s;
  const auto dir = s.write_shard(1);
  Json meta = Json::parse(read_file(dir + "/meta.json"));
  meta.erase("shard");
  write_json(dir + "/meta.json", meta);
  EXPECT_NE(refusal([&] { read_shard_folder(dir); }).find("names no shard"), std::string::npos);
  const auto older = s.write_shard(2);  // a psweep from before the declaration
  meta = Json::parse(read_file(older + "/meta.json"));
  meta.erase("declaration");
  write_json(older + "/meta.json", meta);
  EXPECT_NE(refusal([&] { read_shard_folder(older); }).find("has no declaration"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_shard_folder((s.root / "nowhere").string()); }).find("no meta.json"),
            std::string::npos);
}

TEST(Merge, WritesTheMergedFolderAndFailsWhenIncomplete) {
  Sweep s;
  const auto d1 = s.write_shard(1), d2 = s.write_shard(2), d3 = s.write_shard(3);
  const std::string out = (s.root / "merged").string();
  EXPECT_EQ(run_merge({out, {d1, d2, d3}, {"psweep", "merge"}}), 0);
  EXPECT_EQ(read_runs(out + "/runs.csv", false).rows.size(), s.runs.size() * 2);
  Json meta = Json::parse(read_file(out + "/meta.json"));
  EXPECT_EQ(meta["merged"]["shards"].size(), 3u);
  EXPECT_EQ(meta["merged"]["hosts"], Json({"node1", "node2", "node3"}));
  EXPECT_EQ(meta["merged"]["nodes"], Json({"node1", "node2", "node3"}));
  EXPECT_EQ(meta["merged"]["shards"][0]["nodes"], Json({"node1"}));
  EXPECT_EQ(meta["merged"]["missing_runs"], 0);
  EXPECT_FALSE(meta.contains("shard"));
  const std::string merged = read_file(out + "/runs.csv");
  EXPECT_EQ(run_merge({out, {d1, d3}, {}}), 2);  // OUT holds results: not replaced unasked
  EXPECT_EQ(read_file(out + "/runs.csv"), merged);
  EXPECT_EQ(run_merge({out, {d1, d3}, {}, true}), 1);  // shard 2 missing
  EXPECT_GT(Json::parse(read_file(out + "/meta.json"))["merged"]["missing_runs"], 0);
  EXPECT_EQ(read_file(out + "/previous/runs.csv"), merged);
  EXPECT_EQ(run_merge({d1, {d1, d2}, {}}), 2);  // OUT is a shard folder
}
