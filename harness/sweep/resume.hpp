// Resume: the second stage of a sweep. What the results folder already holds: with --resume, the
// rows of runs.csv (whose repetitions are not run again) and the meta.json the session continues;
// without, an earlier sweep's files are moved to previous/ (previous-2/, ... when taken) and the
// sweep starts afresh.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "config/config.hpp"
#include "config/declaration.hpp"
#include "config/expansion.hpp"
#include "results/stats.hpp"

namespace psweep {

struct Resumed {
  std::vector<RecordedRun> recorded;           // the rows already in runs.csv
  std::set<std::pair<std::string, int>> done;  // (config_id, rep) not to run again
  std::size_t foreign = 0;                     // rows of configurations not in `runs`
};

// With `resume` and an existing out/runs.csv: its rows (a partial last line, a write cut short,
// is cut from the file). Throws ResultsError when its columns are not `columns` or a row is
// malformed. Otherwise sets out's runs.csv, summary.csv and meta.json aside (set_aside_previous)
// and returns nothing recorded.
Resumed resume_or_set_aside(const std::filesystem::path& out, bool resume,
                            const std::vector<RunSpec>& runs,
                            const std::vector<std::string>& columns);

// The meta.json at `path` of the sweep being resumed; nullopt when there is none or it is not JSON
// (with a warning: a new one is written).
std::optional<Json> earlier_meta(const std::string& path);

// With --resume: throws ResultsError when `old` (the folder's meta.json at `meta_path`) records a
// config that expands to other configurations than `config` does, naming the first key of the
// config where the two differ; repetitions still missing would otherwise mix two sweeps in one
// runs.csv. So does a changed external program (its entry under `programs`, or its executable's
// hash in meta.json). A config that changed elsewhere (its name, timeout_s) passes.
void check_same_expansion(const Json& old, const Config& config, const Declaration& declaration,
                          const std::string& meta_path);

// The meta.json this session writes: `fresh` (build_meta's) when there is no `old` one; else `old`
// with a `resumed` entry (date, git, command line, Slurm ids, and a note when the config changed).
// Throws ResultsError when `old` belongs to another shard (or to a whole sweep).
Json continued_meta(const Json& fresh, const std::optional<Json>& old, const std::string& folder);

}  // namespace psweep
