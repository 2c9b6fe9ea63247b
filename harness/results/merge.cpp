// Merge: see merge.hpp. O(rows + runs x repetitions) plus the expansion and the partition.
#include "results/merge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>
#include <unordered_map>

#include "results/csv.hpp"
#include "results/folder.hpp"
#include "results/meta.hpp"
#include "results/results.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

Json value_at(const Json& j, const char* a, const char* b) {
  if (!j.is_object() || !j.contains(a) || !j[a].is_object() || !j[a].contains(b)) return nullptr;
  return j[a][b];
}

// The nodes the rows ran on (runs.csv's node column): a shard requeued after a node was lost
// ran on two, and several Slurm nodes may share one host.
std::set<std::string> row_nodes(const RunsFile& runs) {
  std::set<std::string> nodes;
  const auto column = std::find(runs.header.begin(), runs.header.end(), "node");
  if (column == runs.header.end()) return nodes;
  const auto i = static_cast<std::size_t>(column - runs.header.begin());
  for (const auto& row : runs.rows)
    if (!row[i].empty()) nodes.insert(row[i]);
  return nodes;
}

// What meta.json keeps of each shard: where and when it ran.
Json shard_entry(const ShardFolder& f) {
  return {{"dir", f.dir},
          {"shard", to_string(f.shard)},
          {"host", value_at(f.meta, "machine", "hostname")},
          {"nodes", row_nodes(f.runs)},
          {"cpu_model", value_at(f.meta, "machine", "cpu_model")},
          {"online_cpus", value_at(f.meta, "machine", "online_cpus")},
          {"date", f.meta.value("date", Json(nullptr))},
          {"slurm", f.meta.value("slurm", Json(nullptr))},
          {"sessions", f.meta.value("sessions", Json::array())},
          {"rows", f.runs.rows.size()}};
}

std::string runs_text(const std::vector<std::pair<std::string, int>>& runs, std::size_t most) {
  std::string text;
  for (std::size_t i = 0; i < runs.size() && i < most; ++i)
    text += fmt::format("{}{} rep {}", i ? ", " : "", runs[i].first, runs[i].second);
  if (runs.size() > most) text += fmt::format(", ... ({} in all)", runs.size());
  return text;
}

// The shard folders given, each read whole; OUT must not be one of them.
std::vector<ShardFolder> read_shards(const MergeOptions& opt) {
  if (opt.shard_dirs.empty()) throw ResultsError("give OUT and at least one shard folder");
  std::vector<ShardFolder> folders;
  for (const auto& dir : opt.shard_dirs) {
    std::error_code ec;
    if (fs::equivalent(opt.out, dir, ec))
      throw ResultsError(fmt::format("OUT {} is one of the shard folders", opt.out));
    folders.push_back(read_shard_folder(dir));
  }
  check_same_sweep(folders);
  return folders;
}

std::size_t missing_runs(const Merged& merged) {
  std::size_t missing = 0;
  for (const auto& m : merged.missing) missing += m.runs.size();
  return missing;
}

// The merged sweep's meta.json: the first shard's, with where every shard ran and what the merge
// found missing, duplicated or unexpected.
std::set<std::string> shard_hosts(const std::vector<ShardFolder>& folders) {
  std::set<std::string> hosts;
  for (const auto& f : folders)
    if (auto host = value_at(f.meta, "machine", "hostname"); host.is_string()) hosts.insert(host);
  return hosts;
}

void write_merged_meta(const MergeOptions& opt, const std::vector<ShardFolder>& folders,
                       const Merged& merged) {
  Json meta = folders.front().meta;
  for (const char* key : {"shard", "sessions", "resumed"}) meta.erase(key);
  meta["date"] = utc_now();
  meta["command_line"] = opt.command_line;
  meta["slurm"] = slurm_job();
  Json shards = Json::array();
  for (const auto& f : folders) shards.push_back(shard_entry(f));
  meta["merged"] = {{"shards", shards},
                    {"shard_count", folders.front().shard.count},
                    {"hosts", shard_hosts(folders)},
                    {"nodes", row_nodes(merged.runs)},
                    {"missing_runs", missing_runs(merged)},
                    {"duplicated_runs", merged.duplicated.size()},
                    {"unexpected_rows", merged.unexpected.size()}};
  write_json((fs::path(opt.out) / "meta.json").string(), meta);
}

