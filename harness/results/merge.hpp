// Merge: `psweep merge OUT SHARD_DIR...` joins the folders of `psweep CONFIG --shard I/N` into one
// results folder (runs.csv, summary.csv, meta.json), as if one machine had run the whole sweep.
//
// Every shard folder must come from the same sweep: the same config, the same git commit and psim
// declaration (a different build would measure something else), and the same number of shards. The
// config is expanded and partitioned again, so the merge knows which runs each shard owes: a
// missing run is reported with the shard that owes it and the command that completes it; a run
// present twice (a folder given twice, two folders of one shard) is kept once and reported. A
// missing or duplicated run still writes OUT, but the exit status is 1, so a dependent Slurm job
// stops. runs.csv rows are ordered by configuration (expansion order), then repetition.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "config/config.hpp"
#include "config/expansion.hpp"
#include "config/shard.hpp"
#include "results/results.hpp"

namespace psweep {

struct MergeOptions {
  std::string out;
  std::vector<std::string> shard_dirs;
  std::vector<std::string> command_line;
  bool replace = false;  // OUT holds results: set them aside (previous/) instead of refusing
};

// 0: merged and complete; 1: merged with missing or duplicated runs, or an I/O error; 2: refused
// (not shard folders, different sweeps, bad files).
int run_merge(const MergeOptions& options);

// One shard folder as read back: meta.json and the rows of runs.csv.
struct ShardFolder {
  std::string dir;
  Json meta;
  ShardSpec shard;
  RunsFile runs;  // empty when the shard wrote no runs.csv
};

// Throws ResultsError naming the folder when it is not a shard folder.
ShardFolder read_shard_folder(const std::string& dir);

// Throws ResultsError when the folders are not shards of one sweep (config, commit, declaration,
// shard count, runs.csv columns).
void check_same_sweep(const std::vector<ShardFolder>& folders);

struct MissingRuns {
  int shard = 0;                                  // 1-based, the shard that owes them
  std::vector<std::pair<std::string, int>> runs;  // (config_id, rep)
};

struct Merged {
  RunsFile runs;                     // each (config_id, rep) once, in expansion order
  std::vector<MissingRuns> missing;  // per shard, in shard order; only shards owing runs
  std::vector<std::pair<std::string, int>> duplicated;  // (config_id, rep) seen more than once
  std::vector<std::string> unexpected;  // "dir: config_id" rows of no configuration of the config
};

// Joins the rows of `folders`; `shard_of[i]` is the 0-based shard of runs[i].
Merged merge_rows(const std::vector<RunSpec>& runs, const std::vector<int>& shard_of,
                  int repetitions, const std::vector<ShardFolder>& folders);

}  // namespace psweep
