// Resume: see resume.hpp.
#include "sweep/resume.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>

#include "results/folder.hpp"
#include "results/meta.hpp"
#include "results/results.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

// "shard I/N" or "the whole sweep", from a meta.json.
std::string shard_text(const Json& meta) {
  if (!meta.contains("shard")) return "the whole sweep";
  return fmt::format("shard {}/{}", meta["shard"].value("index", 0),
                     meta["shard"].value("count", 0));
}

// The key path of the first place, in `a`'s order, where `a` and `b` differ ("sweep.N[2]").
std::string first_difference(const Json& a, const Json& b, const std::string& path) {
  const auto key = [&](const std::string& k) { return path.empty() ? k : path + "." + k; };
  if (a.is_object() && b.is_object()) {
    for (const auto& [k, value] : a.items()) {
      if (!b.contains(k)) return key(k);
      if (std::string d = first_difference(value, b[k], key(k)); !d.empty()) return d;
    }
    for (const auto& [k, value] : b.items())
      if (!a.contains(k)) return key(k);
    return "";
  }
  if (a.is_array() && b.is_array()) {
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
      if (std::string d = first_difference(a[i], b[i], fmt::format("{}[{}]", path, i)); !d.empty())
        return d;
    return a.size() == b.size() ? "" : fmt::format("{}[{}]", path, std::min(a.size(), b.size()));
  }
  return a == b ? "" : path;
}

}  // namespace

namespace {

// An external program is not in its configurations' ids (its name is): a changed command, or an
// executable rebuilt since, would mix two programs' runs under one name.
void check_same_programs(const Json& old, const Config& config, const std::string& meta_path) {
  const Json before = old.contains("config") ? old["config"].value("programs", Json()) : Json();
  if (const std::string key =
          first_difference(before, config.raw.value("programs", Json()), "programs");
      !key.empty())
    throw ResultsError(fmt::format(
        "{}: {}: differs from the programs of the sweep recorded in {}; --force mixes both in "
        "one runs.csv",
        config.file, key, meta_path));
  const Json now = programs_meta(config);
  for (const auto& [name, program] : now.items()) {
    const Json was = old.value("programs", Json::object()).value(name, Json::object());
    const Json hash_was = was.value("executable_hash", Json()), hash = program["executable_hash"];
    if (!hash_was.is_null() && !hash.is_null() && hash_was != hash)
      throw ResultsError(fmt::format(
          "{}: programs.{}: {} changed since the sweep started (its hash is not the one {} "
          "records); --force mixes the two builds in one runs.csv",
          config.file, name, program["executable"].get<std::string>(), meta_path));
  }
}

}  // namespace

void check_same_expansion(const Json& old, const Config& config, const Declaration& declaration,
                          const std::string& meta_path) {
  check_same_programs(old, config, meta_path);
  if (!old.contains("config") || old["config"] == config.raw) return;
  std::vector<std::string> before, now;
  try {
    for (const RunSpec& run : expand(parse_config(old["config"].dump(), meta_path), declaration))
      before.push_back(run.id);
  } catch (const ConfigError&) {
    // Not a config this psweep reads: not the same sweep either (before stays empty).
  }
  for (const RunSpec& run : expand(config, declaration)) now.push_back(run.id);
  if (before == now) return;
  // The keys that make the configurations first: a changed name is not why they differ.
  std::string key;
  for (const char* k : {"base", "sweep", "combine", "scene_file", "pin"})
    if (key.empty())
      key = first_difference(old["config"].value(k, Json()), config.raw.value(k, Json()), k);
  if (key.empty()) key = first_difference(old["config"], config.raw, "");
  throw ResultsError(fmt::format(
      "{}: {}: expands to other configurations than the sweep recorded in {}; --force mixes both "
      "in one runs.csv",
      config.file, key.empty() ? "the config" : key, meta_path));
}

Resumed resume_or_set_aside(const fs::path& out, bool resume, const std::vector<RunSpec>& runs,
                            const std::vector<std::string>& columns) {
  const std::string runs_csv = (out / "runs.csv").string();
  Resumed r;
  if (!resume || !fs::exists(runs_csv)) {
    if (resume)
      std::fprintf(stderr, "psweep: nothing to resume in %s; starting the sweep\n", out.c_str());
    set_aside_previous(out);
    return r;
  }
  const RunsFile file = read_runs(runs_csv, true);
  if (!file.header.empty() && file.header != columns)
    throw ResultsError(runs_csv + ": its columns differ from this psweep's");
  r.recorded = recorded_runs(file, runs_csv);
  std::set<std::string> ids;
  for (const auto& run : runs) ids.insert(run.id);
  for (const auto& row : r.recorded) {
    if (!ids.count(row.config_id)) ++r.foreign;
    r.done.insert({row.config_id, row.rep});
  }
  return r;
}

std::optional<Json> earlier_meta(const std::string& path) {
  if (!fs::exists(path)) return std::nullopt;
  try {
    return Json::parse(read_file(path));
  } catch (const nlohmann::json::exception&) {
    std::fprintf(stderr, "psweep: warning: %s unreadable; writing a new one\n", path.c_str());
    return std::nullopt;
  }
}

Json continued_meta(const Json& fresh, const std::optional<Json>& old, const std::string& folder) {
  if (!old) return fresh;
  if (shard_text(*old) != shard_text(fresh))
    throw ResultsError(fmt::format("{} holds {}, not {} (each shard needs its own folder)", folder,
                                   shard_text(*old), shard_text(fresh)));
  Json session = {{"date", fresh["date"]},
                  {"git", fresh["git"]},
                  {"command_line", fresh["command_line"]},
                  {"slurm", fresh["slurm"]}};
  if (old->contains("config") && (*old)["config"] != fresh["config"])
    session["note"] = "the config changed since the sweep started";
  Json meta = *old;
  meta["resumed"].push_back(session);
  return meta;
}

}  // namespace psweep