// What the merge could not make whole, on stderr: the shards that owe runs (with the command
// that completes each), duplicated runs, rows of no configuration.
void report_gaps(const std::vector<ShardFolder>& folders, const Merged& merged) {
  const ShardFolder& first = folders.front();
  const int count = first.shard.count;
  const std::string config_file = first.meta.value("config_file", std::string("CONFIG"));
  for (const auto& m : merged.missing) {
    auto given = std::find_if(folders.begin(), folders.end(),
                              [&](const ShardFolder& f) { return f.shard.index == m.shard; });
    std::fprintf(stderr,
                 "psweep merge: shard %d/%d owes %zu runs (%s); complete it with:\n"
                 "  psweep %s --shard %d/%d --out %s --resume\n",
                 m.shard, count, m.runs.size(), runs_text(m.runs, 3).c_str(), config_file.c_str(),
                 m.shard, count,
                 given != folders.end() ? given->dir.c_str() : "SHARD_DIR (no folder given)");
  }
  if (!merged.duplicated.empty())
    std::fprintf(stderr, "psweep merge: %zu runs appear more than once (the first kept): %s\n",
                 merged.duplicated.size(), runs_text(merged.duplicated, 3).c_str());
  for (std::size_t i = 0; i < merged.unexpected.size() && i < 3; ++i)
    std::fprintf(stderr, "psweep merge: left out a row of no configuration of the config: %s\n",
                 merged.unexpected[i].c_str());
  if (merged.unexpected.size() > 3)
    std::fprintf(stderr, "psweep merge: ... %zu such rows in all\n", merged.unexpected.size());
}

int merge(const MergeOptions& opt) {
  const std::vector<ShardFolder> folders = read_shards(opt);
  const ShardFolder& first = folders.front();
  // The shards' own config and psim declaration, so the merge expands and partitions exactly as
  // they did, whatever psim is installed here.
  const Config config = parse_config(first.meta["config"].dump(), first.dir + "/meta.json");
  Declaration declaration;
  try {
    declaration = parse_declaration(first.meta["declaration"].dump());
  } catch (const std::runtime_error& e) {
    throw ResultsError(fmt::format("{}/meta.json: declaration: {}", first.dir, e.what()));
  }
  const std::vector<RunSpec> runs = expand(config, declaration);
  const int count = first.shard.count;
  const Merged merged =
      merge_rows(runs, assign_shards(config, declaration, count), config.repetitions, folders);

  const FolderLock lock(opt.out);
  if (holds_results(opt.out)) {
    if (!opt.replace)
      throw ResultsError(fmt::format(
          "{} already holds results; give --replace to keep them in {}/previous/ and merge anew, "
          "or choose another OUT",
          opt.out, opt.out));
    set_aside_previous(opt.out);
  }
  const std::string runs_csv = (fs::path(opt.out) / "runs.csv").string();
  std::string text = merged.runs.header.empty() ? "" : csv_line(merged.runs.header);
  for (const auto& row : merged.runs.rows) text += csv_line(row);
  write_file_atomically(runs_csv, text);
  write_summary((fs::path(opt.out) / "summary.csv").string(), runs,
                recorded_runs(merged.runs, runs_csv));
  write_merged_meta(opt, folders, merged);

  std::fprintf(stderr,
               "psweep merge: %zu folders of %d shards (hosts: %s): %zu runs of %zu "
               "configurations in %s\n",
               folders.size(), count,
               fmt::format("{}", fmt::join(shard_hosts(folders), ", ")).c_str(),
               merged.runs.rows.size(), runs.size(), opt.out.c_str());
  report_gaps(folders, merged);
  return missing_runs(merged) || !merged.duplicated.empty() || !merged.unexpected.empty() ? 1 : 0;
}

}  // namespace

ShardFolder read_shard_folder(const std::string& dir) {
  const fs::path meta_path = fs::path(dir) / "meta.json";
  if (!fs::exists(meta_path))
    throw ResultsError(fmt::format("{}: no meta.json; not a folder of psweep --shard", dir));
  ShardFolder f;
  f.dir = dir;
  try {
    f.meta = Json::parse(read_file(meta_path.string()));
  } catch (const nlohmann::json::exception& e) {
    throw ResultsError(fmt::format("{}: not valid JSON ({})", meta_path.string(), e.what()));
  }
  const Json index = value_at(f.meta, "shard", "index"), count = value_at(f.meta, "shard", "count");
  if (!index.is_number_integer() || !count.is_number_integer())
    throw ResultsError(fmt::format(
        "{}: meta.json names no shard; a whole sweep, not a shard of one (psweep --shard I/N)",
        dir));
  f.shard = {index.get<int>(), count.get<int>()};
  if (f.shard.count < 1 || f.shard.index < 1 || f.shard.index > f.shard.count)
    throw ResultsError(fmt::format("{}: meta.json: shard {} is not I/N with 1 <= I <= N", dir,
                                   to_string(f.shard)));
  for (const char* key : {"config", "declaration"})
    if (!f.meta.contains(key)) throw ResultsError(fmt::format("{}: meta.json has no {}", dir, key));
  const fs::path runs_csv = fs::path(dir) / "runs.csv";
  if (fs::exists(runs_csv)) f.runs = read_runs(runs_csv.string(), false);
  return f;
}

