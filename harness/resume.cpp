// Resume: see resume.hpp.
#include "resume.hpp"

#include <fmt/format.h>

#include <cstdio>

#include "results.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

// Moves the files of an earlier sweep in `out` to out/previous/, replacing what was there.
void set_aside_previous(const fs::path& out) {
  const fs::path previous = out / "previous";
  bool moved = false;
  for (const char* name : {"runs.csv", "summary.csv", "meta.json"}) {
    if (!fs::exists(out / name)) continue;
    if (!moved) {
      fs::remove_all(previous);
      fs::create_directories(previous);
      moved = true;
    }
    fs::rename(out / name, previous / name);
  }
  if (moved)
    std::fprintf(
        stderr,
        "psweep: moved the earlier results in %s to %s (use --resume to continue a sweep)\n",
        out.c_str(), previous.c_str());
}

// "shard I/N" or "the whole sweep", from a meta.json.
std::string shard_text(const Json& meta) {
  if (!meta.contains("shard")) return "the whole sweep";
  return fmt::format("shard {}/{}", meta["shard"].value("index", 0),
                     meta["shard"].value("count", 0));
}

}  // namespace

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