void check_same_sweep(const std::vector<ShardFolder>& folders) {
  const ShardFolder& a = folders.front();
  for (const ShardFolder& b : folders) {
    if (b.meta["config"] != a.meta["config"])
      throw ResultsError(
          fmt::format("{} and {} ran different configs; shards of one sweep only", a.dir, b.dir));
    if (b.meta["declaration"] != a.meta["declaration"])
      throw ResultsError(fmt::format(
          "{} and {} ran psims that declare different engines or metrics; shards of one build only",
          a.dir, b.dir));
    const Json commit_a = value_at(a.meta, "git", "commit"),
               commit_b = value_at(b.meta, "git", "commit");
    if (commit_a != commit_b)
      throw ResultsError(
          fmt::format("{} ran commit {} and {} commit {}; shards of one "
                      "build only (their timings would not compare)",
                      a.dir, commit_a.dump(), b.dir, commit_b.dump()));
    if (!a.runs.header.empty() && !b.runs.header.empty() && a.runs.header != b.runs.header)
      throw ResultsError(fmt::format("{} and {}: runs.csv columns differ", a.dir, b.dir));
    if (b.shard.count != a.shard.count)
      throw ResultsError(fmt::format("{} is shard {} and {} shard {}: different splits", a.dir,
                                     to_string(a.shard), b.dir, to_string(b.shard)));
  }
}

Merged merge_rows(const std::vector<RunSpec>& runs, const std::vector<int>& shard_of,
                  int repetitions, const std::vector<ShardFolder>& folders) {
  std::unordered_map<std::string, std::size_t> index_of;
  for (std::size_t i = 0; i < runs.size(); ++i) index_of.emplace(runs[i].id, i);
  const auto reps = static_cast<std::size_t>(repetitions);
  Merged m;
  for (const ShardFolder& f : folders)
    if (m.runs.header.empty()) m.runs.header = f.runs.header;
  std::vector<bool> seen(runs.size() * reps, false);
  std::vector<std::tuple<std::size_t, int, const std::vector<std::string>*>> kept;
  for (const ShardFolder& f : folders) {
    if (f.runs.header.empty()) continue;
    const std::string path = f.dir + "/runs.csv";
    const std::size_t id_col = column(f.runs, "config_id", path),
                      rep_col = column(f.runs, "rep", path);
    for (const auto& row : f.runs.rows) {
      const std::string& id = row[id_col];
      auto it = index_of.find(id);
      int rep = -1;
      try {
        rep = std::stoi(row[rep_col]);
      } catch (const std::logic_error&) {
      }
      if (it == index_of.end() || rep < 0 || rep >= repetitions) {
        m.unexpected.push_back(fmt::format("{}: {} rep {}", f.dir, id, row[rep_col]));
        continue;
      }
      auto slot = it->second * reps + static_cast<std::size_t>(rep);
      if (seen[slot]) {
        m.duplicated.emplace_back(id, rep);
        continue;
      }
      seen[slot] = true;
      kept.emplace_back(it->second, rep, &row);
    }
  }
  std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) {
    return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
  });
  for (const auto& k : kept) m.runs.rows.push_back(*std::get<2>(k));

  std::map<int, std::vector<std::pair<std::string, int>>> owed;
  for (std::size_t i = 0; i < runs.size(); ++i)
    for (std::size_t r = 0; r < reps; ++r)
      if (!seen[i * reps + r]) owed[shard_of[i] + 1].emplace_back(runs[i].id, static_cast<int>(r));
  for (auto& [shard, list] : owed) m.missing.push_back({shard, std::move(list)});
  return m;
}

int run_merge(const MergeOptions& opt) {
  try {
    return merge(opt);
  } catch (const ResultsError& e) {
    std::fprintf(stderr, "psweep merge: %s\n", e.what());
    return 2;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "psweep merge: the shards' config: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "psweep merge: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace psweep
